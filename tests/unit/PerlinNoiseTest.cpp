// Improved Perlin noise (synthesis/PerlinNoise.h): determinism across calls, seeds and threads; the
// documented range; continuity across lattice cells; the same smoothness and detail far from the origin.
#include "synthesis/PerlinNoise.h"

#include "quadtree/TemplateTriangulation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <thread>
#include <vector>

namespace terrain {
namespace {

std::vector<double> samplePatch(const PerlinNoise& noise, double x0, double y0, int n, double step)
{
    std::vector<double> values;
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            values.push_back(noise(x0 + i * step, y0 + j * step));
        }
    }
    return values;
}

struct Stats {
    double mean = 0;
    double stddev = 0;
    double maxAbs = 0;
};

Stats stats(const std::vector<double>& v)
{
    Stats s;
    for (double x : v) {
        s.mean += x;
        s.maxAbs = std::max(s.maxAbs, std::abs(x));
    }
    s.mean /= static_cast<double>(v.size());
    for (double x : v) {
        s.stddev += (x - s.mean) * (x - s.mean);
    }
    s.stddev = std::sqrt(s.stddev / static_cast<double>(v.size()));
    return s;
}

TEST(PerlinNoise, SameInputSameBitsOnEveryCallAndThread)
{
    PerlinNoise noise(42);
    std::vector<double> first = samplePatch(noise, -37.3, 12.9, 64, 0.173);
    std::vector<double> again = samplePatch(PerlinNoise(42), -37.3, 12.9, 64, 0.173);
    std::vector<double> onThread;
    std::thread worker([&] { onThread = samplePatch(noise, -37.3, 12.9, 64, 0.173); });
    worker.join();
    ASSERT_EQ(first.size(), again.size());
    EXPECT_EQ(std::memcmp(first.data(), again.data(), first.size() * sizeof(double)), 0);
    EXPECT_EQ(std::memcmp(first.data(), onThread.data(), first.size() * sizeof(double)), 0);
}

TEST(PerlinNoise, SeedsGiveDifferentNoise)
{
    PerlinNoise a(1);
    PerlinNoise b(2);
    // Off the lattice lines a value depends on four hashed gradients: two seeds agree on all four
    // with probability 8^-4, so at most a handful of 1000 points may coincide.
    int same = 0;
    for (int i = 0; i < 1000; ++i) {
        double x = 0.37 + i * 0.9137;
        double y = 0.21 + 0.5317 * x;
        same += a(x, y) == b(x, y) ? 1 : 0;
    }
    EXPECT_LE(same, 3);
}

TEST(PerlinNoise, ZeroAtLatticePointsAndWithinDocumentedRange)
{
    PerlinNoise noise(7);
    for (int y = -5; y <= 5; ++y) {
        for (int x = -5; x <= 5; ++x) {
            EXPECT_EQ(noise(x, y), 0.0);
        }
    }
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> uni(-1000.0, 1000.0);
    std::vector<double> values;
    for (int i = 0; i < 200000; ++i) {
        values.push_back(noise(uni(rng), uni(rng)));
    }
    Stats s = stats(values);
    EXPECT_LE(s.maxAbs, 1.0);
    EXPECT_GT(s.maxAbs, 0.8) << "the scaled noise should use most of [-1, 1]";
    EXPECT_NEAR(s.mean, 0.0, 0.01);
    EXPECT_NEAR(s.stddev, 0.30, 0.04) << "documented standard deviation";
}

TEST(PerlinNoise, ContinuousAcrossLatticeCells)
{
    PerlinNoise noise(11);
    // Approaching each cell border from both sides gives the same value (C0), and a small step gives a
    // small change everywhere: the gradient of the scaled noise is bounded by a few units per cell.
    for (int k = -3; k <= 3; ++k) {
        for (double y : {0.25, 0.5, 3.7}) {
            double left = noise(std::nextafter(static_cast<double>(k), -1e9), y);
            double right = noise(static_cast<double>(k), y);
            EXPECT_NEAR(left, right, 1e-12);
            EXPECT_NEAR(noise(y, std::nextafter(static_cast<double>(k), -1e9)), noise(y, k), 1e-12);
        }
    }
    double maxSlope = 0;
    const double h = 1e-4;
    for (int i = 0; i < 100000; ++i) {
        double x = -5.0 + i * 1e-4;
        maxSlope = std::max(maxSlope, std::abs(noise(x + h, 0.3 * x) - noise(x, 0.3 * x)) / h);
    }
    EXPECT_LT(maxSlope, 4.0);
    EXPECT_GT(maxSlope, 0.5);
}

TEST(PerlinNoise, AsSmoothAndDetailedFarFromTheOrigin)
{
    // 10^7 lattice cells: 500 km at a 5 cm finest wavelength, the worst case of an 8-octave fractal.
    PerlinNoise noise(5);
    const double far = 1e7;
    Stats nearStats = stats(samplePatch(noise, 0.0, 0.0, 300, 0.37));
    Stats farStats = stats(samplePatch(noise, far, far, 300, 0.37));
    EXPECT_NEAR(farStats.stddev / nearStats.stddev, 1.0, 0.1);
    // Second differences at 1e-4 cells stay tiny (smooth, no staircase from lost fraction bits) and
    // first differences are as large as near the origin (detail kept).
    const double h = 1e-4;
    for (double origin : {0.0, far}) {
        double maxSecond = 0;
        double maxFirst = 0;
        for (int i = 0; i < 20000; ++i) {
            double x = origin + i * 0.0137;
            double y = origin + 0.5;
            double a = noise(x - h, y);
            double b = noise(x, y);
            double c = noise(x + h, y);
            maxSecond = std::max(maxSecond, std::abs(a - 2 * b + c));
            maxFirst = std::max(maxFirst, std::abs(c - b));
        }
        EXPECT_LT(maxSecond, 1e-6) << "origin " << origin;
        EXPECT_GT(maxFirst, 1e-4) << "origin " << origin;
    }
}

TEST(PerlinNoise, Cell32IsTheSameNoiseOnTheLow32BitsOfTheCell)
{
    // Fractal's vectorised loops call cell32 with the cell's low 32 bits; operator() and cell take the
    // full index. The same bits for negative cells, cells past 2^31 and past 2^32 (which wrap).
    PerlinNoise noise(13);
    for (std::int64_t base : {std::int64_t{0}, std::int64_t{-5}, std::int64_t{2'000'000}, (std::int64_t{1} << 31) - 2,
                              (std::int64_t{1} << 40) + 3, -(std::int64_t{1} << 35)}) {
        for (int i = 0; i < 50; ++i) {
            std::int64_t ix = base + i % 5;
            std::int64_t iy = base - i % 3;
            double tx = (i % 11) / 16.0;  // dyadic: ix + tx is exact, so operator() sees the same fraction
            double ty = (i % 7) / 8.0;
            float full = noise.cell(ix, iy, tx, ty);
            float low =
                noise.cell32(static_cast<std::uint32_t>(ix), static_cast<std::uint32_t>(iy), static_cast<float>(tx),
                             static_cast<float>(ty), PerlinNoise::fade(tx), PerlinNoise::fade(ty));
            EXPECT_EQ(std::memcmp(&full, &low, sizeof(float)), 0) << base;
            double point = noise(static_cast<double>(ix) + tx, static_cast<double>(iy) + ty);
            EXPECT_EQ(point, static_cast<double>(full)) << base;
        }
    }
    // The hash only sees the low 32 bits: cells 2^32 apart share their gradients.
    EXPECT_EQ(noise.cell(7, 9, 0.3, 0.6), noise.cell(7 + (std::int64_t{1} << 32), 9, 0.3, 0.6));
}

TEST(PerlinNoise, BatchedCellsMatchCell32OnEveryPath)
{
    // The vectorised batch (SSE2 loop, AVX2 intrinsics with a table permute for the gradients) against the
    // scalar cell32, bit for bit: random cells over the whole 32-bit range, fractions including the cell
    // borders 0 and 1 (where neighbouring cells must agree exactly).
    PerlinNoise noise(99);
    std::mt19937_64 rng(4);
    for (int round = 0; round < 50; ++round) {
        LatticeBatch batch;
        for (int k = 0; k < LatticeBatch::kSize; ++k) {
            batch.cellX[k] = static_cast<std::uint32_t>(rng());
            batch.cellY[k] = static_cast<std::uint32_t>(rng());
            double tx = k % 9 == 0 ? 0.0 : k % 9 == 1 ? 1.0 : static_cast<double>(rng() >> 11) * 0x1.0p-53;
            double ty = k % 7 == 0 ? 1.0 : static_cast<double>(rng() >> 11) * 0x1.0p-53;
            batch.tx[k] = static_cast<float>(tx);
            batch.ty[k] = static_cast<float>(ty);
            batch.u[k] = PerlinNoise::fade(tx);
            batch.v[k] = PerlinNoise::fade(ty);
        }
        for (SimdPath path : {SimdPath::Baseline, SimdPath::Avx2}) {
            if (!simdPathSupported(path)) {
                continue;
            }
            float out[LatticeBatch::kSize];
            noise.cells(batch, out, path);
            int mismatches = 0;
            for (int k = 0; k < LatticeBatch::kSize; ++k) {
                float scalar =
                    noise.cell32(batch.cellX[k], batch.cellY[k], batch.tx[k], batch.ty[k], batch.u[k], batch.v[k]);
                mismatches += std::memcmp(&scalar, &out[k], sizeof(float)) != 0;
            }
            EXPECT_EQ(mismatches, 0) << (path == SimdPath::Avx2 ? "avx2" : "baseline");
        }
    }
}

TEST(PerlinNoise, GradientChoicesAreUniformAndIndependentBetweenNeighbours)
{
    // Next to a lattice point the noise is its corner's gradient times the offset (the other corners
    // enter with fade(eps) ~ 10 eps^3), so one step along each axis reads the gradient's class: the signs
    // of both components and which one is larger (8 classes, one per gradient). Over 256^2 cells the
    // class of a cell and of its neighbour at (1, 0), (0, 1), (1, 1), (1, -1) and (2, 3) must be
    // independent and uniform: chi-square of the 8 x 8 table below the 0.1 % quantile for 63 degrees of
    // freedom (103.4). A hash without the final multiply, (x * kx) ^ (y * ky), fails this.
    for (std::uint64_t seed : {1u, 77u}) {
        PerlinNoise noise(seed);
        const int n = 256;
        const int origin = -100;
        const double eps = 1e-3;
        std::vector<int> cls(static_cast<std::size_t>(n + 4) * (n + 4));
        for (int j = 0; j < n + 4; ++j) {
            for (int i = 0; i < n + 4; ++i) {
                double x = origin + i;
                double y = origin + j;
                double gx = noise(x + eps, y);
                double gy = noise(x, y + eps);
                cls[static_cast<std::size_t>(j) * (n + 4) + i] =
                    (gx < 0 ? 1 : 0) | (gy < 0 ? 2 : 0) | (std::abs(gx) > std::abs(gy) ? 4 : 0);
            }
        }
        std::vector<int> single(8, 0);
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                ++single[static_cast<std::size_t>(cls[static_cast<std::size_t>(j + 1) * (n + 4) + i])];
            }
        }
        for (int count : single) {
            EXPECT_NEAR(count, n * n / 8, n * n / 8 / 10) << "seed " << seed;
        }
        struct Offset {
            int dx, dy;
        };
        for (Offset d : {Offset{1, 0}, Offset{0, 1}, Offset{1, 1}, Offset{1, -1}, Offset{2, 3}}) {
            std::vector<double> table(64, 0.0);
            for (int j = 1; j < n + 1; ++j) {
                for (int i = 0; i < n; ++i) {
                    int a = cls[static_cast<std::size_t>(j) * (n + 4) + i];
                    int b = cls[static_cast<std::size_t>(j + d.dy) * (n + 4) + i + d.dx];
                    table[static_cast<std::size_t>(a * 8 + b)] += 1.0;
                }
            }
            double expected = n * n / 64.0;
            double chi2 = 0;
            for (double count : table) {
                chi2 += (count - expected) * (count - expected) / expected;
            }
            EXPECT_LT(chi2, 103.4) << "seed " << seed << " offset (" << d.dx << ", " << d.dy << ")";
        }
    }
}

TEST(PerlinNoise, ExtremesBoundTheNoiseAndAreReachedByIt)
{
    // The extremes are measured on the gradients alone; here the noise itself, on 4000 random cells sampled
    // 1/96 of a cell apart (off the extremes' grid), reaches within a few percent of each and never
    // exceeds it: the peak, and the interpolation error at samples 2^-m cells apart, over all cells and in
    // each cell by its corner gradients (PerlinNoise::cellGradients), per sample cell.
    const GradientNoiseExtremes& e = PerlinNoise::extremes();
    EXPECT_GT(e.peak, 0.8);
    EXPECT_LT(e.peak, 1.0) << "no tighter than the gradients' scale";
    for (int m = 1; m < GradientNoiseExtremes::kLevels; ++m) {
        EXPECT_LT(e.interpolationAt(m + 1), e.interpolationAt(m)) << m;
    }
    EXPECT_LT(e.interpolationAt(GradientNoiseExtremes::kLevels + 1), e.interpolationAt(GradientNoiseExtremes::kLevels));
    const PerlinNoise noise(99);
    std::mt19937_64 random(7);
    constexpr int kSteps = 96;
    double peak = 0.0;
    std::array<double, GradientNoiseExtremes::kLevels> interpolation{};
    std::vector<double> p((kSteps + 1) * (kSteps + 1));
    for (int trial = 0; trial < 4000; ++trial) {
        const auto ix = static_cast<std::int64_t>(random() % 100000), iy = static_cast<std::int64_t>(random() % 100000);
        // The cell's own tables, by its corner gradients: they bound this cell, and are reached in it.
        const auto combo = static_cast<std::size_t>(noise.cellGradients(ix, iy));
        double cellPeak = 0.0;
        for (int j = 0; j <= kSteps; ++j) {
            for (int i = 0; i <= kSteps; ++i) {
                const double v = noise.cell(ix, iy, double(i) / kSteps, double(j) / kSteps);
                p[j * (kSteps + 1) + i] = v;
                cellPeak = std::max(cellPeak, std::abs(v));
            }
        }
        peak = std::max(peak, cellPeak);
        EXPECT_LE(cellPeak, e.cellPeak[combo]);
        EXPECT_GT(cellPeak, 0.98 * e.cellPeak[combo] - 0.002);
        auto at = [&](int i, int j) { return p[j * (kSteps + 1) + i]; };
        for (int m = 1; m <= GradientNoiseExtremes::kLevels; ++m) {
            const int split = 1 << m, step = kSteps >> m;
            for (int sy = 0; sy < split; ++sy) {
                for (int sx = 0; sx < split; ++sx) {
                    const int i0 = sx * step, j0 = sy * step;
                    double worst = 0.0;
                    for (int b = 0; b <= step; ++b) {
                        for (int a = 0; a <= step; ++a) {
                            const double surface =
                                interpolateQuad(at(i0, j0), at(i0 + step, j0), at(i0, j0 + step),
                                                at(i0 + step, j0 + step), double(a) / step, double(b) / step);
                            worst = std::max(worst, std::abs(at(i0 + a, j0 + b) - surface));
                        }
                    }
                    interpolation[m - 1] = std::max(interpolation[m - 1], worst);
                    if (m <= GradientNoiseExtremes::kCellLevels) {
                        const float table = e.cellInterpolation[m - 1][combo * split * split +
                                                                       static_cast<std::size_t>(sy * split + sx)];
                        EXPECT_LE(worst, table) << m;
                        EXPECT_GT(worst, 0.95 * table - 0.002) << m;
                    }
                }
            }
        }
    }
    EXPECT_LE(peak, e.peak);
    EXPECT_GT(peak, 0.95 * e.peak);
    for (int m = 1; m <= GradientNoiseExtremes::kLevels; ++m) {
        EXPECT_LE(interpolation[m - 1], e.interpolationAt(m)) << m;
        EXPECT_GT(interpolation[m - 1], 0.85 * e.interpolationAt(m)) << m;
    }
    std::printf("  peak %.4f (noise %.4f); interpolation at 2^-m cells:", e.peak, peak);
    for (int m = 1; m <= GradientNoiseExtremes::kLevels; ++m) {
        std::printf(" %.4f (%.4f)", e.interpolationAt(m), interpolation[m - 1]);
    }
    std::printf("\n");
}

TEST(PerlinNoise, PeriodicNoiseRepeatsExactly)
{
    PerlinNoise noise(9, 16);
    for (int i = 0; i < 200; ++i) {
        double tx = (i % 17) / 17.0;
        double ty = (i % 13) / 13.0;
        std::int64_t ix = i - 100;
        EXPECT_EQ(noise.cell(ix, 3, tx, ty), noise.cell(ix + 16, 3, tx, ty));
        EXPECT_EQ(noise.cell(ix, 3, tx, ty), noise.cell(ix, 3 - 32, tx, ty));
    }
    // Continuous across the wrap: cell 15's right edge equals cell 0's left edge.
    EXPECT_NEAR(noise.cell(15, 2, 1.0, 0.4), noise.cell(0, 2, 0.0, 0.4), 1e-12);
}

}  // namespace
}  // namespace terrain
