// The ground's cover (synthesis/Material.h, DetailSynthesizer.h): placement by curvature and a macro variation,
// blending by the materials' own heights, and the colours the materials bake into every node, each against an
// independent computation: the formulas by hand, finite differences, sampled statistics.
#include "synthesis/DetailSynthesizer.h"
#include "synthesis/Material.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

namespace terrain {
namespace {

const std::filesystem::path kMaterials = TERRAIN_MATERIALS_DIR;

Material parsed(const std::string& text)
{
    auto config = ConfigFile::parse(text, "cover.mat");
    EXPECT_TRUE(config.ok());
    std::vector<std::string> warnings;
    auto material = parseMaterial(*config, warnings);
    EXPECT_TRUE(material.ok()) << (material.ok() ? "" : material.error().message);
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    return material.ok() ? std::move(material).value() : Material{};
}

/// Grass everywhere, rock from 30 degrees (blended over 10) whose displacement stands out by `blendHeight`.
MaterialSet grassAndRock(double blendHeight)
{
    std::vector<Material> m;
    m.push_back(
        parsed("name = grass\ndisplacement = fbm\namplitude = 0.8\nwavelength = 40\nseed = 3\n"
               "tint = 0.55, 0.68, 0.40\n"));
    std::string rock =
        "name = rock\ndisplacement = ridged\namplitude = 3\nwavelength = 24\nseed = 7\nslope = 30, 90\n"
        "slope_blend = 10\ntint = 0.60, 0.57, 0.53\n";
    if (blendHeight > 0.0) {
        rock += "blend_height = " + std::to_string(blendHeight) + "\n";
    }
    m.push_back(parsed(rock));
    return MaterialSet(std::move(m));
}

TEST(GroundCover, ShippedSnowLoadsWithItsRules)
{
    std::vector<std::string> warnings;
    auto set =
        MaterialSet::load({kMaterials / "grass.mat", kMaterials / "rock.mat", kMaterials / "snow.mat"}, warnings);
    ASSERT_TRUE(set.ok()) << set.error().message;
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    const Material& snow = set->materials()[2];
    EXPECT_EQ(snow.name, "snow");
    EXPECT_GT(snow.colourCover, 0.5);
    EXPECT_GT(snow.blendHeight, 0.0);
    EXPECT_GT(snow.placement.variationAmount, 0.0);
    EXPECT_TRUE(set->usesCurvature());
    EXPECT_TRUE(set->blendsByHeight());
    // Gentle ground well above the line, not on a ridge, is snow whatever the variation; steep ground there rock; low
    // ground grass; a sharp ridge above the line keeps less snow than a hollow beside it.
    double w[3];
    set->weights({10.0, 5000.0, 10.0, 1234.0, 5678.0}, {}, w);
    EXPECT_EQ(w[2], 1.0);
    set->weights({70.0, 5000.0, 0.0, 1234.0, 5678.0}, {}, w);
    EXPECT_EQ(w[1], 1.0);
    set->weights({10.0, 2000.0, 0.0, 1234.0, 5678.0}, {}, w);
    EXPECT_EQ(w[0], 1.0);
    double ridge[3], hollow[3];
    for (double x = 0.0; x < 20000.0; x += 997.0) {
        set->weights({10.0, 4100.0, -4.0, x, 0.0}, {}, ridge);
        set->weights({10.0, 4100.0, 4.0, x, 0.0}, {}, hollow);
        EXPECT_LE(ridge[2], hollow[2]) << x;
    }
}

TEST(GroundCover, CurvatureIsTheBendOverOneSample)
{
    // Any plane: 0.
    auto plane = [](double x, double y) { return 3.0 + 0.7 * x - 0.2 * y; };
    const double s = 7.5;
    EXPECT_NEAR(placementCurvature(plane(-s, 0), plane(s, 0), plane(0, -s), plane(0, s), plane(0, 0), s), 0.0, 1e-12);
    // z = a x^2 + b y^2: the slope changes by 2 a s along x and 2 b s along y over one sample; their mean is
    // (a + b) s, as an angle.
    for (double a : {-0.02, -0.001, 0.0005, 0.01, 0.3}) {
        const double b = 0.5 * a;
        auto bowl = [&](double x, double y) { return a * x * x + b * y * y; };
        const double expected = std::atan((a + b) * s) * 180.0 / std::numbers::pi;
        EXPECT_NEAR(placementCurvature(bowl(-s, 0), bowl(s, 0), bowl(0, -s), bowl(0, s), bowl(0, 0), s), expected, 1e-9)
            << a;
    }
    // A material placed on hollows covers a bowl and not a dome.
    const Material m = parsed("name = h\ncurvature = 2, 90\ncurvature_blend = 1\n");
    EXPECT_EQ(m.placement.coverage({0.0, 0.0, 5.0, 0.0, 0.0}), 1.0);
    EXPECT_EQ(m.placement.coverage({0.0, 0.0, -5.0, 0.0, 0.0}), 0.0);
    EXPECT_DOUBLE_EQ(m.placement.coverage({0.0, 0.0, 1.5, 0.0, 0.0}), 0.5);
}

TEST(GroundCover, VariationIsSmoothOfUnitDeviationAndMovesTheEdges)
{
    const Material m = parsed("name = v\nheight = 1000, 2000\nheight_blend = 100\nvariation = 1, 500\nseed = 4\n");
    const MaterialPlacement& p = m.placement;
    // Deviation about 1 over many places, mean about 0, never beyond the clamp.
    double sum = 0.0, squares = 0.0;
    const int count = 40000;
    for (int k = 0; k < count; ++k) {
        const double x = (k % 200) * 137.0 + 0.3, y = (k / 200) * 151.0 + 0.7;
        const double v = p.variation(x, y);
        ASSERT_LE(std::abs(v), 3.0);
        sum += v;
        squares += v * v;
    }
    const double mean = sum / count, deviation = std::sqrt(squares / count - mean * mean);
    EXPECT_NEAR(mean, 0.0, 0.1);
    EXPECT_NEAR(deviation, 1.0, 0.25);
    // Smooth: over a metre of a 500 m wavelength it changes by little.
    double largest = 0.0;
    for (int k = 0; k < 5000; ++k) {
        const double x = 40000.0 + k;
        largest = std::max(largest, std::abs(p.variation(x + 1.0, 77.0) - p.variation(x, 77.0)));
    }
    EXPECT_LT(largest, 0.1);
    // The coverage at the rule's edge follows the noise: where it is positive the edge has moved out (more
    // cover than the plain rule's 0.5 half a blend outside), where negative in.
    const double plain = MaterialPlacement{}.coverage(0.0, 0.0);
    EXPECT_EQ(plain, 1.0);
    int moved = 0;
    for (int k = 0; k < 200; ++k) {
        const double x = k * 211.0, y = 9.0;
        const double v = p.variation(x, y);
        const double c = p.coverage({0.0, 950.0, 0.0, x, y});  // half a blend below the range
        if (v > 0.2) {
            EXPECT_GT(c, 0.5) << x;
            ++moved;
        } else if (v < -0.2) {
            EXPECT_LT(c, 0.5) << x;
            ++moved;
        }
    }
    EXPECT_GT(moved, 100);
    // Without variation: none.
    EXPECT_EQ(MaterialPlacement{}.variation(123.0, 456.0), 0.0);
    // The largest amount moves edges by up to 12 blend widths, no further: ground deeper inside keeps its cover,
    // and a rule without edges (slope 0-90, no height or curvature limits) covers everything.
    const Material strong = parsed("name = s\nheight = 1000, 2000\nheight_blend = 10\nvariation = 4, 200\n");
    const Material everywhere = parsed("name = e\nvariation = 4, 200\n");
    int patches = 0;
    for (int k = 0; k < 400; ++k) {
        const double x = k * 53.0, y = k * 17.0;
        EXPECT_EQ(strong.placement.coverage({10.0, 1500.0, 0.0, x, y}), 1.0) << x;
        EXPECT_EQ(everywhere.placement.coverage({45.0, -300.0, -20.0, x, y}), 1.0) << x;
        patches += strong.placement.coverage({10.0, 1000.0 + 0.1 * k, 0.0, x, y}) < 0.5;
    }
    EXPECT_GT(patches, 20);  // near the edge the noise does thin it
}

TEST(GroundCover, HeightBlendShowsTheHigherMaterialAndLeavesTheSurfaceAlone)
{
    const MaterialSet blended = grassAndRock(2.0), plain = grassAndRock(0.0);
    // Half way into rock's slope blend (c = 0.5): c' = 0.5 + (d_rock - d_grass) / 2, clamped.
    const PlacementSample half{25.0, 0.0, 0.0, 0.0, 0.0};
    double w[2];
    struct Case {
        double grass, rock, rockWeight;
    };
    for (const Case& c :
         {Case{0.0, 0.0, 0.5}, Case{0.0, 1.0, 1.0}, Case{0.0, -1.0, 0.0}, Case{0.2, 0.6, 0.7}, Case{-0.5, -0.9, 0.3}}) {
        const double d[2] = {c.grass, c.rock};
        blended.weights(half, d, w);
        EXPECT_NEAR(w[1], c.rockWeight, 1e-12) << c.grass << " " << c.rock;
        EXPECT_NEAR(w[0] + w[1], 1.0, 1e-12);
        plain.weights(half, d, w);
        EXPECT_DOUBLE_EQ(w[1], 0.5);  // no blend height: the displacements change nothing
    }
    // Coverage 0 and 1 stay: flat ground is grass and cliffs rock however high the other stands.
    const double tall[2] = {-50.0, 50.0};
    blended.weights({5.0, 0.0, 0.0, 0.0, 0.0}, tall, w);
    EXPECT_EQ(w[1], 0.0);
    const double deep[2] = {50.0, -50.0};
    blended.weights({60.0, 0.0, 0.0, 0.0, 0.0}, deep, w);
    EXPECT_EQ(w[1], 1.0);

    // On a grid across the blend: the surface is the same bits with and without the blend height, the
    // weights the ground shows differ, and they follow the rule above with the displacements the grid made.
    const int n = 33;
    std::vector<float> slope(n * n), height(n * n, 0.0f);
    for (int k = 0; k < n * n; ++k) {
        slope[k] = static_cast<float>(18.0 + 24.0 * (k % n) / (n - 1));
    }
    const SampleGrid grid{1000.0, 2000.0, 0, 0, 0.5, n, n};
    std::vector<float> surfaceBlended(n * n), surfacePlain(n * n);
    std::vector<std::uint8_t> weightsBlended(n * n * 2), weightsPlain(n * n * 2);
    blended.displacementGrid(grid, slope, height, surfaceBlended, {}, {}, {}, weightsBlended);
    plain.displacementGrid(grid, slope, height, surfacePlain, {}, {}, {}, weightsPlain);
    EXPECT_EQ(std::memcmp(surfaceBlended.data(), surfacePlain.data(), surfacePlain.size() * sizeof(float)), 0);
    int differing = 0;
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const int k = j * n + i;
            const PlacementSample at{slope[k], 0.0, 0.0, grid.x(i), grid.y(j)};
            const double d[2] = {static_cast<float>(blended.materials()[0].displacementAt(at.x, at.y)),
                                 static_cast<float>(blended.materials()[1].displacementAt(at.x, at.y))};
            blended.weights(at, d, w);
            EXPECT_EQ(weightsBlended[2 * k + 1], static_cast<std::uint8_t>(std::lround(w[1] * 255.0)))
                << i << ", " << j;
            differing += weightsBlended[2 * k + 1] != weightsPlain[2 * k + 1];
        }
    }
    EXPECT_GT(differing, n * n / 4);
}

TEST(GroundCover, CoverIsTheMaterialsColoursByTheirWeights)
{
    Material ground = parsed("name = g\ntint = 0.5, 1.0, 0.5\n");
    Material snow = parsed("name = s\ncolour = 0.9, 0.92, 0.96\ncolour_cover = 0.75\n");
    const MaterialSet set(std::vector<Material>{ground, snow});
    const std::array<float, 3> map = {0.4f, 0.3f, 0.2f};
    // By hand: grass keeps the map's colour tinted by a third of its tint over the tint's brightness; snow
    // (tint 1) replaces three quarters of the map's with its own.
    const double luminance = 0.2126 * 0.5 + 0.7152 * 1.0 + 0.0722 * 0.5;
    const double tint[3] = {0.5 / luminance, 1.0 / luminance, 0.5 / luminance};
    const double colour[3] = {0.9, 0.92, 0.96};
    for (double s : {0.0, 0.3, 1.0}) {
        const double w[2] = {1.0 - s, s};
        const auto got = set.cover(map, w);
        for (int c = 0; c < 3; ++c) {
            const double grass = map[c] * (1.0 + 0.35 * (tint[c] - 1.0));
            const double white = map[c] + 0.75 * (colour[c] - map[c]);
            EXPECT_NEAR(got[c], (1.0 - s) * grass + s * white, 1e-6) << s << " " << c;
        }
    }
}

TEST(GroundCover, NodeTexturesTakeTheCoverAtTheirTexelsPlaces)
{
    Material ground = parsed("name = g\n");
    Material snow = parsed("name = s\ncolour = 1, 1, 1\ncolour_cover = 1\n");
    const MaterialSet set(std::vector<Material>{ground, snow});
    const int n = 5;
    // Snow's weight rises across x: 0, 64, 128, 192, 255.
    std::vector<std::uint8_t> weights(n * n * 4, 0);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const int s = std::min(255, 64 * i);
            weights[(j * n + i) * 4] = static_cast<std::uint8_t>(255 - s);
            weights[(j * n + i) * 4 + 1] = static_cast<std::uint8_t>(s);
        }
    }
    for (int t : {5, 9}) {
        const std::vector<std::uint8_t> black(static_cast<std::size_t>(t) * t * 3, 0);
        const auto covered = coverTexture(set, black, t, weights, n);
        ASSERT_EQ(covered.size(), black.size());
        for (int j = 0; j < t; ++j) {
            for (int i = 0; i < t; ++i) {
                // Texel i lies at sample i (n - 1) / (t - 1); the weight between samples is linear.
                const double x = i * (n - 1.0) / (t - 1.0);
                const int x0 = std::min(static_cast<int>(x), n - 2);
                const double s =
                    (std::min(255, 64 * x0) + (x - x0) * (std::min(255, 64 * (x0 + 1)) - std::min(255, 64 * x0))) /
                    255.0;
                for (int c = 0; c < 3; ++c) {
                    EXPECT_NEAR(covered[(j * t + i) * 3 + c], s * 255.0, 0.51) << t << ": " << i << ", " << j;
                }
            }
        }
    }
}

}  // namespace
}  // namespace terrain
