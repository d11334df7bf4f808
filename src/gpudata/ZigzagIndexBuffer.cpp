// Zigzag index buffer (paper 3.2.10, figures 3.6 and 3.7): vertex-cache-sized bands, rows inside each
// band, SW-NE diagonals (quadtree/TemplateTriangulation.h), skirts (3.2.6) around the ring. The list and
// the strip are generated separately from the same band plan; the tests check they agree triangle by
// triangle.
#include "gpudata/ZigzagIndexBuffer.h"

#include "core/Check.h"
#include "gpudata/TemplateMesh.h"

#include <algorithm>
#include <limits>

namespace terrain {
namespace {

struct Band {
    int c0 = 0;         ///< westmost column of the band's quads
    int width = 0;      ///< quads
    bool north = true;  ///< rows run south to north (then east to west within a row)
};

/// ceil(quads / maxWidth) bands, widths balanced, alternating north- and southbound.
std::vector<Band> planBands(int quads, int maxWidth)
{
    const int count = (quads + maxWidth - 1) / maxWidth;
    std::vector<Band> bands;
    int c0 = 0;
    for (int b = 0; b < count; ++b) {
        const int width = quads / count + (b < quads % count ? 1 : 0);
        bands.push_back({c0, width, b % 2 == 0});
        c0 += width;
    }
    TERRAIN_ASSERT(c0 == quads);
    return bands;
}

/// Calls row(j, c0, width, east) for every row of every band in drawing order.
template <class RowFn>
void forEachRow(int chunkSize, int bandWidth, RowFn&& row)
{
    const int quads = chunkSize - 1;
    for (const Band& band : planBands(quads, std::min(bandWidth, quads))) {
        for (int r = 0; r < quads; ++r) {
            const int j = band.north ? r : quads - 1 - r;
            row(j, band.c0, band.width, !band.north);
        }
    }
}

/// Appends `run` to `strip`, joined by degenerate triangles so that run[0] starts an even (unflipped)
/// triangle: ..., x, x, [x,] r0, r0, r1, ... Every window of three in the joint repeats an index.
void appendRun(std::vector<std::uint32_t>& strip, const std::vector<std::uint32_t>& run)
{
    if (!strip.empty()) {
        const std::uint32_t last = strip.back();
        strip.push_back(last);
        if (strip.size() % 2 == 0) {
            strip.push_back(last);
        }
        strip.push_back(run.front());
    }
    strip.insert(strip.end(), run.begin(), run.end());
}

void appendSkirtList(int n, std::vector<std::uint32_t>& out)
{
    const int ring = skirtRingLength(n);
    for (int a = 0; a < ring; ++a) {
        const int b = (a + 1) % ring;
        const GridCoord ca = skirtRingCoord(n, a);
        const GridCoord cb = skirtRingCoord(n, b);
        const std::uint32_t ea = gridVertexIndex(n, ca.i, ca.j);
        const std::uint32_t eb = gridVertexIndex(n, cb.i, cb.j);
        const std::uint32_t sa = skirtVertexIndex(n, a);
        const std::uint32_t sb = skirtVertexIndex(n, b);
        // The ring runs counter-clockwise seen from above, so the outside is to the right of a -> b:
        // (e_a, s_a, e_b) and (e_b, s_a, s_b) are counter-clockwise seen from there.
        out.insert(out.end(), {ea, sa, eb, eb, sa, sb});
    }
}

std::vector<std::uint32_t> skirtStripRun(int n)
{
    const int ring = skirtRingLength(n);
    std::vector<std::uint32_t> run;
    run.reserve(2 * static_cast<std::size_t>(ring + 1));
    for (int p = 0; p <= ring; ++p) {
        const int q = p % ring;
        const GridCoord c = skirtRingCoord(n, q);
        run.push_back(gridVertexIndex(n, c.i, c.j));
        run.push_back(skirtVertexIndex(n, q));
    }
    return run;
}

std::vector<std::uint32_t> buildList(int n, int bandWidth, bool withSkirts)
{
    std::vector<std::uint32_t> out;
    out.reserve(3 * templateTriangleCount(n, withSkirts));
    forEachRow(n, bandWidth, [&](int j, int c0, int width, bool east) {
        for (int k = 0; k < width; ++k) {
            const int i = east ? c0 + k : c0 + width - 1 - k;
            const std::uint32_t sw = gridVertexIndex(n, i, j);
            const std::uint32_t se = gridVertexIndex(n, i + 1, j);
            const std::uint32_t ne = gridVertexIndex(n, i + 1, j + 1);
            const std::uint32_t nw = gridVertexIndex(n, i, j + 1);
            // Both halves of the quad share the SW-NE diagonal; order and rotation as the strip has them.
            if (east) {
                out.insert(out.end(), {nw, sw, ne, ne, sw, se});
            } else {
                out.insert(out.end(), {se, ne, sw, sw, ne, nw});
            }
        }
    });
    if (withSkirts) {
        appendSkirtList(n, out);
    }
    TERRAIN_ASSERT(out.size() == 3 * templateTriangleCount(n, withSkirts));
    return out;
}

std::vector<std::uint32_t> buildStrip(int n, int bandWidth, bool withSkirts)
{
    std::vector<std::uint32_t> strip;
    std::vector<std::uint32_t> run;
    forEachRow(n, bandWidth, [&](int j, int c0, int width, bool east) {
        // Going east a row is north, south, north, ... (first triangle NW, SW, NE); going west it is
        // south, north, ... from the east end (first triangle SE, NE, SW). Both put the diagonal SW-NE.
        run.clear();
        for (int k = 0; k <= width; ++k) {
            const int i = east ? c0 + k : c0 + width - k;
            const std::uint32_t south = gridVertexIndex(n, i, j);
            const std::uint32_t north = gridVertexIndex(n, i, j + 1);
            if (east) {
                run.insert(run.end(), {north, south});
            } else {
                run.insert(run.end(), {south, north});
            }
        }
        appendRun(strip, run);
    });
    if (withSkirts) {
        appendRun(strip, skirtStripRun(n));
    }
    return strip;
}

}  // namespace

int zigzagBandWidth(int vertexCacheSize)
{
    TERRAIN_EXPECTS(vertexCacheSize >= kMinVertexCacheSize, "vertex cache size must be at least 4 entries");
    return (vertexCacheSize - kBandCacheReserve) / kBandCacheEntriesPerQuad;
}

std::vector<std::uint32_t> buildZigzagIndices(int chunkSize, int vertexCacheSize, bool withSkirts)
{
    return buildBandedIndices(chunkSize, zigzagBandWidth(vertexCacheSize), ZigzagPrimitive::kTriangleList, withSkirts);
}

std::vector<std::uint32_t> buildZigzagStrip(int chunkSize, int vertexCacheSize, bool withSkirts)
{
    return buildBandedIndices(chunkSize, zigzagBandWidth(vertexCacheSize), ZigzagPrimitive::kTriangleStrip, withSkirts);
}

std::vector<std::uint32_t> buildBandedIndices(int chunkSize, int bandWidth, ZigzagPrimitive primitive, bool withSkirts)
{
    TERRAIN_EXPECTS(isValidChunkSize(chunkSize), "chunk size must be 2^k + 1 in [3, 1025]");
    TERRAIN_EXPECTS(bandWidth >= 1, "band width must be at least one quad");
    return primitive == ZigzagPrimitive::kTriangleList ? buildList(chunkSize, bandWidth, withSkirts)
                                                       : buildStrip(chunkSize, bandWidth, withSkirts);
}

IndexType indexTypeFor(std::uint64_t vertexCount)
{
    return vertexCount <= std::uint64_t{std::numeric_limits<std::uint16_t>::max()} + 1 ? IndexType::kUint16
                                                                                       : IndexType::kUint32;
}

std::vector<std::uint16_t> narrowIndices(const std::vector<std::uint32_t>& indices)
{
    std::vector<std::uint16_t> out;
    out.reserve(indices.size());
    for (const std::uint32_t index : indices) {
        TERRAIN_EXPECTS(index <= std::numeric_limits<std::uint16_t>::max(), "index does not fit in 16 bits");
        out.push_back(static_cast<std::uint16_t>(index));
    }
    return out;
}

}  // namespace terrain
