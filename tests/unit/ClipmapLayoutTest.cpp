// Seed 002's geometry clipmap layout (lod/ClipmapLayout.h) against brute force: the footprints cover each
// ring's cells once and leave exactly the finer window; windows nest with their perimeter on the coarser
// grid and follow the viewer; the toroidal updates are exactly the samples that entered; the transition
// weight is 1 on every perimeter and 0 where the finer ring takes over, and continuous as the viewer moves.
#include "lod/ClipmapLayout.h"

#include "MapTestSupport.h"
#include "quadtree/ChunkGeometry.h"

#include <gtest/gtest.h>
#include <cmath>
#include <set>

namespace terrain {
namespace {

/// A 65-sample-chunk map of 8 static levels at 10 m: root side 640 m x 128 = 81920 m.
QuadtreeExtent extent()
{
    return {-1000.0, 2000.0, 10.0 * 64 * 128};
}

/// Viewer positions: some random over the terrain and beyond, some on sample lattice points.
std::vector<std::pair<double, double>> viewers(int count)
{
    std::vector<std::pair<double, double>> out;
    for (int k = 0; k < count; ++k) {
        out.push_back({-3000.0 + 90000.0 * test::unitNoise(5, k, 0), 90000.0 * test::unitNoise(5, k, 1)});
    }
    out.push_back({-1000.0, 2000.0});
    out.push_back({-1000.0 + 10.0 * 37, 2000.0 + 10.0 * 1000});
    return out;
}

TEST(ClipmapLayoutTest, ValidSizesAreOneLessThanAPowerOfTwo)
{
    for (int n : {15, 31, 63, 127, 255, 511, 1023}) {
        EXPECT_TRUE(isValidClipmapSize(n)) << n;
    }
    for (int n : {0, 1, 3, 7, 16, 17, 254, 256, 2047, -1}) {
        EXPECT_FALSE(isValidClipmapSize(n)) << n;
    }
}

TEST(ClipmapLayoutTest, PiecesCoverEachRingCellOnceExceptTheFinerWindow)
{
    for (int n : {15, 31, 63, 255}) {
        for (auto [x, y] : viewers(12)) {
            ClipmapLayout layout(extent(), 65, n, 10, 6);
            layout.moveTo(x, y);
            for (int ring = 0; ring < layout.ringCount(); ++ring) {
                std::vector<int> count(static_cast<std::size_t>((n - 1) * (n - 1)), 0);
                int blocks = 0;
                for (const ClipmapPiece& piece : layout.pieces(ring)) {
                    blocks += piece.kind == ClipmapPieceKind::kBlock ? 1 : 0;
                    ASSERT_GE(piece.cells.x0, 0);
                    ASSERT_LE(piece.cells.x1, n - 1);
                    ASSERT_GE(piece.cells.y0, 0);
                    ASSERT_LE(piece.cells.y1, n - 1);
                    for (auto j = piece.cells.y0; j < piece.cells.y1; ++j) {
                        for (auto i = piece.cells.x0; i < piece.cells.x1; ++i) {
                            ++count[static_cast<std::size_t>(j * (n - 1) + i)];
                        }
                    }
                }
                EXPECT_EQ(blocks, ring == 0 ? 16 : 12);
                // The finer window, from its own origin: its cells lie in this ring's grid at half the index.
                LatticeRect finer;
                if (ring > 0) {
                    const ClipmapWindow& f = layout.window(ring - 1);
                    const ClipmapWindow& w = layout.window(ring);
                    finer = {f.x0 / 2 - w.x0, f.y0 / 2 - w.y0, (f.x0 + n - 1) / 2 - w.x0, (f.y0 + n - 1) / 2 - w.y0};
                    EXPECT_EQ(layout.hole(ring), finer);
                }
                for (int j = 0; j < n - 1; ++j) {
                    for (int i = 0; i < n - 1; ++i) {
                        ASSERT_EQ(count[static_cast<std::size_t>(j * (n - 1) + i)], finer.contains(i, j) ? 0 : 1)
                            << "n " << n << " ring " << ring << " cell (" << i << ", " << j << ")";
                    }
                }
            }
        }
    }
}

TEST(ClipmapLayoutTest, WindowsNestOnTheCoarserGridAndFollowTheViewer)
{
    const int n = 63, m = 16;
    for (auto [x, y] : viewers(40)) {
        ClipmapLayout layout(extent(), 65, n, 12, 3);
        layout.moveTo(x, y);
        for (int ring = 0; ring < layout.ringCount(); ++ring) {
            const ClipmapWindow& w = layout.window(ring);
            EXPECT_EQ(w.level, 12 - ring);
            // Even origins: the perimeter lies on the next coarser grid.
            EXPECT_EQ(w.x0 % 2, 0);
            EXPECT_EQ(w.y0 % 2, 0);
            // The viewer within one sample of the window's centre.
            const double s = layout.spacing(ring);
            EXPECT_NEAR(s, extent().rootSize / (64.0 * std::ldexp(1.0, w.level)), 1e-9);
            EXPECT_LE(std::abs((x - extent().originX) / s - (static_cast<double>(w.x0) + (n - 1) / 2.0)), 1.0 + 1e-9)
                << ring;
            EXPECT_LE(std::abs((y - extent().originY) / s - (static_cast<double>(w.y0) + (n - 1) / 2.0)), 1.0 + 1e-9)
                << ring;
            if (ring > 0) {
                // m - 1 or m coarse cells between the finer window and this one's perimeter on each side.
                const LatticeRect h = layout.hole(ring);
                for (auto lo : {h.x0, h.y0}) {
                    EXPECT_TRUE(lo == m - 1 || lo == m) << lo;
                }
            }
        }
    }
}

TEST(ClipmapLayoutTest, UpdatesAreExactlyTheSamplesThatEnteredEachWindow)
{
    const int n = 31;
    ClipmapLayout layout(extent(), 65, n, 9, 5);
    std::vector<ClipmapWindow> before;
    double x = 30000.0, y = 40000.0;
    for (int step = 0; step < 120; ++step) {
        // Mostly small moves, now and then a jump larger than a window.
        const double reach = step % 17 == 5 ? 20000.0 : 120.0;
        x += reach * (test::unitNoise(9, step, 0) - 0.5);
        y += reach * (test::unitNoise(9, step, 1) - 0.5);
        const auto updates = layout.moveTo(x, y);
        ASSERT_EQ(updates.size(), static_cast<std::size_t>(layout.ringCount()));
        for (int ring = 0; ring < layout.ringCount(); ++ring) {
            const ClipmapWindow& now = layout.window(ring);
            std::set<std::pair<std::int64_t, std::int64_t>> expected, got;
            for (std::int64_t j = now.y0; j < now.y0 + n; ++j) {
                for (std::int64_t i = now.x0; i < now.x0 + n; ++i) {
                    const bool old = step > 0 && i >= before[static_cast<std::size_t>(ring)].x0 &&
                                     i < before[static_cast<std::size_t>(ring)].x0 + n &&
                                     j >= before[static_cast<std::size_t>(ring)].y0 &&
                                     j < before[static_cast<std::size_t>(ring)].y0 + n;
                    if (!old) {
                        expected.insert({i, j});
                    }
                }
            }
            std::size_t total = 0;
            for (const LatticeRect& r : updates[static_cast<std::size_t>(ring)]) {
                ASSERT_FALSE(r.empty());
                total += static_cast<std::size_t>(r.area());
                for (auto j = r.y0; j < r.y1; ++j) {
                    for (auto i = r.x0; i < r.x1; ++i) {
                        got.insert({i, j});
                    }
                }
            }
            EXPECT_EQ(total, got.size()) << "step " << step << " ring " << ring << ": rectangles overlap";
            ASSERT_EQ(got, expected) << "step " << step << " ring " << ring;
        }
        before.assign(&layout.window(0), &layout.window(0) + layout.ringCount());
    }
    // Not moving updates nothing.
    for (const auto& rects : layout.moveTo(x, y)) {
        EXPECT_TRUE(rects.empty());
    }
}

TEST(ClipmapLayoutTest, ToroidalTexelsOfAnyWindowAreEachTexelOnce)
{
    const int n = 15;
    for (std::int64_t x0 :
         {std::int64_t{-40}, std::int64_t{-14}, std::int64_t{0}, std::int64_t{6}, std::int64_t{1000002}}) {
        std::vector<int> seen(n, 0);
        for (std::int64_t g = x0; g < x0 + n; ++g) {
            const int t = toroidalTexel(g, n);
            ASSERT_GE(t, 0);
            ASSERT_LT(t, n);
            ++seen[static_cast<std::size_t>(t)];
            EXPECT_EQ(t, toroidalTexel(g + 3 * n, n));
        }
        EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), n) << x0;
    }
}

TEST(ClipmapLayoutTest, BlendIsOneOnThePerimeterZeroWhereTheFinerRingMeetsItAndContinuous)
{
    for (int n : {15, 63, 255}) {
        for (auto [x, y] : viewers(15)) {
            ClipmapLayout layout(extent(), 65, n, 11, 7);
            layout.moveTo(x, y);
            for (int ring = 0; ring < layout.ringCount(); ++ring) {
                const ClipmapWindow& w = layout.window(ring);
                const bool coarsest = ring + 1 == layout.ringCount();
                for (std::int64_t k = 0; k < n; ++k) {
                    // The perimeter: the coarser ring's surface exactly.
                    for (auto [gx, gy] : {std::pair{w.x0 + k, w.y0},
                                          {w.x0 + k, w.y0 + n - 1},
                                          {w.x0, w.y0 + k},
                                          {w.x0 + n - 1, w.y0 + k}}) {
                        EXPECT_EQ(layout.blend(ring, static_cast<double>(gx), static_cast<double>(gy)),
                                  coarsest ? 0.0 : 1.0)
                            << "n " << n << " ring " << ring << " perimeter (" << gx << ", " << gy << ")";
                    }
                }
                if (ring == 0) {
                    continue;
                }
                // Where the finer ring's perimeter meets this ring: this ring's own samples.
                const LatticeRect h = layout.hole(ring);
                for (std::int64_t k = h.x0; k <= h.x1; ++k) {
                    for (auto [i, j] :
                         {std::pair{k, h.y0}, {k, h.y1}, {h.x0, k - h.x0 + h.y0}, {h.x1, k - h.x0 + h.y0}}) {
                        EXPECT_EQ(layout.blend(ring, static_cast<double>(w.x0 + i), static_cast<double>(w.y0 + j)), 0.0)
                            << "n " << n << " ring " << ring << " hole edge (" << i << ", " << j << ")";
                    }
                }
            }
            // Continuity: a step of the viewer changes no weight by more than the step over the width.
            ClipmapLayout moved = layout;
            const double step = 0.37;
            moved.moveTo(x + step, y - step);
            for (int ring = 0; ring + 1 < layout.ringCount(); ++ring) {
                if (moved.window(ring).x0 != layout.window(ring).x0 ||
                    moved.window(ring).y0 != layout.window(ring).y0) {
                    continue;  // the window shifted: compare where both have samples below
                }
                const ClipmapWindow& w = layout.window(ring);
                for (int k = 0; k < 200; ++k) {
                    const double gx = static_cast<double>(w.x0) + (n - 1) * test::unitNoise(3, k, 0);
                    const double gy = static_cast<double>(w.y0) + (n - 1) * test::unitNoise(3, k, 1);
                    const double limit = step / layout.spacing(ring) / layout.transitionWidth() * (1 + 1e-9);
                    EXPECT_LE(std::abs(moved.blend(ring, gx, gy) - layout.blend(ring, gx, gy)), limit);
                }
            }
        }
    }
}

TEST(ClipmapLayoutTest, FinerRingsAreSkippedAsTheViewerRises)
{
    ClipmapLayout layout(extent(), 65, 255, 12, 0);
    layout.moveTo(40000.0, 40000.0);
    EXPECT_EQ(layout.finestActiveRing(0.0), 0);
    int previous = 0;
    for (double h = 1.0; h < 1e7; h *= 1.7) {
        const int ring = layout.finestActiveRing(h);
        EXPECT_GE(ring, previous) << h;
        // Rings finer than the one chosen are less than 2.5 h across; the chosen one is not (unless coarsest).
        if (ring > 0) {
            EXPECT_LT(254 * layout.spacing(ring - 1), 2.5 * h);
        }
        if (ring + 1 < layout.ringCount()) {
            EXPECT_GE(254 * layout.spacing(ring), 2.5 * h);
        }
        previous = ring;
    }
    EXPECT_EQ(previous, layout.ringCount() - 1);
}

TEST(ClipmapLayoutTest, EverySampleMapsToTheNodeWhoseSquareHoldsIt)
{
    for (int chunk : {9, 65}) {
        for (int level : {0, 1, 3}) {
            const std::int64_t last = std::int64_t{chunk - 1} << level;
            for (std::int64_t gy = -3; gy <= last + 3; ++gy) {
                for (std::int64_t gx = -3; gx <= last + 3; gx += 1 + (gx > 2 && gx < last - 2 ? 5 : 0)) {
                    const NodeSample s = nodeSampleAt(level, gx, gy, chunk);
                    const std::int64_t cx = std::clamp<std::int64_t>(gx, 0, last);
                    const std::int64_t cy = std::clamp<std::int64_t>(gy, 0, last);
                    ASSERT_EQ(s.id.level, level);
                    ASSERT_LT(s.id.x, 1u << level);
                    ASSERT_LT(s.id.y, 1u << level);
                    EXPECT_EQ(std::int64_t{s.id.x} * (chunk - 1) + s.u - kBorder, cx) << gx << ", " << gy;
                    EXPECT_EQ(std::int64_t{s.id.y} * (chunk - 1) + s.v - kBorder, cy) << gx << ", " << gy;
                    EXPECT_GE(s.u, kBorder);
                    EXPECT_LE(s.u, kBorder + chunk - 1);
                    EXPECT_GE(s.v, kBorder);
                    EXPECT_LE(s.v, kBorder + chunk - 1);
                }
            }
        }
    }
}

}  // namespace
}  // namespace terrain
