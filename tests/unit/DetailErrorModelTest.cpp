// The synthesis model of detail errors (issue 12, synthesis/DetailErrorModel.h) against independent
// references: a closed form for the subdivision term on a quadratic surface (which Kobbelt's rule
// reproduces), random points of the fractal itself for the displacement term, and the per-sample weighting.
#include "synthesis/DetailErrorModel.h"

#include "core/SplitMix64.h"
#include "quadtree/TemplateTriangulation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

namespace terrain {
namespace {

constexpr int kN = 17;
constexpr int kW = kN + 2 * kBorder;

std::shared_ptr<const MaterialSet> materials(const std::vector<std::string>& names)
{
    std::vector<std::filesystem::path> files;
    for (const auto& name : names) {
        files.push_back(std::filesystem::path(TERRAIN_MATERIALS_DIR) / (name + ".mat"));
    }
    std::vector<std::string> warnings;
    auto set = MaterialSet::load(files, warnings);
    EXPECT_TRUE(set.ok()) << set.error().message;
    return std::make_shared<const MaterialSet>(std::move(set).value());
}

std::unique_ptr<const DetailSynthesizer> synthesizer(std::shared_ptr<const MaterialSet> set)
{
    auto s = DetailSynthesizer::create(kN, {"kobbelt", 1.0, std::move(set)});
    EXPECT_TRUE(s.ok());
    return std::move(s).value();
}

TEST(DetailErrorModelTest, SubdivisionTermIsTheClosedFormOnAQuadratic)
{
    // z = a x^2 + b y^2 sampled at spacing s: the 4-point rule reproduces it, so the children's new samples
    // lie on it, and the largest distance from the node's triangles is at a cell centre on the diagonal:
    // (a + b) s^2 / 4 (edge midpoints: a s^2 / 4 and b s^2 / 4).
    auto s = synthesizer(nullptr);
    const DetailErrorModel model(*s, 64.0);
    for (double spacing : {1.0, 4.0, 90.0}) {
        const double a = 0.003, b = 0.001;
        DualHeightMap map;
        map.size = kW;
        for (int j = 0; j < kW; ++j) {
            for (int i = 0; i < kW; ++i) {
                const double x = (i - kBorder) * spacing, y = (j - kBorder) * spacing;
                map.base.push_back(static_cast<float>(a * x * x + b * y * y));
            }
        }
        const double expected = (a + b) * spacing * spacing / 4;
        EXPECT_NEAR(model.nextSubdivisionChange(map), expected,
                    2e-6 * std::max(1.0, static_cast<double>(map.base.back())))
            << "spacing " << spacing;
        // Every cell's bound is the same, so every grandchild is measured: (a + b) s^2 / 4 at the cell centres
        // (children's samples), plus the tail 4/3 of the grandchildren's own next change, (a + b) (s / 4)^2 / 4:
        // 1 + 1/12 of the node's change in all (from the children alone it would be 1 + 1/3).
        WindowPlacement where;
        where.spacing = spacing;
        EXPECT_NEAR(model.boundFromChildren(map, s->synthesizeChildren(map, where), where, 3),
                    (1.0 + DetailErrorModel::kSubdivisionTail / 16.0) * expected,
                    1e-5 * std::max(1.0, static_cast<double>(map.base.back())));
    }
    // A plane is reproduced exactly: nothing to add.
    DualHeightMap plane;
    plane.size = kW;
    for (int k = 0; k < kW * kW; ++k) {
        plane.base.push_back(static_cast<float>(3.0 * (k % kW) - 2.0 * (k / kW) + 100.0));
    }
    EXPECT_LT(model.nextSubdivisionChange(plane), 1e-4);
}

TEST(DetailErrorModelTest, DisplacementTermBoundsTheFractalAtRandomPoints)
{
    // At every level, E_m bounds how far the fractal at a random point of a random cell lies from the
    // triangles through the cell's corners (the surface a node of that spacing draws): points and cells
    // drawn independently of the model's own probes. It never exceeds 2 amplitude and shrinks with depth:
    // by about 4 per level for the fBm once its octaves are resolved, by at least 1.6 for the ridged
    // fractal, whose creases stay sharp.
    for (const std::string name : {"grass", "rock"}) {
        SCOPED_TRACE(name);
        auto set = materials({name});
        auto s = synthesizer(set);
        const double rootSpacing = 1440.0;
        const DetailErrorModel model(*s, rootSpacing);
        const Material& m = set->materials()[0];
        const Fractal& f = *m.displacement;
        SplitMix64 random(99);
        auto uniform = [&] { return static_cast<double>(random.next() >> 11) * 0x1.0p-53; };
        double tightest = 0.0;
        for (int level = 0; level <= 16; ++level) {
            const double spacing = std::ldexp(rootSpacing, -level);
            const double e = model.displacementError(0, level);
            EXPECT_LE(e, 2.0 * m.fractal.amplitude + 1e-12);
            double worst = 0.0;
            for (int k = 0; k < 3000; ++k) {
                const double x0 = std::floor((uniform() - 0.5) * 2e5 / spacing) * spacing + 3e5;
                const double y0 = std::floor((uniform() - 0.5) * 2e5 / spacing) * spacing - 1e5;
                const double fx = uniform(), fy = uniform();
                const double surface = interpolateQuad(f(x0, y0), f(x0 + spacing, y0), f(x0, y0 + spacing),
                                                       f(x0 + spacing, y0 + spacing), fx, fy);
                worst = std::max(worst, std::abs(f(x0 + fx * spacing, y0 + fy * spacing) - surface));
            }
            EXPECT_LE(worst, e) << "level " << level;
            tightest = std::max(tightest, worst / e);
            std::printf("%s level %2d spacing %9.3f m: E %.4f m, largest at random points %.4f m (%.2f of E)\n",
                        name.c_str(), level, spacing, e, worst, worst / e);
            if (level >= 13) {
                const double ratio = model.displacementError(0, level) / model.displacementError(0, level - 1);
                EXPECT_LT(ratio, name == "grass" ? 0.35 : 0.62) << "level " << level;
            }
        }
        EXPECT_GT(tightest, 0.3) << "the bound should not be far above the fractal's own deviations";
    }
}

TEST(DetailErrorModelTest, DisplacementTermWeighsTheMaterialsPerSample)
{
    // Two materials: a sample's error is its weights times the materials' errors; the node's term is the
    // largest over its samples (half a weight step of slack per material for the rounding to bytes).
    auto s = synthesizer(materials({"grass", "rock"}));
    const DetailErrorModel model(*s, 1440.0);
    const int level = 8;
    const double eg = model.displacementError(0, level), er = model.displacementError(1, level);
    ASSERT_GT(er, eg);
    std::vector<std::uint8_t> weights(kN * kN * 4, 0);
    for (std::size_t k = 0; k < weights.size(); k += 4) {
        weights[k] = 255;  // all grass
    }
    EXPECT_NEAR(model.displacementTerm(weights, level), (255.5 * eg + 0.5 * er) / 255, 1e-12);
    weights[40] = 55;  // one sample 200 / 255 rock
    weights[41] = 200;
    EXPECT_NEAR(model.displacementTerm(weights, level), (55.5 * eg + 200.5 * er) / 255, 1e-12);
    EXPECT_LT(model.displacementTerm(weights, level), eg + er) << "not the sum of both materials' worst";
    EXPECT_EQ(model.worstDisplacementError(level), er);
}

TEST(DetailErrorModelTest, PrepsLeafErrorIsTheModelsBoundOfTheDisplacedLeaf)
{
    auto s = synthesizer(materials({"grass", "rock"}));
    MapHeader h;
    h.chunkSize = kN;
    h.levels = 3;
    h.sampleSpacing = 10.0;
    h.heightStep = 0.5;
    h.heightOffset = 1800.0;
    const NodeId id{2, 1, 3};
    std::vector<std::uint16_t> codes(kW * kW);
    for (int j = 0; j < kW; ++j) {
        for (int i = 0; i < kW; ++i) {
            codes[j * kW + i] = static_cast<std::uint16_t>(400 + 7 * i + 3 * j + ((i * j) % 11) * 4);
        }
    }
    auto leafError = leafDetailErrorFunction(*s);
    const float got = leafError(h, id, codes);
    DualHeightMap leaf;
    leaf.size = kW;
    for (std::uint16_t c : codes) {
        leaf.base.push_back(static_cast<float>(h.heightStep * c));
    }
    const WindowPlacement where = windowPlacement(h, id);
    s->displace(where, nullptr, 0, leaf);
    const DetailErrorModel model(*s, h.spacingAt(0));
    EXPECT_EQ(got, model.boundFromChildren(leaf, s->synthesizeChildren(leaf, where), where, id.level));
    EXPECT_GT(got, 0.0f);
    EXPECT_EQ(detailDisplacementRange(*s), 6.0);  // rock's 3 m amplitude, twice
}

}  // namespace
}  // namespace terrain
