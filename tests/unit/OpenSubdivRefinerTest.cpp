// OpenSubdiv as the oracle and as the alternative schemes of `detail_subdivision_scheme`: bilinear equals
// Kobbelt with omega = 0 at every child sample; Catmull-Clark is the tensor-product cubic B-spline rule
// (approximating: even samples move) and smooths; both keep shared samples of neighbouring children
// bit-identical and give the same bits on any number of threads in any order.
#include "synthesis/OpenSubdivRefiner.h"

#include "SubdivisionTestSupport.h"
#include "synthesis/KobbeltSubdivider.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace terrain {
namespace {

std::size_t idx(int x, int y, int w)
{
    return static_cast<std::size_t>(y) * w + x;
}

/// A parent window of rough heights: independent random values in [100, 1100) m.
std::vector<float> roughWindow(int chunkSize, std::uint32_t seed)
{
    const int w = windowSize(chunkSize);
    std::vector<float> window(static_cast<std::size_t>(w) * w);
    for (int y = 0; y < w; ++y) {
        for (int x = 0; x < w; ++x) {
            window[idx(x, y, w)] = static_cast<float>(100.0 + 1000.0 * test::unitNoise(seed, x, y));
        }
    }
    return window;
}

std::vector<float> refine(const Subdivider& subdivider, std::span<const float> parent, int quadrant)
{
    std::vector<float> child(parent.size());
    subdivider.subdivide(parent, quadrant, child);
    return child;
}

/// Parent window index of child window index c's sample (even c) or of the sample before it (odd c).
int parentIndex(int chunkSize, int q, int c)
{
    return 2 + q * (chunkSize - 1) / 2 + (c - 2 - ((c - 2) & 1)) / 2;
}

// ---- Bilinear: the oracle ----

TEST(OpenSubdivRefiner, BilinearEqualsKobbeltWithOmegaZeroAtEveryChildSample)
{
    // Both compute the exact average of 1, 2 or 4 parent samples (exact in double for these heights) and
    // round it to float once, so they agree bit for bit, borders included.
    for (int n : {3, 5, 9, 17, 65}) {
        OpenSubdivRefiner bilinear(n, OpenSubdivScheme::Bilinear);
        KobbeltSubdivider linear(n, 0.0);
        for (std::uint32_t seed : {1u, 2u}) {
            auto parent = roughWindow(n, seed);
            for (int q = 0; q < 4; ++q) {
                auto expected = refine(linear, parent, q);
                auto actual = refine(bilinear, parent, q);
                ASSERT_EQ(actual.size(), expected.size());
                for (std::size_t i = 0; i < actual.size(); ++i) {
                    ASSERT_EQ(actual[i], expected[i]) << "N " << n << " quadrant " << q << " sample " << i;
                }
            }
        }
    }
}

TEST(OpenSubdivRefiner, BilinearIsNotKobbelt)
{
    // The oracle must be able to fail: with omega = 1 the odd samples differ.
    const int n = 9;
    auto parent = roughWindow(n, 3);
    auto osd = refine(OpenSubdivRefiner(n, OpenSubdivScheme::Bilinear), parent, 0);
    auto kobbelt = refine(KobbeltSubdivider(n, 1.0), parent, 0);
    EXPECT_NE(osd, kobbelt);
}

// ---- Catmull-Clark ----

/// One regular Catmull-Clark step along one axis is cubic B-spline subdivision: an even sample takes
/// (1, 6, 1) / 8 of the parent sample and its neighbours, an odd one (1, 1) / 2 of the two around it.
double bsplineReference(std::span<const float> parent, int chunkSize, int quadrant, int cx, int cy)
{
    const int w = windowSize(chunkSize);
    auto taps = [&](int q, int c) {
        int p = parentIndex(chunkSize, q, c);
        std::vector<std::pair<int, double>> out;
        if ((c & 1) == 0) {
            out = {{p - 1, 1.0 / 8}, {p, 6.0 / 8}, {p + 1, 1.0 / 8}};
        } else {
            out = {{p, 0.5}, {p + 1, 0.5}};
        }
        return out;
    };
    double sum = 0.0;
    for (auto [y, wy] : taps(quadrant >> 1, cy)) {
        for (auto [x, wx] : taps(quadrant & 1, cx)) {
            sum += wx * wy * parent[idx(x, y, w)];
        }
    }
    return sum;
}

TEST(OpenSubdivRefiner, CatmullClarkIsTheCubicBSplineRuleAtEveryChildSample)
{
    for (int n : {3, 9, 65}) {
        const int w = windowSize(n);
        OpenSubdivRefiner catmark(n, OpenSubdivScheme::CatmullClark);
        auto parent = roughWindow(n, 4);
        for (int q = 0; q < 4; ++q) {
            auto child = refine(catmark, parent, q);
            double worst = 0.0;
            for (int cy = 0; cy < w; ++cy) {
                for (int cx = 0; cx < w; ++cx) {
                    worst = std::max(worst, std::abs(child[idx(cx, cy, w)] - bsplineReference(parent, n, q, cx, cy)));
                }
            }
            EXPECT_LT(worst, 1e-4) << "N " << n << " quadrant " << q;  // heights < 1100 m: float step 6e-5
        }
    }
}

TEST(OpenSubdivRefiner, CatmullClarkApproximatesAndSmooths)
{
    // Not interpolating: the parent's samples move (by design; see OpenSubdivRefiner.h). Smoother: on rough
    // data the largest second difference of a child is well below Kobbelt's, which keeps the parent's
    // samples and overshoots between them.
    const int n = 65;
    const int w = windowSize(n);
    auto parent = roughWindow(n, 5);
    auto catmark = refine(OpenSubdivRefiner(n, OpenSubdivScheme::CatmullClark), parent, 1);
    auto kobbelt = refine(KobbeltSubdivider(n, 1.0), parent, 1);
    int moved = 0;
    auto secondDifference = [&](const std::vector<float>& child) {
        double worst = 0.0;
        for (int y = 1; y + 1 < w; ++y) {
            for (int x = 1; x + 1 < w; ++x) {
                double h = child[idx(x, y, w)];
                worst = std::max({worst, std::abs(child[idx(x - 1, y, w)] - 2 * h + child[idx(x + 1, y, w)]),
                                  std::abs(child[idx(x, y - 1, w)] - 2 * h + child[idx(x, y + 1, w)])});
            }
        }
        return worst;
    };
    for (int cy = 0; cy < w; cy += 2) {
        for (int cx = 0; cx < w; cx += 2) {
            moved += catmark[idx(cx, cy, w)] != kobbelt[idx(cx, cy, w)] ? 1 : 0;  // Kobbelt's are the parent's
        }
    }
    EXPECT_GT(moved, (w / 2) * (w / 2) * 9 / 10);
    EXPECT_LT(secondDifference(catmark), 0.5 * secondDifference(kobbelt));
}

TEST(OpenSubdivRefiner, BothSchemesReproducePlanes)
{
    const int n = 17;
    const int w = windowSize(n);
    auto plane = [](double x, double y) { return 812.5 + 3.25 * x - 1.75 * y; };
    std::vector<float> parent(static_cast<std::size_t>(w) * w);
    for (int y = 0; y < w; ++y) {
        for (int x = 0; x < w; ++x) {
            parent[idx(x, y, w)] = static_cast<float>(plane(x, y));
        }
    }
    for (auto scheme : {OpenSubdivScheme::Bilinear, OpenSubdivScheme::CatmullClark}) {
        OpenSubdivRefiner refiner(n, scheme);
        for (int q = 0; q < 4; ++q) {
            auto child = refine(refiner, parent, q);
            for (int cy = 0; cy < w; ++cy) {
                for (int cx = 0; cx < w; ++cx) {
                    double x = 2 + (q & 1) * (n - 1) / 2 + (cx - 2) * 0.5;
                    double y = 2 + (q >> 1) * (n - 1) / 2 + (cy - 2) * 0.5;
                    ASSERT_EQ(child[idx(cx, cy, w)], static_cast<float>(plane(x, y)))
                        << "quadrant " << q << " child (" << cx << ", " << cy << ")";
                }
            }
        }
    }
}

// ---- Neighbours, threads, order ----

TEST(OpenSubdivRefiner, SiblingsAndCousinsAgreeBitForBitOnSharedSamples)
{
    for (auto scheme : {OpenSubdivScheme::Bilinear, OpenSubdivScheme::CatmullClark}) {
        for (int n : {5, 65}) {
            test::ParentBlock block(n, 4, test::roughHeights(12));
            OpenSubdivRefiner refiner(n, scheme);
            auto children = block.children(refiner, test::inOrder(block.jobCount()), 1);
            auto check = test::checkSharedSamples(block, children);
            EXPECT_EQ(check.compared, test::expectedSharedCount(block));
            EXPECT_EQ(check.mismatched, 0)
                << "scheme " << static_cast<int>(scheme) << " N " << n << ": " << check.firstMismatch;
        }
    }
}

TEST(OpenSubdivRefiner, SameBitsOnOneAndTwoThreadsInAnyOrder)
{
    const int n = 65;
    test::ParentBlock block(n, 3, test::roughHeights(6));
    for (auto scheme : {OpenSubdivScheme::Bilinear, OpenSubdivScheme::CatmullClark}) {
        OpenSubdivRefiner refiner(n, scheme);  // one refiner shared by both threads
        auto serial = block.children(refiner, test::inOrder(block.jobCount()), 1);
        auto threaded = block.children(refiner, test::scrambledOrder(block.jobCount(), 8), 2);
        for (std::size_t job = 0; job < serial.size(); ++job) {
            EXPECT_EQ(std::memcmp(serial[job].data(), threaded[job].data(), serial[job].size() * sizeof(float)), 0)
                << "scheme " << static_cast<int>(scheme) << " job " << job;
        }
    }
}

// ---- The factory ----

TEST(OpenSubdivRefiner, FactoryMakesBothSchemes)
{
    struct Case {
        const char* name;
        OpenSubdivScheme scheme;
    };
    for (auto [name, scheme] :
         {Case{"bilinear", OpenSubdivScheme::Bilinear}, Case{"catmull-clark", OpenSubdivScheme::CatmullClark}}) {
        auto subdivider = makeSubdivider(name, 17, 1.0);
        ASSERT_TRUE(subdivider.ok()) << subdivider.error().message;
        auto* refiner = dynamic_cast<const OpenSubdivRefiner*>(subdivider->get());
        ASSERT_NE(refiner, nullptr) << name;
        EXPECT_EQ(refiner->scheme(), scheme) << name;
        EXPECT_EQ(refiner->chunkSize(), 17) << name;
    }
    EXPECT_FALSE(makeSubdivider("catmull_clark", 17, 1.0).ok());
}

}  // namespace
}  // namespace terrain
