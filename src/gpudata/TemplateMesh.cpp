// Template mesh (paper 3.2.9, eq. 3.7) with its skirt ring (3.2.6).
#include "gpudata/TemplateMesh.h"

#include "core/Check.h"

namespace terrain {

namespace {

void expectChunkSize(int chunkSize)
{
    TERRAIN_EXPECTS(isValidChunkSize(chunkSize), "chunk size must be 2^k + 1 in [3, 1025]");
}

}  // namespace

TemplateMesh buildTemplateMesh(int chunkSize)
{
    expectChunkSize(chunkSize);
    TemplateMesh mesh;
    mesh.chunkSize = chunkSize;
    mesh.vertices.reserve(templateVertexCount(chunkSize, true));
    for (int j = 0; j < chunkSize; ++j) {
        for (int i = 0; i < chunkSize; ++i) {
            mesh.vertices.push_back({static_cast<std::uint16_t>(i), static_cast<std::uint16_t>(j), 0, 0});
        }
    }
    const int ring = skirtRingLength(chunkSize);
    for (int p = 0; p < ring; ++p) {
        const GridCoord c = skirtRingCoord(chunkSize, p);
        mesh.vertices.push_back({static_cast<std::uint16_t>(c.i), static_cast<std::uint16_t>(c.j), 1, 0});
    }
    TERRAIN_ASSERT(mesh.vertices.size() == templateVertexCount(chunkSize, true));
    return mesh;
}

std::uint32_t gridVertexIndex(int chunkSize, int i, int j)
{
    TERRAIN_EXPECTS(i >= 0 && i < chunkSize && j >= 0 && j < chunkSize, "grid coordinates outside the chunk");
    return static_cast<std::uint32_t>(j) * static_cast<std::uint32_t>(chunkSize) + static_cast<std::uint32_t>(i);
}

int skirtRingLength(int chunkSize)
{
    expectChunkSize(chunkSize);
    return 4 * (chunkSize - 1);
}

GridCoord skirtRingCoord(int chunkSize, int ringPosition)
{
    const int side = chunkSize - 1;
    TERRAIN_EXPECTS(ringPosition >= 0 && ringPosition < skirtRingLength(chunkSize), "ring position outside the ring");
    const int along = ringPosition % side;
    switch (ringPosition / side) {
        case 0:
            return {along, 0};  // south edge, going east
        case 1:
            return {side, along};  // east edge, going north
        case 2:
            return {side - along, side};  // north edge, going west
        default:
            return {0, side - along};  // west edge, going south
    }
}

std::uint32_t skirtVertexIndex(int chunkSize, int ringPosition)
{
    TERRAIN_EXPECTS(ringPosition >= 0 && ringPosition < skirtRingLength(chunkSize), "ring position outside the ring");
    return static_cast<std::uint32_t>(templateVertexCount(chunkSize, false)) + static_cast<std::uint32_t>(ringPosition);
}

std::uint64_t templateVertexCount(int chunkSize, bool withSkirts)
{
    expectChunkSize(chunkSize);
    const auto n = static_cast<std::uint64_t>(chunkSize);
    return n * n + (withSkirts ? 4 * (n - 1) : 0);
}

std::uint64_t templateTriangleCount(int chunkSize, bool withSkirts)
{
    expectChunkSize(chunkSize);
    const auto quads = static_cast<std::uint64_t>(chunkSize - 1);
    return 2 * quads * quads + (withSkirts ? 2 * 4 * quads : 0);
}

}  // namespace terrain
