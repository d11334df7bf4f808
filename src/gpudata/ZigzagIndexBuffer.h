// The zigzag index order of the template mesh (paper 3.2.10, figures 3.6 and 3.7), tuned by
// `vertex_cache_size` (Appendix A): the grid is cut into vertical bands a little under half the vertex
// cache wide, and each band is drawn row by row so that every vertex is transformed about once (ACMR
// near (w + 1) / (2 w) for bands of w quads). Pure CPU code: no GL here, the renderer uploads the result.
//
// Order, for chunk size N (Q = N - 1 quads per side) and band width w:
//   - bands from west to east, ceil(Q / w) of them, widths balanced (they differ by at most one quad);
//   - even bands (0, 2, ...) run south to north, odd bands north to south, so a band starts where the
//     previous one ended and the column they share is still cached;
//   - rows of a northbound band run east to west, rows of a southbound band west to east. With the
//     SW-NE diagonal a row's strip starts with its south vertex going west and its north vertex going
//     east: either way with the row already cached, which is what keeps the first row of a band cheap;
//   - the triangle list is exactly the strip's triangles, in the same order and vertex rotation;
//   - skirts last: one quad per edge segment, once around the ring (TemplateMesh.h), so each edge vertex
//     and its skirt duplicate are used twice in a row.
// Every grid quad (i, j)-(i+1, j+1) is split along its south-west to north-east diagonal
// (quadtree/TemplateTriangulation.h); all triangles are counter-clockwise seen from above (+z), skirt
// triangles counter-clockwise seen from outside the chunk.
#pragma once

#include <cstdint>
#include <vector>

namespace terrain {

/// Smallest `vertex_cache_size` the zigzag is defined for (vertices): a band one quad wide needs
/// kBandCacheEntriesPerQuad * 1 + kBandCacheReserve of them.
constexpr int kMinVertexCacheSize = 4;

/// Band width rule: w = (vertex_cache_size - kBandCacheReserve) / kBandCacheEntriesPerQuad quads.
/// Reason: the first row of a band loads both of its vertex rows, 2 (w + 1) vertices, and all of the
/// upper row must still be in a FIFO cache when the second row starts; after that a row needs only
/// w + 1 entries. One quad wider and the upper row is lost, every later row misses again and ACMR jumps
/// (0.586 -> 1.125 at FIFO 16 for w = 8). Narrower bands only reload more band edges.
/// How produced: meshopt_analyzeVertexCache (FIFO of the tuned size, no warps), 65 x 65 grid without
/// skirts, every band width 1..64 tried (the test ZigzagIndexBuffer.BandWidthRuleIsBestMeasured keeps
/// this true). Rule vs best:
///   FIFO   rule w   ACMR     best w   best ACMR
///     4      1     1.0079      1       1.0079
///     8      3     0.6798      3       0.6798
///    12      5     0.6095      5       0.6095
///    16      7     0.5861      7       0.5861
///    24     11     0.5548     11       0.5548
///    32     15     0.5470     13       0.5470   (13..15 all give 5 bands)
///    48     23     0.5314     22       0.5314   (22..31 all give 3 bands)
///    64     31     0.5314     22       0.5314
/// For comparison at FIFO 16: row-major order 1.016, meshopt_optimizeVertexCache 0.633.
constexpr int kBandCacheEntriesPerQuad = 2;  ///< vertices per quad of band width: the band's two rows
constexpr int kBandCacheReserve = 2;         ///< vertices: each row has w + 1 vertices, not w

/// Band width (quads) for a FIFO vertex cache of `vertexCacheSize` entries; >= 1, not yet clamped to
/// the chunk. Precondition: vertexCacheSize >= kMinVertexCacheSize (the config reader checks the
/// user's value and reports an error before it gets here).
int zigzagBandWidth(int vertexCacheSize);

enum class ZigzagPrimitive {
    kTriangleList,   ///< 3 indices per triangle
    kTriangleStrip,  ///< one strip joined by degenerate triangles (figure 3.7); GL_TRIANGLE_STRIP, no restart
};

/// Indexed triangle list of the template mesh in zigzag order for `vertexCacheSize`, indices into
/// buildTemplateMesh(chunkSize).vertices: the 2 (N - 1)^2 grid triangles, then with `withSkirts` the
/// 8 (N - 1) skirt triangles. Preconditions: isValidChunkSize(chunkSize),
/// vertexCacheSize >= kMinVertexCacheSize.
std::vector<std::uint32_t> buildZigzagIndices(int chunkSize, int vertexCacheSize, bool withSkirts);

/// The same triangles as buildZigzagIndices, in the same order and winding, as a single triangle strip
/// (even triangles (s[k], s[k+1], s[k+2]), odd ones (s[k+1], s[k], s[k+2]), as GL draws them) with
/// degenerate triangles joining the rows, bands and the skirt ring. Same preconditions.
std::vector<std::uint32_t> buildZigzagStrip(int chunkSize, int vertexCacheSize, bool withSkirts);

/// The zigzag with an explicit band width in quads (clamped to N - 1), for measurements.
/// Preconditions: isValidChunkSize(chunkSize), bandWidth >= 1.
std::vector<std::uint32_t> buildBandedIndices(int chunkSize, int bandWidth, ZigzagPrimitive primitive, bool withSkirts);

/// Index width the renderer should upload.
enum class IndexType {
    kUint16,  ///< GL_UNSIGNED_SHORT: every index fits in 16 bits (chunk sizes up to 129 with skirts)
    kUint32,  ///< GL_UNSIGNED_INT
};

/// The narrowest index type that addresses `vertexCount` vertices.
IndexType indexTypeFor(std::uint64_t vertexCount);

/// `indices` as 16-bit indices. Precondition: every index <= 65535 (indexTypeFor gave kUint16).
std::vector<std::uint16_t> narrowIndices(const std::vector<std::uint32_t>& indices);

}  // namespace terrain
