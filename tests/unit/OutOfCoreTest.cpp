// Out-of-core prep (issue 15, part 4): a build streamed in bands with its grid in a scratch file writes
// the same bytes as the in-memory build of the same input, whatever the input's shape, holes, error bound
// and thread count; from a GDAL GeoTIFF read block by block as from a field in memory; a budget too small
// even out of core is an error that leaves no file. Also the byte sizes --memory accepts.
#include "core/Parse.h"
#include "heightfield/HeightFieldIo.h"
#include "heightfield/HeightRows.h"
#include "quadtree/QuadtreeBuilder.h"

#include "MapTestSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

namespace terrain {
namespace {

/// A rough 1000 x 900 field with small holes (3 x 3, a row's end, a corner) and a 200 x 200 void whose
/// centre lies more than 64 rings from any data (the far fill's block means), spread over three bands.
HeightField holedField()
{
    HeightField field = test::roughField(1000, 900, 31, 200, 3000);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (int j = 300; j < 303; ++j) {
        for (int i = 40; i < 43; ++i) {
            field.at(i, j) = nan;
        }
    }
    field.at(999, 0) = nan;
    field.at(0, 899) = nan;
    for (int j = 500; j < 700; ++j) {
        for (int i = 600; i < 800; ++i) {
            field.at(i, j) = nan;
        }
    }
    return field;
}

/// Budgets that force several bands of this input: the band takes a quarter of the budget, each thread a
/// 1025^2 square of codes.
std::uint64_t smallBudget(int threads)
{
    return threads == 1 ? std::uint64_t{16} << 20 : std::uint64_t{23} << 20;
}

/// The map `rows` give, built in memory or out of core within `budget` (0: smallBudget).
test::Bytes build(HeightRows& rows, BuildOptions options, const std::filesystem::path& path, bool outOfCore,
                  std::uint64_t budget = 0)
{
    options.forceOutOfCore = outOfCore;
    options.memoryBudget = outOfCore ? (budget ? budget : smallBudget(options.threads)) : 0;
    auto report = buildMap(rows, options, path);
    EXPECT_TRUE(report.ok()) << report.error().message;
    if (!report.ok()) {
        return {};
    }
    EXPECT_EQ(report->outOfCore, outOfCore);
    return test::readFileBytes(path);
}

TEST(OutOfCoreTest, BandsAndScratchGridWriteTheInMemoryBytes)
{
    struct Case {
        const char* name;
        double maxError;
        bool roughness;
        int chunk;
    };
    const Case cases[] = {
        {"lossless, roughness", 0.0, true, 17}, {"lossy 2 m", 2.0, false, 17}, {"lossless, chunk 33", 0.0, true, 33}};
    const HeightField field = holedField();
    test::ScratchDir dir;
    for (const Case& c : cases) {
        for (int threads : {1, 2}) {
            SCOPED_TRACE(std::string(c.name) + ", " + std::to_string(threads) + " thread(s)");
            BuildOptions options = test::testOptions(c.chunk, threads);
            options.maxError = c.maxError;
            options.measureRoughness = c.roughness;
            FieldRows whole(field);
            const test::Bytes reference = build(whole, options, dir / "memory.map", false);
            FieldRows streamed(field);
            const test::Bytes banded = build(streamed, options, dir / "bands.map", true);
            ASSERT_GT(reference.size(), 1000u);
            EXPECT_TRUE(banded == reference) << "the out-of-core build wrote other bytes";
        }
    }
}

TEST(OutOfCoreTest, GeoTiffReadInBlocksGivesTheInMemoryBytes)
{
    // The field as a tiled deflate Float32 GeoTIFF with nodata, made by GDAL's own tool: heights 0.1 m
    // apart (a lattice), holes where the PNG holds 0.
    test::ScratchDir dir;
    HeightField field = holedField();
    for (float& v : field.samples) {
        v = std::isnan(v) ? 0.0f : std::round(v);
    }
    ASSERT_TRUE(writePngHeightField(dir / "source.png", field).ok());
    const auto tif = dir / "input.tif";
    const test::RunResult run = test::runProgram("gdal_translate", {"-q",
                                                                    "-ot",
                                                                    "Float32",
                                                                    "-scale",
                                                                    "0",
                                                                    "65535",
                                                                    "0",
                                                                    "6553.5",
                                                                    "-a_nodata",
                                                                    "0",
                                                                    "-a_srs",
                                                                    "EPSG:32613",
                                                                    "-a_ullr",
                                                                    "500000",
                                                                    "4109000",
                                                                    "510000",
                                                                    "4100000",
                                                                    "-co",
                                                                    "TILED=YES",
                                                                    "-co",
                                                                    "BLOCKXSIZE=128",
                                                                    "-co",
                                                                    "BLOCKYSIZE=128",
                                                                    "-co",
                                                                    "COMPRESS=DEFLATE",
                                                                    (dir / "source.png").string(),
                                                                    tif.string()});
    ASSERT_EQ(run.exitCode, 0) << run.output;
    const std::filesystem::path inputs[] = {tif};
    for (int threads : {1, 2}) {
        SCOPED_TRACE(std::to_string(threads) + " thread(s)");
        BuildOptions options = test::testOptions(17, threads);
        options.spacing.reset();  // the geotransform's 10 m
        auto whole = openHeightRows(inputs);
        ASSERT_TRUE(whole.ok()) << whole.error().message;
        ASSERT_EQ((*whole)->held(), nullptr) << "GDAL input must be read in rows, not held";
        const test::Bytes reference = build(**whole, options, dir / "memory.map", false);
        auto streamed = openHeightRows(inputs);
        ASSERT_TRUE(streamed.ok()) << streamed.error().message;
        // GDAL's block cache takes at least 16 MiB beside the band (gdalCacheBytesFor): one band of this input.
        const test::Bytes banded = build(**streamed, options, dir / "bands.map", true, std::uint64_t{64} << 20);
        ASSERT_GT(reference.size(), 1000u);
        EXPECT_TRUE(banded == reference) << "the out-of-core build wrote other bytes";
    }
}

TEST(OutOfCoreTest, ABudgetForFewerThreadsThanAskedBuildsOnThoseAndSaysSo)
{
    test::ScratchDir dir;
    // Chunks of 257: each thread holds a subtree of 768^2 samples, so 18 MiB holds fewer than 8 of them.
    BuildOptions options = test::testOptions(257, 8);
    const test::Bytes reference = [&] {
        FieldRows rows(holedField());
        return build(rows, options, dir / "memory.map", false);
    }();
    std::vector<std::string> said;
    options.warn = [&](std::string_view message) { said.emplace_back(message); };
    options.forceOutOfCore = true;
    options.memoryBudget = std::uint64_t{18} << 20;
    auto report = buildMap(holedField(), options, dir / "fewer.map");
    ASSERT_TRUE(report.ok()) << report.error().message;
    EXPECT_GT(report->threads, 1);
    EXPECT_LT(report->threads, 8);
    EXPECT_TRUE(report->outOfCore);
    EXPECT_LE(report->estimatedBytes, options.memoryBudget);
    EXPECT_TRUE(test::readFileBytes(dir / "fewer.map") == reference);
    ASSERT_EQ(said.size(), 1u);
    const std::string expected = "building on " + std::to_string(report->threads) + " thread(s) of the 8 asked";
    EXPECT_NE(said[0].find(expected), std::string::npos) << said[0];
    // With room for all, all are used and nothing is said.
    said.clear();
    options.memoryBudget = std::uint64_t{64} << 20;
    report = buildMap(holedField(), options, dir / "all.map");
    ASSERT_TRUE(report.ok()) << report.error().message;
    EXPECT_EQ(report->threads, 8);
    EXPECT_TRUE(said.empty());
}

TEST(OutOfCoreTest, BudgetTooSmallEvenOutOfCoreIsAnErrorThatLeavesNoFile)
{
    test::ScratchDir dir;
    BuildOptions options = test::testOptions(17, 2);
    options.memoryBudget = std::uint64_t{4} << 20;
    const auto path = dir / "small.map";
    auto report = buildMap(holedField(), options, path);
    ASSERT_FALSE(report.ok());
    const std::string& message = report.error().message;
    EXPECT_NE(message.find("memory budget of 4.0 MiB is too small for a 1000x900 input"), std::string::npos) << message;
    EXPECT_NE(message.find("--memory"), std::string::npos) << message;
    EXPECT_FALSE(std::filesystem::exists(path));
    EXPECT_TRUE(std::filesystem::is_empty(dir.path())) << "no temporary or scratch file left behind";

    // The advice is a fixed point: following it once works (it moved each time it was followed: 212, then
    // 250, 260.5, 261.3 MiB), in memory or with --out-of-core. And it is the least that works: 1 MiB less fails.
    for (bool outOfCore : {false, true}) {
        SCOPED_TRACE(outOfCore ? "--out-of-core" : "in memory if it fits");
        options.forceOutOfCore = outOfCore;
        options.memoryBudget = std::uint64_t{4} << 20;
        auto refused = buildMap(holedField(), options, path);
        ASSERT_FALSE(refused.ok());
        const std::string& advice = refused.error().message;
        const std::size_t at = advice.find("--memory ");
        ASSERT_NE(at, std::string::npos) << advice;
        const std::uint64_t advised = std::stoull(advice.substr(at + 9)) << 20;
        options.memoryBudget = advised;
        auto followed = buildMap(holedField(), options, dir / "followed.map");
        EXPECT_TRUE(followed.ok()) << "--memory " << (advised >> 20) << "M: " << followed.error().message;
        options.memoryBudget = advised - (std::uint64_t{1} << 20);
        EXPECT_FALSE(buildMap(holedField(), options, dir / "less.map").ok()) << "the advice is the least budget";
    }
}

TEST(OutOfCoreTest, ByteSizesTakeKMGSuffixesAndRejectTheRest)
{
    EXPECT_EQ(*parseByteSize("256M"), std::uint64_t{256} << 20);
    EXPECT_EQ(*parseByteSize("1G"), std::uint64_t{1} << 30);
    EXPECT_EQ(*parseByteSize("1.5g"), std::uint64_t{3} << 29);
    EXPECT_EQ(*parseByteSize("64k"), std::uint64_t{64} << 10);
    EXPECT_EQ(*parseByteSize("100000"), 100000u);
    for (const char* bad : {"", "M", "lots", "12X", "-1G", "0", "0.5", "1e30", "nan", "256 M"}) {
        auto parsed = parseByteSize(bad);
        ASSERT_FALSE(parsed.ok()) << "'" << bad << "' parsed as " << *parsed;
        EXPECT_NE(parsed.error().message.find(std::string("'") + bad + "'"), std::string::npos)
            << parsed.error().message;
    }
}

}  // namespace
}  // namespace terrain
