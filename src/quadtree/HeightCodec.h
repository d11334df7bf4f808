// Static heights on disk (docs/design.md, "Static heights on disk"): each node is coded as the residual
// from the Kobbelt 4-point prediction of its parent (quadtree/FourPointSubdivision.h with omega = 1: weights
// -1/16, 9/16, 9/16, -1/16 in each direction, tensor product), so static and dynamic nodes are two cases of
// one step: parent -> subdivide -> add.
//
// A node's heights form a window of W = N + 2 * kBorder samples per side, 16-bit codes, row-major with
// rows running south to north. Window samples outside the terrain grid are never stored: they are the
// point reflection of the samples inside (2 h(edge) - h(mirror), clamped to 16 bits), which keeps the
// surface's slope across the terrain edge and is the same at every level.
#pragma once

#include "core/Expected.h"
#include "quadtree/MapFormat.h"

#include <cstdint>
#include <span>
#include <vector>

namespace terrain {

/// Inclusive range of window indices (both axes) whose samples lie inside the terrain grid.
struct WindowRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    bool contains(int x, int y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
};

/// The window geometry of nodes of one map.
class NodeWindow {
public:
    explicit NodeWindow(const MapHeader& header);

    int chunkSize() const { return mChunk; }
    int size() const { return mSize; }  ///< W = N + 2 * kBorder
    std::size_t sampleCount() const { return static_cast<std::size_t>(mSize) * mSize; }
    /// The part of `id`'s window inside the grid of its level (static levels only).
    WindowRect insideRect(const NodeId& id) const;

private:
    const MapHeader* mHeader;
    int mChunk;
    int mSize;
};

/// Overwrites the window samples outside `inside` with the point reflection of the inside samples
/// (x first, then y), clamped to [0, 65535].
void fillOutside(std::span<std::uint16_t> window, int size, const WindowRect& inside);

/// The Kobbelt 4-point prediction of child `quadrant`'s whole window from its parent's window
/// (subdivideFourPoint in integers, omega = 1), rounded to the nearest code (ties up). Even-even samples
/// equal the parent's samples exactly. `size` is windowSize(chunkSize); `out` has size*size.
void predictChildWindow(std::span<const std::uint16_t> parent, int size, int chunkSize, int quadrant,
                        std::span<std::int32_t> out);

/// Codes a node's heights. `window` holds the node's samples (outside ones ignored); for a non-root node
/// `parent` is its parent's decoded window, and every residual (window - prediction) at a coded sample must
/// be a multiple of `bin` (the builder reconstructs the grid so that it is). Returns the payload's height
/// stream: u32 raw size, then zlib of zigzag varints.
std::vector<std::uint8_t> encodeNodeHeights(const NodeWindow& geometry, const NodeId& id,
                                            std::span<const std::uint16_t> window,
                                            std::span<const std::uint16_t> parent, std::uint32_t bin,
                                            int zlibLevel = 4);

/// Decodes a node's height stream into `window` (size*size codes, outside samples filled by reflection).
/// `parent` is the parent's decoded window (empty for the root). Errors say what was wrong with the
/// stream; callers prefix the file and node.
Status decodeNodeHeights(const NodeWindow& geometry, const NodeId& id, std::span<const std::uint8_t> stream,
                         std::span<const std::uint16_t> parent, std::uint32_t bin, std::span<std::uint16_t> window);

/// Root samples are predicted from the previous sample in raster order (left; first column: below).
/// The builder uses this to reconstruct lossy root samples the way the decoder will.
inline std::int32_t rootPrediction(std::span<const std::uint16_t> window, int size, const WindowRect& inside, int x,
                                   int y)
{
    if (x > inside.x0) {
        return window[static_cast<std::size_t>(y) * size + x - 1];
    }
    if (y > inside.y0) {
        return window[static_cast<std::size_t>(y - 1) * size + x];
    }
    return 0;
}

/// Nearest multiple of `bin` (odd) to `residual`: the dead-zone-free uniform quantizer whose reconstruction
/// error is at most (bin - 1) / 2 codes.
inline std::int32_t quantizeResidual(std::int32_t residual, std::uint32_t bin)
{
    auto b = static_cast<std::int32_t>(bin);
    std::int32_t half = (b - 1) / 2;
    std::int32_t shifted = residual + half;
    std::int32_t q = shifted >= 0 ? shifted / b : -((-shifted + b - 1) / b);
    return q * b;
}

}  // namespace terrain
