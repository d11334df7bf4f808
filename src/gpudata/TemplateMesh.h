// The template mesh (paper 3.2.9, eq. 3.7): one flat N x N grid shared by every chunk, plus the ring
// of skirt vertices of 3.2.6. A node contributes only scale, translation and its heights; the vertex
// program turns grid coordinates into a position and lowers skirt vertices by the node's skirt depth.
// Pure CPU code: no GL here, the renderer uploads what this builds.
//
// Chunk sizes: the template supports every N a map may have, isValidChunkSize (quadtree/ChunkGeometry.h).
#pragma once

#include "quadtree/ChunkGeometry.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace terrain {

/// One vertex of the template mesh, uploaded as it is (6 bytes, no conversion):
///   offset 0: i, j as two unsigned 16-bit integer attributes (glVertexAttribIPointer, GL_UNSIGNED_SHORT);
///   offset 4: skirt as one unsigned 8-bit integer attribute (GL_UNSIGNED_BYTE);
///   offset 5: padding, always 0 so the uploaded bytes are deterministic.
struct TemplateVertex {
    std::uint16_t i = 0;     ///< grid column, 0 .. N-1, increasing east
    std::uint16_t j = 0;     ///< grid row, 0 .. N-1, increasing north (j = 0 is the south edge)
    std::uint8_t skirt = 0;  ///< 1: skirt duplicate of edge vertex (i, j), hangs skirt depth below it
    std::uint8_t padding = 0;
};
static_assert(sizeof(TemplateVertex) == 6 && offsetof(TemplateVertex, j) == 2 && offsetof(TemplateVertex, skirt) == 4,
              "the GL side uploads TemplateVertex with these offsets");

/// Grid coordinates of a template vertex.
struct GridCoord {
    int i = 0;
    int j = 0;
};

/// The template mesh of one chunk size. Vertex order:
///   [0, N^2): grid vertex (i, j) at index j * N + i (gridVertexIndex), skirt = 0;
///   [N^2, N^2 + 4 (N - 1)): the skirt ring (skirtVertexIndex), one duplicate of every edge vertex with
///   skirt = 1, counter-clockwise seen from above starting at the south-west corner: the south edge
///   going east, the east edge going north, the north edge going west, the west edge going south.
/// Each corner appears once in the ring, so the skirts of two sides meet at the corner's vertical.
struct TemplateMesh {
    int chunkSize = 0;  ///< N
    std::vector<TemplateVertex> vertices;
};

/// Builds the template mesh for chunks of `chunkSize` samples per side.
/// Precondition: isValidChunkSize(chunkSize).
TemplateMesh buildTemplateMesh(int chunkSize);

/// Index of grid vertex (i, j), i, j in [0, N). Precondition: valid chunk size and coordinates.
std::uint32_t gridVertexIndex(int chunkSize, int i, int j);

/// Number of skirt vertices (and of skirt segments): 4 (N - 1).
int skirtRingLength(int chunkSize);

/// Grid coordinates of the edge vertex at `ringPosition` in [0, skirtRingLength) of the skirt ring.
GridCoord skirtRingCoord(int chunkSize, int ringPosition);

/// Index of the skirt vertex at `ringPosition` in [0, skirtRingLength): N^2 + ringPosition.
std::uint32_t skirtVertexIndex(int chunkSize, int ringPosition);

/// Vertices of the template: N^2, plus 4 (N - 1) with skirts. Precondition: valid chunk size.
std::uint64_t templateVertexCount(int chunkSize, bool withSkirts);

/// Triangles one chunk draws: 2 (N - 1)^2 for the grid, plus 8 (N - 1) with skirts (one quad per edge
/// segment on each of the 4 sides). Precondition: valid chunk size.
std::uint64_t templateTriangleCount(int chunkSize, bool withSkirts);

}  // namespace terrain
