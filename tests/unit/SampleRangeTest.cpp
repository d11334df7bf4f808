// Samples that would destroy the quantization are refused before anything is built (quadtree/QuantizedGrid.h,
// checkSampleRange): infinite samples, untagged no-data values and spikes far outside the rest of the terrain,
// heights beyond kMaxHeightMetres; relief of any real shape is not. No-data values are compared in the
// samples' own type (heightfield/HeightField.h, isNoDataValue), and --clamp keeps heights within a range.
#include "MapTestSupport.h"
#include "TestSupport.h"

#include "heightfield/HeightField.h"
#include "quadtree/MapFile.h"
#include "quadtree/QuadtreeBuilder.h"
#include "quadtree/QuantizedGrid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace terrain {
namespace {

constexpr float kFloatMax = std::numeric_limits<float>::max();
constexpr float kInf = std::numeric_limits<float>::infinity();

/// A 129 x 129 hillside between about 800 and 1200 m.
float hill(int i, int j)
{
    return 1000.0f + 200.0f * std::sin(static_cast<float>(i) / 9.0f) * std::cos(static_cast<float>(j) / 7.0f);
}

Status rangeOf(const HeightField& field, double scale = 1.0, double offset = 0.0)
{
    SampleStatistics statistics(field.width, field.height);
    statistics.addRows(0, field.height, field.samples);
    return checkSampleRange(statistics, scale, offset);
}

bool mentions(const Status& status, const std::string& text)
{
    return !status.ok() && status.error().message.find(text) != std::string::npos;
}

TEST(SampleRangeTest, InfiniteSamplesAreRefusedWithWhereTheFirstIs)
{
    for (float bad : {kInf, -kInf}) {
        const HeightField field =
            test::makeHeightField(129, 129, [&](int i, int j) { return i == 7 && j == 3 ? bad : hill(i, j); });
        const Status status = rangeOf(field);
        EXPECT_TRUE(mentions(status, "1 sample(s) are infinite")) << status.error().message;
        EXPECT_TRUE(mentions(status, "sample (7, 3)")) << status.error().message;
        EXPECT_TRUE(mentions(status, bad > 0 ? "--nodata inf" : "--nodata -inf")) << status.error().message;
    }
}

TEST(SampleRangeTest, UntaggedNoDataAndSpikesFarOutsideTheTerrainAreRefusedNamingTheValue)
{
    struct Case {
        const char* what;
        float value;
        int count;  ///< samples holding it: a block of the field's first rows
        const char* says;
    };
    const Case cases[] = {
        {"float max, 1% of the field", kFloatMax, 170, "--nodata 3.40282347e+38"},
        {"-float max", -kFloatMax, 170, "--nodata -3.40282347e+38"},
        {"a 1e30 spike", 1e30f, 1, "--nodata 1.00000002e+30"},
        {"-32768 under 30% of the field (an untagged SRTM void or sea)", -32768.0f, 5000, "--nodata -32768"},
        {"-1e20", -1e20f, 3, "--nodata -1.00000002e+20"},
    };
    for (const Case& c : cases) {
        int k = 0;
        const HeightField field =
            test::makeHeightField(129, 129, [&](int i, int j) { return k++ < c.count ? c.value : hill(i, j); });
        const Status status = rangeOf(field);
        EXPECT_TRUE(mentions(status, c.says)) << c.what << ": " << (status.ok() ? "accepted" : status.error().message);
        EXPECT_TRUE(mentions(status, "--clamp")) << c.what;
        EXPECT_TRUE(mentions(status, c.value > 0 ? "far above" : "far below")) << c.what;
    }
}

TEST(SampleRangeTest, ReliefOfRealShapesIsAccepted)
{
    struct Case {
        const char* what;
        HeightField field;
    };
    const Case cases[] = {
        {"a hillside", test::makeHeightField(129, 129, hill)},
        // A 6 km volcano on a plain at sea level: far from the plain's median, but its slopes fill the gap.
        {"a volcano on a plain", test::makeHeightField(257, 257,
                                                       [](int i, int j) {
                                                           const double r = std::hypot(i - 128.0, j - 128.0);
                                                           return static_cast<float>(std::max(0.0, 6000.0 - 200.0 * r));
                                                       })},
        // An 8.8 km peak on one sample of a flat field: no real relief gap is 10 km wide.
        {"a lone peak",
         test::makeHeightField(129, 129, [](int i, int j) { return i == 64 && j == 64 ? 8848.0f : 0.0f; })},
        // Trench to summit on one grid, as a global grid has.
        {"ocean and mountains",
         test::makeHeightField(
             129, 129,
             [](int i, int j) { return static_cast<float>(-11000.0 + 19848.0 * (i + 129.0 * j) / (129.0 * 129.0)); })},
        {"a flat field", test::makeHeightField(17, 17, [](int, int) { return 42.0f; })},
    };
    for (const Case& c : cases) {
        const Status status = rangeOf(c.field);
        EXPECT_TRUE(status.ok()) << c.what << ": " << status.error().message;
    }
}

TEST(SampleRangeTest, HeightsBeyondTheWidestRangeNameTheScaleAndOffset)
{
    const HeightField field = test::makeHeightField(33, 33, hill);
    EXPECT_TRUE(mentions(rangeOf(field, 1e6), "check -v and --offset"));
    EXPECT_TRUE(mentions(rangeOf(field, 1.0, 2e7), "check -v and --offset"));
    EXPECT_TRUE(rangeOf(field, 1.0, -9e6).ok());
    // A relief of 4e-7 m at -1e7 m: steps no position resolves there (it crashed the texture sampler).
    EXPECT_TRUE(mentions(rangeOf(field, 1e-9, -1e7), "finer than positions resolve"));
    EXPECT_TRUE(rangeOf(field, 1e-9, 0.0).ok()) << "the same relief near 0 is fine";
}

TEST(SampleRangeTest, NoDataIsComparedInTheSamplesOwnType)
{
    // What gdalinfo prints for a float32 raster's float max (17 digits) is not float max as a double.
    const double printed = 3.40282346638529011e+38;
    ASSERT_NE(printed, static_cast<double>(kFloatMax));
    EXPECT_TRUE(isNoDataValue(kFloatMax, printed));
    EXPECT_TRUE(isNoDataValue(-kFloatMax, -printed));
    EXPECT_FALSE(isNoDataValue(kFloatMax, -printed));
    // Printed to 9 digits, as checkSampleRange suggests it.
    EXPECT_TRUE(isNoDataValue(1e30f, 1.00000002e+30));
    EXPECT_TRUE(isNoDataValue(-9999.0f, -9999.0));
    EXPECT_FALSE(isNoDataValue(-9999.5f, -9999.0));
    EXPECT_TRUE(isNoDataValue(0.1f, 0.1));  // 0.1 as a float is not 0.1 as a double
    // Beyond the float range: the infinity of its sign (a double raster's value read as float).
    EXPECT_TRUE(isNoDataValue(kInf, 1e300));
    EXPECT_TRUE(isNoDataValue(-kInf, -std::numeric_limits<double>::infinity()));
    EXPECT_FALSE(isNoDataValue(kInf, -1e300));
    EXPECT_FALSE(isNoDataValue(kFloatMax, 1e300));
    EXPECT_FALSE(isNoDataValue(std::nanf(""), std::nan("")));
    EXPECT_FALSE(isNoDataValue(5.0f, std::nan("")));
}

TEST(SampleRangeTest, ABuildRefusesBadSamplesAndClampKeepsThemWithinItsRange)
{
    const HeightField spiked =
        test::makeHeightField(65, 65, [](int i, int j) { return i == 30 && j == 20 ? 1e30f : hill(i, j); });
    test::ScratchDir dir;
    BuildOptions options = test::testOptions(17);
    auto refused = buildMap(spiked, options, dir / "spike.map");
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.error().message.find("sample (30, 20)"), std::string::npos) << refused.error().message;
    EXPECT_TRUE(dir.list().empty());

    options.clampMetres = std::array<double, 2>{0.0, 1100.0};
    auto clamped = buildMap(spiked, options, dir / "clamped.map");
    ASSERT_TRUE(clamped.ok()) << clamped.error().message;
    auto map = MapFile::open(dir / "clamped.map", ReaderKind::Stream);
    ASSERT_TRUE(map.ok()) << map.error().message;
    const MapHeader& h = (*map)->header();
    const DirectoryEntry& root = (*map)->directory().front();
    EXPECT_LE(h.heightOf(root.maxCode), 1100.0 + h.heightStep);
    EXPECT_GE(h.heightOf(root.maxCode), 1100.0 - h.heightStep) << "the hill reaches above 1100 m";
    EXPECT_GE(h.heightOf(root.minCode), 800.0 - h.heightStep);
}

}  // namespace
}  // namespace terrain
