// Materials whose amplitude follows the terrain's own roughness (issue 14: relative_amplitude): parsing, the
// fractal's measured deviation against brute force, the octaves left out over fine data, the displacement
// against the law (point by point and in its statistics), the error model scaled with it, and the settings
// made for a map.
#include "MapTestSupport.h"

#include "heightfield/Roughness.h"
#include "synthesis/DetailErrorModel.h"
#include "synthesis/DetailSynthesizer.h"
#include "synthesis/Material.h"

#include <gtest/gtest.h>

#include <cmath>

namespace terrain {
namespace {

Expected<Material> parse(const std::string& text)
{
    auto config = ConfigFile::parse(text, "relative.mat");
    if (!config) {
        return config.error();
    }
    std::vector<std::string> warnings;
    return parseMaterial(*config, warnings);
}

const char* kFbm = "displacement = fbm\noctaves = 6\ngain = 0.45\nwavelength = 40\namplitude = 0.8\nseed = 3\n";

TEST(RelativeMaterialTest, ParsesAndMeasuresTheFractalsDeviation)
{
    auto m = parse(std::string(kFbm) + "relative_amplitude = 0.5\n");
    ASSERT_TRUE(m.ok()) << m.error().message;
    EXPECT_EQ(m->relativeAmplitude, 0.5);
    // Brute force over a regular grid of places (not the measurement's pseudo-random ones): within 5 %.
    double sum = 0.0;
    int count = 0;
    const double r = 40.0;
    for (int j = 0; j < 80; ++j) {
        for (int i = 0; i < 80; ++i) {
            const double x = 1234.5 + i * 37.3, y = -987.25 + j * 41.9;
            const double h = m->displacementAt(x, y);
            const double dx = h - 0.5 * (m->displacementAt(x - r, y) + m->displacementAt(x + r, y));
            const double dy = h - 0.5 * (m->displacementAt(x, y - r) + m->displacementAt(x, y + r));
            sum += dx * dx + dy * dy;
            count += 2;
        }
    }
    const double brute = std::sqrt(sum / count);
    EXPECT_NEAR(m->fractalDeviation, brute, 0.05 * brute);
    EXPECT_GT(m->fractalDeviation, 0.0);
    EXPECT_LT(m->fractalDeviation, 0.8);

    auto absolute = parse(kFbm);
    ASSERT_TRUE(absolute.ok());
    EXPECT_EQ(absolute->relativeAmplitude, 0.0);
    EXPECT_EQ(absolute->fractalDeviation, 0.0);

    auto zero = parse(std::string(kFbm) + "relative_amplitude = 0\n");
    ASSERT_FALSE(zero.ok());
    EXPECT_NE(zero.error().message.find("relative.mat:7: relative_amplitude"), std::string::npos)
        << zero.error().message;
    EXPECT_NE(zero.error().message.find("[0.001, 100]"), std::string::npos) << zero.error().message;
    auto flat = parse("displacement = fbm\namplitude = 0\nrelative_amplitude = 1\n");
    ASSERT_FALSE(flat.ok());
    EXPECT_NE(flat.error().message.find("relative_amplitude needs an amplitude > 0"), std::string::npos)
        << flat.error().message;
}

TEST(RelativeMaterialTest, OverFineDataTheOctavesItHasAreLeftOut)
{
    auto m = parse(std::string(kFbm) + "relative_amplitude = 0.5\n");
    ASSERT_TRUE(m.ok());
    // 90 m data: every octave (40 m .. 1.25 m) is finer; nothing changes.
    const Material coarse = relativeTo(*m, 90.0);
    EXPECT_EQ(coarse.fractal.octaves, 6);
    EXPECT_EQ(coarse.displacement, m->displacement);
    // 10 m data has the 40, 20 and 10 m octaves: 3 are left, from 5 m, the fallback amplitude by 0.45^3.
    const Material fine = relativeTo(*m, 10.0);
    EXPECT_EQ(fine.fractal.octaves, 3);
    EXPECT_DOUBLE_EQ(fine.fractal.wavelength, 5.0);
    EXPECT_NEAR(fine.fractal.amplitude, 0.8 * 0.45 * 0.45 * 0.45, 1e-12);
    ASSERT_TRUE(fine.displacement);
    EXPECT_GT(fine.fractalDeviation, 0.0);
    EXPECT_NEAR(fine.fractalDeviation, fractalMidpointDeviation(*fine.displacement), 1e-12);
    // 1 m data (lidar) has all of them: no displacement left, placement and textures stay.
    const Material lidar = relativeTo(*m, 1.0);
    EXPECT_FALSE(lidar.displacement);
    EXPECT_EQ(lidar.kind, DisplacementKind::None);
    // Absolute materials are what their file says, over any data.
    auto absolute = parse(kFbm);
    ASSERT_TRUE(absolute.ok());
    EXPECT_EQ(relativeTo(*absolute, 1.0).fractal.octaves, 6);
}

/// Laws on a 4 x 4 leaf grid of 16-cell leaves at 10 m: A = 1 m in the west half, 8 m in the east, H 0.7.
std::shared_ptr<const RoughnessNoise> twoLaws()
{
    RoughnessGrid grid;
    grid.leavesPerSide = 4;
    for (int y = 0; y < 4; ++y) {
        for (int x = 0; x < 4; ++x) {
            grid.laws.push_back({x < 2 ? 1.0 : 8.0, 0.7});
        }
    }
    return std::make_shared<const RoughnessNoise>(grid, 16, 10.0, 0);
}

TEST(RelativeMaterialTest, TheDisplacementFollowsTheLaw)
{
    auto m = parse(std::string("displacement = fbm\noctaves = 5\nwavelength = 4\namplitude = 1\nseed = 9\n") +
                   "relative_amplitude = 0.5\n");
    ASSERT_TRUE(m.ok()) << m.error().message;
    auto set = std::make_shared<const MaterialSet>(std::vector<Material>{*m});
    const auto laws = twoLaws();
    auto synthesizer = DetailSynthesizer::create(17, {"kobbelt", 1.0, set, nullptr, laws});
    ASSERT_TRUE(synthesizer.ok()) << synthesizer.error().message;
    const DetailSynthesizer& s = **synthesizer;
    EXPECT_TRUE(s.isRelative(0));
    // A window of 2.5 m samples (2 levels below the 10 m data) over the whole map: 257 x 257.
    const int w = 257;
    const double spacing = 2.5;
    DualHeightMap map;
    map.size = w;
    const WindowPlacement where{0.0, 0.0, 0.0, spacing, 0, 0};
    const auto scales = s.materialScales(0, 0, w, w, spacing);
    ASSERT_EQ(scales.size(), 1u);
    ASSERT_EQ(scales[0].size(), static_cast<std::size_t>(w) * w);
    std::vector<float> displacement(scales[0].size());
    set->displacementGrid(where.grid(w), std::vector<float>(displacement.size(), 0.0f),
                          std::vector<float>(displacement.size(), 0.0f), displacement, {}, scales);
    // Point by point: the fractal times 0.5 x the law's deviation at 4 m / the fractal's own deviation.
    for (int j = 0; j < w; j += 7) {
        for (int i = 0; i < w; i += 5) {
            const double u = i * spacing / 10.0, v = j * spacing / 10.0;
            const double law = laws->deviationAt(u, v, 4.0);
            const double expected = m->displacementAt(i * spacing, j * spacing) * 0.5 * law / m->fractalDeviation;
            // deviationGrid interpolates D between the 10 m samples: (delta log D)^2 / 8 relative, with log D
            // changing by up to ln 8 / 16 per sample here (a law 8x rougher one leaf further east).
            ASSERT_NEAR(displacement[static_cast<std::size_t>(j) * w + i], expected, 3e-3 * std::abs(expected) + 1e-6)
                << i << "," << j;
        }
    }
    // In its statistics: the RMS midpoint deviation at 4 m (lag 2 samples) over each half's inner leaves
    // (where the law is uniform) is 0.5 x the law's there, and the east's 8x the west's.
    auto deviation = [&](int i0, int i1) { return midpointDeviation(displacement, w, w, 2, i0, 8, i1, w - 8).rms(); };
    const double west = deviation(8, 40), east = deviation(216, 248);
    const double lawWest = 1.0 * std::pow(0.4, 0.7), lawEast = 8.0 * std::pow(0.4, 0.7);
    EXPECT_NEAR(west, 0.5 * lawWest, 0.15 * 0.5 * lawWest);
    EXPECT_NEAR(east, 0.5 * lawEast, 0.15 * 0.5 * lawEast);
    EXPECT_NEAR(east / west, 8.0, 0.4);
    // The bound: the amplitude times the largest factor anywhere (the east's).
    EXPECT_NEAR(s.materialBound(), 1.0 * 0.5 * laws->maxDeviation(4.0) / m->fractalDeviation, 1e-9);
    double largest = 0.0;
    for (float d : displacement) {
        largest = std::max(largest, static_cast<double>(std::abs(d)));
    }
    EXPECT_LE(largest, s.materialBound());
}

TEST(RelativeMaterialTest, TheErrorModelScalesWithTheMaterial)
{
    auto m = parse(std::string(kFbm) + "relative_amplitude = 0.5\n");
    ASSERT_TRUE(m.ok());
    auto set = std::make_shared<const MaterialSet>(std::vector<Material>{*m});
    auto synthesizer = DetailSynthesizer::create(17, {"kobbelt", 1.0, set, nullptr, twoLaws()}).value();
    const DetailErrorModel model(*synthesizer, 80.0);
    const std::vector<std::uint8_t> weights(17 * 17 * 4, 0);
    const std::vector<std::vector<float>> one{std::vector<float>(17 * 17, 1.0f)};
    std::vector<std::vector<float>> varying{std::vector<float>(17 * 17, 1.0f)};
    varying[0][17 * 8 + 8] = 3.0f;
    for (int level = 3; level <= 8; ++level) {
        const double plain = model.displacementTerm(weights, level);
        EXPECT_DOUBLE_EQ(model.displacementTerm(weights, level, one), plain);
        EXPECT_DOUBLE_EQ(model.displacementTerm(weights, level, varying), 3.0 * plain) << "the worst sample's";
    }
}

TEST(RelativeMaterialTest, SettingsForAMapFollowItsLaws)
{
    auto m = parse(std::string(kFbm) + "relative_amplitude = 0.5\n");
    ASSERT_TRUE(m.ok());
    DetailSettings settings{"kobbelt", 1.0, std::make_shared<const MaterialSet>(std::vector<Material>{*m})};
    MapHeader header;
    header.chunkSize = 17;
    header.sampleSpacing = 10.0;
    // Without laws: as given.
    DetailSettings none = settingsForMap(settings, header, true);
    EXPECT_EQ(none.materials, settings.materials);
    EXPECT_FALSE(none.laws);
    EXPECT_FALSE(none.roughness);
    RoughnessGrid grid;
    grid.leavesPerSide = 2;
    grid.laws.assign(4, RoughnessLaw{2.0, 0.8});
    header.roughness = grid;
    DetailSettings made = settingsForMap(settings, header, true);
    ASSERT_TRUE(made.laws);
    EXPECT_EQ(made.roughness, made.laws);
    EXPECT_EQ(made.materials->materials()[0].fractal.octaves, 3) << "relativeTo the map's 10 m";
    // The roughness octaves stop at the material's first wavelength left (5 m).
    EXPECT_EQ(made.laws->octaves(), RoughnessNoise::octavesDownTo(10.0, 5.0));
    EXPECT_FALSE(settingsForMap(settings, header, false).roughness);
    EXPECT_TRUE(settingsForMap(settings, header, false).laws);
}

}  // namespace
}  // namespace terrain

namespace terrain {
namespace {

TEST(RelativeMaterialTest, ShippedMaterialsDeviations)
{
    const std::filesystem::path dir = TERRAIN_MATERIALS_DIR;
    for (const char* name : {"grass.mat", "rock.mat"}) {
        std::vector<std::string> warnings;
        auto m = loadMaterial(dir / name, warnings);
        ASSERT_TRUE(m.ok()) << m.error().message;
        std::printf("%s: amplitude %.3f m, wavelength %.1f m, fractal deviation %.4f m, relative %.3f\n", name,
                    m->fractal.amplitude, m->fractal.wavelength, m->fractalDeviation, m->relativeAmplitude);
    }
}

}  // namespace
}  // namespace terrain
