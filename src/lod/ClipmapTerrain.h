// The data of geometry clipmap rings (seed 002), without GL: per ring an n x n toroidal array of heights
// and colours taken from the resident quadtree nodes of the ring's level (static nodes from the map, dynamic
// ones synthesized: the quadtree's own synthesis, so both LOD modes show the same terrain). A sample whose
// node is not resident yet is upsampled from the coarser ring (bilinear: seed 002's prediction without the
// residual) and filled again once the node arrives. What changed is kept as rectangles for the renderer to
// upload. Upsampled samples the viewer has seen change to their node's heights over morphSeconds once it
// arrives, from what was drawn before (heights, colours, sky visibility, material weights, normals: no pop as data
// streams in).
// Memory: 22 bytes per sample per ring (30 with material weights, plus 4 r^2 with normal maps), fixed by n and the
// ring count.
#pragma once

#include "lod/ClipmapLayout.h"
#include "lod/NodeData.h"

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

namespace terrain {

/// One ring's samples, toroidal: sample (gx, gy) of the window at texel (gx mod n, gy mod n), row-major.
struct ClipmapRing {
    std::vector<float> heights;  ///< metres above the map's height offset (as NodeData::heights)
    /// RGBA8, the nodes' textures at the samples; alpha the sun's visibility there (255 without shadows)
    std::vector<std::uint8_t> colour;
    std::vector<std::uint8_t> materials;  ///< RGBA8, the nodes' 4 material weights at the samples; or empty
    /// Per sample (current, previous): the sky's visibility at the samples (the nodes' horizons; 255 where a
    /// node has none), and what it was drawn as when the sample's morph started.
    std::vector<std::uint8_t> sky;
    /// The nodes' normal maps (NodeData::normalMap: x, y as RG8_SNORM) on a toroidal (r n)^2 texel grid, r texels
    /// a cell (normalTexelsPerCell), sample g's texel at r g mod r n; or empty.
    std::vector<std::int8_t> normals;
    /// Per sample (previous, since): the height drawn before the sample last changed in view and the time it
    /// changed (ClipmapTerrain::clock(), seconds from the first update; kNoMorph when it never did). The drawn
    /// height is heights once done = clamp((clock - since) / morphSeconds, 0, 1) is 1, else
    /// previous + (heights - previous) * done (drawnSample).
    std::vector<float> morph;
    /// What the colours, material weights and normal texels were drawn as when their sample's morph started
    /// (same layouts; drawn as previous + (current - previous) * the morph's fraction done).
    std::vector<std::uint8_t> previousColour;
    std::vector<std::uint8_t> previousMaterials;
    std::vector<std::int8_t> previousNormals;
    std::vector<LatticeRect> changed;  ///< level-grid samples changed since ClipmapTerrain::clearChanges()
    float zMin = 0.0f, zMax = 0.0f;    ///< over the window, heights and morphs' previous heights
    /// A node whose samples are upsampled for now, and the update time they were first upsampled at.
    struct Upsampled {
        NodeId id;
        double since = 0.0;
    };
    std::unordered_map<std::uint64_t, Upsampled> upsampled;  ///< by node key
};

/// The sun the rings' shadows are drawn for (radians, as light/Horizon.h measures them): direction angle from +x
/// towards +y, elevation.
struct ClipmapSun {
    double azimuth = 0.0;
    double elevation = 0.0;
};

/// ClipmapRing::morph's time of a sample that never changed in view (far in the past: its morph is over).
inline constexpr float kNoMorph = -1e30f;

class ClipmapTerrain {
public:
    /// Rings of `layout` (its size and count), nodes of `chunkSize` samples with `textureSize` texels a side.
    /// With `materials`, the rings keep the nodes' material weights too (for the detail textures); with
    /// `normalMapTexels` > 0, the nodes' normal maps of that many texels a side (dynamic_texture_size,
    /// normalMapTexels()), at r = max(1, (normalMapTexels - 1) / (chunkSize - 1)) texels a cell. Samples that
    /// were drawn upsampled morph to their node's heights over `morphSeconds` (clipmap_morph_seconds; 0 pops).
    /// With `sun`, the colours' alpha is the sun's visibility at the samples and ClipmapRing::sky the sky's (the
    /// nodes' horizons, NodeData::horizons; 1 where a node has none), blended and morphed with the colours;
    /// without, both are 1 (the viewer's shadows = false).
    ClipmapTerrain(const ClipmapLayout& layout, int chunkSize, int textureSize, bool materials = false,
                   int normalMapTexels = 0, double morphSeconds = 0.0, std::optional<ClipmapSun> sun = std::nullopt);

    /// After layout.moveTo() returned `entered`: fills the samples that entered each window and fills again
    /// the samples of nodes that became resident since they were upsampled (and, below a ring that changed,
    /// the upsampled samples of the finer rings), coarse rings first. `resident` gives a node's data or null.
    /// `now` is the viewer's clock (seconds, never decreasing; video mode: the frame's time): a sample
    /// upsampled at an earlier update has been drawn, so its change morphs from `now`; one upsampled and
    /// filled at the same time (a video frame's loading rounds) was never drawn and changes at once.
    void update(const ClipmapLayout& layout, const std::vector<std::vector<LatticeRect>>& entered,
                const ResidentNodeLookup& resident, double now = 0.0);

    /// The nodes the windows of rings `firstRing` and coarser need: each node of a ring's level whose square
    /// meets the ring's window (clamped to the terrain), coarse rings first.
    std::vector<NodeId> wanted(const ClipmapLayout& layout, int firstRing = 0) const;

    /// The surface of ring `ring` at world (x, y) metres, bilinear between its samples as drawn at the last
    /// update's time (morphs included; metres above the map's offset); the position is clamped to the window.
    double heightAt(const ClipmapLayout& layout, int ring, double x, double y) const;

    /// The surface ring `ring` draws at world (x, y) metres, as shaders/clipmap.vert makes it: each vertex's
    /// height blended towards the coarser ring's bilinear surface by its transition weight, linear on the
    /// triangles of its cells (south-west to north-east diagonals), at the last update's time. Metres above the
    /// map's offset; empty outside the ring's window.
    std::optional<double> ringSurface(const ClipmapLayout& layout, int ring, double x, double y) const;
    /// The drawn surface at (x, y) with rings `firstRing` and coarser drawn: the finest drawn ring whose window
    /// holds the point (ClipmapRenderer draws each ring where the finer one does not). Empty outside them all.
    std::optional<double> drawnHeight(const ClipmapLayout& layout, int firstRing, double x, double y) const;

    int ringCount() const { return static_cast<int>(mRings.size()); }
    /// Normal texels a cell of the rings (0 without normal maps).
    int normalTexelsPerCell() const { return mNormalPerCell; }
    const ClipmapRing& ring(int ring) const { return mRings[static_cast<std::size_t>(ring)]; }
    /// Ring `ring`'s rectangles changed since clearChanges(): what the renderer uploads, reading the rings
    /// without changing them.
    const std::vector<LatticeRect>& changed(int ring) const { return mRings[static_cast<std::size_t>(ring)].changed; }
    /// Starts a frame's changes: the viewer clears them before a frame's updates, the previous frame having
    /// drawn (uploaded) them.
    void clearChanges();
    /// Nodes whose samples are upsampled, over all rings.
    std::size_t upsampledNodes() const;
    /// Bytes the rings hold.
    std::size_t bytes() const;
    double morphSeconds() const { return mMorphSeconds; }
    /// The clock the morphs run on: seconds from the first update to the last one, in float as the shaders
    /// take it (uNow). Relative to the first update so that it keeps its precision however late a path starts.
    float clock() const { return mFirst ? 0.0f : static_cast<float>(mNow - mEpoch); }
    /// How far the morph of ring `ring`'s sample at texel `t` has gone now, in [0, 1] (as shaders/clipmap.vert).
    float morphDone(int ring, std::size_t t) const;
    /// Ring `ring`'s sample at toroidal texel `t` as drawn now (its morph applied; shaders/clipmap.vert does
    /// the same in float).
    float drawnSample(int ring, std::size_t t) const;

private:
    /// How fill() treats the morphs of the samples it writes.
    enum class Fill {
        kEntered,  ///< samples new to the window: no morph, whatever the texel held before
        kUnseen,   ///< samples never drawn as they were (upsampled in this update): changed ones at once
        kSeen,     ///< samples drawn as they were: changed ones (and ones not morphing) morph from what is drawn
    };
    /// Fills the samples of `rect` (level grid) of ring `r`, clipped to its window; records the change.
    void fill(const ClipmapLayout& layout, int r, LatticeRect rect, const ResidentNodeLookup& resident, Fill how);
    /// The sun's visibility at `node`'s N x N samples (sun, sky a sample) for mSun, derived once a node into
    /// `cache`; null without a sun or without the node's horizons.
    const std::vector<std::uint8_t>* sunVisibility(
        const NodeData* node, std::unordered_map<std::uint64_t, std::vector<std::uint8_t>>& cache) const;
    /// `node`'s bytes at its sample (u, v) (inner samples, 0 .. N - 1) into out: the colour (RGBA8: its nearest
    /// texel, and the sun's visibility there, `visibility`'s (sunVisibility) or 255), the sky's visibility (the
    /// same way), and with `materials` the material weights (RGBA8). Which of the three the node has (none
    /// without a node).
    std::array<bool, 3> nodeBytes(const NodeData* node, const std::vector<std::uint8_t>* visibility, int u, int v,
                                  bool materials, std::span<std::uint8_t> out) const;
    /// The normal texels of the samples of `rect` (level grid, within the window) of ring `r`; `state` is
    /// fill()'s per sample of `rect`: a restarted morph's fraction done before, or whether it was reset.
    void fillNormals(const ClipmapLayout& layout, int r, const LatticeRect& rect, const ResidentNodeLookup& resident,
                     const std::vector<float>& state);

    int mSamples;
    int mChunk;
    int mTexture;
    int mNormalTexels = 0;   ///< the nodes' normal map texels a side, 0 for none
    int mNormalPerCell = 0;  ///< r
    double mMorphSeconds = 0.0;
    std::optional<ClipmapSun> mSun;
    bool mFirst = true;   ///< no update yet
    double mEpoch = 0.0;  ///< the first update's time
    double mNow = 0.0;    ///< the last update's time
    std::vector<ClipmapRing> mRings;
};

}  // namespace terrain
