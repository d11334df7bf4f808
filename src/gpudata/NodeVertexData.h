// Per-node vertex data for the template mesh (3.2.8-3.2.9) on the CPU: what each vertex of one node needs to
// geomorph, as terrain.vert computes it from the node pools' textures. The reference of that computation for
// tests and the brute-force renderer of RenderBench; the viewer does not use it. Pure CPU code: no GL here.
#pragma once

#include "gpudata/TemplateMesh.h"

#include <cstdint>
#include <span>
#include <vector>

namespace terrain {

/// One vertex's data (20 bytes), parallel to TemplateMesh::vertices:
///   own, parent: metres above the map's height offset of the node's own surface sample and of the parent's
///     surface at the vertex (eq. 3.4: the vertex moves between them with the morph factor);
///   ownNormal, parentNormal: x and y of the unit surface normals, as signed 16-bit normalised integers
///     (z = sqrt(1 - x^2 - y^2) is always positive for a height field);
///   materialWeights: the blend weights of up to 4 materials' detail textures (0..255), 0 without materials.
/// Skirt vertices copy their edge vertex.
struct NodeVertex {
    float own = 0.0f;
    float parent = 0.0f;
    std::int16_t ownNormal[2] = {0, 0};
    std::int16_t parentNormal[2] = {0, 0};
    std::uint8_t materialWeights[4] = {0, 0, 0, 0};
};
static_assert(sizeof(NodeVertex) == 20, "the GL side uploads NodeVertex as 2 floats, 4 shorts and 4 bytes");

/// Builds the vertex data of a node from its surface window ((N + 4)^2 heights in metres above the map's
/// offset, 2-sample border, rows south to north) and its material weights (N x N x 4 bytes, or empty).
/// The parent's surface follows the template triangulation (SW-NE diagonals) through the node's even
/// samples, which are the parent's samples (DetailSynthesizer.h, "Nesting"); its normal at a parent
/// sample uses central differences over two node samples, and at other vertices (x, y) is the mean of the
/// two parent samples' that the vertex lies between, as the parent's triangles interpolate it. `spacing`: metres
/// between the node's samples.
std::vector<NodeVertex> buildNodeVertices(const TemplateMesh& mesh, std::span<const float> window, double spacing,
                                          std::span<const std::uint8_t> materialWeights);

}  // namespace terrain
