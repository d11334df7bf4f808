// Per-node vertex data for the template mesh (3.2.8-3.2.9): what each vertex of one node needs to
// geomorph, computed once when the node is uploaded, so the vertex program does no texture fetches.
// Pure CPU code: no GL here.
#pragma once

#include "render/TemplateMesh.h"

#include <cstdint>
#include <span>
#include <vector>

namespace terrain {

/// One vertex's data (16 bytes), parallel to TemplateMesh::vertices:
///   own, parent: metres above the map's height offset of the node's own sample and of the parent's
///     surface at the vertex (eq. 3.4: the vertex moves between them with the morph factor);
///   ownNormal, parentNormal: x and y of the unit surface normals, as signed 16-bit normalised integers
///     (z = sqrt(1 - x^2 - y^2) is always positive for a height field).
/// Skirt vertices copy their edge vertex.
struct NodeVertex {
    float own = 0.0f;
    float parent = 0.0f;
    std::int16_t ownNormal[2] = {0, 0};
    std::int16_t parentNormal[2] = {0, 0};
};
static_assert(sizeof(NodeVertex) == 16, "the GL side uploads NodeVertex as 2 floats and 4 shorts");

/// Builds the vertex data of a node from its window of codes ((N + 4)^2, 2-sample border, rows south to
/// north). The parent's surface follows the template triangulation (SW-NE diagonals); its normal at a
/// parent sample uses central differences over two node samples, and at other vertices the mean of the
/// two parent samples the vertex lies between. `heightStep`: metres per code; `spacing`: metres between
/// the node's samples.
std::vector<NodeVertex> buildNodeVertices(const TemplateMesh& mesh, std::span<const std::uint16_t> window,
                                          double heightStep, double spacing);

}  // namespace terrain
