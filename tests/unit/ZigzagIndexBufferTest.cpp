#include "gpudata/ZigzagIndexBuffer.h"

#include "gpudata/TemplateMesh.h"

#include <meshoptimizer.h>

#include <gtest/gtest.h>
#include <algorithm>
#include <array>
#include <cstdio>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

namespace terrain {
namespace {

constexpr int kChunkSizes[] = {3, 5, 17, 33, 65, 129};

using Triangle = std::array<std::uint32_t, 3>;

std::vector<Triangle> listTriangles(const std::vector<std::uint32_t>& indices)
{
    EXPECT_EQ(indices.size() % 3, 0u);
    std::vector<Triangle> out;
    for (std::size_t k = 0; k + 2 < indices.size(); k += 3) {
        out.push_back({indices[k], indices[k + 1], indices[k + 2]});
    }
    return out;
}

/// What GL_TRIANGLE_STRIP draws: odd triangles swap their first two vertices; triangles that repeat an
/// index are degenerate and draw nothing.
std::vector<Triangle> decodeStrip(const std::vector<std::uint32_t>& strip)
{
    std::vector<Triangle> out;
    for (std::size_t k = 0; k + 2 < strip.size(); ++k) {
        const Triangle t = k % 2 == 0 ? Triangle{strip[k], strip[k + 1], strip[k + 2]}
                                      : Triangle{strip[k + 1], strip[k], strip[k + 2]};
        if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) {
            out.push_back(t);
        }
    }
    return out;
}

/// The same triangle with the same winding gives the same key whatever vertex it starts with.
Triangle canonical(Triangle t)
{
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    return t;
}

struct Vec3 {
    double x, y, z;
};
Vec3 sub(Vec3 a, Vec3 b)
{
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
Vec3 cross(Vec3 a, Vec3 b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

/// Template vertex as a point: grid (i, j) at height 0, skirt vertices one unit below.
Vec3 position(const TemplateVertex& v)
{
    return {double(v.i), double(v.j), v.skirt ? -1.0 : 0.0};
}

/// Checks everything a renderer relies on in the triangles of the template (list order):
/// grid first, each quad split once along SW-NE, CCW from above; then one outward-facing skirt quad
/// per edge segment; nothing twice; indices in range.
void checkTemplateTriangles(int n, const std::vector<Triangle>& tris, bool withSkirts)
{
    const TemplateMesh mesh = buildTemplateMesh(n);
    const int quads = n - 1;
    const std::size_t gridTriangles = templateTriangleCount(n, false);
    ASSERT_EQ(tris.size(), templateTriangleCount(n, withSkirts));

    std::vector<Triangle> keys;
    for (const Triangle& t : tris) {
        for (const std::uint32_t v : t) {
            ASSERT_LT(v, templateVertexCount(n, withSkirts));
        }
        keys.push_back(canonical(t));
    }
    std::sort(keys.begin(), keys.end());
    EXPECT_EQ(std::adjacent_find(keys.begin(), keys.end()), keys.end()) << "a triangle appears twice";

    // Grid: lower-right half (SW, SE, NE) and upper-left half (SW, NE, NW) of each quad, once each.
    std::vector<int> lower(static_cast<std::size_t>(quads * quads), 0);
    std::vector<int> upper(lower.size(), 0);
    for (std::size_t k = 0; k < gridTriangles; ++k) {
        const TemplateVertex& a = mesh.vertices[tris[k][0]];
        const TemplateVertex& b = mesh.vertices[tris[k][1]];
        const TemplateVertex& c = mesh.vertices[tris[k][2]];
        ASSERT_EQ(a.skirt + b.skirt + c.skirt, 0) << "grid triangle " << k << " uses a skirt vertex";
        const int twiceArea = (b.i - a.i) * (c.j - a.j) - (b.j - a.j) * (c.i - a.i);
        ASSERT_EQ(twiceArea, 1) << "grid triangle " << k << ": not a counter-clockwise half quad";
        const int i0 = std::min({a.i, b.i, c.i});
        const int j0 = std::min({a.j, b.j, c.j});
        int sw = 0, se = 0, ne = 0, nw = 0;
        for (const TemplateVertex* v : {&a, &b, &c}) {
            sw += v->i == i0 && v->j == j0;
            se += v->i == i0 + 1 && v->j == j0;
            ne += v->i == i0 + 1 && v->j == j0 + 1;
            nw += v->i == i0 && v->j == j0 + 1;
        }
        ASSERT_TRUE(sw == 1 && ne == 1 && se + nw == 1)
            << "grid triangle " << k << " is not a half quad split along the SW-NE diagonal";
        (se == 1 ? lower : upper)[static_cast<std::size_t>(j0 * quads + i0)] += 1;
    }
    for (std::size_t q = 0; q < lower.size(); ++q) {
        ASSERT_EQ(lower[q], 1) << "quad " << q % quads << ", " << q / quads;
        ASSERT_EQ(upper[q], 1) << "quad " << q % quads << ", " << q / quads;
    }
    if (!withSkirts) {
        return;
    }

    // Skirts: per side and segment, one triangle with two edge vertices and one with two skirt
    // vertices, sharing a diagonal, both facing out of the chunk.
    struct Side {
        int outX, outY;
    };
    const Side sides[4] = {{0, -1}, {1, 0}, {0, 1}, {-1, 0}};  // south, east, north, west
    std::vector<int> topHalves(static_cast<std::size_t>(4 * quads), 0);
    std::vector<int> bottomHalves(topHalves.size(), 0);
    for (std::size_t k = gridTriangles; k < tris.size(); ++k) {
        const TemplateVertex* v[3] = {&mesh.vertices[tris[k][0]], &mesh.vertices[tris[k][1]],
                                      &mesh.vertices[tris[k][2]]};
        const bool onSide[4] = {
            v[0]->j == 0 && v[1]->j == 0 && v[2]->j == 0,
            v[0]->i == quads && v[1]->i == quads && v[2]->i == quads,
            v[0]->j == quads && v[1]->j == quads && v[2]->j == quads,
            v[0]->i == 0 && v[1]->i == 0 && v[2]->i == 0,
        };
        ASSERT_EQ(std::count(onSide, onSide + 4, true), 1) << "skirt triangle " << k << " not along one side";
        const int side = static_cast<int>(std::find(onSide, onSide + 4, true) - onSide);
        const auto along = [&](const TemplateVertex* p) { return side % 2 == 0 ? p->i : p->j; };
        const int lo = std::min({along(v[0]), along(v[1]), along(v[2])});
        const int hi = std::max({along(v[0]), along(v[1]), along(v[2])});
        ASSERT_EQ(hi - lo, 1) << "skirt triangle " << k << " spans more than one edge segment";
        const int skirts = v[0]->skirt + v[1]->skirt + v[2]->skirt;
        ASSERT_TRUE(skirts == 1 || skirts == 2) << "skirt triangle " << k;
        // The two vertices of the same kind sit at both ends of the segment, so the two halves of a
        // segment share the diagonal between the odd one out and the other end.
        for (int a = 0; a < 3; ++a) {
            for (int b = a + 1; b < 3; ++b) {
                if (v[a]->skirt == v[b]->skirt) {
                    ASSERT_NE(along(v[a]), along(v[b])) << "skirt triangle " << k << " is degenerate";
                }
            }
        }
        const Vec3 normal = cross(sub(position(*v[1]), position(*v[0])), sub(position(*v[2]), position(*v[0])));
        EXPECT_EQ(normal.z, 0.0) << "skirt triangle " << k << " is not vertical";
        EXPECT_GT(normal.x * sides[side].outX + normal.y * sides[side].outY, 0.0)
            << "skirt triangle " << k << " faces into the chunk";
        (skirts == 1 ? topHalves : bottomHalves)[static_cast<std::size_t>(side * quads + lo)] += 1;
    }
    for (std::size_t s = 0; s < topHalves.size(); ++s) {
        ASSERT_EQ(topHalves[s], 1) << "side " << s / quads << " segment " << s % quads;
        ASSERT_EQ(bottomHalves[s], 1) << "side " << s / quads << " segment " << s % quads;
    }
}

TEST(ZigzagIndexBuffer, AllChunkAndCacheSizesGiveTheTemplateTriangles)
{
    for (const int n : kChunkSizes) {
        for (int cache = kMinVertexCacheSize; cache <= 64; ++cache) {
            SCOPED_TRACE("chunk " + std::to_string(n) + ", vertex cache " + std::to_string(cache));
            const std::vector<std::uint32_t> list = buildZigzagIndices(n, cache, true);
            ASSERT_NO_FATAL_FAILURE(checkTemplateTriangles(n, listTriangles(list), true));
            // The strip draws exactly the list's triangles: same order, same first vertex, same winding.
            const std::vector<std::uint32_t> strip = buildZigzagStrip(n, cache, true);
            ASSERT_EQ(decodeStrip(strip), listTriangles(list));
        }
    }
}

TEST(ZigzagIndexBuffer, WithoutSkirtsIsTheGridPrefix)
{
    for (const int n : kChunkSizes) {
        SCOPED_TRACE("chunk " + std::to_string(n));
        const std::vector<std::uint32_t> grid = buildZigzagIndices(n, 16, false);
        ASSERT_NO_FATAL_FAILURE(checkTemplateTriangles(n, listTriangles(grid), false));
        const std::vector<std::uint32_t> all = buildZigzagIndices(n, 16, true);
        ASSERT_TRUE(std::equal(grid.begin(), grid.end(), all.begin()));
        const std::vector<std::uint32_t> gridStrip = buildZigzagStrip(n, 16, false);
        EXPECT_EQ(decodeStrip(gridStrip), listTriangles(grid));
        for (const std::uint32_t v : gridStrip) {
            ASSERT_LT(v, templateVertexCount(n, false));
        }
    }
}

TEST(ZigzagIndexBuffer, ExplicitBandWidthsAllValid)
{
    for (const int n : {3, 17, 65}) {
        for (int w = 1; w <= n + 1; ++w) {
            SCOPED_TRACE("chunk " + std::to_string(n) + ", band width " + std::to_string(w));
            const auto list = buildBandedIndices(n, w, ZigzagPrimitive::kTriangleList, true);
            ASSERT_NO_FATAL_FAILURE(checkTemplateTriangles(n, listTriangles(list), true));
            const auto strip = buildBandedIndices(n, w, ZigzagPrimitive::kTriangleStrip, true);
            ASSERT_EQ(decodeStrip(strip), listTriangles(list));
        }
    }
}

// The smallest chunk drawn for a 4-entry cache (bands one quad wide), written out: vertices
//
//   6 7 8
//   3 4 5
//   0 1 2
//
// Band 0 (column 0) runs north, rows going west; band 1 (column 1) runs south, rows going east.
TEST(ZigzagIndexBuffer, SmallestChunkOrder)
{
    const std::vector<std::uint32_t> expected = {
        1, 4, 0, 0, 4, 3,  // quad (0, 0): SE, NE, SW then SW, NE, NW
        4, 7, 3, 3, 7, 6,  // quad (0, 1)
        7, 4, 8, 8, 4, 5,  // quad (1, 1): NW, SW, NE then NE, SW, SE
        4, 1, 5, 5, 1, 2,  // quad (1, 0)
    };
    EXPECT_EQ(buildZigzagIndices(3, 4, false), expected);
    const std::vector<std::uint32_t> strip = {1, 4, 0, 3, 3, 4, 4, 7, 3, 6, 6, 7, 7, 4, 8, 5, 5, 4, 4, 1, 5, 2};
    EXPECT_EQ(buildZigzagStrip(3, 4, false), strip);
}

double acmr(const std::vector<std::uint32_t>& indices, std::size_t vertexCount, unsigned cacheSize)
{
    return meshopt_analyzeVertexCache(indices.data(), indices.size(), vertexCount, cacheSize, 0, 0).acmr;
}

std::vector<std::uint32_t> rowMajorGrid(int n)
{
    std::vector<std::uint32_t> out;
    for (int j = 0; j + 1 < n; ++j) {
        for (int i = 0; i + 1 < n; ++i) {
            const std::uint32_t sw = gridVertexIndex(n, i, j), se = gridVertexIndex(n, i + 1, j);
            const std::uint32_t ne = gridVertexIndex(n, i + 1, j + 1), nw = gridVertexIndex(n, i, j + 1);
            out.insert(out.end(), {sw, se, ne, sw, ne, nw});
        }
    }
    return out;
}

// Pinned quality: measured by meshoptimizer's FIFO model, grid only.
TEST(ZigzagIndexBuffer, VertexCacheMissRatioOf65Chunk)
{
    const int n = 65;
    const std::size_t vertices = templateVertexCount(n, false);
    const double zigzag16 = acmr(buildZigzagIndices(n, 16, false), vertices, 16);
    const double zigzag32 = acmr(buildZigzagIndices(n, 32, false), vertices, 32);
    EXPECT_LE(zigzag16, 0.59);
    EXPECT_LE(zigzag32, 0.55);

    const std::vector<std::uint32_t> rowMajor = rowMajorGrid(n);
    std::vector<std::uint32_t> optimized(rowMajor.size());
    meshopt_optimizeVertexCache(optimized.data(), rowMajor.data(), rowMajor.size(), vertices);
    const double rowMajor16 = acmr(rowMajor, vertices, 16);
    const double meshopt16 = acmr(optimized, vertices, 16);
    const double meshopt32 = acmr(optimized, vertices, 32);
    EXPECT_LT(zigzag16, meshopt16);
    EXPECT_LT(zigzag32, meshopt32);

    RecordProperty("acmr_zigzag16_fifo16", std::to_string(zigzag16));
    RecordProperty("acmr_zigzag32_fifo32", std::to_string(zigzag32));
    RecordProperty("acmr_row_major_fifo16", std::to_string(rowMajor16));
    RecordProperty("acmr_meshopt_fifo16", std::to_string(meshopt16));
    std::printf(
        "ACMR 65x65 grid: zigzag(16) %.4f @FIFO16, zigzag(32) %.4f @FIFO32, row-major %.4f @FIFO16, "
        "meshopt_optimizeVertexCache %.4f @FIFO16 %.4f @FIFO32\n",
        zigzag16, zigzag32, rowMajor16, meshopt16, meshopt32);
}

// The band width rule of ZigzagIndexBuffer.h is as good as the best band width tried, measured; also
// prints the table quoted there.
TEST(ZigzagIndexBuffer, BandWidthRuleIsBestMeasured)
{
    const int n = 65;
    const std::size_t vertices = templateVertexCount(n, false);
    std::printf("FIFO  rule w  ACMR    best w  best ACMR\n");
    for (const int cache : {4, 6, 8, 12, 16, 24, 32, 48, 64}) {
        const int rule = zigzagBandWidth(cache);
        const double ruleAcmr = acmr(buildZigzagIndices(n, cache, false), vertices, static_cast<unsigned>(cache));
        int bestWidth = 0;
        double best = std::numeric_limits<double>::infinity();
        for (int w = 1; w < n; ++w) {
            const double a = acmr(buildBandedIndices(n, w, ZigzagPrimitive::kTriangleList, false), vertices,
                                  static_cast<unsigned>(cache));
            if (a < best) {
                best = a;
                bestWidth = w;
            }
        }
        std::printf("%4d  %6d  %.4f  %6d  %.4f\n", cache, rule, ruleAcmr, bestWidth, best);
        EXPECT_LE(ruleAcmr, best + 1e-6) << "vertex cache " << cache;
    }
}

TEST(ZigzagIndexBuffer, StripNeedsFewerIndices)
{
    const std::size_t list = buildZigzagIndices(65, 16, true).size();
    const std::size_t strip = buildZigzagStrip(65, 16, true).size();
    std::printf("65x65 with skirts, vertex cache 16: list %zu indices, strip %zu (%.2f)\n", list, strip,
                double(strip) / double(list));
    EXPECT_LT(strip * 2, list);
}

TEST(ZigzagIndexBuffer, IndexTypeFollowsVertexCount)
{
    EXPECT_EQ(indexTypeFor(1), IndexType::kUint16);
    EXPECT_EQ(indexTypeFor(65536), IndexType::kUint16);
    EXPECT_EQ(indexTypeFor(65537), IndexType::kUint32);
    EXPECT_EQ(indexTypeFor(templateVertexCount(129, true)), IndexType::kUint16);
    EXPECT_EQ(indexTypeFor(templateVertexCount(257, true)), IndexType::kUint32);

    const std::vector<std::uint32_t> wide = buildZigzagIndices(129, 16, true);
    const std::vector<std::uint16_t> narrow = narrowIndices(wide);
    ASSERT_EQ(narrow.size(), wide.size());
    EXPECT_TRUE(std::equal(narrow.begin(), narrow.end(), wide.begin()));
}

TEST(ZigzagIndexBufferDeathTest, BadInputsArePreconditionFailures)
{
    EXPECT_DEATH((void)zigzagBandWidth(0), "vertex cache size must be at least 4");
    EXPECT_DEATH((void)zigzagBandWidth(3), "vertex cache size must be at least 4");
    EXPECT_DEATH((void)buildZigzagIndices(65, 0, true), "vertex cache size must be at least 4");
    EXPECT_DEATH((void)buildZigzagIndices(2, 16, true), "chunk size must be 2\\^k \\+ 1");
    EXPECT_DEATH((void)buildZigzagStrip(64, 16, false), "chunk size must be 2\\^k \\+ 1");
    EXPECT_DEATH((void)buildBandedIndices(65, 0, ZigzagPrimitive::kTriangleList, false),
                 "band width must be at least one quad");
    EXPECT_DEATH((void)narrowIndices({0, 65536}), "index does not fit in 16 bits");
}

}  // namespace
}  // namespace terrain
