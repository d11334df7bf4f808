// fBm and ridged multifractal displacement (synthesis/Fractal.h): determinism (point vs grid, threads),
// range, continuity, exactness 500 km from the origin, statistics that follow amplitude, lacunarity and
// gain, and the cached basis / cached fractal within their documented errors.
#include "heightfield/Image.h"
#include "synthesis/Fractal.h"

#include "TestSupport.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <random>
#include <span>
#include <thread>
#include <vector>

namespace terrain {
namespace {

FractalParams fbm(int octaves = 8, double wavelength = 32.0, double amplitude = 2.0)
{
    FractalParams p;
    p.octaves = octaves;
    p.wavelength = wavelength;
    p.amplitude = amplitude;
    p.seed = 17;
    return p;
}

FractalParams ridged()
{
    FractalParams p = fbm();
    p.type = FractalType::Ridged;
    return p;
}

/// A tileable 64 x 64 gray bitmap: periodic noise, so the basis has no seam.
std::shared_ptr<const BasisTable> testBitmap()
{
    PerlinNoise noise(4, 8);
    Image image{64, 64, 1, std::vector<std::uint8_t>(64 * 64)};
    for (int y = 0; y < 64; ++y) {
        for (int x = 0; x < 64; ++x) {
            double v = noise(x / 8.0, y / 8.0);
            image.pixel(x, y)[0] = static_cast<std::uint8_t>(std::lround(127.5 + 127.5 * v));
        }
    }
    return std::make_shared<BasisTable>(BasisTable::fromImage(image));
}

struct Case {
    const char* name;
    FractalParams params;
    bool bitmap = false;
};

std::vector<Case> allCases()
{
    std::vector<Case> cases;
    for (FractalCache cache : {FractalCache::None, FractalCache::Basis, FractalCache::Fractal}) {
        const char* names[3][2] = {{"fbm", "ridged"},
                                   {"fbm/cached basis", "ridged/cached basis"},
                                   {"fbm/cached fractal", "ridged/cached fractal"}};
        FractalParams f = fbm();
        f.cache = cache;
        FractalParams r = ridged();
        r.cache = cache;
        cases.push_back({names[static_cast<int>(cache)][0], f});
        cases.push_back({names[static_cast<int>(cache)][1], r});
    }
    cases.push_back({"bitmap fbm", fbm(), true});
    cases.push_back({"bitmap ridged", ridged(), true});
    return cases;
}

Fractal make(const Case& c)
{
    return c.bitmap ? Fractal(c.params, testBitmap()) : Fractal(c.params);
}

std::vector<float> window(const Fractal& f, double x0, double y0, double spacing, int n)
{
    std::vector<float> out(static_cast<std::size_t>(n) * n);
    f.evaluateGrid(SampleGrid{x0, y0, 0, 0, spacing, n, n}, out);
    return out;
}

double stddev(const std::vector<double>& v)
{
    double mean = 0;
    for (double x : v) {
        mean += x;
    }
    mean /= static_cast<double>(v.size());
    double var = 0;
    for (double x : v) {
        var += (x - mean) * (x - mean);
    }
    return std::sqrt(var / static_cast<double>(v.size()));
}

TEST(Fractal, PointAndGridBitIdenticalOnEveryThread)
{
    for (const Case& c : allCases()) {
        SCOPED_TRACE(c.name);
        Fractal f = make(c);
        const double x0 = 499'987.25;
        const double y0 = -123'456.5;
        const double spacing = 0.0625;
        const int n = 69;
        std::vector<float> grid = window(f, x0, y0, spacing, n);
        std::vector<float> again = window(make(c), x0, y0, spacing, n);
        std::vector<float> threaded;
        std::thread worker([&] { threaded = window(f, x0, y0, spacing, n); });
        worker.join();
        EXPECT_EQ(std::memcmp(grid.data(), again.data(), grid.size() * sizeof(float)), 0);
        EXPECT_EQ(std::memcmp(grid.data(), threaded.data(), grid.size() * sizeof(float)), 0);
        int mismatches = 0;
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                float point = static_cast<float>(f(x0 + i * spacing, y0 + j * spacing));
                mismatches += std::memcmp(&point, &grid[static_cast<std::size_t>(j) * n + i], sizeof(float)) != 0;
            }
        }
        EXPECT_EQ(mismatches, 0);
    }
}

/// Bit-exact comparison of two float spans; counts the samples that differ.
int countMismatches(std::span<const float> a, std::span<const float> b)
{
    int mismatches = 0;
    for (std::size_t k = 0; k < a.size(); ++k) {
        mismatches += std::memcmp(&a[k], &b[k], sizeof(float)) != 0;
    }
    return mismatches;
}

TEST(Fractal, MaskedGridWritesExactlyTheMaskedSamples)
{
    // A mask with runs, isolated samples and a ragged end: masked-out samples keep their sentinel,
    // the others get the full grid's bits, whatever batch (of the vectorised path) they fall in.
    const int n = 69;
    std::vector<std::uint8_t> mask(static_cast<std::size_t>(n) * n);
    std::mt19937 rng(21);
    for (std::size_t k = 0; k < mask.size(); ++k) {
        mask[k] = (k % 7 == 0 || k % 131 < 40 || rng() % 3 == 0) ? 1 : 0;
    }
    const float sentinel = -12345.0f;
    for (const Case& c : allCases()) {
        SCOPED_TRACE(c.name);
        Fractal f = make(c);
        const SampleGrid grid{499'987.25, -123'456.5, 3, -5, 0.0625, n, n};
        std::vector<float> full(grid.count());
        f.evaluateGrid(grid, full);
        std::vector<float> masked(grid.count(), sentinel);
        f.evaluateGrid(grid, masked, mask);
        int untouchedWrong = 0;
        int writtenWrong = 0;
        for (std::size_t k = 0; k < mask.size(); ++k) {
            if (mask[k] == 0) {
                untouchedWrong += masked[k] != sentinel;
            } else {
                writtenWrong += std::memcmp(&masked[k], &full[k], sizeof(float)) != 0;
            }
        }
        EXPECT_EQ(untouchedWrong, 0);
        EXPECT_EQ(writtenWrong, 0);
        // All-zero mask: nothing written.
        std::vector<float> none(grid.count(), sentinel);
        f.evaluateGrid(grid, none, std::vector<std::uint8_t>(grid.count(), 0));
        EXPECT_EQ(none, std::vector<float>(grid.count(), sentinel));
    }
}

TEST(Fractal, NeighbouringWindowsAgreeOnSharedSamples)
{
    // Two node windows on the same sample lattice (same origin and spacing), the second shifted by
    // (37, -21) samples: where they overlap, the global sample (gx0 + i, gy0 + j) has the same bits in
    // both, though it sits at a different position in each window's batches.
    const int n = 69;
    for (const Case& c : allCases()) {
        SCOPED_TRACE(c.name);
        Fractal f = make(c);
        const SampleGrid a{-250'000.0, 500'000.0, 1'000'000, 64, 0.25, n, n};
        SampleGrid b = a;
        b.gx0 += 37;
        b.gy0 -= 21;
        std::vector<float> va(a.count());
        std::vector<float> vb(b.count());
        f.evaluateGrid(a, va);
        f.evaluateGrid(b, vb);
        int shared = 0;
        int mismatches = 0;
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                std::int64_t gx = a.gx0 + i;
                std::int64_t gy = a.gy0 + j;
                std::int64_t bi = gx - b.gx0;
                std::int64_t bj = gy - b.gy0;
                if (bi < 0 || bi >= n || bj < 0 || bj >= n) {
                    continue;
                }
                ++shared;
                const float& fa = va[static_cast<std::size_t>(j) * n + i];
                const float& fb = vb[static_cast<std::size_t>(bj) * n + static_cast<std::size_t>(bi)];
                mismatches += std::memcmp(&fa, &fb, sizeof(float)) != 0;
            }
        }
        EXPECT_EQ(shared, (n - 37) * (n - 21));
        EXPECT_EQ(mismatches, 0);
    }
}

TEST(Fractal, SimdPathsGiveTheSameBits)
{
    // The baseline (SSE2) and AVX2 builds of the vectorised loops, and the point form, must agree bit for
    // bit: near the origin (negative cells), 500 km out, and with a mask.
    if (!simdPathSupported(SimdPath::Avx2)) {
        GTEST_SKIP() << "this CPU has no AVX2: only the baseline path exists";
    }
    EXPECT_EQ(bestSimdPath(), SimdPath::Avx2);
    const int n = 69;
    std::vector<std::uint8_t> mask(static_cast<std::size_t>(n) * n);
    for (std::size_t k = 0; k < mask.size(); ++k) {
        mask[k] = (k * 2654435761u) % 5 < 3 ? 1 : 0;
    }
    for (const Case& c : allCases()) {
        SCOPED_TRACE(c.name);
        Fractal f = make(c);
        for (const SampleGrid& grid :
             {SampleGrid{-3.0, -7.5, -20, 3, 0.1, n, n}, SampleGrid{500'000.0, 499'872.0, 0, 0, 0.25, n, n},
              SampleGrid{-123'456.0, 654'321.0, 77, -9, 1.0 / 64.0, n, n}}) {
            std::vector<float> baseline(grid.count());
            std::vector<float> avx2(grid.count());
            f.evaluateGrid(grid, baseline, {}, SimdPath::Baseline);
            f.evaluateGrid(grid, avx2, {}, SimdPath::Avx2);
            EXPECT_EQ(countMismatches(baseline, avx2), 0) << grid.originX;
            std::vector<float> baselineMasked(grid.count(), 0.0f);
            std::vector<float> avx2Masked(grid.count(), 0.0f);
            f.evaluateGrid(grid, baselineMasked, mask, SimdPath::Baseline);
            f.evaluateGrid(grid, avx2Masked, mask, SimdPath::Avx2);
            EXPECT_EQ(countMismatches(baselineMasked, avx2Masked), 0) << grid.originX;
            int pointMismatches = 0;
            for (int j = 0; j < n; ++j) {
                for (int i = 0; i < n; ++i) {
                    auto point = static_cast<float>(f(grid.x(i), grid.y(j)));
                    pointMismatches +=
                        std::memcmp(&point, &avx2[static_cast<std::size_t>(j) * n + i], sizeof(float)) != 0;
                }
            }
            EXPECT_EQ(pointMismatches, 0) << grid.originX;
        }
    }
}

TEST(Fractal, GridFarBeyondTheVectorRangeMatchesThePointForm)
{
    // 2 x 10^9 m: the finest octave's lattice coordinate passes 2^30 cells, so the grid falls back to the
    // point form's 64-bit split. Still bit-identical, still within the amplitude.
    Fractal f(fbm());
    const int n = 9;
    const SampleGrid grid{2.0e9, -2.0e9, 0, 0, 0.25, n, n};
    std::vector<float> values(grid.count());
    f.evaluateGrid(grid, values);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            auto point = static_cast<float>(f(grid.x(i), grid.y(j)));
            EXPECT_EQ(std::memcmp(&point, &values[static_cast<std::size_t>(j) * n + i], sizeof(float)), 0);
            EXPECT_LE(std::abs(point), 2.0f);
        }
    }
}

TEST(Fractal, EmptyGridWritesNothing)
{
    Fractal f(fbm());
    std::vector<float> out(4, 7.0f);
    f.evaluateGrid(SampleGrid{0.0, 0.0, 0, 0, 1.0, 0, 2}, out);
    f.evaluateGrid(SampleGrid{0.0, 0.0, 0, 0, 1.0, 2, 0}, out);
    EXPECT_EQ(out, std::vector<float>(4, 7.0f));
}

TEST(Fractal, ValuesWithinAmplitudeAndUseTheRange)
{
    for (const Case& c : allCases()) {
        SCOPED_TRACE(c.name);
        Fractal f = make(c);
        double lo = 1e9;
        double hi = -1e9;
        std::mt19937_64 rng(5);
        std::uniform_real_distribution<double> uni(-5000.0, 5000.0);
        for (int i = 0; i < 50000; ++i) {
            double v = f(uni(rng), uni(rng));
            lo = std::min(lo, v);
            hi = std::max(hi, v);
        }
        double a = c.params.amplitude;
        EXPECT_GE(lo, -a);
        EXPECT_LE(hi, a);
        EXPECT_GT(hi - lo, 0.5 * a) << "a displacement that uses almost none of its range";
    }
}

TEST(Fractal, RidgedIsSkewedTowardsItsCrests)
{
    // (offset - |n|)^2 peaks (a cusp: the ridge) where the basis crosses 0 and the basis is mostly
    // small, so values crowd near the top of [-A, A] with a long lower tail of narrow valleys.
    Fractal f(ridged());
    std::vector<double> v;
    for (int i = 0; i < 40000; ++i) {
        v.push_back(f(i * 1.37, i * 0.71));
    }
    std::sort(v.begin(), v.end());
    double median = v[v.size() / 2];
    double top = v[v.size() * 999 / 1000];
    double bottom = v[v.size() / 1000];
    EXPECT_GT(median, 0.0);
    EXPECT_GT(median - bottom, 1.2 * (top - median));
}

TEST(Fractal, SmallStepSmallChangeEverywhere)
{
    // Lipschitz bound from the noise's gradient (< 4 per cell, PerlinNoiseTest) summed over octaves.
    FractalParams p = fbm();
    Fractal f(p);
    double bound = 0;
    double weight = 1;
    double weightSum = 0;
    double frequency = 1.0 / p.wavelength;
    for (int i = 0; i < p.octaves; ++i) {
        bound += weight * 4.0 * frequency;
        weightSum += weight;
        weight *= p.gain;
        frequency *= p.lacunarity;
    }
    bound *= p.amplitude / weightSum;
    const double h = 1e-3;
    for (double origin : {0.0, 500'000.0}) {
        for (int i = 0; i < 20000; ++i) {
            double x = origin + i * 0.0731;
            double y = origin - i * 0.0417;
            EXPECT_LE(std::abs(f(x + h, y) - f(x, y)), bound * h) << x;
            EXPECT_LE(std::abs(f(x, y + h) - f(x, y)), bound * h) << y;
        }
    }
}

TEST(Fractal, SameStatisticsAndSmoothness500KmFromTheOrigin)
{
    // Finest octave: 32 m / 128 = 25 cm, so 1 cm steps resolve it.
    for (FractalType type : {FractalType::Fbm, FractalType::Ridged}) {
        FractalParams p = fbm();
        p.type = type;
        Fractal g(p);
        std::vector<double> nearValues;
        std::vector<double> farValues;
        double nearSlope = 0;
        double nearSecond = 0;
        double farSlope = 0;
        double farSecond = 0;
        for (int j = 0; j < 200; ++j) {
            for (int i = 0; i < 200; ++i) {
                double dx = i * 3.1;
                double dy = j * 2.9;
                nearValues.push_back(g(dx, dy));
                farValues.push_back(g(500'000.0 + dx, 500'000.0 + dy));
            }
        }
        for (int i = 0; i < 20000; ++i) {
            double d = i * 0.173;
            nearSlope = std::max(nearSlope, std::abs(g(d + 0.01, 1.0) - g(d, 1.0)) / 0.01);
            nearSecond = std::max(nearSecond, std::abs(g(d - 0.01, 1.0) - 2 * g(d, 1.0) + g(d + 0.01, 1.0)));
            double a = g(500'000.0 + d - 0.01, 500'001.0);
            double b = g(500'000.0 + d, 500'001.0);
            double c = g(500'000.0 + d + 0.01, 500'001.0);
            farSlope = std::max(farSlope, std::abs(c - b) / 0.01);
            farSecond = std::max(farSecond, std::abs(a - 2 * b + c));
        }
        SCOPED_TRACE(type == FractalType::Fbm ? "fbm" : "ridged");
        EXPECT_NEAR(stddev(farValues) / stddev(nearValues), 1.0, 0.15);
        EXPECT_NEAR(farSlope / nearSlope, 1.0, 0.25);
        // Second differences over 1 cm: no staircase of lost bits. fBm is smooth (C2); ridged has cusps
        // at its crests, as many far away as near.
        EXPECT_LT(farSecond, 1.5 * nearSecond);
        if (type == FractalType::Fbm) {
            EXPECT_LT(farSecond, 0.2 * farSlope * 0.01);
        }
    }
}

TEST(Fractal, StandardDeviationScalesWithAmplitude)
{
    std::vector<double> small;
    std::vector<double> large;
    Fractal a(fbm(8, 32.0, 1.0));
    Fractal b(fbm(8, 32.0, 3.0));
    for (int i = 0; i < 20000; ++i) {
        small.push_back(a(i * 2.3, i * 1.1));
        large.push_back(b(i * 2.3, i * 1.1));
    }
    EXPECT_NEAR(stddev(large) / stddev(small), 3.0, 1e-9);
    // Documented: fBm's standard deviation is about a quarter of its amplitude bound (8 octaves, gain 0.5).
    EXPECT_NEAR(stddev(small), 0.22, 0.06);
}

/// Power in octave bands along many lines: band k spans [f_k / sqrt(lac), f_k * sqrt(lac)] around
/// f_k = lac^k / wavelength. For a self-similar fBm, E_{k+1} / E_k = gain^2.
std::vector<double> bandEnergies(const Fractal& f, int bands)
{
    const FractalParams& p = f.params();
    const std::size_t n = 4096;
    // Nyquist above the top band: 2.2 samples per cycle of lac^(bands - 0.5) / wavelength.
    const double spacing = p.wavelength / (2.2 * std::pow(p.lacunarity, bands - 0.5));
    const double length = spacing * static_cast<double>(n);
    std::vector<double> energy(static_cast<std::size_t>(bands), 0.0);
    for (int line = 0; line < 24; ++line) {
        std::vector<std::complex<double>> a(n);
        for (std::size_t i = 0; i < n; ++i) {
            // Hann window against leakage from the line's ends.
            double w = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n));
            a[i] = w * f(static_cast<double>(i) * spacing, 977.0 * line);
        }
        test::fft(a);
        for (std::size_t k = 1; k < n / 2; ++k) {
            double frequency = static_cast<double>(k) / length;
            double octave = std::log(frequency * p.wavelength) / std::log(p.lacunarity);
            int band = static_cast<int>(std::floor(octave + 0.5));
            if (band >= 0 && band < bands) {
                energy[static_cast<std::size_t>(band)] += std::norm(a[k]);
            }
        }
    }
    return energy;
}

TEST(Fractal, OctaveContentFollowsLacunarityAndGain)
{
    struct Want {
        double lacunarity;
        double gain;
    };
    for (Want want : {Want{2.0, 0.5}, Want{2.0, 0.7}, Want{2.5, 0.6}}) {
        FractalParams p = fbm(8, 32.0, 1.0);
        p.lacunarity = want.lacunarity;
        p.gain = want.gain;
        Fractal f(p);
        std::vector<double> e = bandEnergies(f, 6);
        for (int k = 2; k + 1 < 6; ++k) {
            double ratio = e[static_cast<std::size_t>(k) + 1] / e[static_cast<std::size_t>(k)];
            EXPECT_NEAR(ratio / (want.gain * want.gain), 1.0, 0.3)
                << "lacunarity " << want.lacunarity << " gain " << want.gain << " band " << k;
        }
    }
}

TEST(Fractal, CachedBasisWithinDocumentedErrorAndSameStatistics)
{
    for (FractalType type : {FractalType::Fbm, FractalType::Ridged}) {
        FractalParams p = fbm();
        p.type = type;
        p.cache = FractalCache::Basis;
        Fractal cached(p);
        p.cache = FractalCache::None;
        Fractal exact(p);
        double maxError = 0;
        std::vector<double> c;
        std::vector<double> e;
        std::mt19937_64 rng(8);
        std::uniform_real_distribution<double> uni(-600'000.0, 600'000.0);
        for (int i = 0; i < 100000; ++i) {
            double x = uni(rng);
            double y = uni(rng);
            double v = cached(x, y);
            maxError = std::max(maxError, std::abs(v - cached.uncachedValue(x, y)));
            c.push_back(v);
            e.push_back(exact(x, y));
        }
        SCOPED_TRACE(type == FractalType::Fbm ? "fbm" : "ridged");
        EXPECT_LE(maxError,
                  (type == FractalType::Fbm ? kCachedBasisMaxErrorFbm : kCachedBasisMaxErrorRidged) * p.amplitude);
        EXPECT_GT(maxError, 0.0);
        std::printf("cached basis %s: max error %.4f x amplitude\n", type == FractalType::Fbm ? "fbm" : "ridged",
                    maxError / p.amplitude);
        EXPECT_NEAR(stddev(c) / stddev(e), 1.0, 0.1);
    }
}

TEST(Fractal, CachedFractalWithinDocumentedErrorAndTiles)
{
    for (FractalType type : {FractalType::Fbm, FractalType::Ridged}) {
        FractalParams p = fbm();
        p.type = type;
        p.cache = FractalCache::Fractal;
        Fractal cached(p);
        double tile = cached.tileSize();
        EXPECT_EQ(tile, kCachedFractalTileWavelengths * p.wavelength);
        double maxError = 0;
        std::mt19937_64 rng(9);
        std::uniform_real_distribution<double> uni(-600'000.0, 600'000.0);
        for (int i = 0; i < 100000; ++i) {
            double x = uni(rng);
            double y = uni(rng);
            maxError = std::max(maxError, std::abs(cached(x, y) - cached.uncachedValue(x, y)));
        }
        SCOPED_TRACE(type == FractalType::Fbm ? "fbm" : "ridged");
        EXPECT_LE(maxError,
                  (type == FractalType::Fbm ? kCachedFractalMaxErrorFbm : kCachedFractalMaxErrorRidged) * p.amplitude);
        std::printf("cached fractal %s: max error %.4f x amplitude\n", type == FractalType::Fbm ? "fbm" : "ridged",
                    maxError / p.amplitude);
        // The tileable reference repeats with the tile, seamlessly.
        for (int i = 0; i < 100; ++i) {
            double x = i * 1.37;
            EXPECT_NEAR(cached.uncachedValue(x, 3.0), cached.uncachedValue(x + tile, 3.0 - tile), 1e-9);
        }
    }
}

TEST(Fractal, BitmapBasisWrapsSeamlessly)
{
    auto bitmap = testBitmap();
    // One unit = the whole bitmap: wrapping by whole units gives the same value, and crossing the
    // bitmap's border is as smooth as its interior.
    for (int i = 0; i < 100; ++i) {
        double u = i * 0.0173;
        EXPECT_NEAR((*bitmap)(u, 0.3), (*bitmap)(u + 5.0, 0.3 - 2.0), 1e-6);
    }
    double maxStepAtBorder = 0;
    double maxStepInside = 0;
    for (int i = 0; i < 1000; ++i) {
        double v = i * 0.001;
        maxStepAtBorder = std::max(maxStepAtBorder, std::abs((*bitmap)(1.0 - 1e-4, v) - (*bitmap)(1.0, v)));
        maxStepInside = std::max(maxStepInside, std::abs((*bitmap)(0.5 - 1e-4, v) - (*bitmap)(0.5, v)));
    }
    EXPECT_LT(maxStepAtBorder, 0.01);
    EXPECT_LT(maxStepInside, 0.01);
}

TEST(Fractal, ParamsOutsideTheirRangesAreNamed)
{
    struct Bad {
        void (*change)(FractalParams&);
        const char* says;
    };
    const Bad bad[] = {
        {[](FractalParams& p) { p.octaves = 0; }, "octaves"},
        {[](FractalParams& p) { p.octaves = 25; }, "octaves"},
        {[](FractalParams& p) { p.lacunarity = 1.0; }, "lacunarity"},
        {[](FractalParams& p) { p.gain = 0.0; }, "gain"},
        {[](FractalParams& p) { p.gain = 1.5; }, "gain"},
        {[](FractalParams& p) { p.wavelength = 0.0; }, "wavelength"},
        {[](FractalParams& p) { p.amplitude = -1.0; }, "amplitude"},
        {[](FractalParams& p) { p.ridgeOffset = 2.0; }, "ridge offset"},
        {[](FractalParams& p) { p.ridgeFeedback = -1.0; }, "ridge feedback"},
    };
    EXPECT_EQ(validateFractalParams(FractalParams{}), "");
    for (const Bad& b : bad) {
        FractalParams p;
        b.change(p);
        EXPECT_NE(validateFractalParams(p).find(b.says), std::string::npos) << validateFractalParams(p);
    }
}

}  // namespace
}  // namespace terrain
