// The roughness measure (heightfield/Roughness.h), prep's per-leaf laws, and the noise that continues them
// below the leaves (synthesis/RoughnessNoise.h) with the synthesis around it: against brute force, against
// the law it is calibrated to, and the nesting and seam properties the renderer relies on.
#include "MapTestSupport.h"
#include "TestSupport.h"

#include "heightfield/Roughness.h"
#include "lod/HeightQuery.h"
#include "lod/TerrainNodeSource.h"
#include "quadtree/MapFile.h"
#include "quadtree/QuadtreeBuilder.h"
#include "synthesis/DetailErrorModel.h"
#include "synthesis/RoughnessNoise.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <vector>

namespace terrain {
namespace {

TEST(RoughnessTest, MidpointDeviationIsTheBruteForceSumSkippingNoData)
{
    const int w = 23, h = 17;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-20.0f, 20.0f);
    std::vector<float> heights(static_cast<std::size_t>(w) * h);
    for (float& v : heights) {
        v = u(rng);
    }
    heights[5 * w + 7] = std::numeric_limits<float>::quiet_NaN();
    for (int lag : {1, 2, 3, 8}) {
        for (const auto& [x0, y0, x1, y1] :
             {std::array{0, 0, w, h}, std::array{4, 2, 15, 13}, std::array{10, 5, 11, 6}}) {
            double squares = 0.0;
            std::uint64_t count = 0;
            for (int j = y0; j < y1; ++j) {
                for (int i = x0; i < x1; ++i) {
                    auto at = [&](int a, int b) -> double { return heights[static_cast<std::size_t>(b) * w + a]; };
                    for (const auto& [dx, dy] : {std::pair{lag, 0}, std::pair{0, lag}}) {
                        if (i - dx < 0 || i + dx >= w || j - dy < 0 || j + dy >= h) {
                            continue;
                        }
                        const double d = 2.5 * (at(i, j) - 0.5 * (at(i - dx, j - dy) + at(i + dx, j + dy)));
                        if (std::isfinite(d)) {
                            squares += d * d;
                            ++count;
                        }
                    }
                }
            }
            const MidpointSums sums = midpointDeviation(heights, w, h, lag, x0, y0, x1, y1, 2.5);
            EXPECT_EQ(sums.count, count) << lag;
            EXPECT_NEAR(sums.squares, squares, 1e-9 * squares) << lag;
        }
    }
    // A plane has none.
    std::vector<float> plane(static_cast<std::size_t>(w) * h);
    for (int j = 0; j < h; ++j) {
        for (int i = 0; i < w; ++i) {
            plane[static_cast<std::size_t>(j) * w + i] = static_cast<float>(3.0 * i - 2.0 * j + 100.0);
        }
    }
    EXPECT_EQ(midpointDeviation(plane, w, h, 2, 0, 0, w, h).rms(), 0.0);
}

TEST(RoughnessTest, FitRecoversAPowerLawAndClampsItsExponent)
{
    for (const double exponent : {0.3, 0.7, 1.0}) {
        std::vector<double> rms;
        for (int lag : kRoughnessLags) {
            rms.push_back(4.0 * std::pow(lag, exponent));
        }
        const RoughnessLaw law = fitRoughnessLaw(rms);
        EXPECT_NEAR(law.exponent, exponent, 1e-12);
        EXPECT_NEAR(law.amplitude, 4.0, 1e-12);
        EXPECT_NEAR(law.at(0.25), 4.0 * std::pow(0.25, exponent), 1e-12);
    }
    // Smoother than any fractal (a curve: D grows as r^2): clamped, the amplitude the weighted geometric
    // mean of D(r) / r.
    const RoughnessLaw smooth = fitRoughnessLaw(std::vector<double>{1.0, 4.0, 16.0, 64.0});
    EXPECT_EQ(smooth.exponent, kMaxRoughnessExponent);
    double weighted = 0.0, weights = 0.0;
    for (std::size_t k = 0; k < 4; ++k) {
        weighted += kRoughnessLagWeights[k] * std::log(kRoughnessLags[k]);  // log(r^2 / r)
        weights += kRoughnessLagWeights[k];
    }
    EXPECT_NEAR(smooth.amplitude, std::exp(weighted / weights), 1e-12);
    // The finest lags weigh most: a law that bends at lag 4 follows lags 1 and 2.
    EXPECT_GT(fitRoughnessLaw(std::vector<double>{1.0, 2.0, 2.2, 2.4}).exponent, 0.6);
    // Lags without deviations are left out; none left: no roughness.
    EXPECT_NEAR(fitRoughnessLaw(std::vector<double>{0.0, 2.0, 0.0, 2.0 * std::pow(4.0, 0.5)}).exponent, 0.5, 1e-12);
    EXPECT_EQ(fitRoughnessLaw(std::vector<double>{0.0, 0.0, 0.0, 0.0}).amplitude, 0.0);
}

/// A grid of one law everywhere.
RoughnessGrid uniformGrid(int side, RoughnessLaw law)
{
    RoughnessGrid grid;
    grid.leavesPerSide = side;
    grid.laws.assign(static_cast<std::size_t>(side) * side, law);
    return grid;
}

TEST(RoughnessNoiseTest, ZeroAtTheStaticSamplesAndEachLevelNestsInTheNext)
{
    RoughnessGrid grid = uniformGrid(4, {6.0, 0.6});
    grid.laws[5] = {20.0, 0.9};
    const RoughnessNoise noise(grid, 64, 90.0, 8);
    for (std::int64_t g : {-3, 0, 1, 17, 200, 255}) {
        EXPECT_EQ(noise.at(g, g + 5, 0), 0.0f);
        EXPECT_EQ(noise.at(g, 3 - g, -2), 0.0f);
    }
    int nonzero = 0;
    for (int below = 1; below <= 9; ++below) {
        for (std::int64_t gy = -6; gy < 300; gy += 7) {
            for (std::int64_t gx = -4; gx < 300; gx += 5) {
                // A level's even samples lie on the coarser level's: the octave added there is zero.
                const float coarse = noise.at(gx, gy, below - 1), fine = noise.at(2 * gx, 2 * gy, below);
                ASSERT_EQ(std::memcmp(&coarse, &fine, sizeof coarse), 0) << below << " " << gx << "," << gy;
                nonzero += noise.at(2 * gx + 1, 2 * gy, below) != 0.0f ? 1 : 0;
            }
        }
    }
    EXPECT_GT(nonzero, 1000);
    // The grid form is the point form, bit for bit, masked or not.
    const int w = 21, h = 13;
    std::vector<float> out(static_cast<std::size_t>(w) * h, 1.5f), masked = out;
    std::vector<std::uint8_t> mask(out.size());
    for (std::size_t k = 0; k < mask.size(); ++k) {
        mask[k] = static_cast<std::uint8_t>(k % 3 != 0);
    }
    noise.add(-2, 100, w, h, 5, out);
    noise.add(-2, 100, w, h, 5, masked, mask);
    for (int j = 0; j < h; ++j) {
        for (int i = 0; i < w; ++i) {
            const std::size_t k = static_cast<std::size_t>(j) * w + i;
            const float expected = 1.5f + noise.at(-2 + i, 100 + j, 5);
            EXPECT_EQ(std::memcmp(&out[k], &expected, sizeof expected), 0);
            EXPECT_EQ(masked[k], mask[k] ? expected : 1.5f);
        }
    }
}

TEST(RoughnessNoiseTest, LevelsHaveTheLawsRoughnessAndStayWithinTheBound)
{
    // One law everywhere: at level j below the leaves the RMS midpoint deviations at lags of 1, 2, 4 and 8
    // samples follow A (2^-j L)^H on average (their geometric mean: what c(H) calibrates), each within 1.5x
    // (grid-aligned octaves are not exactly self-similar: measured 0.70 at lag 1 for H = 0.4).
    for (const double exponent : {0.4, 0.8}) {
        const RoughnessLaw law{10.0, exponent};
        const RoughnessNoise noise(uniformGrid(8, law), 64, 100.0, 12);
        const double bound = noise.bound(0);
        for (int level : {4, 6}) {
            const int n = 384;
            std::vector<float> grid(static_cast<std::size_t>(n) * n, 0.0f);
            noise.add(1000, 2000, n, n, level, grid);
            float largest = 0.0f;
            for (float v : grid) {
                largest = std::max(largest, std::abs(v));
            }
            EXPECT_LE(largest, bound);
            double logMean = 0.0;
            for (int lag : kRoughnessLags) {
                const double ratio = midpointDeviation(grid, n, n, lag, 0, 0, n, n).rms() /
                                     (law.amplitude * std::pow(lag * std::exp2(-level), exponent));
                EXPECT_GT(ratio, 1.0 / 1.5) << "H " << exponent << " level " << level << " lag " << lag;
                EXPECT_LT(ratio, 1.5) << "H " << exponent << " level " << level << " lag " << lag;
                logMean += std::log(ratio) / kRoughnessLags.size();
            }
            EXPECT_NEAR(std::exp(logMean), 1.0, 0.06) << "H " << exponent << " level " << level;
        }
    }
}

TEST(RoughnessNoiseTest, TheLawIsInterpolatedBetweenLeafCentres)
{
    RoughnessGrid grid = uniformGrid(2, {1.0, 0.2});
    grid.laws[1] = {16.0, 1.0};  // leaf (1, 0)
    const RoughnessNoise noise(grid, 64, 30.0, 4);
    // At the centres: the leaves' own laws (and beyond them, clamped).
    EXPECT_NEAR(noise.lawAt(32, 32).amplitude, 1.0, 1e-9);
    EXPECT_NEAR(noise.lawAt(96, 32).amplitude, 16.0, 1e-9);
    EXPECT_NEAR(noise.lawAt(-50, -50).exponent, 0.2, 1e-9);
    EXPECT_NEAR(noise.lawAt(400, 10).exponent, 1.0, 1e-9);
    // Half-way: log A and H halfway (a geometric mean of the amplitudes).
    EXPECT_NEAR(noise.lawAt(64, 32).amplitude, 4.0, 1e-9);
    EXPECT_NEAR(noise.lawAt(64, 32).exponent, 0.6, 1e-9);
    // Continuous across the leaf border.
    EXPECT_NEAR(noise.lawAt(63.999, 40).amplitude, noise.lawAt(64.001, 40).amplitude, 1e-3);
}

TEST(RoughnessNoiseTest, PrepMeasuresEachLeafAndFillsThePadding)
{
    // Rough in the west, smooth from x = 16 on: the leaves there get laws to match; the padding (the
    // input is 70 x 40 samples of a 129 x 129 grid) the nearest measured leaf's.
    HeightField field = test::makeHeightField(70, 40, [](int i, int j) {
        const double rough = i < 16 ? 8.0 * test::unitNoise(5, i, j) : 0.1 * test::unitNoise(5, i, j);
        return static_cast<float>(500.0 + 2.0 * i + rough);
    });
    MapHeader header;
    header.chunkSize = 33;
    header.levels = 3;
    const RoughnessGrid grid = measureLeafRoughness(field, 1.0, header, 2);
    ASSERT_EQ(grid.leavesPerSide, 4);
    EXPECT_GT(grid.at(0, 0).amplitude, 20.0 * grid.at(1, 0).amplitude);
    EXPECT_EQ(grid.at(0, 3), grid.at(0, 0)) << "padding: nearest measured leaf";
    EXPECT_EQ(grid.at(3, 3), grid.at(1, 0)) << "padding: nearest measured leaf (leaf 2, 0 is a strip)";
    EXPECT_EQ(measureLeafRoughness(field, 1.0, header, 1), grid) << "threads change nothing";
    // Against the measure itself over the leaf's own samples.
    std::array<double, 4> rms{};
    for (std::size_t k = 0; k < rms.size(); ++k) {
        rms[k] =
            midpointDeviation(field.samples, field.width, field.height, kRoughnessLags[k], 0, 0, 32, 32, 1.0).rms();
    }
    EXPECT_EQ(grid.at(0, 0), fitRoughnessLaw(rms));
}

TEST(RoughnessNoiseTest, ANodesBoundCoversItsNoiseAndIsAtMostItsLeaves)
{
    // Laws varying leaf to leaf: the bound over a node's own square covers the noise there, and is at most
    // the bound of the leaves around it.
    RoughnessGrid grid = uniformGrid(4, {2.0, 0.5});
    for (std::size_t k = 0; k < grid.laws.size(); ++k) {
        grid.laws[k] = {1.0 + 9.0 * static_cast<double>((k * 7) % 5) / 4.0, 0.2 + 0.2 * static_cast<double>(k % 5)};
    }
    const RoughnessNoise noise(grid, 16, 50.0, 6);
    for (int below : {1, 2, 4}) {
        for (const auto& [x, y] : {std::pair{0, 0}, std::pair{5, 3}, std::pair{13, 9}}) {
            // Node (x, y) of its level: 16 cells from global sample (16 x, 16 y).
            const double spacing = std::ldexp(50.0, -below);
            const double bound = noise.nodeBound(spacing, 16 * x, 16 * y, 16);
            const int leafX = (16 * x >> below) / 16, leafY = (16 * y >> below) / 16;
            EXPECT_LE(bound, noise.bound(below, leafX, leafY, leafX, leafY) * (1.0 + 1e-8));
            // All the octaves over its square cover the noise at the finest level's samples inside it.
            double worst = 0.0;
            const int finer = 6 - below;
            for (int j = 0; j <= 16 << finer; ++j) {
                for (int i = 0; i <= 16 << finer; ++i) {
                    const std::int64_t gx = (16 * x << finer) + i, gy = (16 * y << finer) + j;
                    worst = std::max(worst, std::abs(static_cast<double>(noise.at(gx, gy, 6))));
                }
            }
            const double scale = std::ldexp(1.0, -below);
            EXPECT_LE(worst,
                      noise.boundOver(0, 16 * x * scale, 16 * y * scale, 16 * (x + 1) * scale, 16 * (y + 1) * scale))
                << below << " " << x << "," << y;
            EXPECT_GT(bound, 0.0);
        }
    }
}

TEST(RoughnessNoiseTest, ASynthesizerRefusesNoiseMadeForAnotherChunkSize)
{
    auto noise = std::make_shared<const RoughnessNoise>(uniformGrid(2, {1.0, 0.5}), 64, 90.0, 2);
    DetailSettings settings;
    settings.roughness = noise;
    auto wrong = DetailSynthesizer::create(17, settings);
    ASSERT_FALSE(wrong.ok());
    EXPECT_NE(wrong.error().message.find("roughness"), std::string::npos) << wrong.error().message;
    EXPECT_TRUE(DetailSynthesizer::create(65, settings).ok());
}

/// A map of rough hills at 160 m (3 roughness octaves above the 40 m of grass), and the viewer's
/// synthesizer for it with the roughness continued.
class RoughSynthesisTest : public ::testing::Test {
protected:
    static constexpr int kChunk = 17;
    void SetUp() override
    {
        mPlain = test::grassAndRockSynthesizer(kChunk);
        BuildOptions options = test::testOptions(kChunk, 2);
        options.spacing = 160.0;
        options.leafDetailError = leafDetailErrorFunction(*mPlain, true);
        auto built = buildMap(test::roughField(129, 129, 9, 0, 900), options, mDir / "rough.map");
        ASSERT_TRUE(built.ok()) << built.error().message;
        mMap = MapFile::open(mDir / "rough.map", ReaderKind::Stream).value();
        ASSERT_TRUE(mMap->header().roughness.has_value());
        DetailSettings settings = mPlain->settings();
        settings.roughness = makeRoughnessNoise(mMap->header(), settings.materials.get());
        ASSERT_EQ(settings.roughness->octaves(), 3);
        mRough = DetailSynthesizer::create(kChunk, settings).value();
    }
    test::ScratchDir mDir;
    std::unique_ptr<const DetailSynthesizer> mPlain, mRough;
    std::unique_ptr<MapFile> mMap;
};

TEST_F(RoughSynthesisTest, NodesNestAndShareTheirEdgesBitForBit)
{
    // Every node of a 2 x 2 block of leaves and 3 levels of dynamic nodes below: a child's even samples are
    // its parent's (base and surface), and neighbours of one level agree on their shared edge samples.
    TerrainNodeSource source(*mMap, {mRough.get(), 0.0});
    const int n = kChunk, w = n + 2 * kBorder;
    const int leafLevel = static_cast<int>(mMap->header().levels) - 1;
    std::vector<NodePtr> level = {source.loadRoot().value()};
    while (level.front()->id.level < leafLevel + 3) {
        std::vector<NodePtr> next;
        for (const NodePtr& node : level) {
            const bool wanted = node->id.level < leafLevel || (node->id.x >> (node->id.level - leafLevel + 1)) == 1;
            if (!wanted && node->id.level >= leafLevel) {
                continue;
            }
            auto children = source.loadChildren(*node);
            ASSERT_TRUE(children.ok()) << children.error().message;
            for (const NodePtr& child : *children) {
                if (node->id.level >= leafLevel) {
                    for (int j = 0; j < n; j += 2) {
                        for (int i = 0; i < n; i += 2) {
                            const int qx = (child->id.x & 1) * (n - 1) / 2, qy = (child->id.y & 1) * (n - 1) / 2;
                            const std::size_t c = static_cast<std::size_t>(j + kBorder) * w + i + kBorder;
                            const std::size_t p =
                                static_cast<std::size_t>(qy + j / 2 + kBorder) * w + qx + i / 2 + kBorder;
                            const float a = child->heights.height(c), b = node->heights.height(p);
                            ASSERT_EQ(std::memcmp(&a, &b, sizeof a), 0) << child->id.toString() << " " << i << "," << j;
                        }
                    }
                }
                next.push_back(child);
            }
        }
        level = std::move(next);
    }
    // Shared edges among the deepest level.
    std::map<std::pair<std::int64_t, std::int64_t>, float> seen;
    int compared = 0;
    for (const NodePtr& node : level) {
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                if (i != 0 && i != n - 1 && j != 0 && j != n - 1) {
                    continue;
                }
                const float z = node->heights.height(static_cast<std::size_t>(j + kBorder) * w + i + kBorder);
                auto [it, inserted] = seen.try_emplace({node->id.x * (n - 1) + i, node->id.y * (n - 1) + j}, z);
                if (!inserted) {
                    ++compared;
                    EXPECT_EQ(std::memcmp(&it->second, &z, sizeof z), 0) << node->id.toString();
                }
            }
        }
    }
    EXPECT_GT(compared, 200);
}

TEST_F(RoughSynthesisTest, ErrorsBoundWhatTheRoughnessAddsBelow)
{
    // A dynamic node's error bounds its surface against its great-grandchildren's samples, roughness
    // octaves included. The bound measures the node's children exactly; the levels below them add relief
    // that its tail has to cover: the great-grandchildren lie further from the node than the children do.
    TerrainNodeSource source(*mMap, {mRough.get(), 0.0});
    const int n = kChunk, w = n + 2 * kBorder;
    const int leafLevel = static_cast<int>(mMap->header().levels) - 1;
    NodePtr node = source.loadRoot().value();
    int checked = 0, deeperAddsError = 0;
    while (node->id.level <= leafLevel) {
        node = source.loadChildren(*node).value()[1];
    }
    ASSERT_FALSE(node->isStatic);
    for (int depth = 0; depth < 2; ++depth) {
        double worst = 0.0, children = 0.0;
        const ChildNodes as = source.loadChildren(*node).value();
        for (const NodePtr& a : as) {
            const double ax0 = (a->id.x - (node->id.x << 1)) * (n - 1) * 0.5;
            const double ay0 = (a->id.y - (node->id.y << 1)) * (n - 1) * 0.5;
            for (int j = 0; j < n; ++j) {
                for (int i = 0; i < n; ++i) {
                    const double z = a->heights.height(static_cast<std::size_t>(j + kBorder) * w + i + kBorder);
                    children = std::max(children, std::abs(z - nodeSurfaceAt(*node, n, ax0 + i * 0.5, ay0 + j * 0.5)));
                }
            }
            const ChildNodes bs = source.loadChildren(*a).value();
            for (const NodePtr& b : bs) {
                const ChildNodes cs = source.loadChildren(*b).value();
                for (const NodePtr& c : cs) {
                    const double scale = 0.125;
                    const double x0 = (c->id.x - (node->id.x << 3)) * (n - 1) * scale;
                    const double y0 = (c->id.y - (node->id.y << 3)) * (n - 1) * scale;
                    for (int j = 0; j < n; ++j) {
                        for (int i = 0; i < n; ++i) {
                            const double z = c->heights.height(static_cast<std::size_t>(j + kBorder) * w + i + kBorder);
                            worst =
                                std::max(worst, std::abs(z - nodeSurfaceAt(*node, n, x0 + i * scale, y0 + j * scale)));
                        }
                    }
                }
            }
        }
        EXPECT_LE(worst, node->deltaC) << node->id.toString();
        deeperAddsError += worst > children ? 1 : 0;
        ++checked;
        node = source.loadChildren(*node).value()[2];
    }
    EXPECT_EQ(checked, 2);
    EXPECT_EQ(deeperAddsError, 2) << "the levels below the children should add to the error here";
}

}  // namespace
}  // namespace terrain
