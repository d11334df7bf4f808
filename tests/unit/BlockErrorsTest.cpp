// Per-block simplification errors (lod/BlockErrors.h) against brute force written from the definition: the
// fine surface (template triangulation) and the coarse block under both diagonal splits, evaluated on a grid
// eight times finer than the samples (every sample and quad centre among its points, plus many between).
#include "MapTestSupport.h"

#include "lod/BlockErrors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace terrain {
namespace {

/// A piecewise linear surface over a grid of samples, the triangles given by `swne` (true: every quad split
/// from south-west to north-east), evaluated by barycentric weights at (x, y) in samples.
double linearAt(const std::vector<double>& s, int stride, double step, int i0, int j0, double x, double y, bool swne)
{
    // The quad of the grid (spacing `step`, from (i0, j0)) holding (x, y), and the position in it.
    const double qx = (x - i0) / step, qy = (y - j0) / step;
    const int ci =
        std::min(static_cast<int>(std::floor(qx)), static_cast<int>(std::round((stride - 1 - i0) / step)) - 1);
    const int cj =
        std::min(static_cast<int>(std::floor(qy)), static_cast<int>(std::round((stride - 1 - j0) / step)) - 1);
    const double u = qx - ci, v = qy - cj;
    auto at = [&](int di, int dj) {
        const int i = i0 + static_cast<int>((ci + di) * step), j = j0 + static_cast<int>((cj + dj) * step);
        return s[static_cast<std::size_t>(j) * stride + i];
    };
    const double a = at(0, 0), b = at(1, 0), c = at(0, 1), d = at(1, 1);
    if (swne) {
        return u >= v ? a + u * (b - a) + v * (d - b) : a + v * (c - a) + u * (d - c);
    }
    return u + v <= 1.0 ? a + u * (b - a) + v * (c - a) : d + (1.0 - u) * (c - d) + (1.0 - v) * (b - d);
}

std::vector<float> randomSurface(int n, int seed, double roughness)
{
    std::vector<float> s(static_cast<std::size_t>(n) * n);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            s[static_cast<std::size_t>(j) * n + i] =
                static_cast<float>(100.0 + 20.0 * std::sin(0.11 * i + seed) * std::cos(0.07 * j) +
                                   roughness * (test::unitNoise(seed, i, j) - 0.5));
        }
    }
    return s;
}

TEST(BlockErrorsTest, MatchesDenseBruteForceUnderBothDiagonals)
{
    for (const auto& [n, blockQuads, roughness] :
         {std::tuple{33, 8, 3.0}, std::tuple{17, 4, 0.0}, std::tuple{65, 8, 10.0}, std::tuple{17, 16, 1.0}}) {
        const std::vector<float> surface = randomSurface(n, n + blockQuads, roughness);
        const BlockErrors errors = computeBlockErrors(surface, n, blockQuads);
        ASSERT_EQ(errors.blocksPerSide, (n - 1) / blockQuads);
        ASSERT_EQ(1 << errors.levels, blockQuads);
        const std::vector<double> s(surface.begin(), surface.end());
        constexpr int kDense = 8;  // points per sample spacing
        for (int by = 0; by < errors.blocksPerSide; ++by) {
            for (int bx = 0; bx < errors.blocksPerSide; ++bx) {
                const int i0 = bx * blockQuads, j0 = by * blockQuads;
                double previous = 0.0;
                for (int d = 1; d <= errors.levels; ++d) {
                    double brute = 0.0;
                    for (int q = 0; q <= blockQuads * kDense; ++q) {
                        for (int p = 0; p <= blockQuads * kDense; ++p) {
                            const double x = i0 + static_cast<double>(p) / kDense;
                            const double y = j0 + static_cast<double>(q) / kDense;
                            const double fine = linearAt(s, n, 1.0, 0, 0, x, y, true);
                            for (bool swne : {true, false}) {
                                const double coarse = linearAt(s, n, 1 << d, i0, j0, x, y, swne);
                                brute = std::max(brute, std::abs(fine - coarse));
                            }
                        }
                    }
                    previous = std::max(previous, brute);
                    const double got = errors.at(bx, by, d);
                    EXPECT_GE(got, previous) << "n " << n << " block " << bx << "," << by << " d " << d;
                    EXPECT_NEAR(got, previous, 1e-4 * previous + 1e-6) << "n " << n << " d " << d;
                }
            }
        }
    }
}

TEST(BlockErrorsTest, PlanesAreExactAtEveryLevelAndABumpOnlyInItsBlocks)
{
    const int n = 33;
    std::vector<float> plane(static_cast<std::size_t>(n) * n);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            plane[static_cast<std::size_t>(j) * n + i] = static_cast<float>(0.25 * i - 0.5 * j);  // exact in float
        }
    }
    const BlockErrors flat = computeBlockErrors(plane, n, 8);
    for (float lambda : flat.lambda) {
        EXPECT_EQ(lambda, 0.0f);
    }
    // One sample raised 3 m inside block (1, 2), off every coarse grid: that block alone changes, by 3 m at
    // d = 1 already (the sample is dropped), and no level reports less than a finer one.
    std::vector<float> bump = plane;
    bump[static_cast<std::size_t>(2 * 8 + 3) * n + (1 * 8 + 5)] += 3.0f;
    const BlockErrors bumped = computeBlockErrors(bump, n, 8);
    for (int by = 0; by < 4; ++by) {
        for (int bx = 0; bx < 4; ++bx) {
            for (int d = 1; d <= 3; ++d) {
                if (bx == 1 && by == 2) {
                    EXPECT_EQ(bumped.at(bx, by, d), 3.0f) << d;
                } else {
                    EXPECT_EQ(bumped.at(bx, by, d), 0.0f) << bx << "," << by << " d " << d;
                }
            }
        }
    }
}

TEST(BlockErrorsTest, TriangleErrorIsTheExactMaximumOverTheTriangle)
{
    const int n = 17;
    std::vector<float> s(static_cast<std::size_t>(n) * n);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            s[static_cast<std::size_t>(j) * n + i] = static_cast<float>(10.0 * test::unitNoise(7, i, j) + 0.3 * i);
        }
    }
    auto fine = [&](double x, double y) {
        const int i = std::min(static_cast<int>(x), n - 2), j = std::min(static_cast<int>(y), n - 2);
        const double fx = x - i, fy = y - j;
        auto h = [&](int a, int b) -> double { return s[static_cast<std::size_t>(j + b) * n + i + a]; };
        return fx >= fy ? (1 - fx) * h(0, 0) + (fx - fy) * h(1, 0) + fy * h(1, 1)
                        : (1 - fy) * h(0, 0) + (fy - fx) * h(0, 1) + fx * h(1, 1);
    };
    const glm::ivec2 triangles[][3] = {{{0, 0}, {8, 0}, {3, 1}},
                                       {{2, 2}, {2, 9}, {7, 5}},
                                       {{16, 0}, {0, 16}, {9, 11}},
                                       {{4, 4}, {5, 4}, {4, 5}},
                                       {{1, 3}, {13, 4}, {6, 6}},
                                       // Edges through samples between their ends, and the node's far
                                       // row and column.
                                       {{0, 0}, {6, 3}, {2, 5}},
                                       {{16, 16}, {10, 13}, {16, 4}},
                                       {{3, 16}, {15, 12}, {9, 16}}};
    for (const auto& t : triangles) {
        const double exact = triangleError(s, n, t[0], t[1], t[2]);
        // Dense barycentric sampling: never above the exact maximum, and close to it.
        double sampled = 0.0;
        const int steps = 256;
        auto h = [&](glm::ivec2 v) -> double { return s[static_cast<std::size_t>(v.y) * n + v.x]; };
        for (int a = 0; a <= steps; ++a) {
            for (int b = 0; a + b <= steps; ++b) {
                const double wa = a / double(steps), wb = b / double(steps), wc = 1.0 - wa - wb;
                const double x = wa * t[0].x + wb * t[1].x + wc * t[2].x, y = wa * t[0].y + wb * t[1].y + wc * t[2].y;
                const double plane = wa * h(t[0]) + wb * h(t[1]) + wc * h(t[2]);
                sampled = std::max(sampled, std::abs(fine(x, y) - plane));
            }
        }
        EXPECT_LE(sampled, exact + 1e-9);
        EXPECT_GE(sampled, 0.97 * exact);
        EXPECT_GT(exact, 0.0);
    }
    EXPECT_EQ(triangleError(s, n, {0, 0}, {4, 4}, {8, 8}), 0.0) << "no area";
}

TEST(BlockErrorsDeathTest, RejectsBlocksThatDoNotTileTheNode)
{
    const std::vector<float> surface(33 * 33, 0.0f);
    EXPECT_DEATH(computeBlockErrors(surface, 33, 6), "power of two");
    EXPECT_DEATH(computeBlockErrors(surface, 33, 64), "power of two");
    EXPECT_DEATH(computeBlockErrors(std::vector<float>(10, 0.0f), 33, 8), "N x N");
}

}  // namespace
}  // namespace terrain
