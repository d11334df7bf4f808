// The contract between the renderers and their GLSL programs, declared once: vertex attribute locations, the
// layout of a drawn node's per-instance constants, the texture unit of every sampler and the tessellation
// blocks' level codes. Every program is compiled with them as #defines (shaderContractDefines(), inserted by
// ShaderProgram), the renderers bind samplers by the same tables (bindSamplerUnits), and ShaderContractGLTest
// compiles every program variant and checks its attributes and samplers against these.
#pragma once

#include "lod/TessellationLevels.h"

#include <array>
#include <span>
#include <string>
#include <vector>

namespace terrain {

class ShaderProgram;

namespace contract {

// ---- Vertex attributes ----
inline constexpr int kGridLocation = 0;   ///< aGrid: a template or footprint vertex (terrain.vert, clipmap.vert)
inline constexpr int kSkirtLocation = 1;  ///< aSkirt: 1 for a skirt vertex (terrain.vert)
inline constexpr int kPatchLocation = 0;  ///< aPatch: a block or skirt patch's number (terrain_tess.vert)
/// aNode0, aNode1, aNode2: the drawn node's NodeInstance, a vec4 each from this location on.
inline constexpr int kNodeLocation = 2;
/// aLayerOrigin[k]: after the node's constants, one vec4 per detail layer (DetailLayers::origin).
inline constexpr int kLayerOriginLocation = 5;

/// A drawn node's constants, per instance of the template mesh or of the tessellation patches (aNode0..2).
struct NodeInstance {
    // aNode0
    float originX = 0.0f;  ///< the node's south-west corner minus the camera, metres
    float originY = 0.0f;
    float spacing = 0.0f;  ///< metres between the node's samples
    float morph = 1.0f;    ///< eq. 3.5: 0 the parent's surface, 1 the node's own
    // aNode1
    float skirtDepth = 0.0f;   ///< metres the skirts hang below the edge (3.2.6)
    float layer = 0.0f;        ///< the node's layer in its pool array
    float parentLayer = 0.0f;  ///< the parent's layer in the parent's pool array
    float lowest = 0.0f;       ///< the slot's lowest height, metres (its 16-bit codes span lowest .. + range)
    // aNode2
    float quadrantX = 0.0f;  ///< the node's quadrant in its parent's square: 0 or 0.5
    float quadrantY = 0.0f;
    float heightRange = 0.0f;  ///< metres the slot's codes span
    float index = 0.0f;        ///< the node's place in the frame's drawing order (terrain.vert's pixel counts)
};
/// vec4 attributes a NodeInstance takes.
inline constexpr int kNodeInstanceVec4s = 3;
static_assert(sizeof(NodeInstance) == kNodeInstanceVec4s * 4 * sizeof(float), "NodeInstance is aNode0..2");
static_assert(kLayerOriginLocation == kNodeLocation + kNodeInstanceVec4s, "layer origins follow the node");

// ---- Texture units ----

/// A sampler uniform and the texture unit it reads.
struct SamplerUnit {
    const char* uniform;
    int unit;
};

/// The quadtree renderer's programs (terrain.*, terrain_tess.vert). Units 0-10; own pool arrays and parent pool
/// arrays apart, so a draw binds one pair of arrays.
namespace terrain_units {
inline constexpr int kColour = 0;            ///< the node's colour texture (own pool array)
inline constexpr int kHeights = 1;           ///< surface windows (own pool array)
inline constexpr int kDetail = 2;            ///< the materials' detail layers (DetailLayers)
inline constexpr int kWeights = 3;           ///< material weights (own pool array)
inline constexpr int kParentNormals = 4;     ///< the parent's vertex normals (own pool array)
inline constexpr int kLevels = 5;            ///< tessellation: the frame's block codes (texture buffer)
inline constexpr int kNormalMaps = 6;        ///< normal maps (own pool array)
inline constexpr int kParentColour = 7;      ///< colour textures (the parent's pool array)
inline constexpr int kParentNormalMaps = 8;  ///< normal maps (the parent's pool array)
inline constexpr int kAerialTable = 9;       ///< the frame's aerial-perspective table (AtmosphereTables)
inline constexpr int kLight = 10;            ///< the sun's and sky's visibility at the nodes' samples (own array)
}  // namespace terrain_units
inline constexpr std::array<SamplerUnit, 11> kTerrainSamplers = {{
    {"uColour", terrain_units::kColour},
    {"uHeights", terrain_units::kHeights},
    {"uDetail", terrain_units::kDetail},
    {"uWeights", terrain_units::kWeights},
    {"uParentNormals", terrain_units::kParentNormals},
    {"uLevels", terrain_units::kLevels},
    {"uNormalMaps", terrain_units::kNormalMaps},
    {"uParentColour", terrain_units::kParentColour},
    {"uParentNormalMaps", terrain_units::kParentNormalMaps},
    {"uAerialTable", terrain_units::kAerialTable},
    {"uLight", terrain_units::kLight},
}};

/// The clipmap renderer's programs (clipmap.*): the rings' textures now and as they were drawn before their morph.
namespace clipmap_units {
inline constexpr int kHeights = 0;
inline constexpr int kColour = 1;
inline constexpr int kDetail = 2;
inline constexpr int kMaterials = 3;
inline constexpr int kNormals = 4;
inline constexpr int kMorph = 5;
inline constexpr int kPreviousColour = 6;
inline constexpr int kPreviousMaterials = 7;
inline constexpr int kPreviousNormals = 8;
inline constexpr int kAerialTable = 9;
inline constexpr int kSkyVisibility = 10;
}  // namespace clipmap_units
inline constexpr std::array<SamplerUnit, 11> kClipmapSamplers = {{
    {"uHeights", clipmap_units::kHeights},
    {"uColour", clipmap_units::kColour},
    {"uDetail", clipmap_units::kDetail},
    {"uMaterials", clipmap_units::kMaterials},
    {"uNormals", clipmap_units::kNormals},
    {"uMorph", clipmap_units::kMorph},
    {"uPreviousColour", clipmap_units::kPreviousColour},
    {"uPreviousMaterials", clipmap_units::kPreviousMaterials},
    {"uPreviousNormals", clipmap_units::kPreviousNormals},
    {"uAerialTable", clipmap_units::kAerialTable},
    {"uSkyVisibility", clipmap_units::kSkyVisibility},
}};

/// The sky's program (sky.*): the frame's sky table (AtmosphereTables).
inline constexpr std::array<SamplerUnit, 1> kSkySamplers = {{{"uSkyTable", 0}}};

/// The definitions every program is compiled with: the locations above (GRID_LOCATION, SKIRT_LOCATION,
/// PATCH_LOCATION, NODE0_LOCATION .. NODE2_LOCATION, LAYER_ORIGIN_LOCATION) and the block codes' fields
/// (BlockLevels::code: BLOCK_LEVEL_MASK, BLOCK_SNAP_SHIFT, BLOCK_SNAP_BITS, BLOCK_CULLED_BIT), as "NAME VALUE".
std::vector<std::string> shaderContractDefines();

/// Sets each sampler of `table` that `program` uses to its unit (a sampler the program lacks is skipped).
void bindSamplerUnits(const ShaderProgram& program, std::span<const SamplerUnit> table);

}  // namespace contract
}  // namespace terrain
