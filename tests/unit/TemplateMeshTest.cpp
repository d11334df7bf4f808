#include "gpudata/TemplateMesh.h"

#include <gtest/gtest.h>
#include <cstdlib>
#include <cstring>
#include <set>
#include <utility>

namespace terrain {
namespace {

constexpr int kChunkSizes[] = {3, 5, 17, 33, 65, 129};

TEST(TemplateMesh, GridVerticesAreRowMajorAndFlat)
{
    for (const int n : kChunkSizes) {
        const TemplateMesh mesh = buildTemplateMesh(n);
        ASSERT_EQ(mesh.chunkSize, n);
        ASSERT_EQ(mesh.vertices.size(), templateVertexCount(n, true));
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                const std::uint32_t k = gridVertexIndex(n, i, j);
                ASSERT_EQ(k, static_cast<std::uint32_t>(j * n + i));
                const TemplateVertex& v = mesh.vertices[k];
                EXPECT_EQ(v.i, i);
                EXPECT_EQ(v.j, j);
                EXPECT_EQ(v.skirt, 0);
                EXPECT_EQ(v.padding, 0);
            }
        }
    }
}

TEST(TemplateMesh, EveryEdgeVertexHasExactlyOneSkirtDuplicate)
{
    for (const int n : kChunkSizes) {
        const TemplateMesh mesh = buildTemplateMesh(n);
        const int ring = skirtRingLength(n);
        ASSERT_EQ(ring, 4 * (n - 1));
        std::set<std::pair<int, int>> seen;
        for (int p = 0; p < ring; ++p) {
            const TemplateVertex& v = mesh.vertices[skirtVertexIndex(n, p)];
            EXPECT_EQ(v.skirt, 1);
            EXPECT_EQ(v.padding, 0);
            EXPECT_TRUE(v.i == 0 || v.j == 0 || v.i == n - 1 || v.j == n - 1) << "not an edge vertex";
            const GridCoord c = skirtRingCoord(n, p);
            EXPECT_EQ(v.i, c.i);
            EXPECT_EQ(v.j, c.j);
            EXPECT_TRUE(seen.insert({v.i, v.j}).second) << "duplicated edge vertex " << v.i << ", " << v.j;
        }
        EXPECT_EQ(seen.size(), static_cast<std::size_t>(n * n - (n - 2) * (n - 2)));  // all edge vertices
    }
}

// The ring of the smallest chunk, N = 3: positions around the edge, counter-clockwise from the south-west.
//
//   j=2   6 5 4
//   j=1   7 . 3
//   j=0   0 1 2
//        i=0 1 2
TEST(TemplateMesh, SkirtRingOfSmallestChunk)
{
    const GridCoord expected[] = {{0, 0}, {1, 0}, {2, 0}, {2, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};
    ASSERT_EQ(skirtRingLength(3), 8);
    for (int p = 0; p < 8; ++p) {
        const GridCoord c = skirtRingCoord(3, p);
        EXPECT_EQ(c.i, expected[p].i) << p;
        EXPECT_EQ(c.j, expected[p].j) << p;
        EXPECT_EQ(skirtVertexIndex(3, p), static_cast<std::uint32_t>(9 + p));
    }
}

TEST(TemplateMesh, SkirtRingIsACounterClockwiseLoopOfUnitSteps)
{
    for (const int n : kChunkSizes) {
        const int ring = skirtRingLength(n);
        long long twiceArea = 0;
        for (int p = 0; p < ring; ++p) {
            const GridCoord a = skirtRingCoord(n, p);
            const GridCoord b = skirtRingCoord(n, (p + 1) % ring);
            EXPECT_EQ(std::abs(b.i - a.i) + std::abs(b.j - a.j), 1) << "ring position " << p;
            twiceArea += static_cast<long long>(a.i) * b.j - static_cast<long long>(b.i) * a.j;
        }
        EXPECT_EQ(twiceArea, 2LL * (n - 1) * (n - 1)) << "positive: counter-clockwise seen from above";
    }
}

TEST(TemplateMesh, Counts)
{
    struct Case {
        int chunkSize;
        std::uint64_t vertices, verticesWithSkirts, triangles, trianglesWithSkirts;
    };
    const Case cases[] = {
        {3, 9, 17, 8, 24},
        {5, 25, 41, 32, 64},
        {65, 4225, 4481, 8192, 8704},
        {129, 16641, 17153, 32768, 33792},
        {1025, 1050625, 1054721, 2097152, 2105344},
    };
    for (const Case& c : cases) {
        EXPECT_EQ(templateVertexCount(c.chunkSize, false), c.vertices) << c.chunkSize;
        EXPECT_EQ(templateVertexCount(c.chunkSize, true), c.verticesWithSkirts) << c.chunkSize;
        EXPECT_EQ(templateTriangleCount(c.chunkSize, false), c.triangles) << c.chunkSize;
        EXPECT_EQ(templateTriangleCount(c.chunkSize, true), c.trianglesWithSkirts) << c.chunkSize;
    }
}

TEST(TemplateMesh, VertexBytesAreTheDocumentedLayout)
{
    const TemplateMesh mesh = buildTemplateMesh(3);
    const TemplateVertex& v = mesh.vertices[skirtVertexIndex(3, 3)];  // skirt under (2, 1)
    unsigned char bytes[sizeof(TemplateVertex)];
    std::memcpy(bytes, &v, sizeof bytes);
    std::uint16_t i = 0;
    std::uint16_t j = 0;
    std::memcpy(&i, bytes, 2);
    std::memcpy(&j, bytes + 2, 2);
    EXPECT_EQ(i, 2);
    EXPECT_EQ(j, 1);
    EXPECT_EQ(bytes[4], 1);
    EXPECT_EQ(bytes[5], 0);
}

TEST(TemplateMeshDeathTest, InvalidChunkSizeIsAPreconditionFailure)
{
    EXPECT_DEATH(buildTemplateMesh(2), "chunk size must be 2\\^k \\+ 1");
    EXPECT_DEATH(buildTemplateMesh(64), "chunk size must be 2\\^k \\+ 1");
    EXPECT_DEATH((void)templateTriangleCount(0, true), "chunk size must be 2\\^k \\+ 1");
    EXPECT_DEATH((void)templateVertexCount(2049, false), "chunk size must be 2\\^k \\+ 1");
    EXPECT_DEATH((void)skirtRingCoord(5, 16), "ring position outside the ring");
    EXPECT_DEATH((void)gridVertexIndex(5, 5, 0), "grid coordinates outside the chunk");
}

}  // namespace
}  // namespace terrain
