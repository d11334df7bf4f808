// Height field readers and writers: real files, exact values from hand-made bytes (written here byte by
// byte, independently of our writers, so a symmetric writer/reader bug cannot hide), round trips, no-data,
// and clear errors naming the file for every kind of bad input.
#include "heightfield/HeightFieldIo.h"
#include "heightfield/Image.h"

#include "TestSupport.h"

#include <gtest/gtest.h>
#include <png.h>
#include <zlib.h>
#include <algorithm>
#include <bit>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace terrain {
namespace {

using Bytes = std::vector<std::uint8_t>;

const float kNaN = std::numeric_limits<float>::quiet_NaN();

// ---- Byte-level helpers, deliberately independent of the code under test. ----

/// Builds little-endian file contents field by field.
struct LeBytes {
    Bytes bytes;

    LeBytes& text(const std::string& s)
    {
        bytes.insert(bytes.end(), s.begin(), s.end());
        return *this;
    }
    LeBytes& u(std::uint64_t value, int size)
    {
        for (int k = 0; k < size; ++k) {
            bytes.push_back(static_cast<std::uint8_t>(value >> (8 * k)));
        }
        return *this;
    }
    LeBytes& i16(int value) { return u(static_cast<std::uint16_t>(static_cast<std::int16_t>(value)), 2); }
    LeBytes& u16(int value) { return u(static_cast<std::uint16_t>(value), 2); }
    LeBytes& i32(std::int32_t value) { return u(static_cast<std::uint32_t>(value), 4); }
    LeBytes& u32(std::uint32_t value) { return u(value, 4); }
    LeBytes& f32(float value) { return u(std::bit_cast<std::uint32_t>(value), 4); }
    LeBytes& f64(double value) { return u(std::bit_cast<std::uint64_t>(value), 8); }
    LeBytes& padTo(std::size_t size)
    {
        bytes.resize(std::max(bytes.size(), size), 0);
        return *this;
    }
};

void writeBytes(const std::filesystem::path& path, const Bytes& bytes)
{
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

Bytes readBytes(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// A PNG written straight through libpng (not our writer). `rows` top to bottom, 16-bit big-endian.
bool writeTestPng(const std::filesystem::path& path, int width, int height, int colorType, int bitDepth,
                  const Bytes& pixels)
{
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (!file) {
        return false;
    }
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png_create_info_struct(png);
    const std::size_t rowBytes = pixels.size() / static_cast<std::size_t>(height);
    std::vector<png_bytep> rows(static_cast<std::size_t>(height));
    for (std::size_t y = 0; y < rows.size(); ++y) {
        rows[y] = const_cast<png_bytep>(pixels.data() + y * rowBytes);
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        std::fclose(file);
        return false;
    }
    png_init_io(png, file);
    png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), bitDepth, colorType,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    png_write_image(png, rows.data());
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    return true;
}

/// A 16-bit gray PNG read straight through libpng: rows top to bottom as stored.
std::vector<std::vector<std::uint16_t>> readGray16Rows(const std::filesystem::path& path)
{
    std::vector<std::vector<std::uint16_t>> result;
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) {
        return result;
    }
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png_create_info_struct(png);
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, nullptr);
        std::fclose(file);
        return result;
    }
    png_init_io(png, file);
    png_read_png(png, info, PNG_TRANSFORM_IDENTITY, nullptr);
    const png_uint_32 width = png_get_image_width(png, info);
    const png_uint_32 height = png_get_image_height(png, info);
    if (png_get_bit_depth(png, info) == 16 && png_get_color_type(png, info) == PNG_COLOR_TYPE_GRAY) {
        png_bytepp rows = png_get_rows(png, info);
        result.resize(height, std::vector<std::uint16_t>(width));
        for (png_uint_32 y = 0; y < height; ++y) {
            for (png_uint_32 x = 0; x < width; ++x) {
                result[y][x] = static_cast<std::uint16_t>((rows[y][2 * x] << 8) | rows[y][2 * x + 1]);
            }
        }
    }
    png_destroy_read_struct(&png, &info, nullptr);
    std::fclose(file);
    return result;
}

/// One PNG chunk with its CRC, for hand-made headers.
void appendPngChunk(Bytes& out, const char* type, const Bytes& data)
{
    auto be32 = [&](std::uint32_t v) {
        for (int k = 3; k >= 0; --k) {
            out.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
        }
    };
    be32(static_cast<std::uint32_t>(data.size()));
    Bytes typed(type, type + 4);
    typed.insert(typed.end(), data.begin(), data.end());
    out.insert(out.end(), typed.begin(), typed.end());
    be32(static_cast<std::uint32_t>(crc32(0, typed.data(), static_cast<uInt>(typed.size()))));
}

/// A PNG whose IHDR claims width x height (16-bit gray) followed by a token IDAT: no real image data.
Bytes pngWithHeader(std::uint32_t width, std::uint32_t height)
{
    Bytes out = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    Bytes ihdr;
    for (std::uint32_t v : {width, height}) {
        for (int k = 3; k >= 0; --k) {
            ihdr.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
        }
    }
    ihdr.insert(ihdr.end(), {16, 0, 0, 0, 0});  // bit depth 16, gray, deflate, adaptive filter, no interlace
    appendPngChunk(out, "IHDR", ihdr);
    appendPngChunk(out, "IDAT", {0x78, 0x9c, 0x03, 0x00});
    appendPngChunk(out, "IEND", {});
    return out;
}

HeightField makeField(int width, int height, const std::vector<float>& samples)
{
    HeightField field;
    field.width = width;
    field.height = height;
    field.samples = samples;
    return field;
}

/// Compares samples exactly, NaN matching NaN.
void expectSamplesEqual(const HeightField& actual, const HeightField& expected)
{
    ASSERT_EQ(actual.width, expected.width);
    ASSERT_EQ(actual.height, expected.height);
    ASSERT_EQ(actual.samples.size(), expected.samples.size());
    for (int j = 0; j < expected.height; ++j) {
        for (int i = 0; i < expected.width; ++i) {
            const float e = expected.at(i, j);
            const float a = actual.at(i, j);
            if (std::isnan(e)) {
                EXPECT_TRUE(std::isnan(a)) << "at (" << i << ", " << j << "): " << a;
            } else {
                EXPECT_EQ(a, e) << "at (" << i << ", " << j << ")";
            }
        }
    }
}

std::pair<float, float> minMax(const HeightField& field)
{
    const auto [lo, hi] = std::minmax_element(field.samples.begin(), field.samples.end());
    return {*lo, *hi};
}

// ---- PNG ----

TEST(HeightFieldIoTest, ReadsTheBundledDemoTerrain)
{
    auto field = readHeightField(test::demoDataPath("trinidad_co_srtm3_crop_1025.png"));
    ASSERT_TRUE(field.ok()) << field.error().message;
    EXPECT_EQ(field->width, 1025);
    EXPECT_EQ(field->height, 1025);
    EXPECT_EQ(minMax(*field), std::make_pair(2011.0f, 4322.0f));
    EXPECT_TRUE(field->integerSamples);
    EXPECT_FALSE(field->spacing);
    EXPECT_FALSE(field->verticalScale);
    EXPECT_EQ(field->description, "PNG 16-bit gray 1025x1025");
}

TEST(HeightFieldIoTest, PngTopRowBecomesTheNorthEdge)
{
    // Compared with an independent libpng read of the same file: PNG row r is j = height - 1 - r.
    const auto path = test::testDataPath("jacksboro_fault_dem_403x344.png");
    auto field = readPngHeightField(path);
    ASSERT_TRUE(field.ok()) << field.error().message;
    EXPECT_EQ(field->width, 403);
    EXPECT_EQ(field->height, 344);
    EXPECT_EQ(minMax(*field), std::make_pair(236.0f, 1076.0f));
    const auto rows = readGray16Rows(path);
    ASSERT_EQ(rows.size(), 344u);
    int mismatches = 0;
    for (int r = 0; r < 344; ++r) {
        for (int i = 0; i < 403; ++i) {
            mismatches += field->at(i, 343 - r) != float(rows[r][i]) ? 1 : 0;
        }
    }
    EXPECT_EQ(mismatches, 0);
}

TEST(HeightFieldIoTest, ReadsHandMade8BitPngNorthUp)
{
    // Drawn as stored (north row first):   1  2  3
    //                                      4  5  6
    test::ScratchDir dir;
    ASSERT_TRUE(writeTestPng(dir / "tiny.png", 3, 2, PNG_COLOR_TYPE_GRAY, 8, {1, 2, 3, 4, 5, 6}));
    auto field = readPngHeightField(dir / "tiny.png");
    ASSERT_TRUE(field.ok()) << field.error().message;
    expectSamplesEqual(*field, makeField(3, 2, {4, 5, 6, 1, 2, 3}));
    EXPECT_EQ(field->description, "PNG 8-bit gray 3x2");
}

TEST(HeightFieldIoTest, PngRoundTripsAtBothBitDepths)
{
    struct Case {
        int bitDepth;
        std::vector<float> written;
        std::vector<float> read;  // after rounding and clamping to the bit depth's range
    };
    const Case cases[] = {
        {16, {0, 1, 65535, 40000, 2.6f, -5, 70000, 12345.4f}, {0, 1, 65535, 40000, 3, 0, 65535, 12345}},
        {8, {0, 1, 255, 128, 2.5f, -5, 300, 99.4f}, {0, 1, 255, 128, 2, 0, 255, 99}},  // 2.5 rounds to even
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.bitDepth);
        test::ScratchDir dir;
        ASSERT_TRUE(writePngHeightField(dir / "out.png", makeField(4, 2, c.written), c.bitDepth).ok());
        auto field = readPngHeightField(dir / "out.png");
        ASSERT_TRUE(field.ok()) << field.error().message;
        expectSamplesEqual(*field, makeField(4, 2, c.read));
        EXPECT_EQ(field->description, "PNG " + std::to_string(c.bitDepth) + "-bit gray 4x2");
        EXPECT_EQ(dir.list(), std::vector<std::string>{"out.png"});
    }
}

TEST(HeightFieldIoTest, PngWriterStoresNorthRowFirst)
{
    test::ScratchDir dir;
    ASSERT_TRUE(writePngHeightField(dir / "out.png", makeField(2, 2, {10, 20, 30, 40})).ok());
    const auto rows = readGray16Rows(dir / "out.png");
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_EQ(rows[0], (std::vector<std::uint16_t>{30, 40}));
    EXPECT_EQ(rows[1], (std::vector<std::uint16_t>{10, 20}));
}

TEST(HeightFieldIoTest, PngRejectsColourImagesByName)
{
    test::ScratchDir dir;
    ASSERT_TRUE(writeTestPng(dir / "colour.png", 1, 1, PNG_COLOR_TYPE_RGB, 8, {1, 2, 3}));
    auto field = readPngHeightField(dir / "colour.png");
    EXPECT_ERROR_MENTIONS(field, dir / "colour.png", "expected a grayscale PNG, found RGB");
}

TEST(HeightFieldIoTest, PngNoDataOption)
{
    test::ScratchDir dir;
    ASSERT_TRUE(writeTestPng(dir / "holes.png", 2, 1, PNG_COLOR_TYPE_GRAY, 8, {0, 7}));
    HeightFieldReadOptions options;
    options.noData = 0.0;
    auto field = readPngHeightField(dir / "holes.png", options);
    ASSERT_TRUE(field.ok()) << field.error().message;
    expectSamplesEqual(*field, makeField(2, 1, {kNaN, 7}));
}

TEST(HeightFieldIoTest, BadPngFilesGiveErrorsNamingTheFile)
{
    test::ScratchDir dir;
    const Bytes real = readBytes(test::testDataPath("jacksboro_fault_dem_403x344.png"));
    ASSERT_GT(real.size(), 1000u);
    struct Case {
        const char* name;
        Bytes bytes;
        const char* mention;
    };
    const Case cases[] = {
        {"text.png", Bytes{'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd'}, "not a PNG file"},
        {"empty.png", Bytes{}, "not a PNG file"},
        {"truncated.png", Bytes(real.begin(), real.begin() + static_cast<std::ptrdiff_t>(real.size() / 2)),
         "truncated"},
        {"header_only.png", Bytes(real.begin(), real.begin() + 40), "PNG"},
        {"zero_width.png", pngWithHeader(0, 5), "corrupt PNG header"},
        // Refused before any allocation: 1000000 x 1000000 x 2 bytes does not fit in memory.
        {"absurd.png", pngWithHeader(1000000, 1000000), "1000000x1000000"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        writeBytes(dir / c.name, c.bytes);
        auto field = readPngHeightField(dir / c.name);
        EXPECT_ERROR_MENTIONS(field, dir / c.name, c.mention);
    }
}

TEST(HeightFieldIoTest, PngWriterRefusesWhatItCannotStore)
{
    test::ScratchDir dir;
    EXPECT_FALSE(writePngHeightField(dir / "a.png", makeField(2, 1, {1, 2}), 12).ok());
    auto nan = writePngHeightField(dir / "b.png", makeField(2, 1, {1, kNaN}));
    EXPECT_ERROR_MENTIONS(nan, dir / "b.png", "sample (1, 0) is no-data");
    auto shape = writePngHeightField(dir / "c.png", makeField(3, 1, {1, 2}));
    EXPECT_ERROR_MENTIONS(shape, dir / "c.png", "3x1");
    auto empty = writePngHeightField(dir / "d.png", makeField(0, 0, {}));
    EXPECT_ERROR_MENTIONS(empty, dir / "d.png", "0x0");
    EXPECT_TRUE(dir.list().empty()) << "a failed write must leave no file behind";
}

// ---- VTP .bt ----

/// A .bt 1.1-1.3 header with the given fields (little-endian, 256 bytes).
LeBytes btHeader(int minor, std::int32_t columns, std::int32_t rows, int dataSize, int floatFlag, int units,
                 double left, double right, double bottom, double top, float verticalScale = 0.0f)
{
    LeBytes b;
    b.text("binterr1." + std::to_string(minor)).i32(columns).i32(rows).i16(dataSize).i16(floatFlag).i16(units);
    b.i16(0).i16(-2).f64(left).f64(right).f64(bottom).f64(top).i16(0).f32(verticalScale).padTo(256);
    return b;
}

TEST(HeightFieldIoTest, BtHandMadeInt16ColumnsWestToEastEachSouthToNorth)
{
    // The grid, north row on top:    40 50 60
    //                                10 20 30
    // stored column by column, each column south to north.
    test::ScratchDir dir;
    LeBytes b = btHeader(3, 3, 2, 2, 0, 1, 1000.0, 1020.0, 2000.0, 2010.0, 0.5f);
    b.i16(10).i16(40).i16(20).i16(50).i16(30).i16(60);
    writeBytes(dir / "tiny.bt", b.bytes);
    auto field = readHeightField(dir / "tiny.bt");
    ASSERT_TRUE(field.ok()) << field.error().message;
    expectSamplesEqual(*field, makeField(3, 2, {10, 20, 30, 40, 50, 60}));
    EXPECT_TRUE(field->integerSamples);
    ASSERT_TRUE(field->spacing);
    EXPECT_DOUBLE_EQ(*field->spacing, 10.0);
    EXPECT_EQ(field->verticalScale, 0.5);
    EXPECT_DOUBLE_EQ(field->originX, 1000.0);
    EXPECT_DOUBLE_EQ(field->originY, 2000.0);
    EXPECT_EQ(field->description, "BT 1.3 int16 3x2, metres, spacing 10 m, vertical scale 0.5 m");
}

TEST(HeightFieldIoTest, BtHandMadeVersion10FloatWithItsOwnHeaderLayout)
{
    // BT 1.0: int32 data size at 18, UTM flag at 22, float extents at 26, float flag at 42.
    test::ScratchDir dir;
    LeBytes b;
    b.text("binterr1.0").i32(2).i32(2).i32(4).i16(1).i16(13).f32(0).f32(30).f32(0).f32(30).i16(1).padTo(256);
    b.f32(1.5f).f32(-2.25f).f32(1000.0f).f32(-32768.0f);
    writeBytes(dir / "old.bt", b.bytes);
    auto field = readBtHeightField(dir / "old.bt");
    ASSERT_TRUE(field.ok()) << field.error().message;
    expectSamplesEqual(*field, makeField(2, 2, {1.5f, 1000.0f, -2.25f, kNaN}));
    EXPECT_FALSE(field->integerSamples);
    EXPECT_EQ(field->spacing, 30.0);
    EXPECT_EQ(field->verticalScale, 1.0);
    EXPECT_EQ(field->description, "BT 1.0 float32 2x2, metres, spacing 30 m");
}

TEST(HeightFieldIoTest, BtHandMadeInt32InUsSurveyFeet)
{
    // 3937 US survey feet are exactly 1200 m.
    test::ScratchDir dir;
    LeBytes b = btHeader(1, 2, 3, 4, 0, 3, 0.0, 3937.0, 3937.0, 3 * 3937.0);
    b.i32(100000).i32(-100000).i32(-32768).i32(7).i32(8).i32(2000000);
    writeBytes(dir / "feet.bt", b.bytes);
    auto field = readBtHeightField(dir / "feet.bt");
    ASSERT_TRUE(field.ok()) << field.error().message;
    expectSamplesEqual(*field, makeField(2, 3, {100000, 7, -100000, 8, kNaN, 2000000}));
    ASSERT_TRUE(field->spacing);
    EXPECT_NEAR(*field->spacing, 1200.0, 1e-9);
    EXPECT_NEAR(field->originY, 1200.0, 1e-9);
    EXPECT_EQ(field->verticalScale, 1.0);  // no vertical scale field before 1.3: heights are metres
    EXPECT_TRUE(field->integerSamples);
}

TEST(HeightFieldIoTest, BtDegreesAreConvertedAtTheCentreLatitude)
{
    // 0.5 degree steps around 37.5 N: y 0.5 * 110574 m, x 0.5 * 111320 * cos(37.5 deg) m.
    test::ScratchDir dir;
    LeBytes b = btHeader(2, 3, 3, 2, 0, 0, -106.0, -105.0, 37.0, 38.0);
    b.padTo(256 + 9 * 2);
    writeBytes(dir / "geo.bt", b.bytes);
    auto field = readBtHeightField(dir / "geo.bt");
    ASSERT_TRUE(field.ok()) << field.error().message;
    ASSERT_TRUE(field->spacing);
    EXPECT_NEAR(*field->spacing, 0.5 * 110574.0, 1e-6);
    EXPECT_EQ(field->originX, 0.0) << "degrees are not a metric origin";
    const double x = 0.5 * 111320.0 * std::cos(37.5 * 3.14159265358979323846 / 180.0);
    EXPECT_NE(field->description.find("x spacing is " + std::to_string(static_cast<int>(std::round(x)))),
              std::string::npos)
        << field->description;
}

TEST(HeightFieldIoTest, BtNoDataMarkersBecomeNaN)
{
    test::ScratchDir dir;
    LeBytes b = btHeader(3, 2, 2, 4, 1, 1, 0, 1, 0, 1);
    b.f32(-32768.0f).f32(kNaN).f32(5.0f).f32(0.0f);
    writeBytes(dir / "float.bt", b.bytes);
    HeightFieldReadOptions options;
    options.noData = 0.0;  // in addition to the format's own marker
    auto field = readBtHeightField(dir / "float.bt", options);
    ASSERT_TRUE(field.ok()) << field.error().message;
    expectSamplesEqual(*field, makeField(2, 2, {kNaN, 5.0f, kNaN, kNaN}));
}

TEST(HeightFieldIoTest, BtRoundTripsEverySampleTypeAndVersion)
{
    const HeightField source = [] {
        HeightField f = makeField(4, 3, {-12, 0, 7, 3000, 2, kNaN, 55, -1, 100000, 9, 4, 1});
        f.spacing = 10.0;
        f.originX = 1000.0;
        f.originY = -500.0;
        return f;
    }();
    HeightField fractional = source;
    for (float& v : fractional.samples) {
        v = std::isnan(v) ? v : v + 0.25f;
    }
    struct Type {
        BtSampleType type;
        const char* name;
    };
    for (const Type& t : {Type{BtSampleType::Int16, "int16"}, Type{BtSampleType::Int32, "int32"},
                          Type{BtSampleType::Float32, "float32"}}) {
        for (int minor = 0; minor <= 3; ++minor) {
            SCOPED_TRACE(std::string(t.name) + " 1." + std::to_string(minor));
            test::ScratchDir dir;
            const HeightField& written = t.type == BtSampleType::Float32 ? fractional : source;
            ASSERT_TRUE(writeBtHeightField(dir / "out.bt", written, t.type, minor).ok());
            EXPECT_EQ(dir.list(), std::vector<std::string>{"out.bt"});
            auto field = readBtHeightField(dir / "out.bt");
            ASSERT_TRUE(field.ok()) << field.error().message;
            HeightField expected = written;
            if (t.type == BtSampleType::Int16) {
                expected.at(0, 2) = 32767;  // 100000 clamped to the int16 range
            }
            expectSamplesEqual(*field, expected);
            EXPECT_EQ(field->integerSamples, t.type != BtSampleType::Float32);
            EXPECT_EQ(field->spacing, 10.0);
            EXPECT_EQ(field->originX, 1000.0);
            EXPECT_EQ(field->originY, -500.0);
            EXPECT_EQ(field->verticalScale, 1.0);
            EXPECT_EQ(field->description.rfind("BT 1." + std::to_string(minor) + " " + t.name + " 4x3", 0), 0u)
                << field->description;
        }
    }
}

TEST(HeightFieldIoTest, BtVerticalMappingSurvivesEveryVersion)
{
    // 1.3 stores the vertical scale; older versions and any offset get metres instead.
    HeightField source = makeField(2, 1, {100, 200});
    source.verticalScale = 0.25;
    struct Case {
        int minor;
        double offset;
        std::vector<float> natives;
        double scale;
    };
    const Case cases[] = {
        {3, 0.0, {100, 200}, 0.25},
        {2, 0.0, {25, 50}, 1.0},
        {0, 0.0, {25, 50}, 1.0},
        {3, 10.0, {35, 60}, 1.0},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.minor);
        test::ScratchDir dir;
        source.verticalOffset = c.offset;
        ASSERT_TRUE(writeBtHeightField(dir / "out.bt", source, BtSampleType::Float32, c.minor).ok());
        auto field = readBtHeightField(dir / "out.bt");
        ASSERT_TRUE(field.ok()) << field.error().message;
        expectSamplesEqual(*field, makeField(2, 1, c.natives));
        EXPECT_EQ(field->verticalScale, c.scale);
        EXPECT_EQ(field->verticalOffset, 0.0);
    }
}

TEST(HeightFieldIoTest, BtInt16WriterKeepsFiniteValuesOffTheNoDataMarker)
{
    test::ScratchDir dir;
    ASSERT_TRUE(writeBtHeightField(dir / "out.bt", makeField(3, 1, {-40000, -32768, kNaN}), BtSampleType::Int16).ok());
    auto field = readBtHeightField(dir / "out.bt");
    ASSERT_TRUE(field.ok()) << field.error().message;
    expectSamplesEqual(*field, makeField(3, 1, {-32767, -32767, kNaN}));
}

TEST(HeightFieldIoTest, BadBtFilesGiveErrorsNamingTheFile)
{
    auto good = [] { return btHeader(3, 3, 2, 2, 0, 1, 0, 2, 0, 1); };
    auto withSamples = [](LeBytes b, std::size_t sampleBytes) {
        b.bytes.resize(256 + sampleBytes, 0);
        return b.bytes;
    };
    struct Case {
        const char* name;
        Bytes bytes;
        const char* mention;
    };
    const Case cases[] = {
        {"magic.bt",
         [&] {
             LeBytes b = good();
             std::copy_n("notbterr", 8, b.bytes.begin());
             return withSamples(b, 12);
         }(),
         "not a VTP Binary Terrain file"},
        {"version.bt",
         [&] {
             LeBytes b = good();
             b.bytes[9] = '7';
             return withSamples(b, 12);
         }(),
         "found \"binterr1.7\""},
        {"empty.bt", Bytes{}, "truncated: a BT header is 256 bytes, the file has 0"},
        {"short_header.bt",
         [&] {
             LeBytes b = good();
             b.bytes.resize(100);
             return b.bytes;
         }(),
         "the file has 100"},
        {"truncated.bt", withSamples(good(), 7), "truncated: expected 12 bytes of samples, found 7"},
        {"zero_columns.bt", withSamples(btHeader(3, 0, 2, 2, 0, 1, 0, 2, 0, 1), 12), "BT size is 0x2"},
        {"negative_rows.bt", withSamples(btHeader(3, 3, -2, 2, 0, 1, 0, 2, 0, 1), 12), "BT size is 3x-2"},
        {"data_size.bt", withSamples(btHeader(3, 3, 2, 3, 0, 1, 0, 2, 0, 1), 18), "data size is 3"},
        {"half_float.bt", withSamples(btHeader(3, 3, 2, 2, 1, 1, 0, 2, 0, 1), 12), "2-byte floating-point"},
        {"float_flag.bt", withSamples(btHeader(3, 3, 2, 4, 5, 1, 0, 2, 0, 1), 24), "floating-point flag is 5"},
        {"units.bt", withSamples(btHeader(3, 3, 2, 2, 0, 7, 0, 2, 0, 1), 12), "horizontal units code is 7"},
        {"vscale.bt", withSamples(btHeader(3, 3, 2, 2, 0, 1, 0, 2, 0, 1, -1.0f), 12), "vertical scale"},
        // Refused before any allocation: 4 TB of samples.
        {"absurd.bt", withSamples(btHeader(3, 1000000, 1000000, 2, 0, 1, 0, 2, 0, 1), 12), "1000000x1000000"},
    };
    test::ScratchDir dir;
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        writeBytes(dir / c.name, c.bytes);
        auto field = readBtHeightField(dir / c.name);
        EXPECT_ERROR_MENTIONS(field, dir / c.name, c.mention);
    }
}

TEST(HeightFieldIoTest, BtWriterRefusesBadArguments)
{
    test::ScratchDir dir;
    auto version = writeBtHeightField(dir / "a.bt", makeField(1, 1, {1}), BtSampleType::Int16, 4);
    EXPECT_ERROR_MENTIONS(version, dir / "a.bt", "1.4");
    HeightField badSpacing = makeField(1, 1, {1});
    badSpacing.spacing = -3.0;
    auto spacing = writeBtHeightField(dir / "b.bt", badSpacing, BtSampleType::Int16);
    EXPECT_ERROR_MENTIONS(spacing, dir / "b.bt", "spacing");
    EXPECT_TRUE(dir.list().empty());
}

// ---- Terragen .ter ----

LeBytes terHeader()
{
    return LeBytes().text("TERRAGENTERRAIN ");
}

TEST(HeightFieldIoTest, TerHandMadeRowsSouthToNorth)
{
    // The grid, north row on top:   -2 -4 100
    //                                0  2   4
    // metres = SCAL.z * (BaseHeight + e * HeightScale / 65536) = 2 * (100 + e / 4) = 200 + e / 2.
    test::ScratchDir dir;
    LeBytes b = terHeader();
    b.text("SIZE").u16(1).u16(0).text("XPTS").u16(3).u16(0).text("YPTS").u16(2).u16(0);
    b.text("SCAL").f32(10).f32(10).f32(2).text("CRAD").f32(6370).text("CRVM").u32(0);
    b.text("ALTW").i16(16384).i16(100).i16(0).i16(2).i16(4).i16(-2).i16(-4).i16(100).text("EOF ");
    writeBytes(dir / "tiny.ter", b.bytes);
    auto field = readHeightField(dir / "tiny.ter");
    ASSERT_TRUE(field.ok()) << field.error().message;
    expectSamplesEqual(*field, makeField(3, 2, {0, 2, 4, -2, -4, 100}));
    EXPECT_TRUE(field->integerSamples);
    EXPECT_EQ(field->spacing, 10.0);
    EXPECT_EQ(field->verticalScale, 0.5);
    EXPECT_EQ(field->verticalOffset, 200.0);
    EXPECT_EQ(field->description, "Terragen 3x2, spacing 10 m, HeightScale 16384, BaseHeight 100, vertical SCAL 2 m");
}

TEST(HeightFieldIoTest, TerSquareWithDefaultScaleAndAlignmentPadding)
{
    // SIZE only (square), no SCAL (30 m), 9 points: 2 bytes pad the ALTW chunk to 4-byte alignment.
    test::ScratchDir dir;
    LeBytes b = terHeader();
    b.text("SIZE").u16(2).u16(0).text("ALTW").i16(256).i16(-5);
    for (int v = 1; v <= 9; ++v) {
        b.i16(v);
    }
    LeBytes padded = b;
    padded.u16(0).text("EOF ");
    LeBytes unpadded = b;
    unpadded.text("EOF ");
    LeBytes noEof = b;
    for (const auto& [name, bytes] : {std::pair{"padded.ter", padded.bytes}, std::pair{"unpadded.ter", unpadded.bytes},
                                      std::pair{"no_eof.ter", noEof.bytes}}) {
        SCOPED_TRACE(name);
        writeBytes(dir / name, bytes);
        auto field = readTerHeightField(dir / name);
        ASSERT_TRUE(field.ok()) << field.error().message;
        expectSamplesEqual(*field, makeField(3, 3, {1, 2, 3, 4, 5, 6, 7, 8, 9}));
        EXPECT_EQ(field->spacing, 30.0);
        EXPECT_EQ(field->verticalScale, 30.0 * 256 / 65536);
        EXPECT_EQ(field->verticalOffset, -150.0);
    }
}

TEST(HeightFieldIoTest, TerKeepsTheFileEncodingWhenWritingBack)
{
    test::ScratchDir dir;
    LeBytes b = terHeader();
    b.text("SIZE").u16(1).u16(0).text("XPTS").u16(3).u16(0).text("YPTS").u16(2).u16(0);
    b.text("SCAL").f32(12.5f).f32(12.5f).f32(12.5f);
    // A narrow range: re-quantizing would pick a much smaller HeightScale, so only keeping the natives passes.
    b.text("ALTW").i16(777).i16(-40).i16(-1000).i16(1000).i16(0).i16(1).i16(-1).i16(123).text("EOF ");
    writeBytes(dir / "in.ter", b.bytes);
    auto original = readTerHeightField(dir / "in.ter");
    ASSERT_TRUE(original.ok()) << original.error().message;
    ASSERT_TRUE(writeTerHeightField(dir / "out.ter", *original).ok());
    auto again = readTerHeightField(dir / "out.ter");
    ASSERT_TRUE(again.ok()) << again.error().message;
    expectSamplesEqual(*again, *original);
    EXPECT_EQ(again->verticalScale, original->verticalScale);
    EXPECT_EQ(again->verticalOffset, original->verticalOffset);
    EXPECT_EQ(again->spacing, 12.5);
    EXPECT_EQ(again->description, "Terragen 3x2, spacing 12.5 m, HeightScale 777, BaseHeight -40");
}

TEST(HeightFieldIoTest, TerWriterQuantizesMetresWithinHalfAStep)
{
    // Heights given as metres (PNG-like natives) are re-encoded; they come back within half a step.
    auto demo = readHeightField(test::demoDataPath("trinidad_co_srtm3_crop_1025.png"));
    ASSERT_TRUE(demo.ok()) << demo.error().message;
    struct Case {
        const char* name;
        HeightField field;
    };
    HeightField scaled = makeField(3, 2, {-1.5f, 0.0f, 1.0e4f, 2.25f, 7.0f, 8848.0f});
    scaled.verticalScale = 0.5;
    scaled.verticalOffset = -20.0;
    scaled.spacing = 25.0;
    HeightField flat = makeField(2, 2, {42, 42, 42, 42});
    const Case cases[] = {{"demo", *demo}, {"scaled", scaled}, {"flat", flat}};
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        test::ScratchDir dir;
        ASSERT_TRUE(writeTerHeightField(dir / "out.ter", c.field).ok());
        EXPECT_EQ(dir.list(), std::vector<std::string>{"out.ter"});
        auto field = readTerHeightField(dir / "out.ter");
        ASSERT_TRUE(field.ok()) << field.error().message;
        ASSERT_EQ(field->width, c.field.width);
        ASSERT_EQ(field->height, c.field.height);
        EXPECT_EQ(field->spacing, c.field.spacing.value_or(30.0));
        const double step = *field->verticalScale;
        EXPECT_GT(step, 0.0);
        double worst = 0.0;
        for (std::size_t k = 0; k < c.field.samples.size(); ++k) {
            const double expected = c.field.verticalOffset + c.field.verticalScale.value_or(1.0) * c.field.samples[k];
            const double actual = field->verticalOffset + step * field->samples[k];
            worst = std::max(worst, std::abs(actual - expected));
        }
        EXPECT_LE(worst, 0.5 * step + 1e-9);
        EXPECT_LT(step, 0.2) << "the encoding should use most of the int16 range";
    }
}

TEST(HeightFieldIoTest, BadTerFilesGiveErrorsNamingTheFile)
{
    auto sized = [] {
        return terHeader().text("SIZE").u16(1).u16(0).text("XPTS").u16(3).u16(0).text("YPTS").u16(2).u16(0);
    };
    struct Case {
        const char* name;
        Bytes bytes;
        const char* mention;
    };
    const Case cases[] = {
        {"magic.ter", LeBytes().text("TERRAGENTERRAIX ").text("SIZE").u16(1).u16(0).bytes,
         "not a Terragen terrain file"},
        {"empty.ter", Bytes{}, "not a Terragen terrain file"},
        {"unknown.ter", sized().text("ABCD").u32(0).bytes, "unknown chunk \"ABCD\" at byte 40"},
        {"no_altw.ter", sized().text("EOF ").bytes, "before an ALTW"},
        {"truncated.ter", sized().text("ALTW").i16(1).i16(0).i16(1).i16(2).u(3, 1).bytes,
         "truncated: expected 12 bytes of samples, found 5"},
        {"zero_xpts.ter", terHeader().text("SIZE").u16(1).u16(0).text("XPTS").u16(0).u16(0).bytes, "XPTS is 0"},
        {"altw_first.ter", terHeader().text("ALTW").i16(1).i16(0).bytes, "before the SIZE chunk"},
        {"late_ypts.ter",
         sized().text("ALTW").i16(1).i16(0).i16(1).i16(2).i16(3).i16(4).i16(5).i16(6).text("YPTS").u16(2).u16(0).bytes,
         "comes after the elevations"},
        {"bad_scal.ter", sized().text("SCAL").f32(30).f32(-1).f32(30).bytes, "SCAL chunk holds -1"},
        {"short_scal.ter", sized().text("SCAL").f32(30).bytes, "truncated SCAL chunk"},
    };
    test::ScratchDir dir;
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        writeBytes(dir / c.name, c.bytes);
        auto field = readTerHeightField(dir / c.name);
        EXPECT_ERROR_MENTIONS(field, dir / c.name, c.mention);
    }
}

TEST(HeightFieldIoTest, TerWriterRefusesWhatItCannotStore)
{
    test::ScratchDir dir;
    auto nan = writeTerHeightField(dir / "a.ter", makeField(2, 1, {kNaN, 1}));
    EXPECT_ERROR_MENTIONS(nan, dir / "a.ter", "no-data");
    auto wide = writeTerHeightField(dir / "b.ter", makeField(70000, 1, std::vector<float>(70000, 1.0f)));
    EXPECT_ERROR_MENTIONS(wide, dir / "b.ter", "too large for Terragen");
    auto range = writeTerHeightField(dir / "c.ter", makeField(2, 1, {-1e9f, 1e9f}));
    EXPECT_ERROR_MENTIONS(range, dir / "c.ter", "Terragen");
    EXPECT_TRUE(dir.list().empty());
}

// ---- Raw 16-bit ----

TEST(HeightFieldIoTest, RawHandMadeBytesAreNorthUp)
{
    // Stored north row first, big-endian signed:   1  -2  300
    //                                              -7  4    5
    test::ScratchDir dir;
    const Bytes bytes = {0x00, 0x01, 0xff, 0xfe, 0x01, 0x2c, 0xff, 0xf9, 0x00, 0x04, 0x00, 0x05};
    writeBytes(dir / "tiny.r16", bytes);
    HeightFieldReadOptions options;
    options.rawWidth = 3;
    options.rawHeight = 2;
    options.rawSigned = true;
    options.rawBigEndian = true;
    auto field = readHeightField(dir / "tiny.r16", options);
    ASSERT_TRUE(field.ok()) << field.error().message;
    expectSamplesEqual(*field, makeField(3, 2, {-7, 4, 5, 1, -2, 300}));
    EXPECT_EQ(field->description, "raw 16-bit signed big-endian 3x2");
    EXPECT_FALSE(field->spacing);

    // The same bytes as unsigned little-endian.
    options.rawSigned = false;
    options.rawBigEndian = false;
    auto little = readHeightField(dir / "tiny.r16", options);
    ASSERT_TRUE(little.ok()) << little.error().message;
    expectSamplesEqual(*little, makeField(3, 2, {0xf9ff, 0x0400, 0x0500, 0x0100, 0xfeff, 0x2c01}));
}

TEST(HeightFieldIoTest, RawRoundTripsInEveryVariant)
{
    for (bool isSigned : {false, true}) {
        for (bool bigEndian : {false, true}) {
            SCOPED_TRACE(std::string(isSigned ? "signed" : "unsigned") + (bigEndian ? " big" : " little"));
            test::ScratchDir dir;
            const HeightField source = isSigned ? makeField(3, 2, {-32768, -1, 0, 1, 32767, 1234})
                                                : makeField(3, 2, {0, 1, 255, 256, 65535, 40000});
            ASSERT_TRUE(writeRawHeightField(dir / "out.raw", source, isSigned, bigEndian).ok());
            EXPECT_EQ(readBytes(dir / "out.raw").size(), 12u);
            HeightFieldReadOptions options;
            options.rawWidth = 3;
            options.rawHeight = 2;
            options.rawSigned = isSigned;
            options.rawBigEndian = bigEndian;
            auto field = readRawHeightField(dir / "out.raw", options);
            ASSERT_TRUE(field.ok()) << field.error().message;
            expectSamplesEqual(*field, source);
        }
    }
}

TEST(HeightFieldIoTest, RawSignedNoDataRoundTripsThroughTheOption)
{
    test::ScratchDir dir;
    ASSERT_TRUE(writeRawHeightField(dir / "srtm.bin", makeField(2, 1, {kNaN, 5}), true, true).ok());
    HeightFieldReadOptions options;
    options.rawWidth = 2;
    options.rawHeight = 1;
    options.rawSigned = true;
    options.rawBigEndian = true;
    auto plain = readHeightField(dir / "srtm.bin", options);
    ASSERT_TRUE(plain.ok()) << plain.error().message;
    expectSamplesEqual(*plain, makeField(2, 1, {-32768, 5}));
    options.noData = -32768.0;
    auto masked = readHeightField(dir / "srtm.bin", options);
    ASSERT_TRUE(masked.ok()) << masked.error().message;
    expectSamplesEqual(*masked, makeField(2, 1, {kNaN, 5}));

    auto unsignedNaN = writeRawHeightField(dir / "u.raw", makeField(1, 1, {kNaN}), false);
    EXPECT_ERROR_MENTIONS(unsignedNaN, dir / "u.raw", "no-data");
}

TEST(HeightFieldIoTest, BadRawInputGivesErrorsNamingTheFile)
{
    test::ScratchDir dir;
    writeBytes(dir / "twelve.raw", Bytes(12, 0));
    struct Case {
        int width;
        int height;
        const char* mention;
    };
    const Case cases[] = {
        {0, 0, "does not store its size"},
        {3, 0, "got 3x0"},
        {-3, 2, "got -3x2"},
        {3, 3, "has exactly 18 bytes, this one has 12"},
        {2, 2, "has exactly 8 bytes, this one has 12"},
        {1000000, 1000000, "this one has 12"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.mention);
        HeightFieldReadOptions options;
        options.rawWidth = c.width;
        options.rawHeight = c.height;
        auto field = readHeightField(dir / "twelve.raw", options);
        EXPECT_ERROR_MENTIONS(field, dir / "twelve.raw", c.mention);
    }
}

// ---- Choosing the reader ----

TEST(HeightFieldIoTest, ExtensionsAreMatchedCaseInsensitively)
{
    test::ScratchDir dir;
    const HeightField source = makeField(2, 2, {1, 2, 3, 4});
    ASSERT_TRUE(writePngHeightField(dir / "a.PNG", source).ok());
    ASSERT_TRUE(writeBtHeightField(dir / "b.Bt", source, BtSampleType::Int16).ok());
    ASSERT_TRUE(writeTerHeightField(dir / "c.TER", source).ok());
    ASSERT_TRUE(writeRawHeightField(dir / "d.RAW", source).ok());
    ASSERT_TRUE(writeRawHeightField(dir / "e.R16", source).ok());
    ASSERT_TRUE(writeRawHeightField(dir / "f.Bin", source).ok());
    HeightFieldReadOptions options;
    options.rawWidth = 2;
    options.rawHeight = 2;
    for (const char* name : {"a.PNG", "b.Bt", "c.TER", "d.RAW", "e.R16", "f.Bin"}) {
        SCOPED_TRACE(name);
        auto field = readHeightField(dir / name, options);
        ASSERT_TRUE(field.ok()) << field.error().message;
        EXPECT_EQ(field->width, 2);
        EXPECT_EQ(field->height, 2);
    }
}

TEST(HeightFieldIoTest, UnknownExtensionAndMissingFileAreClearErrors)
{
    test::ScratchDir dir;
    writeBytes(dir / "map.tif", Bytes(16, 0));
    writeBytes(dir / "noext", Bytes(16, 0));
    auto tif = readHeightField(dir / "map.tif");
    // Extensions other than our own readers' go to GDAL, which names what it could not read.
    EXPECT_ERROR_MENTIONS(tif, dir / "map.tif", "GDAL cannot read it as a raster");
    auto none = readHeightField(dir / "noext");
    EXPECT_ERROR_MENTIONS(none, dir / "noext", "GDAL cannot read it as a raster");
    HeightFieldReadOptions options;
    options.rawWidth = 1;
    options.rawHeight = 1;
    for (const char* name : {"missing.png", "missing.bt", "missing.ter", "missing.raw"}) {
        SCOPED_TRACE(name);
        auto field = readHeightField(dir / name, options);
        EXPECT_ERROR_MENTIONS(field, dir / name, "cannot open");
    }
    std::filesystem::create_directory(dir / "folder.bt");
    auto folder = readHeightField(dir / "folder.bt");
    EXPECT_ERROR_MENTIONS(folder, dir / "folder.bt", "is a directory");
}

TEST(HeightFieldIoTest, WritersFailCleanlyIntoAMissingDirectory)
{
    const std::filesystem::path dir = "/nonexistent-dir/tengine";
    const HeightField field = makeField(1, 1, {1});
    const Status png = writePngHeightField(dir / "x.png", field);
    EXPECT_ERROR_MENTIONS(png, dir / "x.png", "cannot create");
    const Status bt = writeBtHeightField(dir / "x.bt", field, BtSampleType::Int16);
    EXPECT_ERROR_MENTIONS(bt, dir / "x.bt", "cannot create");
    const Status ter = writeTerHeightField(dir / "x.ter", field);
    EXPECT_ERROR_MENTIONS(ter, dir / "x.ter", "cannot create");
    const Status raw = writeRawHeightField(dir / "x.raw", field);
    EXPECT_ERROR_MENTIONS(raw, dir / "x.raw", "cannot create");
}

TEST(HeightFieldIoTest, DemoTerrainRoundTripsExactlyThroughPngBtAndRaw)
{
    auto demo = readHeightField(test::demoDataPath("trinidad_co_srtm3_crop_1025.png"));
    ASSERT_TRUE(demo.ok()) << demo.error().message;
    test::ScratchDir dir;
    ASSERT_TRUE(writePngHeightField(dir / "d.png", *demo).ok());
    ASSERT_TRUE(writeBtHeightField(dir / "d.bt", *demo, BtSampleType::Int16).ok());
    ASSERT_TRUE(writeRawHeightField(dir / "d.raw", *demo).ok());
    HeightFieldReadOptions options;
    options.rawWidth = 1025;
    options.rawHeight = 1025;
    for (const char* name : {"d.png", "d.bt", "d.raw"}) {
        SCOPED_TRACE(name);
        auto field = readHeightField(dir / name, options);
        ASSERT_TRUE(field.ok()) << field.error().message;
        EXPECT_TRUE(field->samples == demo->samples);
    }
    // Byte-identical to the original PNG's pixel rows.
    const auto original = readGray16Rows(test::demoDataPath("trinidad_co_srtm3_crop_1025.png"));
    EXPECT_TRUE(readGray16Rows(dir / "d.png") == original);
}

// ---- Oversized headers ----

TEST(HeightFieldIoTest, OversizedDimensionsAreRefusedBeforeAllocating)
{
    // Tiny hand-made files whose headers claim the largest sizes their fields can hold, and sizes that
    // would fit in memory but not in the file. Each read runs in a child that may allocate at most 1 GiB
    // more (RLIMIT_AS): a reader that allocated before refusing would throw std::bad_alloc there.
    auto btSamples = [](LeBytes b) {
        b.bytes.resize(256 + 12, 0);
        return b.bytes;
    };
    auto terWithSize = [](int sizeField, int xPoints, int yPoints) {
        LeBytes b = terHeader().text("SIZE").u16(sizeField).u16(0);
        if (xPoints > 0) {
            b.text("XPTS").u16(xPoints).u16(0).text("YPTS").u16(yPoints).u16(0);
        }
        return b.text("ALTW").i16(1).i16(0).i16(1).i16(2).i16(3).bytes;
    };
    struct Case {
        const char* name;
        Bytes bytes;
        const char* size;  ///< how the message must give the size
        int rawWidth = 0, rawHeight = 0;
    };
    const Case cases[] = {
        {"png-largest.png", pngWithHeader(0x7fffffff, 0x7fffffff), "2147483647x2147483647"},
        {"png-2^30.png", pngWithHeader(1u << 30, 1u << 30), "1073741824x1073741824"},
        {"png-fits-memory.png", pngWithHeader(20000, 20000), "20000x20000"},  // 800 MB pixels + 1.6 GB floats
        {"bt-largest.bt", btSamples(btHeader(3, 0x7fffffff, 0x7fffffff, 4, 1, 1, 0, 2, 0, 1)), "2147483647x2147483647"},
        {"bt-2^30.bt", btSamples(btHeader(3, 1 << 30, 1 << 30, 2, 0, 1, 0, 2, 0, 1)), "1073741824x1073741824"},
        {"bt-fits-memory.bt", btSamples(btHeader(3, 10000, 10000, 2, 0, 1, 0, 2, 0, 1)), "10000x10000"},
        {"ter-largest-size.ter", terWithSize(65535, 0, 0), "65536x65536"},
        {"ter-largest-points.ter", terWithSize(65534, 65535, 65535), "65535x65535"},
        {"ter-fits-memory.ter", terWithSize(9999, 10000, 10000), "10000x10000"},
        {"raw-largest.raw", Bytes(12, 0), "2147483647x2147483647", 0x7fffffff, 0x7fffffff},
        {"raw-2^30.raw", Bytes(12, 0), "1073741824x1073741824", 1 << 30, 1 << 30},
        {"raw-fits-memory.raw", Bytes(12, 0), "10000x10000", 10000, 10000},
    };
    test::ScratchDir dir;
    std::string checked;
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        writeBytes(dir / c.name, c.bytes);
        const auto path = dir / c.name;
        HeightFieldReadOptions options;
        options.rawWidth = c.rawWidth;
        options.rawHeight = c.rawHeight;
        const auto run = test::runWithMemoryLimit([&] {
            auto field = readHeightField(path, options);
            return field.ok() ? std::string("accepted") : "refused: " + field.error().message;
        });
        ASSERT_EQ(run.outcome, test::LimitedRun::Outcome::Returned) << test::describe(run);
        ASSERT_EQ(run.text.rfind("refused: ", 0), 0u) << test::describe(run);
        EXPECT_TRUE(run.text.find(path.string()) != std::string::npos) << run.text;
        EXPECT_TRUE(run.text.find(c.size) != std::string::npos) << run.text << "\ndoes not give the size " << c.size;
        const auto named = run.text.find(path.string() + ": ");
        checked += std::string(c.name) + ": " +
                   (named == std::string::npos ? run.text : run.text.substr(named + path.string().size() + 2)) + "; ";
    }
    // PNG textures and weight maps go through the image reader: the same refusal.
    for (const char* name : {"png-2^30.png", "png-fits-memory.png"}) {
        const auto path = dir / name;
        const auto run = test::runWithMemoryLimit([&] {
            auto image = readPngImage(path, 3);
            return image.ok() ? std::string("accepted") : "refused: " + image.error().message;
        });
        ASSERT_EQ(run.outcome, test::LimitedRun::Outcome::Returned) << name << ": " << test::describe(run);
        EXPECT_EQ(run.text.rfind("refused: " + path.string(), 0), 0u) << name << ": " << run.text;
    }
    ::testing::Test::RecordProperty("checked", checked);
}

}  // namespace
}  // namespace terrain
