// The data of geometry clipmap rings (seed 002), without GL: per ring an n x n toroidal array of heights
// and colours taken from the resident quadtree nodes of the ring's level (static nodes from the map, dynamic
// ones synthesized: the quadtree's own synthesis, so both LOD modes show the same terrain). A sample whose
// node is not resident yet is upsampled from the coarser ring (bilinear: seed 002's prediction without the
// residual) and filled again once the node arrives. What changed is kept as rectangles for the renderer to
// upload. Memory: 8 bytes per sample per ring (12 with material weights, plus 2 r^2 with normal maps), fixed
// by n and the ring count.
#pragma once

#include "lod/ClipmapLayout.h"
#include "lod/NodeData.h"

#include <cstdint>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

namespace terrain {

/// One ring's samples, toroidal: sample (gx, gy) of the window at texel (gx mod n, gy mod n), row-major.
struct ClipmapRing {
    std::vector<float> heights;           ///< metres above the map's height offset (as NodeData::heights)
    std::vector<std::uint8_t> colour;     ///< RGBA8 (alpha 255), the nodes' textures at the samples
    std::vector<std::uint8_t> materials;  ///< RGBA8, the nodes' 4 material weights at the samples; or empty
    /// The nodes' normal maps (NodeData::normalMap: x, y as RG8_SNORM) on a toroidal (r n)^2 texel grid, r texels
    /// a cell (normalTexelsPerCell), sample g's texel at r g mod r n; or empty.
    std::vector<std::int8_t> normals;
    std::vector<LatticeRect> changed;  ///< level-grid samples changed since the renderer last took them
    float zMin = 0.0f, zMax = 0.0f;    ///< over the window
    std::unordered_map<std::uint64_t, NodeId> upsampled;  ///< nodes (by key) whose samples are upsampled for now
};

class ClipmapTerrain {
public:
    /// Rings of `layout` (its size and count), nodes of `chunkSize` samples with `textureSize` texels a side.
    /// With `materials`, the rings keep the nodes' material weights too (for the detail textures); with
    /// `normalMapTexels` > 0, the nodes' normal maps of that many texels a side (dynamic_texture_size,
    /// normalMapTexels()), at r = max(1, (normalMapTexels - 1) / (chunkSize - 1)) texels a cell.
    ClipmapTerrain(const ClipmapLayout& layout, int chunkSize, int textureSize, bool materials = false,
                   int normalMapTexels = 0);

    /// After layout.moveTo() returned `entered`: fills the samples that entered each window and fills again
    /// the samples of nodes that became resident since they were upsampled (and, below a ring that changed,
    /// the upsampled samples of the finer rings), coarse rings first. `resident` gives a node's data or null.
    void update(const ClipmapLayout& layout, const std::vector<std::vector<LatticeRect>>& entered,
                const ResidentNodeLookup& resident);

    /// The nodes the windows of rings `firstRing` and coarser need: each node of a ring's level whose square
    /// meets the ring's window (clamped to the terrain), coarse rings first.
    std::vector<NodeId> wanted(const ClipmapLayout& layout, int firstRing = 0) const;

    /// The surface of ring `ring` at world (x, y) metres, bilinear between its samples (metres above the map's
    /// offset); the position is clamped to the ring's window.
    double heightAt(const ClipmapLayout& layout, int ring, double x, double y) const;

    /// The surface ring `ring` draws at world (x, y) metres, as shaders/clipmap.vert makes it: each vertex's
    /// height blended towards the coarser ring's bilinear surface by its transition weight, linear on the
    /// triangles of its cells (south-west to north-east diagonals). Metres above the map's offset; empty
    /// outside the ring's window.
    std::optional<double> ringSurface(const ClipmapLayout& layout, int ring, double x, double y) const;
    /// The drawn surface at (x, y) with rings `firstRing` and coarser drawn: the finest drawn ring whose window
    /// holds the point (ClipmapRenderer draws each ring where the finer one does not). Empty outside them all.
    std::optional<double> drawnHeight(const ClipmapLayout& layout, int firstRing, double x, double y) const;

    int ringCount() const { return static_cast<int>(mRings.size()); }
    /// Normal texels a cell of the rings (0 without normal maps).
    int normalTexelsPerCell() const { return mNormalPerCell; }
    const ClipmapRing& ring(int ring) const { return mRings[static_cast<std::size_t>(ring)]; }
    /// Takes ring `ring`'s changed rectangles (the renderer uploads them).
    std::vector<LatticeRect> takeChanged(int ring);
    /// Nodes whose samples are upsampled, over all rings.
    std::size_t upsampledNodes() const;
    /// Bytes the rings hold.
    std::size_t bytes() const;

private:
    /// Fills the samples of `rect` (level grid) of ring `r`, clipped to its window; records the change.
    void fill(const ClipmapLayout& layout, int r, LatticeRect rect, const ResidentNodeLookup& resident);
    /// The normal texels of the samples of `rect` (level grid, within the window) of ring `r`.
    void fillNormals(const ClipmapLayout& layout, int r, const LatticeRect& rect, const ResidentNodeLookup& resident);

    int mSamples;
    int mChunk;
    int mTexture;
    int mNormalTexels = 0;   ///< the nodes' normal map texels a side, 0 for none
    int mNormalPerCell = 0;  ///< r
    std::vector<ClipmapRing> mRings;
};

}  // namespace terrain
