// Ground truth for the roughness the synthesis continues below the data (issue 14): real 90 m SRTM decimated
// by 4 and by 16 (360 m and 1440 m spacing), built into maps with the default material and the roughness
// measured by prep, then the synthesized surface sampled at 90 m over a mountainous region, aligned with
// the original samples, against the real data there. Roughness is the RMS midpoint deviation
// d(x, r) = h(x) - (h(x - r) + h(x + r)) / 2 along east-west and north-south lines (slope-free).
#include "MapTestSupport.h"
#include "TestSupport.h"

#include "heightfield/HeightFieldIo.h"
#include "heightfield/Roughness.h"
#include "lod/HeightQuery.h"
#include "lod/TerrainNodeSource.h"
#include "quadtree/MapFile.h"
#include "quadtree/QuadtreeBuilder.h"
#include "synthesis/DetailRecipeSetup.h"
#include "synthesis/DetailSynthesizer.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace terrain {
namespace {

constexpr double kSpacing = 90.0;
/// The lags of the comparison, in 90 m samples: 90, 180, 360 and 720 m.
constexpr std::array<int, 4> kLags = {1, 2, 4, 8};

struct Region {
    int x0, y0, size;  ///< in samples of the 90 m original
};

std::array<double, kLags.size()> roughnessOf(std::span<const float> heights, int width, int height)
{
    std::array<double, kLags.size()> d{};
    for (std::size_t k = 0; k < kLags.size(); ++k) {
        d[k] = midpointDeviation(heights, width, height, kLags[k], 0, 0, width, height).rms();
    }
    return d;
}

/// Every `factor`-th sample of `field` (both ways), as a coarser DEM of the same place.
HeightField decimate(const HeightField& field, int factor)
{
    const int w = (field.width - 1) / factor + 1, h = (field.height - 1) / factor + 1;
    return test::makeHeightField(w, h, [&](int i, int j) { return field.at(i * factor, j * factor); });
}

class RoughnessGroundTruthTest : public ::testing::Test {
protected:
    static void SetUpTestSuite()
    {
        auto field = readHeightField(test::demoDataPath("trinidad_co_srtm3_crop_1025.png"));
        ASSERT_TRUE(field.ok()) << field.error().message;
        sField = new HeightField(std::move(field).value());
        sDir = new test::ScratchDir();
    }
    static void TearDownTestSuite()
    {
        delete sField;
        delete sDir;
    }

    /// The synthesized surface of the map made from the `factor` times decimated original, sampled at 90 m
    /// over `region`.
    static std::vector<float> synthesized(int factor, const Region& region, bool roughness)
    {
        const auto path = *sDir / ("decimated-" + std::to_string(factor) + (roughness ? "" : "-plain") + ".map");
        HeightField coarse = decimate(*sField, factor);
        BuildOptions options = test::testOptions(65, 2);
        options.spacing = kSpacing * factor;
        std::vector<std::string> warnings;
        auto materials = loadDetailMaterials({std::filesystem::path(TERRAIN_MATERIALS_DIR) / "grass.mat"}, warnings);
        EXPECT_TRUE(materials.ok());
        auto built = buildMap(std::move(coarse), options, path);
        EXPECT_TRUE(built.ok()) << built.error().message;
        auto map = MapFile::open(path, ReaderKind::Stream);
        EXPECT_TRUE(map.ok());
        DetailSettings settings;
        settings.materials = materials.value();
        if (roughness) {
            settings.roughness = makeRoughnessNoise((*map)->header(), settings.materials.get());
            EXPECT_TRUE(settings.roughness);
        }
        auto synthesizer = DetailSynthesizer::create(65, settings).value();
        TerrainNodeSource source(**map, {synthesizer.get(), 0.0});
        const int depth = static_cast<int>((*map)->header().levels) - 1 + static_cast<int>(std::log2(factor));
        SurfaceSampler sampler(**map, source, depth, 1024);
        std::vector<float> out(static_cast<std::size_t>(region.size) * region.size);
        for (int j = 0; j < region.size; ++j) {
            for (int i = 0; i < region.size; ++i) {
                auto sample = sampler.at((region.x0 + i) * kSpacing, (region.y0 + j) * kSpacing);
                EXPECT_TRUE(sample.ok()) << sample.error().message;
                out[static_cast<std::size_t>(j) * region.size + i] = static_cast<float>(sample->height);
            }
        }
        return out;
    }

    static std::vector<float> original(const Region& region)
    {
        std::vector<float> out(static_cast<std::size_t>(region.size) * region.size);
        for (int j = 0; j < region.size; ++j) {
            for (int i = 0; i < region.size; ++i) {
                out[static_cast<std::size_t>(j) * region.size + i] = sField->at(region.x0 + i, region.y0 + j);
            }
        }
        return out;
    }

    static HeightField* sField;
    static test::ScratchDir* sDir;
};

HeightField* RoughnessGroundTruthTest::sField = nullptr;
test::ScratchDir* RoughnessGroundTruthTest::sDir = nullptr;

TEST_F(RoughnessGroundTruthTest, DecimatedDataSynthesizesTheRealRoughness)
{
    // The roughest 256 x 256 block of the crop (23 km a side), on the 16-sample grid so it starts on a
    // sample of both decimated copies.
    Region region{0, 0, 256};
    double roughest = 0.0;
    for (int y = 0; y + 256 <= sField->height; y += 128) {
        for (int x = 0; x + 256 <= sField->width; x += 128) {
            const auto d = roughnessOf(original({x, y, 256}), 256, 256);
            if (d[0] > roughest) {
                roughest = d[0];
                region = {x, y, 256};
            }
        }
    }
    const auto real = roughnessOf(original(region), region.size, region.size);
    std::printf("region %d,%d %dx%d (90 m samples); RMS midpoint deviation, metres, at 90 / 180 / 360 / 720 m\n",
                region.x0, region.y0, region.size, region.size);
    std::printf("  real 90 m data              %7.2f %7.2f %7.2f %7.2f\n", real[0], real[1], real[2], real[3]);
    for (int factor : {4, 16}) {
        for (bool roughness : {false, true}) {
            const auto d = roughnessOf(synthesized(factor, region, roughness), region.size, region.size);
            std::printf(
                "  from %2dx decimated, %-9s %7.2f %7.2f %7.2f %7.2f   real / synthesized %5.2f %5.2f %5.2f %5.2f\n",
                factor, roughness ? "rough" : "plain", d[0], d[1], d[2], d[3], real[0] / d[0], real[1] / d[1],
                real[2] / d[2], real[3] / d[3]);
            if (roughness) {
                for (std::size_t k = 0; k < kLags.size(); ++k) {
                    EXPECT_LT(real[k] / d[k], 2.0) << factor << "x, lag " << kLags[k] * kSpacing << " m";
                    EXPECT_GT(real[k] / d[k], 0.5) << factor << "x, lag " << kLags[k] * kSpacing << " m";
                }
            }
        }
    }
}

}  // namespace
}  // namespace terrain
