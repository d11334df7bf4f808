// Geometry clipmaps (seed 002: Asirvatham & Hoppe, GPU Gems 2 chapter 2, after Losasso & Hoppe 2004): the
// layout, without GL. Ring i (0 = finest) is an n x n window of the map's grid at quadtree level
// finest - i, nested in ring i + 1 with its outer perimeter on the coarser grid:
//   - window origins are even in their own level (so the perimeter lies on the next coarser grid); ring 0's
//     is the one nearest to centring the viewer, each coarser ring's the one of the two nesting offsets
//     (m - 1 or m coarse cells from the finer window) that keeps it even: the finer window is never centred,
//     it is one cell off on one side (seed 002, figure 2-4);
//   - a ring is drawn by the seed's footprints (m = (n + 1) / 4): twelve m x m blocks, four m x 3 ring
//     fix-ups and the L-shaped interior trim on the side where the finer window leaves a cell (ring 0: all
//     sixteen blocks and the centre cross);
//   - as the viewer moves, windows shift by whole (even) samples and only the samples that entered are
//     filled, addressed toroidally (2D wraparound: texel = sample mod n);
//   - a transition region of width w = n / 10 near each window's perimeter blends geometry (and normals)
//     to the next coarser ring: weight 0 inside, 1 on the perimeter, so neighbouring rings meet exactly.
#pragma once

#include "lod/LodSelector.h"
#include "quadtree/NodeId.h"

#include <cstdint>
#include <vector>

namespace terrain {

/// A half-open rectangle of integer lattice coordinates: [x0, x1) x [y0, y1).
struct LatticeRect {
    std::int64_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    bool empty() const { return x1 <= x0 || y1 <= y0; }
    bool contains(std::int64_t x, std::int64_t y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
    std::int64_t area() const { return empty() ? 0 : (x1 - x0) * (y1 - y0); }
    bool operator==(const LatticeRect&) const = default;
};

/// The seed's footprint kinds.
enum class ClipmapPieceKind { kBlock, kFixup, kTrim };

/// One footprint instance: the grid cells it triangulates, relative to its ring's window origin.
struct ClipmapPiece {
    ClipmapPieceKind kind = ClipmapPieceKind::kBlock;
    LatticeRect cells;
};

/// One ring's window: n x n samples of quadtree level `level` from sample (x0, y0) of that level's grid.
struct ClipmapWindow {
    int level = 0;
    std::int64_t x0 = 0, y0 = 0;
};

/// Smallest and largest clipmap sizes: n = 2^k - 1.
inline constexpr int kMinClipmapSamples = 15;
inline constexpr int kMaxClipmapSamples = 1023;
bool isValidClipmapSize(int samples);

class ClipmapLayout {
public:
    /// Rings for quadtree levels finestLevel (ring 0) down to coarsestLevel, n = `samples` per side
    /// (isValidClipmapSize), over `extent` whose nodes have `chunkSize` samples a side (spacing of level k:
    /// rootSize / ((chunkSize - 1) 2^k)). Preconditions checked: 0 <= coarsestLevel <= finestLevel <= 30.
    ClipmapLayout(const QuadtreeExtent& extent, int chunkSize, int samples, int finestLevel, int coarsestLevel);

    int samples() const { return mSamples; }
    /// m = (n + 1) / 4: a block's samples per side.
    int blockSamples() const { return (mSamples + 1) / 4; }
    /// w = n / 10 samples: the transition region's width (seed 002).
    int transitionWidth() const { return mSamples / 10; }
    int ringCount() const { return static_cast<int>(mWindows.size()); }
    const ClipmapWindow& window(int ring) const { return mWindows[static_cast<std::size_t>(ring)]; }
    /// Metres between ring `ring`'s samples.
    double spacing(int ring) const;
    /// World position (metres) of sample (gx, gy) of ring `ring`'s level grid.
    double worldX(int ring, double gx) const { return mExtent.originX + gx * spacing(ring); }
    double worldY(int ring, double gy) const { return mExtent.originY + gy * spacing(ring); }

    /// Places every window around the viewer at (x, y) metres. Returns per ring the samples (level grid
    /// coordinates) that entered its window since the last call, as disjoint rectangles covering exactly
    /// the new window minus the old: the whole window on the first call, nothing when it did not move.
    std::vector<std::vector<LatticeRect>> moveTo(double x, double y);

    /// The footprints drawing ring `ring`: together they cover each cell of its window once, except the cells
    /// of the finer ring's window (ring 0: every cell).
    std::vector<ClipmapPiece> pieces(int ring) const;
    /// The finer ring's window in ring `ring`'s cells, relative to its origin (ring 0: empty).
    LatticeRect hole(int ring) const;

    /// The transition weight of ring `ring` at its level-grid position (gx, gy) for the viewer at (x, y)
    /// metres (the last moveTo): 0 within the inner region, rising linearly over transitionWidth() samples to
    /// 1 on and beyond the window's perimeter (the coarsest ring: always 0, it has nothing to blend to).
    double blend(int ring, double gx, double gy) const;

    /// The finest ring worth drawing for a viewer `height` metres above the terrain: rings whose window
    /// is less than 2.5 x that height across are skipped (seed 002 disables finer levels as the viewer
    /// rises, their detail being sub-pixel and their window all below). 0 when close to the ground.
    int finestActiveRing(double height) const;

private:
    QuadtreeExtent mExtent;
    int mChunk;
    int mSamples;
    std::vector<ClipmapWindow> mWindows;
    bool mPlaced = false;
    double mViewerX = 0.0, mViewerY = 0.0;
};

/// Where sample (gx, gy) of quadtree level `level`'s grid is stored: the node holding it (nodes have
/// `chunkSize` samples a side and share their edges; a shared sample goes to the node east / north of it,
/// except on the grid's last row and column) and its window index (u, v) in that node's window (border
/// included: u = gx - node.x (N - 1) + kBorder). Samples outside the grid are clamped to it.
struct NodeSample {
    NodeId id;
    int u = 0, v = 0;
};
NodeSample nodeSampleAt(int level, std::int64_t gx, std::int64_t gy, int chunkSize);

/// The texel of lattice coordinate g in a toroidal (wrap-around) texture of n texels: g mod n in [0, n).
inline int toroidalTexel(std::int64_t g, int n)
{
    const std::int64_t r = g % n;
    return static_cast<int>(r < 0 ? r + n : r);
}

}  // namespace terrain
