// Block edge levels (lod/TessellationLevels.h) against a brute force written from the definition: for each
// edge, the largest d whose lambda(d) of every block on the edge, times C (eq. 3.3), is at most the nearer
// block distance, searched from the coarsest level down (the code searches up); the interior is the finest
// edge; and what that guarantees: every block within the budget at its own distance.
#include "MapTestSupport.h"

#include "lod/LodSelector.h"
#include "lod/TessellationLevels.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace terrain {
namespace {

constexpr double kDegrees = std::numbers::pi / 180.0;

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
    camera.yaw = yaw * kDegrees;
    camera.pitch = pitch * kDegrees;
    camera.farPlane = 1e6;
    return camera;
}

Aabb blockBox(const Aabb& node, int b, int bx, int by)
{
    const double size = (node.hi.x - node.lo.x) / b;
    return {{node.lo.x + bx * size, node.lo.y + by * size, node.lo.z},
            {node.lo.x + (bx + 1) * size, node.lo.y + (by + 1) * size, node.hi.z}};
}

TEST(TessellationLevelsTest, EdgesTakeTheCoarsestLevelBothBlocksAllowAndInteriorsTheFinestEdge)
{
    const int n = 65;
    const std::vector<float> surface = hills(n, 3, 6.0);
    const BlockErrors errors = computeBlockErrors(surface, n, 8);
    const auto [lo, hi] = std::minmax_element(surface.begin(), surface.end());
    const Aabb node{{0.0, 0.0, *lo}, {640.0, 640.0, *hi}};
    const double pixels = 1.0;
    int mixed = 0;
    for (const Camera& camera :
         {cameraAt({320.0, -50.0, 360.0}, 0.0, -10.0), cameraAt({100.0, 100.0, 900.0}, 30.0, -60.0),
          cameraAt({-400.0, 320.0, 500.0}, 90.0, -5.0), cameraAt({320.0, -2500.0, 1500.0}, 0.0, -25.0)}) {
        const BlockLevels levels = chooseBlockLevels(errors, node, camera, pixels);
        const int b = errors.blocksPerSide;
        ASSERT_EQ(levels.blocksPerSide, b);
        const double c = lodDistanceFactor(camera, pixels);
        const double k = verticalErrorFactor(camera);
        auto distanceOf = [&](int bx, int by) { return lodDistance(camera, k, blockBox(node, b, bx, by)); };
        // Brute force per edge: from the coarsest level down, the first that every block on it allows.
        auto brute = [&](std::vector<std::pair<int, int>> blocks) {
            double d = 1e300;
            for (auto [bx, by] : blocks) {
                d = std::min(d, distanceOf(bx, by));
            }
            for (int level = errors.levels; level >= 1; --level) {
                bool fits = true;
                for (auto [bx, by] : blocks) {
                    fits = fits && errors.at(bx, by, level) * c <= d;
                }
                if (fits) {
                    return level;
                }
            }
            return 0;
        };
        std::vector<int> seen(4, 0);
        for (int by = 0; by < b; ++by) {
            for (int bx = 0; bx <= b; ++bx) {
                std::vector<std::pair<int, int>> blocks;
                if (bx > 0)
                    blocks.emplace_back(bx - 1, by);
                if (bx < b)
                    blocks.emplace_back(bx, by);
                EXPECT_EQ(levels.northEdges[static_cast<std::size_t>(by * (b + 1) + bx)], brute(blocks))
                    << bx << "," << by;
            }
        }
        for (int by = 0; by <= b; ++by) {
            for (int bx = 0; bx < b; ++bx) {
                std::vector<std::pair<int, int>> blocks;
                if (by > 0)
                    blocks.emplace_back(bx, by - 1);
                if (by < b)
                    blocks.emplace_back(bx, by);
                EXPECT_EQ(levels.eastEdges[static_cast<std::size_t>(by * b + bx)], brute(blocks)) << bx << "," << by;
            }
        }
        for (int by = 0; by < b; ++by) {
            for (int bx = 0; bx < b; ++bx) {
                const int interior = levels.interior[static_cast<std::size_t>(by * b + bx)];
                EXPECT_EQ(interior, std::min({int{levels.northEdges[static_cast<std::size_t>(by * (b + 1) + bx)]},
                                              int{levels.northEdges[static_cast<std::size_t>(by * (b + 1) + bx + 1)]},
                                              int{levels.eastEdges[static_cast<std::size_t>(by * b + bx)]},
                                              int{levels.eastEdges[static_cast<std::size_t>((by + 1) * b + bx)]}}));
                // The guarantee: the block drawn at its interior level is within the budget where it is.
                if (interior > 0) {
                    EXPECT_LE(errors.at(bx, by, interior) * c, distanceOf(bx, by));
                }
                ++seen[static_cast<std::size_t>(interior)];
            }
        }
        mixed += std::count_if(seen.begin(), seen.end(), [](int s) { return s > 0; }) >= 2 ? 1 : 0;
        std::printf("levels 0..3: %d %d %d %d blocks\n", seen[0], seen[1], seen[2], seen[3]);
    }
    EXPECT_GE(mixed, 3) << "the cases must mix levels inside a node";
}

TEST(TessellationLevelsTest, MovingAwayNeverMakesALevelFinerAndPlanesAreCoarsest)
{
    const int n = 33;
    const std::vector<float> surface = hills(n, 5, 4.0);
    const BlockErrors errors = computeBlockErrors(surface, n, 8);
    const auto [lo, hi] = std::minmax_element(surface.begin(), surface.end());
    const Aabb node{{0.0, 0.0, *lo}, {320.0, 320.0, *hi}};
    BlockLevels previous;
    for (double back = 0.0; back <= 3000.0; back += 150.0) {
        const Camera camera = cameraAt({160.0, -20.0 - back, 340.0 + 0.2 * back}, 0.0, -12.0);
        const BlockLevels levels = chooseBlockLevels(errors, node, camera, 2.0);
        if (!previous.interior.empty()) {
            for (std::size_t k = 0; k < levels.northEdges.size(); ++k) {
                EXPECT_GE(levels.northEdges[k], previous.northEdges[k]) << back;
            }
            for (std::size_t k = 0; k < levels.interior.size(); ++k) {
                EXPECT_GE(levels.interior[k], previous.interior[k]) << back;
            }
        }
        previous = levels;
    }
    // A plane has no error at any level: every edge takes the coarsest, however close the camera is.
    std::vector<float> plane(static_cast<std::size_t>(n) * n);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            plane[static_cast<std::size_t>(j) * n + i] = static_cast<float>(0.5 * i + 0.25 * j);
        }
    }
    const BlockLevels flat =
        chooseBlockLevels(computeBlockErrors(plane, n, 8), node, cameraAt({10.0, 10.0, 5.0}, 45.0, -20.0), 0.5);
    for (std::uint8_t level : flat.interior) {
        EXPECT_EQ(level, 3);
    }
}

}  // namespace
}  // namespace terrain
