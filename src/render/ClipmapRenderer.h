// The geometry clipmap renderer (seed 002: Asirvatham & Hoppe, GPU Gems 2 chapter 2), lod_mode = clipmap:
// per ring an n x n elevation layer (R32F), morph layer (RG32F), sky visibility layer (RG8) and colour layer (RGBA8) in
// texture arrays, updated toroidally with the samples lod/ClipmapTerrain changed (glTexSubImage3D of the rectangles,
// split where they wrap); the rings drawn by instancing the footprints of lod/ClipmapLayout (one vertex and index
// buffer per footprint size, SW-NE diagonals like the quadtree's template), each footprint culled against the view
// frustum by its box, finest ring first (front to back). The vertex program blends heights and normals to
// the coarser ring in the transition region (shaders/clipmap.vert); zero-area triangles along each ring's
// perimeter close the T-junctions with the coarser ring exactly as the seed's degenerate triangles do.
// Samples a node replaced while they were in view morph in (ClipmapRing::morph and the previous colour,
// material and normal layers; clipmap_morph_seconds). Same sky, sun, haze, colours and materials' detail
// textures as the quadtree renderer.
#pragma once

#include "core/Camera.h"
#include "core/Expected.h"
#include "lod/ClipmapLayout.h"
#include "lod/ClipmapTerrain.h"
#include "quadtree/MapFormat.h"
#include "render/DetailLayers.h"
#include "render/GlObjects.h"
#include "render/ShaderProgram.h"
#include "render/Sky.h"

#include <filesystem>
#include <map>
#include <memory>
#include <utility>
#include <vector>

namespace terrain {

/// One clipmap frame's figures.
struct ClipmapStats {
    std::uint64_t triangles = 0;      ///< in the footprints drawn (zero-area perimeter triangles not counted)
    std::size_t pieces = 0;           ///< footprints drawn
    std::size_t culledPieces = 0;     ///< footprints outside the frustum
    std::size_t rings = 0;            ///< rings drawn
    std::size_t uploadedSamples = 0;  ///< samples copied to the GPU this frame
};

class ClipmapRenderer {
public:
    /// Programs from `shaderDirectory` (clipmap.vert/.frag, sky), textures for `layout`'s rings. Errors carry
    /// the GL's log.
    /// With `materials`, their detail textures (render/DetailLayers.h) are drawn over the rings' colours,
    /// weighted by the rings' material weights (the terrain must keep them: ClipmapTerrain's `materials`).
    /// With `normalTexelsPerCell` > 0 the rings' normal maps light the terrain (ClipmapTerrain's, that many
    /// texels a cell), blended to the coarser ring's like the colours; else the vertex normals of the heights.
    static Expected<std::unique_ptr<ClipmapRenderer>> create(const std::filesystem::path& shaderDirectory,
                                                             const MapHeader& header, const ClipmapLayout& layout,
                                                             const MaterialSet* materials = nullptr,
                                                             int normalTexelsPerCell = 0,
                                                             const LightingModel& lighting = {});

    /// Uploads what `terrain` changed, then clears, draws the sky and rings `firstRing` to the coarsest for
    /// `camera` (layout placed for it by moveTo).
    ClipmapStats draw(const ClipmapLayout& layout, const ClipmapTerrain& terrain, int firstRing, const Camera& camera,
                      const SceneStyle& style);

    /// GPU bytes of the ring layers (fixed by n and the ring count).
    std::size_t textureBytes() const { return mTextureBytes; }

private:
    struct Mesh {
        gl::VertexArray vao;
        gl::Buffer vertices;
        gl::Buffer indices;
        GLsizei count = 0;
        std::uint64_t triangles = 0;
    };
    explicit ClipmapRenderer(const MapHeader& header) : mHeader(header) {}
    /// A vertex array of integer grid vertices (x, y) and triangle indices.
    static Mesh makeMesh(const std::vector<GLint>& vertices, const std::vector<std::uint32_t>& indices);
    /// The footprint of w x h cells (made the first time it is asked for).
    const Mesh& footprint(std::int64_t w, std::int64_t h);
    void upload(const ClipmapTerrain& terrain, int ring, ClipmapStats& stats);
    /// Binds the rings' textures (and the detail layers) to their units (render/ShaderContract.h).
    void bindRingTextures() const;

    MapHeader mHeader;
    int mSamples = 0;
    /// [kNear] with the materials' detail layers (or the only one without), [kFar] without the layers'
    /// loop, for footprints beyond every layer's fade.
    std::vector<ShaderProgram> mPrograms;
    static constexpr std::size_t kNear = 0;
    static constexpr std::size_t kFar = 1;
    DetailLayers mDetail;
    Sky mSky;
    gl::Texture mHeights;        ///< GL_TEXTURE_2D_ARRAY R32F, a layer per ring
    gl::Texture mMorph;          ///< GL_TEXTURE_2D_ARRAY RG32F (ClipmapRing::morph), a layer per ring
    gl::Texture mSkyVisibility;  ///< GL_TEXTURE_2D_ARRAY RG8 (ClipmapRing::sky: current, previous), a layer per ring
    gl::Texture mColour;         ///< GL_TEXTURE_2D_ARRAY RGBA8, a layer per ring
    /// ClipmapRing's previous colours, material weights and normals, as mColour, mMaterials and mNormals.
    gl::Texture mPreviousColour;
    gl::Texture mPreviousMaterials;
    gl::Texture mPreviousNormals;
    gl::Texture mNormals;    ///< GL_TEXTURE_2D_ARRAY RG8_SNORM normal maps, (r n)^2 a ring; none without normal maps
    int mNormalPerCell = 0;  ///< r
    gl::Texture mMaterials;  ///< GL_TEXTURE_2D_ARRAY RGBA8 material weights, a layer per ring; none without layers
    std::map<std::pair<std::int64_t, std::int64_t>, Mesh> mFootprints;
    Mesh mPerimeter;  ///< zero-area triangles (a, midpoint, b) along a window's perimeter
    std::size_t mTextureBytes = 0;
};

}  // namespace terrain
