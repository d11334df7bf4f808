// The declarative command line (apps/CommandLine.h) and prep's table on it (apps/PrepArguments.h): good and
// bad values of every flag, table-driven, the errors naming the flag, and --help generated from the table.
#include "apps/CommandLine.h"
#include "apps/PrepArguments.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace terrain {
namespace {

bool mentions(const std::string& text, const std::string& part)
{
    return text.find(part) != std::string::npos;
}

/// A command line with a number in [1, 10], a whole number in [-5, 5], a size, a switch, an optional
/// attached value and positional arguments, recording what it was given.
struct Recorder {
    double number = 0;
    long long whole = 0;
    std::pair<int, int> size{0, 0};
    bool flag = false;
    std::string attached = "unset";
    std::vector<std::string> positional;
    CommandLine line;

    Recorder()
    {
        line.flags = {
            {"--number", "N", "a number",
             [this](const std::string& v) -> Status {
                 auto n = numberIn(v, 1, 10, "metres");
                 TERRAIN_TRY(n);
                 number = *n;
                 return {};
             }},
            {"--whole", "W", "a whole number\nover two lines",
             [this](const std::string& v) -> Status {
                 auto n = wholeNumberIn(v, -5, 5);
                 TERRAIN_TRY(n);
                 whole = *n;
                 return {};
             }},
            {"--size", "WxH", "a size",
             [this](const std::string& v) -> Status {
                 auto s = sizeIn(v, 16, 16384);
                 TERRAIN_TRY(s);
                 size = *s;
                 return {};
             }},
            {"-f", "", "a switch",
             [this](const std::string&) -> Status {
                 flag = true;
                 return {};
             }},
            {"--oracle", "", "a switch or --oracle=B",
             [this](const std::string& v) -> Status {
                 attached = v;
                 return {};
             },
             true},
        };
        line.positional = [this](const std::string& a) -> Status {
            positional.push_back(a);
            return {};
        };
        line.unknownHint = " (see --help)";
    }
};

TEST(CommandLineTest, GoodArgumentsApplyInOrder)
{
    struct Case {
        std::vector<std::string> args;
        double number;
        long long whole;
        std::vector<std::string> positional;
    };
    const Case cases[] = {
        {{}, 0, 0, {}},
        {{"--number", "2.5"}, 2.5, 0, {}},
        {{"--number=10", "--whole", "-5"}, 10, -5, {}},
        {{"--number", "1", "--number", "3"}, 3, 0, {}},
        {{"a", "--whole", "5", "b"}, 0, 5, {"a", "b"}},
        {{"-", "-500", "-1e3", ""}, 0, 0, {"-", "-500", "-1e3", ""}},
    };
    for (const Case& c : cases) {
        Recorder r;
        const Status status = r.line.parse(c.args);
        ASSERT_TRUE(status.ok()) << status.error().message;
        EXPECT_EQ(r.number, c.number);
        EXPECT_EQ(r.whole, c.whole);
        EXPECT_EQ(r.positional, c.positional);
    }
    Recorder r;
    ASSERT_TRUE(r.line.parse(std::vector<std::string>{"--size", "640x480", "-f", "--oracle"}).ok());
    EXPECT_EQ(r.size, (std::pair{640, 480}));
    EXPECT_TRUE(r.flag);
    EXPECT_EQ(r.attached, "");
    ASSERT_TRUE(r.line.parse(std::vector<std::string>{"--oracle=8"}).ok());
    EXPECT_EQ(r.attached, "8");
}

TEST(CommandLineTest, BadArgumentsAreErrorsNamingTheFlagAndTheValue)
{
    const double big = std::numeric_limits<double>::max();
    struct Case {
        std::vector<std::string> args;
        std::string error;  ///< the whole message
    };
    const Case cases[] = {
        {{"--number"}, "--number needs a value"},
        {{"--number", "abc"}, "--number: 'abc' is not a number in [1, 10] metres"},
        {{"--number", ""}, "--number: '' is not a number in [1, 10] metres"},
        {{"--number", "0.999"}, "--number: '0.999' is not a number in [1, 10] metres"},
        {{"--number", "nan"}, "--number: 'nan' is not a number in [1, 10] metres"},
        {{"--number", "inf"}, "--number: 'inf' is not a number in [1, 10] metres"},
        {{"--number", "-inf"}, "--number: '-inf' is not a number in [1, 10] metres"},
        {{"--number", "1e999"}, "--number: '1e999' is not a number in [1, 10] metres"},
        {{"--number", std::to_string(big)},
         "--number: '" + std::to_string(big) + "' is not a number in [1, 10] metres"},
        {{"--number", "5x"}, "--number: '5x' is not a number in [1, 10] metres"},
        {{"--number=", "5"}, "--number: '' is not a number in [1, 10] metres"},
        {{"--whole", "2.5"}, "--whole: '2.5' is not a whole number in [-5, 5]"},
        {{"--whole", "6"}, "--whole: '6' is not a whole number in [-5, 5]"},
        {{"--whole", "-9223372036854775808"}, "--whole: '-9223372036854775808' is not a whole number in [-5, 5]"},
        {{"--whole", "99999999999999999999"}, "--whole: '99999999999999999999' is not a whole number in [-5, 5]"},
        {{"--size", "15x480"}, "--size: '15x480' is not WIDTHxHEIGHT (16 to 16384 pixels each)"},
        {{"--size", "640"}, "--size: '640' is not WIDTHxHEIGHT (16 to 16384 pixels each)"},
        {{"--size", "640x480x2"}, "--size: '640x480x2' is not WIDTHxHEIGHT (16 to 16384 pixels each)"},
        {{"--size", "-640x480"}, "--size: '-640x480' is not WIDTHxHEIGHT (16 to 16384 pixels each)"},
        {{"--size", "99999999999x480"}, "--size: '99999999999x480' is not WIDTHxHEIGHT (16 to 16384 pixels each)"},
        {{"-f=1"}, "unknown option '-f=1' (see --help)"},
        {{"--bogus"}, "unknown option '--bogus' (see --help)"},
        {{"--bogus=1"}, "unknown option '--bogus=1' (see --help)"},
        {{"-x"}, "unknown option '-x' (see --help)"},
        {{"--number", "2", "--whole"}, "--whole needs a value"},
    };
    for (const Case& c : cases) {
        Recorder r;
        const Status status = r.line.parse(c.args);
        ASSERT_FALSE(status.ok()) << c.error;
        EXPECT_EQ(status.error().message, c.error);
    }
    // A switch given a value, and positional arguments where none are taken.
    Recorder r;
    r.line.flags[3].name = "--flag";
    EXPECT_EQ(r.line.parse(std::vector<std::string>{"--flag=1"}).error().message, "--flag takes no value");
    r.line.positional = nullptr;
    EXPECT_EQ(r.line.parse(std::vector<std::string>{"x"}).error().message, "unexpected argument 'x'");
    r.line.passUnknown = true;
    EXPECT_EQ(r.line.parse(std::vector<std::string>{"--bogus"}).error().message, "unexpected argument '--bogus'");
}

TEST(CommandLineTest, HelpListsTheTableAlignedAt23Columns)
{
    Recorder r;
    r.line.flags.push_back({"--a-very-long-flag-name", "VALUE", "long", nullptr});
    EXPECT_EQ(r.line.help(),
              "  --number N           a number\n"
              "  --whole W            a whole number\n"
              "                       over two lines\n"
              "  --size WxH           a size\n"
              "  -f                   a switch\n"
              "  --oracle             a switch or --oracle=B\n"
              "  --a-very-long-flag-name VALUE  long\n");
}

// ---- prep ----

Expected<PrepArguments> prep(std::vector<std::string> args)
{
    args.insert(args.begin(), "in.png");
    return parsePrepArguments(args, 3, "grass.mat");
}

TEST(CommandLineTest, PrepTakesEveryFlagsValue)
{
    auto parsed = prep({"-t",
                        "t.png",
                        "--srs",
                        "EPSG:32613",
                        "-w",
                        "w.png",
                        "-h",
                        "90",
                        "-v",
                        "0.1",
                        "-o",
                        "out.map",
                        "--offset",
                        "-100",
                        "--chunk",
                        "33",
                        "--max-error",
                        "2",
                        "--height-codec",
                        "pifs",
                        "--texture-size",
                        "65",
                        "--threads",
                        "2",
                        "--memory",
                        "256M",
                        "--out-of-core",
                        "--raw-size",
                        "10x20",
                        "--raw-signed",
                        "--raw-big-endian",
                        "--nodata",
                        "-inf",
                        "--clamp",
                        "-5,1e7",
                        "--material",
                        "rock.mat",
                        "--no-roughness",
                        "--detail-scheme",
                        "bilinear",
                        "--detail-factor",
                        "0.5",
                        "second.png"});
    ASSERT_TRUE(parsed.ok()) << parsed.error().message;
    const PrepArguments& a = *parsed;
    EXPECT_EQ(a.inputs, (std::vector<std::filesystem::path>{"in.png", "second.png"}));
    EXPECT_EQ(a.build.texture, std::filesystem::path("t.png"));
    EXPECT_EQ(a.read.targetSrs, "EPSG:32613");
    EXPECT_EQ(a.build.weights, std::filesystem::path("w.png"));
    EXPECT_EQ(a.build.spacing, 90.0);
    EXPECT_EQ(a.build.verticalScale, 0.1);
    EXPECT_EQ(a.output, std::filesystem::path("out.map"));
    EXPECT_EQ(a.build.offset, -100.0);
    EXPECT_EQ(a.build.chunkSize, 33);
    EXPECT_EQ(a.build.maxError, 2.0);
    EXPECT_EQ(a.build.heightCoding, kHeightCodingPifs);
    EXPECT_EQ(a.build.textureSize, 65);
    EXPECT_EQ(a.build.threads, 2);
    EXPECT_EQ(a.build.memoryBudget, std::uint64_t{256} << 20);
    EXPECT_TRUE(a.build.forceOutOfCore);
    EXPECT_EQ(a.read.rawWidth, 10);
    EXPECT_EQ(a.read.rawHeight, 20);
    EXPECT_TRUE(a.read.rawSigned);
    EXPECT_TRUE(a.read.rawBigEndian);
    EXPECT_EQ(a.read.noData, -std::numeric_limits<double>::infinity());
    EXPECT_EQ(a.build.clampMetres, (std::array<double, 2>{-5, 1e7}));
    EXPECT_EQ(a.materials, (std::vector<std::filesystem::path>{"rock.mat"}));
    EXPECT_TRUE(a.noRoughness);
    EXPECT_EQ(a.detail.scheme, "bilinear");
    EXPECT_EQ(a.detail.omega, 0.5);
    EXPECT_EQ(a.warnings.size(), 1u) << "--detail-factor has no effect with bilinear";

    auto defaults = prep({});
    ASSERT_TRUE(defaults.ok()) << defaults.error().message;
    EXPECT_EQ(defaults->build.threads, 3);
    EXPECT_EQ(defaults->materials, (std::vector<std::filesystem::path>{"grass.mat"}));
    EXPECT_EQ(defaults->build.textureSize, 0);
    auto bounds = prep({"--chunk",
                        "1025",
                        "--texture-size",
                        "0",
                        "--threads",
                        "1024",
                        "-h",
                        "1e-6",
                        "-v",
                        "1e9",
                        "--offset",
                        "1e7",
                        "--max-error",
                        "0",
                        "--detail-factor",
                        "2",
                        "--memory",
                        "1",
                        "--no-material",
                        "--nodata",
                        "3.40282346638529011e+38"});
    EXPECT_TRUE(bounds.ok()) << bounds.error().message;
}

TEST(CommandLineTest, PrepRefusesEveryOutOfRangeValueByName)
{
    struct Case {
        std::vector<std::string> args;
        std::string error;  ///< a part of the message
    };
    const std::string maxDouble = "1.7976931348623157e308";
    const Case cases[] = {
        {{"-h"}, "-h needs a value"},
        {{"-h", ""}, "-h: '' is not a number"},
        {{"-h", "abc"}, "-h: 'abc' is not a number"},
        {{"-h", "0"}, "-h: the spacing must be in [1e-06, 1e+06] metres, got 0"},
        {{"-h", "-90"}, "-h: the spacing must be in"},
        {{"-h", "nan"}, "-h: 'nan' is not a number"},
        {{"-h", "inf"}, "-h: 'inf' is not a number"},
        {{"-h", maxDouble}, "-h: the spacing must be in"},
        {{"-v", "0"}, "-v: the vertical scale must be in [1e-09, 1e+09] metres a unit, got 0"},
        {{"-v", "-1"}, "-v: the vertical scale must be in"},
        {{"-v", "1e300"}, "-v: the vertical scale must be in"},
        {{"-v", "-inf"}, "-v: '-inf' is not a number"},
        {{"--offset", "x"}, "--offset: 'x' is not a number"},
        {{"--offset", "-1e308"}, "--offset: must be within +-1e+07 metres"},
        {{"--offset", "nan"}, "--offset: 'nan' is not a number"},
        {{"--max-error", "-0.5"}, "--max-error: must be in [0, 1e+07] metres, got -0.5"},
        {{"--max-error", "1e8"}, "--max-error: must be in [0, 1e+07] metres"},
        {{"--chunk", "64"}, "--chunk: chunk size 64 must be 2^k+1 between 3 and 1025"},
        {{"--chunk", "0"}, "--chunk: chunk size 0 must be"},
        {{"--chunk", "-4294967231"}, "--chunk: chunk size -4294967231 must be"},
        {{"--chunk", "2049"}, "--chunk: chunk size 2049 must be"},
        {{"--chunk", "9223372036854775808"}, "--chunk: '9223372036854775808' is not an integer"},
        {{"--chunk", "65.0"}, "--chunk: '65.0' is not an integer"},
        {{"--chunk", ""}, "--chunk: '' is not an integer"},
        {{"--texture-size", "100"}, "--texture-size: texture size 100 must be 2^k+1"},
        {{"--texture-size", "-4294967231"}, "--texture-size: texture size -4294967231"},
        {{"--texture-size", "1e9"}, "--texture-size: '1e9' is not an integer"},
        {{"--threads", "0"}, "--threads: thread count 0 must be in [1, 1024]"},
        {{"--threads", "-1"}, "--threads: thread count -1"},
        {{"--threads", "1025"}, "--threads: thread count 1025"},
        {{"--threads", "4294967298"}, "--threads: thread count 4294967298"},
        {{"--memory", "0"}, "--memory: '0' is not a size in bytes"},
        {{"--memory", "lots"}, "--memory: 'lots' is not a size in bytes"},
        {{"--memory", "-1G"}, "--memory: '-1G' is not a size in bytes"},
        {{"--memory", "1e30"}, "--memory: '1e30' is not a size in bytes"},
        {{"--memory", "nanM"}, "--memory: 'nanM' is not a size in bytes"},
        {{"--memory", ""}, "--memory: '' is not a size in bytes"},
        {{"--raw-size", "10"}, "--raw-size: '10' is not WIDTHxHEIGHT"},
        {{"--raw-size", "0x0"}, "--raw-size: '0x0' is not WIDTHxHEIGHT"},
        {{"--raw-size", "2147483648x1"}, "--raw-size: '2147483648x1'"},
        {{"--nodata", "nan"}, "--nodata: 'nan' is not a number"},
        {{"--nodata", ""}, "--nodata: '' is not a number"},
        {{"--clamp", "5"}, "--clamp: '5' is not LO,HI"},
        {{"--clamp", "9,1"}, "--clamp: '9,1' is not LO,HI"},
        {{"--clamp", "0,1e308"}, "--clamp: '0,1e308' is not LO,HI"},
        {{"--clamp", "nan,1"}, "--clamp: 'nan,1' is not LO,HI"},
        {{"--clamp", ","}, "--clamp: ',' is not LO,HI"},
        {{"--detail-factor", "2.5"}, "--detail-factor: omega must be in [0, 2], got 2.5"},
        {{"--detail-factor", "-0.1"}, "--detail-factor: omega must be in [0, 2]"},
        {{"--detail-factor", "nan"}, "--detail-factor: 'nan' is not a number"},
        {{"--detail-scheme", "loop"}, "--detail-scheme: unknown scheme 'loop'"},
        {{"--height-codec", "jpeg"}, "--height-codec: unknown codec 'jpeg'"},
        {{"--height-codec"}, "--height-codec needs a value"},
        {{"--material"}, "--material needs a value"},
        {{"--out-of-core=1"}, "--out-of-core takes no value"},
        {{"--bogus"}, "unknown option '--bogus' (see prep --help)"},
        {{"--no-material", "--material", "a.mat"}, "--no-material and --material exclude each other"},
    };
    for (const Case& c : cases) {
        auto parsed = prep(c.args);
        ASSERT_FALSE(parsed.ok()) << c.error;
        EXPECT_TRUE(mentions(parsed.error().message, c.error)) << parsed.error().message << "\nexpected: " << c.error;
    }
    auto none = parsePrepArguments({}, 1, "grass.mat");
    ASSERT_FALSE(none.ok());
    EXPECT_EQ(none.error().message, "no height field given (see prep --help)");
}

TEST(CommandLineTest, PrepHelpListsEveryFlag)
{
    const std::string usage = prepUsage();
    EXPECT_TRUE(usage.starts_with("usage: prep <heightfield>... [options]\n"));
    for (const char* flag :
         {"-t FILE",          "--srs CRS",        "-w FILE.png",       "-h METRES",          "-v SCALE",
          "-o FILE.map",      "--offset METRES",  "--chunk N",         "--max-error METRES", "--height-codec C",
          "--texture-size T", "--threads N",      "--memory SIZE",     "--out-of-core",      "--raw-size WxH",
          "--raw-signed",     "--raw-big-endian", "--nodata V",        "--clamp LO,HI",      "--material FILE.mat",
          "--no-material",    "--no-roughness",   "--detail-scheme S", "--detail-factor W",  "--help"}) {
        EXPECT_TRUE(mentions(usage, std::string("\n  ") + flag + " ")) << flag;
    }
}

}  // namespace
}  // namespace terrain
