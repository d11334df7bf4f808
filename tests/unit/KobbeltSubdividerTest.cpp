// Kobbelt 4-point subdivision of node windows (paper 3.3.2, 3.4.3): even samples copied exactly, cubics and
// planes reproduced, the same geometry as the static nodes' integer predictor, values equal to a brute-force
// tensor-product reference, and bit-identical shared samples between siblings and cousins on any number of
// threads in any order.
#include "synthesis/KobbeltSubdivider.h"

#include "SubdivisionTestSupport.h"
#include "quadtree/HeightCodec.h"
#include "quadtree/MapFormat.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace terrain {
namespace {

std::size_t idx(int x, int y, int w)
{
    return static_cast<std::size_t>(y) * w + x;
}

/// A parent window of `height(window x, window y)`.
std::vector<float> makeWindow(int chunkSize, const std::function<double(double, double)>& height)
{
    const int w = windowSize(chunkSize);
    std::vector<float> window(static_cast<std::size_t>(w) * w);
    for (int y = 0; y < w; ++y) {
        for (int x = 0; x < w; ++x) {
            window[idx(x, y, w)] = static_cast<float>(height(x, y));
        }
    }
    return window;
}

/// Parent window position (x or y) of child window index c: p0 + (c - 2) / 2.
double parentPosition(int chunkSize, int q, int c)
{
    return 2 + q * (chunkSize - 1) / 2 + (c - 2) * 0.5;
}

std::vector<float> subdivide(std::span<const float> parent, int chunkSize, int quadrant, double omega)
{
    std::vector<float> child(parent.size());
    subdivideChildWindow(parent, chunkSize, quadrant, omega, child);
    return child;
}

constexpr int kChunkSizes[] = {3, 5, 9, 17, 65};
constexpr double kOmegas[] = {0.0, 0.5, 1.0, 2.0};

// ---- Interpolation ----

TEST(KobbeltSubdivider, EvenSamplesAreTheParentsSamplesExactly)
{
    for (int n : kChunkSizes) {
        const int w = windowSize(n);
        auto parent = makeWindow(n, [&](double x, double y) {
            return 100.0 + 1000.0 * test::unitNoise(7, static_cast<int>(x), static_cast<int>(y));
        });
        for (double omega : kOmegas) {
            for (int q = 0; q < 4; ++q) {
                auto child = subdivide(parent, n, q, omega);
                for (int cy = 0; cy < w; cy += 2) {
                    for (int cx = 0; cx < w; cx += 2) {
                        auto px = static_cast<int>(parentPosition(n, q & 1, cx));
                        auto py = static_cast<int>(parentPosition(n, q >> 1, cy));
                        ASSERT_EQ(std::memcmp(&child[idx(cx, cy, w)], &parent[idx(px, py, w)], sizeof(float)), 0)
                            << "N " << n << " omega " << omega << " quadrant " << q << " child (" << cx << ", " << cy
                            << ")";
                    }
                }
            }
        }
    }
}

TEST(KobbeltSubdivider, OmegaOneReproducesBicubicsAtEveryChildSample)
{
    // A tensor-product cubic: the 4-point rule with w = 1/16 reproduces cubics, so every odd sample lands on
    // the polynomial. Values stay within about +-3000 m, so float rounding of the parent (1.2e-4 m) times the
    // rule's gain (1.25 per axis) plus the child's own rounding stays below the tolerance.
    for (int n : {9, 65}) {
        const int w = windowSize(n);
        const double s = 1.0 / (w - 1);  // scale the window to [0, 1]
        auto cubic = [&](double x, double y) {
            double u = x * s - 0.4;
            double v = y * s - 0.55;
            double fx = 3.0 - 20.0 * u + 90.0 * u * u - 300.0 * u * u * u;
            double fy = 1.0 + 15.0 * v - 40.0 * v * v + 250.0 * v * v * v;
            return fx * fy + 50.0 * u * v;
        };
        auto parent = makeWindow(n, cubic);
        for (int q = 0; q < 4; ++q) {
            auto exact = subdivide(parent, n, q, 1.0);
            auto linear = subdivide(parent, n, q, 0.5);
            double worstExact = 0.0;
            double worstOther = 0.0;
            for (int cy = 0; cy < w; ++cy) {
                for (int cx = 0; cx < w; ++cx) {
                    double expected = cubic(parentPosition(n, q & 1, cx), parentPosition(n, q >> 1, cy));
                    worstExact = std::max(worstExact, std::abs(exact[idx(cx, cy, w)] - expected));
                    worstOther = std::max(worstOther, std::abs(linear[idx(cx, cy, w)] - expected));
                }
            }
            EXPECT_LT(worstExact, 1e-3) << "N " << n << " quadrant " << q;
            EXPECT_GT(worstOther, 1e-3) << "omega 0.5 must not reproduce cubics; N " << n << " quadrant " << q;
        }
    }
}

TEST(KobbeltSubdivider, EveryOmegaReproducesPlanes)
{
    const int n = 17;
    const int w = windowSize(n);
    auto plane = [](double x, double y) { return 812.5 + 3.25 * x - 1.75 * y; };
    auto parent = makeWindow(n, plane);
    for (double omega : kOmegas) {
        for (int q = 0; q < 4; ++q) {
            auto child = subdivide(parent, n, q, omega);
            for (int cy = 0; cy < w; ++cy) {
                for (int cx = 0; cx < w; ++cx) {
                    double expected = plane(parentPosition(n, q & 1, cx), parentPosition(n, q >> 1, cy));
                    // Dyadic coefficients: every value and partial sum is exact, so the result is too.
                    ASSERT_EQ(child[idx(cx, cy, w)], static_cast<float>(expected))
                        << "omega " << omega << " quadrant " << q << " child (" << cx << ", " << cy << ")";
                }
            }
        }
    }
}

TEST(KobbeltSubdivider, OmegaZeroIsTheMidpointRule)
{
    const int n = 9;
    const int w = windowSize(n);
    auto parent = makeWindow(n, [](double x, double y) { return 100.0 + 7.0 * x * x + 3.0 * x * y - y * y * y; });
    auto child = subdivide(parent, n, 3, 0.0);
    for (int cy = 1; cy < w; cy += 2) {
        for (int cx = 1; cx < w; cx += 2) {
            int px = static_cast<int>(parentPosition(n, 1, cx));  // the sample south-west of the face centre
            int py = static_cast<int>(parentPosition(n, 1, cy));
            double centre = (double{parent[idx(px, py, w)]} + parent[idx(px + 1, py, w)] + parent[idx(px, py + 1, w)] +
                             parent[idx(px + 1, py + 1, w)]) /
                            4.0;
            EXPECT_EQ(child[idx(cx, cy, w)], static_cast<float>(centre)) << "(" << cx << ", " << cy << ")";
        }
    }
}

// ---- The static nodes' predictor ----

TEST(KobbeltSubdivider, OmegaOneMatchesTheIntegerPredictorOfStaticNodes)
{
    // Fed the same 16-bit codes, the float rule equals HeightCodec's predictChildWindow before its rounding
    // to the nearest code: within half a code (plus a float step at 65535, 2^-8).
    for (int n : {9, 65}) {
        const int w = windowSize(n);
        for (std::uint32_t seed : {1u, 2u, 3u}) {
            std::vector<std::uint16_t> codes(static_cast<std::size_t>(w) * w);
            std::vector<float> heights(codes.size());
            for (int y = 0; y < w; ++y) {
                for (int x = 0; x < w; ++x) {
                    auto code = seed == 3u ? static_cast<std::uint16_t>(((x + y) & 1) ? 65535 : 0)  // worst overshoot
                                           : static_cast<std::uint16_t>(test::hashNoise(seed, x, y) & 0xffff);
                    codes[idx(x, y, w)] = code;
                    heights[idx(x, y, w)] = code;
                }
            }
            for (int q = 0; q < 4; ++q) {
                std::vector<std::int32_t> predicted(codes.size());
                predictChildWindow(codes, w, n, q, predicted);
                auto child = subdivide(heights, n, q, 1.0);
                double worst = 0.0;
                for (std::size_t i = 0; i < child.size(); ++i) {
                    worst = std::max(worst, std::abs(double{child[i]} - predicted[i]));
                }
                EXPECT_LE(worst, 0.5 + 1.0 / 256) << "N " << n << " seed " << seed << " quadrant " << q;
            }
        }
    }
}

// ---- Neighbours, threads, order ----

/// The tensor-product rule at child grid position (gx, gy) of the block, summed directly over the 4 x 4
/// parent samples (a reference written from the formula, not from the separable code under test).
double referenceAt(const test::ParentBlock& block, int gx, int gy, double omega)
{
    auto taps = [&](int g) {
        std::vector<std::pair<int, double>> out;
        if (g % 2 == 0) {
            out.emplace_back(g / 2, 1.0);
        } else {
            int m = (g - 1) / 2;  // g = 2m + 1, m may be negative: g - 1 is even
            double wgt = omega / 16;
            out = {{m - 1, -wgt}, {m, 0.5 + wgt}, {m + 1, 0.5 + wgt}, {m + 2, -wgt}};
        }
        return out;
    };
    double sum = 0.0;
    for (auto [y, wy] : taps(gy)) {
        for (auto [x, wx] : taps(gx)) {
            sum += wx * wy * block.heightAt(x, y);
        }
    }
    return sum;
}

TEST(KobbeltSubdivider, SiblingsAndCousinsAgreeBitForBitOnSharedSamples)
{
    for (int n : {5, 17, 65}) {
        for (double omega : {1.0, 0.7, 0.0}) {
            test::ParentBlock block(n, 4, test::roughHeights(11));
            KobbeltSubdivider subdivider(n, omega);
            auto children = block.children(subdivider, test::inOrder(block.jobCount()), 1);
            auto check = test::checkSharedSamples(block, children);
            EXPECT_EQ(check.compared, test::expectedSharedCount(block));
            EXPECT_GT(check.compared, 0);
            EXPECT_EQ(check.mismatched, 0) << "N " << n << " omega " << omega << ": " << check.firstMismatch;

            // And the shared values are the right ones.
            const int w = block.windowSize();
            double worst = 0.0;
            block.forEachChildSample([&](int job, int cx, int cy, int gx, int gy) {
                double expected = referenceAt(block, gx, gy, omega);
                worst = std::max(worst, std::abs(children[static_cast<std::size_t>(job)][idx(cx, cy, w)] - expected));
            });
            EXPECT_LT(worst, 2e-4) << "N " << n << " omega " << omega;  // heights < 1400 m: float step 1.2e-4
        }
    }
}

TEST(KobbeltSubdivider, SameBitsOnOneAndTwoThreadsInAnyOrder)
{
    const int n = 65;
    test::ParentBlock block(n, 3, test::roughHeights(5));
    KobbeltSubdivider subdivider(n, 1.0);
    auto serial = block.children(subdivider, test::inOrder(block.jobCount()), 1);
    auto scrambled = block.children(subdivider, test::scrambledOrder(block.jobCount(), 9), 1);
    auto threaded = block.children(subdivider, test::scrambledOrder(block.jobCount(), 4), 2);
    for (std::size_t job = 0; job < serial.size(); ++job) {
        const auto bytes = serial[job].size() * sizeof(float);
        EXPECT_EQ(std::memcmp(serial[job].data(), scrambled[job].data(), bytes), 0) << "job " << job;
        EXPECT_EQ(std::memcmp(serial[job].data(), threaded[job].data(), bytes), 0) << "job " << job;
    }
}

// ---- The interface ----

TEST(KobbeltSubdivider, FactoryMakesKobbeltWithOmega)
{
    auto subdivider = makeSubdivider("kobbelt", 9, 0.25);
    ASSERT_TRUE(subdivider.ok()) << subdivider.error().message;
    auto* kobbelt = dynamic_cast<const KobbeltSubdivider*>(subdivider->get());
    ASSERT_NE(kobbelt, nullptr);
    EXPECT_EQ(kobbelt->chunkSize(), 9);
    EXPECT_EQ(kobbelt->omega(), 0.25);

    auto parent = makeWindow(9, [](double x, double y) { return std::sin(x) * 40.0 + y * y; });
    std::vector<float> child(parent.size());
    (*subdivider)->subdivide(parent, 2, child);
    EXPECT_EQ(child, subdivide(parent, 9, 2, 0.25));
}

TEST(KobbeltSubdivider, FactoryNamesAnUnknownScheme)
{
    auto subdivider = makeSubdivider("Kobbelt-ish", 65, 1.0);
    ASSERT_FALSE(subdivider.ok());
    const auto& message = subdivider.error().message;
    EXPECT_NE(message.find("detail_subdivision_scheme"), std::string::npos) << message;
    EXPECT_NE(message.find("'Kobbelt-ish'"), std::string::npos) << message;
    EXPECT_NE(message.find("kobbelt, bilinear or catmull-clark"), std::string::npos) << message;
    EXPECT_FALSE(makeSubdivider("", 65, 1.0).ok());
}

TEST(KobbeltSubdividerDeathTest, WrongWindowSizeIsAPreconditionFailure)
{
    std::vector<float> parent(static_cast<std::size_t>(windowSize(9)) * windowSize(9), 0.0f);
    std::vector<float> child(parent.size() - 1);
    EXPECT_DEATH(subdivideChildWindow(parent, 9, 0, 1.0, child), "W\\*W");
    std::vector<float> full(parent.size());
    EXPECT_DEATH(subdivideChildWindow(parent, 8, 0, 1.0, full), "2\\^k \\+ 1");
    EXPECT_DEATH(subdivideChildWindow(parent, 9, 4, 1.0, full), "quadrant");
}

}  // namespace
}  // namespace terrain
