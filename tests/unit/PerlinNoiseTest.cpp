// Improved Perlin noise (synthesis/PerlinNoise.h): determinism across calls, seeds and threads; the
// documented range; continuity across lattice cells; the same smoothness and detail far from the origin.
#include "synthesis/PerlinNoise.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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
    EXPECT_NEAR(s.stddev, 0.27, 0.04) << "documented standard deviation";
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
