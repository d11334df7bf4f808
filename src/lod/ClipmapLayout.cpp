// Seed 002's geometry clipmap layout (GPU Gems 2 chapter 2: clipmap size, footprints, toroidal updates,
// transition regions); see ClipmapLayout.h.
#include "lod/ClipmapLayout.h"

#include "core/Check.h"
#include "quadtree/ChunkGeometry.h"

#include <algorithm>
#include <cmath>

namespace terrain {

bool isValidClipmapSize(int samples)
{
    return samples >= kMinClipmapSamples && samples <= kMaxClipmapSamples && ((samples + 1) & samples) == 0;
}

ClipmapLayout::ClipmapLayout(const QuadtreeExtent& extent, int chunkSize, int samples, int finestLevel,
                             int coarsestLevel)
    : mExtent(extent), mChunk(chunkSize), mSamples(samples)
{
    TERRAIN_EXPECTS(isValidClipmapSize(samples), "clipmap samples must be 2^k - 1 in [15, 1023]");
    TERRAIN_EXPECTS(0 <= coarsestLevel && coarsestLevel <= finestLevel && finestLevel <= 30,
                    "clipmap levels must satisfy 0 <= coarsest <= finest <= 30");
    TERRAIN_EXPECTS(chunkSize >= 3, "chunks have at least 3 samples");
    for (int level = finestLevel; level >= coarsestLevel; --level) {
        mWindows.push_back({level, 0, 0});
    }
}

double ClipmapLayout::spacing(int ring) const
{
    return mExtent.rootSize / ((mChunk - 1) * std::ldexp(1.0, window(ring).level));
}

namespace {

/// The samples of window `now` not in window `before` (both n wide), as at most two disjoint rectangles.
std::vector<LatticeRect> entered(const ClipmapWindow& before, const ClipmapWindow& now, int n)
{
    const LatticeRect next{now.x0, now.y0, now.x0 + n, now.y0 + n};
    if (std::abs(now.x0 - before.x0) >= n || std::abs(now.y0 - before.y0) >= n) {
        return {next};
    }
    std::vector<LatticeRect> rects;
    // Columns that entered, over the new window's full height.
    LatticeRect columns = next;
    if (now.x0 > before.x0) {
        columns.x0 = before.x0 + n;
    } else {
        columns.x1 = before.x0;
    }
    if (!columns.empty()) {
        rects.push_back(columns);
    }
    // Rows that entered, over the columns both windows have.
    LatticeRect rows{std::max(now.x0, before.x0), next.y0, std::min(now.x0, before.x0) + n, next.y1};
    if (now.y0 > before.y0) {
        rows.y0 = before.y0 + n;
    } else {
        rows.y1 = before.y0;
    }
    if (!rows.empty()) {
        rects.push_back(rows);
    }
    return rects;
}

}  // namespace

std::vector<std::vector<LatticeRect>> ClipmapLayout::moveTo(double x, double y)
{
    const int n = mSamples, m = blockSamples();
    std::vector<ClipmapWindow> next = mWindows;
    for (int ring = 0; ring < ringCount(); ++ring) {
        ClipmapWindow& w = next[static_cast<std::size_t>(ring)];
        if (ring == 0) {
            // The even origin nearest to centring the viewer: it lies within one sample of the centre.
            const double vx = (x - mExtent.originX) / spacing(0), vy = (y - mExtent.originY) / spacing(0);
            w.x0 = 2 * static_cast<std::int64_t>(std::floor((vx - (n - 1) / 2.0) / 2.0 + 0.5));
            w.y0 = 2 * static_cast<std::int64_t>(std::floor((vy - (n - 1) / 2.0) / 2.0 + 0.5));
            continue;
        }
        // m - 1 or m coarse cells below the finer window, whichever is even.
        const ClipmapWindow& finer = next[static_cast<std::size_t>(ring - 1)];
        auto nest = [m](std::int64_t fine) {
            const std::int64_t c = fine / 2 - (m - 1);
            return (c & 1) == 0 ? c : c - 1;
        };
        w.x0 = nest(finer.x0);
        w.y0 = nest(finer.y0);
    }
    std::vector<std::vector<LatticeRect>> updates(mWindows.size());
    for (std::size_t ring = 0; ring < mWindows.size(); ++ring) {
        if (!mPlaced) {
            updates[ring] = {{next[ring].x0, next[ring].y0, next[ring].x0 + n, next[ring].y0 + n}};
        } else if (next[ring].x0 != mWindows[ring].x0 || next[ring].y0 != mWindows[ring].y0) {
            updates[ring] = entered(mWindows[ring], next[ring], n);
        }
    }
    mWindows = std::move(next);
    mPlaced = true;
    mViewerX = x;
    mViewerY = y;
    return updates;
}

LatticeRect ClipmapLayout::hole(int ring) const
{
    if (ring == 0) {
        return {};
    }
    const ClipmapWindow& w = window(ring);
    const ClipmapWindow& finer = window(ring - 1);
    const std::int64_t x = finer.x0 / 2 - w.x0, y = finer.y0 / 2 - w.y0;
    const std::int64_t side = (mSamples - 1) / 2;
    return {x, y, x + side, y + side};
}

std::vector<ClipmapPiece> ClipmapLayout::pieces(int ring) const
{
    const std::int64_t m = blockSamples();
    const std::int64_t b[4] = {0, m - 1, 2 * m, 3 * m - 1};  // block cell offsets, m - 1 cells each
    const std::int64_t f = 2 * m - 2;                        // the 2-cell fix-up gap
    std::vector<ClipmapPiece> out;
    auto add = [&](ClipmapPieceKind kind, std::int64_t x0, std::int64_t y0, std::int64_t w, std::int64_t h) {
        out.push_back({kind, {x0, y0, x0 + w, y0 + h}});
    };
    for (int j = 0; j < 4; ++j) {
        for (int i = 0; i < 4; ++i) {
            const bool inner = (i == 1 || i == 2) && (j == 1 || j == 2);
            if (ring == 0 || !inner) {
                add(ClipmapPieceKind::kBlock, b[i], b[j], m - 1, m - 1);
            }
        }
    }
    if (ring == 0) {
        // The centre cross: the fix-up column and row through every band, and their crossing.
        for (int j = 0; j < 4; ++j) {
            add(ClipmapPieceKind::kFixup, f, b[j], 2, m - 1);
            add(ClipmapPieceKind::kFixup, b[j], f, m - 1, 2);
        }
        add(ClipmapPieceKind::kFixup, f, f, 2, 2);
        return out;
    }
    add(ClipmapPieceKind::kFixup, f, b[0], 2, m - 1);
    add(ClipmapPieceKind::kFixup, f, b[3], 2, m - 1);
    add(ClipmapPieceKind::kFixup, b[0], f, m - 1, 2);
    add(ClipmapPieceKind::kFixup, b[3], f, m - 1, 2);
    // The interior trim: the inner 2m x 2m cells hold the finer window (2m - 1 cells) one cell off centre;
    // the L of cells it leaves, on the side it is away from.
    const LatticeRect inside = hole(ring);
    const std::int64_t tx = inside.x0 == m - 1 ? 3 * m - 2 : m - 1;
    const std::int64_t ty = inside.y0 == m - 1 ? 3 * m - 2 : m - 1;
    TERRAIN_ASSERT((inside.x0 == m - 1 || inside.x0 == m) && (inside.y0 == m - 1 || inside.y0 == m));
    add(ClipmapPieceKind::kTrim, tx, m - 1, 1, 2 * m);
    add(ClipmapPieceKind::kTrim, tx == m - 1 ? m : m - 1, ty, 2 * m - 1, 1);
    return out;
}

double ClipmapLayout::blend(int ring, double gx, double gy) const
{
    if (ring + 1 >= ringCount()) {
        return 0.0;
    }
    // Seed 002: alpha = clamp((|x - v| - ((n - 1) / 2 - w - 1)) / w, 0, 1) per axis, the larger: continuous
    // as the viewer moves, and 1 on the perimeter because the viewer stays within one sample of every
    // window's centre (ring 0 by placement, each coarser one within half a cell of the finer's centre).
    const double s = spacing(ring);
    const double vx = (mViewerX - mExtent.originX) / s, vy = (mViewerY - mExtent.originY) / s;
    const double w = transitionWidth();
    const double d = std::max(std::abs(gx - vx), std::abs(gy - vy));
    return std::clamp((d - ((mSamples - 1) / 2.0 - w - 1.0)) / w, 0.0, 1.0);
}

int ClipmapLayout::finestActiveRing(double height) const
{
    int ring = 0;
    while (ring + 1 < ringCount() && (mSamples - 1) * spacing(ring) < 2.5 * height) {
        ++ring;
    }
    return ring;
}

NodeSample nodeSampleAt(int level, std::int64_t gx, std::int64_t gy, int chunkSize)
{
    const std::int64_t cells = chunkSize - 1;
    const std::int64_t nodes = std::int64_t{1} << level;
    const std::int64_t last = cells * nodes;
    gx = std::clamp<std::int64_t>(gx, 0, last);
    gy = std::clamp<std::int64_t>(gy, 0, last);
    const std::int64_t nx = std::min(gx / cells, nodes - 1), ny = std::min(gy / cells, nodes - 1);
    return {{level, static_cast<std::uint32_t>(nx), static_cast<std::uint32_t>(ny)},
            static_cast<int>(gx - nx * cells) + kBorder,
            static_cast<int>(gy - ny * cells) + kBorder};
}

}  // namespace terrain
