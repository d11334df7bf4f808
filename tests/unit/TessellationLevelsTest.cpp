// Tessellation block levels (lod/TessellationLevels.h): what they guarantee, checked by brute force on the
// surface they draw. Every drawn block, sampled densely under both diagonals, is within the pixel budget at
// its own distance; blocks meeting at a side put the same vertices on it; a plane takes the coarsest level.
#include "MapTestSupport.h"

#include "core/Frustum.h"
#include "lod/LodSelector.h"
#include "lod/TessellationLevels.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace terrain {
namespace {

std::vector<float> hills(int n, int seed, double roughness)
{
    std::vector<float> s(static_cast<std::size_t>(n) * n);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            s[static_cast<std::size_t>(j) * n + i] =
                static_cast<float>(300.0 + 40.0 * std::sin(0.09 * i + seed) * std::cos(0.05 * j) +
                                   roughness * std::pow(test::unitNoise(seed, i, j), 3.0) * (i > n / 2 ? 1.0 : 0.1));
        }
    }
    return s;
}

Camera cameraAt(glm::dvec3 position, double yaw, double pitch)
{
    Camera camera;
    camera.position = position;
    camera.yaw = yaw * kRadiansPerDegree;
    camera.pitch = pitch * kRadiansPerDegree;
    camera.farPlane = 1e6;
    return camera;
}

Aabb blockBox(const Aabb& node, int b, int bx, int by)
{
    const double size = (node.hi.x - node.lo.x) / b;
    return {{node.lo.x + bx * size, node.lo.y + by * size, node.lo.z},
            {node.lo.x + (bx + 1) * size, node.lo.y + (by + 1) * size, node.hi.z}};
}

/// The largest distance, sampled every 1/8 sample under both diagonals, between the drawn surface of block
/// (bx, by) and the node's template surface.
double drawnBlockError(const std::vector<float>& surface, int n, const BlockLevels& levels, int bx, int by)
{
    const int q = levels.blockQuads;
    double worst = 0.0;
    for (int y = 0; y <= 8 * q; ++y) {
        for (int x = 0; x <= 8 * q; ++x) {
            const double lx = bx * q + x / 8.0, ly = by * q + y / 8.0;
            const int i = std::min(static_cast<int>(lx), n - 2), j = std::min(static_cast<int>(ly), n - 2);
            const double fx = lx - i, fy = ly - j;
            auto h = [&](int a, int b) -> double { return surface[static_cast<std::size_t>(j + b) * n + i + a]; };
            const double fine = fx >= fy ? (1 - fx) * h(0, 0) + (fx - fy) * h(1, 0) + fy * h(1, 1)
                                         : (1 - fy) * h(0, 0) + (fy - fx) * h(0, 1) + fx * h(1, 1);
            const auto [first, second] = tessellatedHeights(surface, n, levels, lx, ly);
            worst = std::max({worst, std::abs(fine - first), std::abs(fine - second)});
        }
    }
    return worst;
}

TEST(TessellationLevelsTest, EveryDrawnBlockIsWithinItsBudgetAndSharedSidesMatch)
{
    const int n = 65;
    const std::vector<float> surface = hills(n, 3, 6.0);
    const TessellationErrors errors = computeTessellationErrors(surface, n, 8);
    const auto [lo, hi] = std::minmax_element(surface.begin(), surface.end());
    const Aabb node{{0.0, 0.0, *lo}, {640.0, 640.0, *hi}};
    const double pixels = 1.0;
    int mixed = 0, snappedSides = 0;
    for (const Camera& camera :
         {cameraAt({320.0, -50.0, 360.0}, 0.0, -10.0), cameraAt({100.0, 100.0, 900.0}, 30.0, -60.0),
          cameraAt({-400.0, 320.0, 500.0}, 90.0, -5.0), cameraAt({320.0, -2500.0, 1500.0}, 0.0, -25.0)}) {
        const BlockLevels levels = chooseBlockLevels(errors, node, camera, pixels);
        const int b = levels.blocksPerSide;
        ASSERT_EQ(b, 8);
        const double c = lodDistanceFactor(camera, pixels);
        const double k = verticalErrorFactor(camera);
        const Frustum frustum = Frustum::fromCamera(camera);
        std::vector<int> seen(4, 0);
        for (int by = 0; by < b; ++by) {
            for (int bx = 0; bx < b; ++bx) {
                const auto i = static_cast<std::size_t>(by * b + bx);
                const Aabb box = blockBox(node, b, bx, by);
                ASSERT_EQ(levels.culled[i] != 0, !frustum.intersects(box));
                if (levels.culled[i]) {
                    continue;
                }
                // The guarantee, from the drawn surface itself.
                const double error = drawnBlockError(surface, n, levels, bx, by);
                // Level 0 is the node's own samples: nothing finer exists, and the tessellator may split
                // its quads along the other diagonal.
                if (levels.level[i] == 0) {
                    EXPECT_LE(error, std::max(errors.flip[i] + 1e-6, lodDistance(camera, k, box) / c * (1.0 + 1e-9)))
                        << "block " << bx << "," << by;
                } else {
                    EXPECT_LE(error * c, lodDistance(camera, k, box) * (1.0 + 1e-9))
                        << "block " << bx << "," << by << " level " << int{levels.level[i]};
                }
                ++seen[levels.level[i]];
                for (int side = 0; side < 4; ++side) {
                    snappedSides += levels.snap[4 * i + static_cast<std::size_t>(side)] > levels.level[i] ? 1 : 0;
                }
            }
        }
        // Shared sides: both blocks put the same vertices on them (vertices of every cell on the side).
        auto sideVertices = [&](int bx, int by, int side) {
            const auto i = static_cast<std::size_t>(by * b + bx);
            const int t = levels.level[i], f = 8 >> t;
            const int snap[4] = {levels.snap[4 * i], levels.snap[4 * i + 1], levels.snap[4 * i + 2],
                                 levels.snap[4 * i + 3]};
            std::vector<std::pair<int, int>> out;
            for (int m = 0; m <= f; ++m) {
                const int a = side == kEast ? f : side == kWest ? 0 : m;
                const int cc = side == kNorth ? f : side == kSouth ? 0 : m;
                const glm::ivec2 v = tessellatedVertex(8, bx, by, t, a, cc, snap);
                out.emplace_back(v.x, v.y);
            }
            std::sort(out.begin(), out.end());
            out.erase(std::unique(out.begin(), out.end()), out.end());
            return out;
        };
        for (int by = 0; by < b; ++by) {
            for (int bx = 0; bx + 1 < b; ++bx) {
                if (!levels.culled[static_cast<std::size_t>(by * b + bx)] &&
                    !levels.culled[static_cast<std::size_t>(by * b + bx + 1)]) {
                    EXPECT_EQ(sideVertices(bx, by, kEast), sideVertices(bx + 1, by, kWest)) << bx << "," << by;
                }
                if (!levels.culled[static_cast<std::size_t>(bx * b + by)] &&
                    !levels.culled[static_cast<std::size_t>((bx + 1) * b + by)]) {
                    EXPECT_EQ(sideVertices(by, bx, kNorth), sideVertices(by, bx + 1, kSouth)) << by << "," << bx;
                }
            }
        }
        mixed += std::count_if(seen.begin(), seen.end(), [](int s) { return s > 0; }) >= 2 ? 1 : 0;
        std::printf("levels 0..3: %d %d %d %d blocks, %llu triangles\n", seen[0], seen[1], seen[2], seen[3],
                    static_cast<unsigned long long>(levels.surfaceTriangles()));
    }
    EXPECT_GE(mixed, 3) << "the cases must mix levels inside a node";
    EXPECT_GT(snappedSides, 10) << "the cases must snap sides";
}

TEST(TessellationLevelsTest, OccludedBlocksAwayFromVisibleOnesAreCoarsestAndTheVisibleUnchanged)
{
    const int n = 65;
    const std::vector<float> surface = hills(n, 5, 6.0);
    const TessellationErrors errors = computeTessellationErrors(surface, n, 8);
    const auto [lo, hi] = std::minmax_element(surface.begin(), surface.end());
    const Aabb node{{0.0, 0.0, *lo - 20.0}, {640.0, 640.0, *hi + 20.0}};
    const Camera camera = cameraAt({320.0, -50.0, 360.0}, 0.0, -10.0);
    const double pixels = 1.0;
    const BlockLevels plain = chooseBlockLevels(errors, node, camera, pixels);
    EXPECT_EQ(plain.occludedBlocks, 0);
    const BlockLevels never = chooseBlockLevels(errors, node, camera, pixels, [](const Aabb&) { return false; });
    EXPECT_EQ(never.level, plain.level);
    EXPECT_EQ(never.snap, plain.snap);
    // The east half hidden (bx >= 4). Each box asked about is its block's square, from the node's floor to the
    // block's highest sample (brute force here).
    int asked = 0;
    const BlockLevels levels = chooseBlockLevels(errors, node, camera, pixels, [&](const Aabb& box) {
        const int bx = static_cast<int>(box.lo.x / 80.0 + 0.5), by = static_cast<int>(box.lo.y / 80.0 + 0.5);
        float top = -1e30f;
        for (int j = by * 8; j <= by * 8 + 8; ++j) {
            for (int i = bx * 8; i <= bx * 8 + 8; ++i) {
                top = std::max(top, surface[static_cast<std::size_t>(j) * n + i]);
            }
        }
        EXPECT_EQ(box.hi.z, top) << bx << "," << by;
        EXPECT_EQ(box.lo.z, node.lo.z);
        ++asked;
        return box.lo.x >= 320.0;
    });
    const int b = levels.blocksPerSide;
    int made = 0, interior = 0;
    for (int by = 0; by < b; ++by) {
        for (int bx = 0; bx < b; ++bx) {
            const auto i = static_cast<std::size_t>(by * b + bx);
            ASSERT_EQ(levels.culled[i], plain.culled[i]);
            if (levels.culled[i]) {
                continue;
            }
            const bool besideVisible = bx == b / 2 && !plain.culled[i - 1];
            if (bx < b / 2 || besideVisible) {
                // Visible, or beside a visible one: as chosen without occlusion, and so are the visible
                // blocks' sides.
                EXPECT_EQ(levels.level[i], plain.level[i]) << bx << "," << by;
                if (bx < b / 2) {
                    for (int side = 0; side < 4; ++side) {
                        EXPECT_EQ(levels.snap[4 * i + side], plain.snap[4 * i + side]) << bx << "," << by;
                    }
                }
                continue;
            }
            ++interior;
            EXPECT_EQ(levels.level[i], errors.blocks.levels) << bx << "," << by;
            made += plain.level[i] < errors.blocks.levels ? 1 : 0;
        }
    }
    EXPECT_GT(asked, 0);
    EXPECT_GT(interior, 10);
    EXPECT_EQ(levels.occludedBlocks, made);
    EXPECT_GT(made, 5) << "the hidden blocks must have been finer without the test";
    EXPECT_LT(levels.surfaceTriangles(), plain.surfaceTriangles());
}

TEST(TessellationLevelsTest, APlaneTakesTheCoarsestLevelHoweverCloseAndNearTakesMore)
{
    const int n = 33;
    const auto [lo, hi] = std::pair{0.0, 30.0};
    const Aabb node{{0.0, 0.0, lo}, {320.0, 320.0, hi}};
    std::vector<float> plane(static_cast<std::size_t>(n) * n);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            plane[static_cast<std::size_t>(j) * n + i] = static_cast<float>(0.5 * i + 0.25 * j);
        }
    }
    const BlockLevels flat =
        chooseBlockLevels(computeTessellationErrors(plane, n, 8), node, cameraAt({10.0, 10.0, 5.0}, 45.0, -20.0), 0.5);
    for (std::uint8_t level : flat.level) {
        EXPECT_EQ(level, 3);
    }
    // Rough ground: close up takes more triangles than far away.
    const TessellationErrors rough = computeTessellationErrors(hills(n, 5, 4.0), n, 8);
    const Camera down = cameraAt({160.0, 160.0, 500.0}, 0.0, -89.0), far = cameraAt({160.0, 160.0, 5000.0}, 0.0, -89.0);
    EXPECT_GT(chooseBlockLevels(rough, node, down, 2.0).surfaceTriangles(),
              chooseBlockLevels(rough, node, far, 2.0).surfaceTriangles());
}

TEST(TessellationLevelsTest, MorphedSamplesBlendOddSamplesTowardsTheirEvenNeighbours)
{
    const int n = 17, w = n + 4;
    NodeData node;
    node.heights.size = w;
    node.heights.base.resize(static_cast<std::size_t>(w) * w);
    for (int j = 0; j < w; ++j) {
        for (int i = 0; i < w; ++i) {
            node.heights.base[static_cast<std::size_t>(j) * w + i] =
                static_cast<float>(10.0 * test::unitNoise(3, i, j));
        }
    }
    auto own = [&](int i, int j) { return node.heights.base[static_cast<std::size_t>(j + 2) * w + i + 2]; };
    const std::vector<float> full = morphedSamples(node, n, 1.0f), parent = morphedSamples(node, n, 0.0f),
                             half = morphedSamples(node, n, 0.5f);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const auto k = static_cast<std::size_t>(j) * n + i;
            EXPECT_FLOAT_EQ(full[k], own(i, j));
            // Odd along x: between west and east; along y: south and north; both: south-west and north-east.
            const int dx = i & 1, dy = j & 1;
            const float mean = 0.5f * (own(i - dx, j - dy) + own(i + dx, j + dy));
            EXPECT_FLOAT_EQ(parent[k], (dx | dy) ? mean : own(i, j));
            EXPECT_NEAR(half[k], 0.5 * (full[k] + parent[k]), 1e-5);
        }
    }
}

TEST(TessellationLevelsTest, LevelSwitchesAreTheChangeOfTheDrawnSurfaceWhereBlocksChanged)
{
    const int n = 33;
    const std::vector<float> surface = hills(n, 7, 5.0);
    const TessellationErrors errors = computeTessellationErrors(surface, n, 8);
    const auto [lo, hi] = std::minmax_element(surface.begin(), surface.end());
    const Aabb node{{0.0, 0.0, *lo}, {320.0, 320.0, *hi}};
    const BlockLevels near = chooseBlockLevels(errors, node, cameraAt({160.0, 160.0, 400.0}, 0.0, -89.0), 1.0);
    const BlockLevels far = chooseBlockLevels(errors, node, cameraAt({160.0, 160.0, 1200.0}, 0.0, -89.0), 1.0);
    std::vector<LevelSwitch> none, some;
    levelSwitches(surface, n, near, near, none);
    EXPECT_TRUE(none.empty());
    levelSwitches(surface, n, near, far, some);
    ASSERT_FALSE(some.empty());
    int changedBlocks = 0;
    for (int k = 0; k < 16; ++k) {
        changedBlocks += near.code(k) != far.code(k) ? 1 : 0;
    }
    EXPECT_GT(changedBlocks, 0);
    for (const LevelSwitch& w : some) {
        const auto [b1, b2] = tessellatedHeights(surface, n, near, w.lx, w.ly);
        const auto [a1, a2] = tessellatedHeights(surface, n, far, w.lx, w.ly);
        EXPECT_DOUBLE_EQ(w.metres, std::max(std::abs(a1 - b1), std::abs(a2 - b2)));
        const int block = static_cast<int>(w.ly / 8) * 4 + static_cast<int>(w.lx / 8);
        const bool onChanged = near.code(std::min(block, 15)) != far.code(std::min(block, 15));
        // Points on a block's edge belong to two blocks; the one that changed may be either.
        const bool onEdge = std::fmod(w.lx, 8.0) == 0.0 || std::fmod(w.ly, 8.0) == 0.0;
        EXPECT_TRUE(onChanged || onEdge) << w.lx << "," << w.ly;
    }
}

}  // namespace
}  // namespace terrain
