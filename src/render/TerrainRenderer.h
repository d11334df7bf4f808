// The chunk renderer (paper 3.2.6-3.2.11, 4.2.3): one template mesh for every node, geomorphed and skirted
// in the vertex program, front to back in the selector's order. It draws a frame's draw list (lod/DrawList.h)
// as it is: the LOD layer decided the nodes, their morphs and their tessellation blocks' levels. Node data
// lives in pools allocated once for the cache's capacity (4.2.3): a layer of one of each pool's texture
// arrays per cache slot (NodeCache::slotOf), filled when a slot's node is first drawn. A frame's nodes go in
// one instanced draw per program and pair of arrays (the node's and its parent's; one pair while the pools
// fit one array).
#pragma once

#include "core/Camera.h"
#include "core/Expected.h"
#include "gpudata/BlockTriangles.h"
#include "gpudata/TemplateMesh.h"
#include "lod/DrawList.h"
#include "lod/NodeData.h"
#include "lod/NodeMemory.h"
#include "lod/NodeVisibility.h"
#include "lod/TessellationLevels.h"
#include "quadtree/MapFormat.h"
#include "render/DetailLayers.h"
#include "render/FrameSetup.h"
#include "render/GlObjects.h"
#include "render/PixelCounter.h"
#include "render/ShaderProgram.h"
#include "render/Sky.h"
#include "render/TriangleFeedback.h"
#include "synthesis/Material.h"

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace terrain {

struct RenderStats {
    std::size_t nodes = 0;
    std::size_t staticNodes = 0;
    std::size_t dynamicNodes = 0;
    std::uint64_t triangles = 0;
    std::size_t uploads = 0;   ///< nodes copied into their slots this frame
    std::size_t gpuNodes = 0;  ///< slots that have held a node (filled when first drawn, kept until reused)
    /// Draw calls for the terrain (the sky not counted): in chunks mode one per program and pair of pool arrays
    /// (the nodes', their parents') that has nodes in view (1 when the pools fit one array and no detail layers
    /// split it); in tessellation mode each of those is runs of nodes times ranges of patches (drawPatchRanges); in
    /// blocks mode each is one multi-draw.
    std::size_t drawCalls = 0;
    std::size_t blocks = 0;                ///< tessellation and blocks modes: blocks drawn (not culled)
    std::size_t culledBlocks = 0;          ///< ...: blocks of drawn nodes outside the frustum
    std::size_t occludedBlocks = 0;        ///< ...: blocks drawn at their coarsest, hidden (`occluded`)
    std::uint64_t generatedTriangles = 0;  ///< with transform feedback: the triangles the GL says it made
};

/// The node pools' size and formats.
struct PoolOptions {
    /// Nodes: the cache's capacity (memory_budget or quad_cache_size), a layer per cache slot.
    std::size_t slots = 512;
    bool compressColour = false;  ///< DXT1 colour layers (node_texture_compression), where the GL has S3TC
    /// render_mode = tessellation (or blocks, with blockIndices): blocks of kTessellationBlockQuads quads drawn at
    /// the levels chooseBlockLevels picks (lod/TessellationLevels.h); needs GL 4.0 (tessellationSupported()) without
    /// blockIndices, and nodes with tessellation errors.
    bool tessellation = false;
    /// > 0: nodes carry normal maps of this many texels a side (NodeData::normalMap, synthesis/NormalMap.h;
    /// dynamic_texture_size), and the fragment program lights by them, morphed between the node's and its
    /// parent's like the colours; 0: lit by the vertex normals.
    int normalMapTexels = 0;
    /// Normal maps as RGTC2 blocks (normal_map_compression; lod/NodeTextures.h, compressRgtc2): 1 byte a
    /// texel instead of RG8's 2.
    bool compressNormals = false;
    /// Count each drawn node's visible pixels (visibility_lod; takePixelCounts()): needs GL 4.3 or
    /// its shader storage and early fragment test extensions (pixelCountsSupported()).
    bool pixelCounts = false;
    /// Shadows and sky visibility (shadows): nodes carry horizons (NodeData::horizons, lod/NodeHorizons.h), from
    /// which each slot gets the sun's and sky's visibility at its samples for the frame's sun (re-derived for
    /// every slot when the sun moves); the fragment program reads them bilinearly, morphed like the colours, and
    /// applies them to the sun's and the sky's light.
    bool shadows = false;
    /// Layers of each texture array (0: GL_MAX_ARRAY_TEXTURE_LAYERS): more slots take more arrays per pool.
    /// Tests set a few to draw with several arrays.
    std::size_t layersPerArray = 0;
    /// render_mode = blocks (with `tessellation`): the same blocks at the same levels drawn by the chunk programs from
    /// index lists of the template mesh made each frame (gpudata/BlockTriangles.h), one multi-draw a group, instead
    /// of by tessellation shaders; needs OpenGL 4.3 (multiDrawIndirectSupported()).
    bool blockIndices = false;
};

class TerrainRenderer : public PixelCountSource {
public:
    /// Loads the shaders from `shaderDirectory`, builds the template mesh for `header`'s chunk size with the
    /// zigzag order for `vertexCacheSize`, and allocates the node pools: `pools.slots` nodes' heights,
    /// normals, colour textures and material weights in texture arrays. With
    /// `materials`, their detail textures (render/DetailLayers.h) are drawn over the nodes' colours, blended by
    /// the nodes' material weights (NodeData::materialWeights). `lighting` picks the light and air's variant. Errors
    /// name the file, or the GL limit that the slots exceed. Needs a current GL context.
    static Expected<std::unique_ptr<TerrainRenderer>> create(const std::filesystem::path& shaderDirectory,
                                                             const MapHeader& header, int vertexCacheSize,
                                                             const PoolOptions& pools,
                                                             const MaterialSet* materials = nullptr,
                                                             const LightingModel& lighting = {});

    /// Clears, draws the sky and every node of `frame` (made for its camera) in one instanced draw (two with
    /// detail layers: nodes beyond every layer's fade go in a second one, drawn by a program without the layers),
    /// each node in its cache slot, copied there when the slot held another node. In tessellation mode the
    /// blocks are drawn at the list's levels. With `feedback` (tessellation and blocks modes, for tests), the
    /// camera-relative corners of every triangle drawn are read back by transform feedback, three a triangle, in
    /// drawing order (node by node as drawn, patch by patch: blocks, then skirts; with block indices, block by block,
    /// each block's skirts after its surface: BlockTriangles::append).
    RenderStats draw(const DrawList& frame, const SceneStyle& style, std::vector<glm::vec3>* feedback = nullptr);

    /// Whether this context runs tessellation shaders (OpenGL 4.0).
    static bool tessellationSupported();
    /// Whether this context draws from indirect commands with base instances (OpenGL 4.3): render_mode = blocks.
    static bool multiDrawIndirectSupported();
    /// Whether this context can count visible pixels per node (PoolOptions::pixelCounts): OpenGL 4.3, or
    /// GL_ARB_shader_storage_buffer_object and GL_ARB_shader_image_load_store.
    static bool pixelCountsSupported();
    /// The most slots the pools can have on this context: kMaxPoolArrays texture arrays a pool
    /// (lod/NodeMemory.h) of GL_MAX_ARRAY_TEXTURE_LAYERS layers.
    static std::size_t maxSlots();
    /// Whether this context rasterizes in software (Mesa's llvmpipe, softpipe or swrast: GL_RENDERER), where
    /// compressed textures cost decoding per fetch.
    static bool softwareRasterizer();

    /// Frames between drawing a frame and reading its pixel counts back: the counts of frame F are taken
    /// before drawing frame F + 3, when the GL has normally finished F long ago, so reading them does not
    /// wait (seed 001 reads the previous frame's; a frame later leaves the GPU a frame to finish in).
    static constexpr std::uint64_t kPixelCountLag = 2;
    /// With PoolOptions::pixelCounts: the pixel counts of the oldest frame not yet taken that was drawn at
    /// least `lag` frames before the latest one (kPixelCountLag, or 0 for the frame just drawn, which waits
    /// for the GL to finish it), into `out`; false when there is none. The counts of a frame stay for three
    /// frames: what is not taken by then is dropped (droppedPixelCounts()).
    bool takePixelCounts(PixelCounts& out, std::uint64_t lag);
    /// takePixelCounts(out, kPixelCountLag): what the viewer session takes before each frame's selection.
    bool takePixelCounts(PixelCounts& out) override { return takePixelCounts(out, kPixelCountLag); }
    /// The depth buffer of the frame just drawn (the bound framebuffer's, `width` x `height` from its
    /// origin), rows bottom to top, read at once: waits for the GL. For measuring (tengine
    /// measure_error_every), not for drawing: the pixel counts' depth comes late and does not wait.
    static std::vector<float> readDepth(int width, int height);
    /// Frames whose pixel counts were dropped untaken.
    std::uint64_t droppedPixelCounts() const { return mCounter ? mCounter->dropped() : 0; }

    const SlotBytes& slotBytes() const { return mSlotBytes; }
    std::size_t slots() const { return mSlotData.size(); }

    /// The tessellation mode draws a group's nodes this many at a time, and their patches this many a draw
    /// (drawPatchRanges): one draw for every node and patch would grow Mesa's tessellation output patch by patch.
    static constexpr std::size_t kNodesPerRun = 16;
    static constexpr int kPatchesPerDraw = 8;

private:
    TerrainRenderer(const MapHeader& header) : mHeader(header) {}
    /// create()'s parts: the programs for `defines`, the template mesh's and the tessellation patches' vertex
    /// arrays, and the pools.
    Status createPrograms(const std::filesystem::path& shaderDirectory, std::vector<std::string> defines,
                          const LightingModel& lighting);
    void createTemplateMesh(int vertexCacheSize);
    void createPatches();
    Status createPools(const PoolOptions& pools);
    /// Copies `node` into `slot` unless the slot holds it already.
    void fill(int slot, const NodePtr& node, RenderStats& stats);
    /// Writes the sun's and sky's visibility of the node in `slot` for mSun into its light layer.
    void fillLight(int slot);
    /// draw()'s parts: the frame's nodes in drawing order (filling their slots), their per-instance constants
    /// (and block codes) uploaded, the programs' uniforms, and the instanced draws.
    void orderFrameNodes(const DrawList& frame, RenderStats& stats);
    /// Returns the triangles of the frame's block index lists (render_mode = blocks), else 0.
    std::uint64_t uploadFrameNodes(const DrawList& frame, const SceneStyle& style);
    void setFrameUniforms(const Camera& camera, const SceneStyle& style);
    void drawGroups(RenderStats& stats, TriangleFeedback* feedback);
    /// The tessellation mode's draws of frame nodes [first, last) (one group), `patches` a node: returns the draws.
    int drawPatchRanges(ShaderProgram& program, std::size_t first, std::size_t last, int patches);
    int arrayOf(int slot) const { return slot / static_cast<int>(mLayersPerArray); }
    int layerOf(int slot) const { return slot % static_cast<int>(mLayersPerArray); }

    MapHeader mHeader;
    TemplateMesh mMesh;
    /// The terrain program: [kNear] with the materials' detail layers (or the only one without materials),
    /// [kFar] the same without the layers, for nodes beyond every layer's fade.
    std::vector<ShaderProgram> mPrograms;
    static constexpr std::size_t kNear = 0;
    static constexpr std::size_t kFar = 1;
    Sky mSky;
    SkyOrder mSkyOrder = SkyOrder::AfterTerrain;  ///< before the terrain only where its discards write depth
    gl::VertexArray mTemplateVao;
    gl::Buffer mTemplateVertices;
    gl::Buffer mTemplateIndices;
    GLsizei mIndexCount = 0;
    GLenum mIndexType = GL_UNSIGNED_INT;
    std::uint64_t mTrianglesPerNode = 0;
    DetailLayers mDetail;  ///< the materials' detail textures (none without)

    // The pools: slot s is layer s % mLayersPerArray of array s / mLayersPerArray of each pool.
    struct PoolArrays {
        gl::Texture heights;        ///< GL_R16 (quantizeHeightsR16), (N + 2)^2 per layer
        gl::Texture parentNormals;  ///< GL_RG8_SNORM, ((N + 1) / 2)^2 per layer; none with normal maps
        gl::Texture colour;         ///< DXT1 (or GL_RGB8; GL_RGBA8 with shadows: the sun's visibility in alpha)
        gl::Texture weights;        ///< GL_RGBA4, N^2 per layer; none without materials
        gl::Texture normalMaps;     ///< RGTC2 (or GL_RG8_SNORM), mNormalLayerSize^2 per layer; or none
        gl::Texture light;  ///< GL_RG8, N^2 per layer: the sky's visibility, own and parent's (nearest); or none
    };
    std::vector<PoolArrays> mArrays;
    std::size_t mLayersPerArray = 1;
    std::vector<std::array<float, 2>> mSlotHeights;  ///< per slot: lo and range of its height codes
    int mNormalTexels = 0;
    bool mRgtc2 = false;
    int mNormalLayerSize = 0;  ///< mNormalTexels, padded to a multiple of 4 for RGTC2
    bool mDxt1 = false;
    int mColourLayerSize = 0;
    SlotBytes mSlotBytes;
    std::vector<NodePtr> mSlotData;  ///< per slot: the node it holds (identity for reloads), or null
    bool mShadows = false;
    glm::vec3 mSun{0.0f};        ///< the sun the light layers were derived for (towards it, unit)
    std::size_t mSlotsHeld = 0;  ///< slots that have held a node
    // The frame's per-node constants (terrain.vert's per-instance attributes: mNodeTexels vec4s a node).
    int mNodeTexels = 3;
    std::vector<float> mConstants;
    gl::Buffer mConstantsBuffer;
    // Tessellation mode: patches (blocks, then border skirts) and the frame's block codes.
    bool mTessellation = false;
    int mBlocks = 0;  ///< per side
    gl::VertexArray mPatchVao;
    gl::Buffer mPatchIds;
    gl::Buffer mLevelsBuffer;
    gl::Texture mLevelsTexture;  ///< GL_TEXTURE_BUFFER over mLevelsBuffer, R16UI
    std::vector<std::uint16_t> mCodes;
    // render_mode = blocks: the frame's index lists (in mTemplateIndices, bound to the template's vertex array) and
    // one indirect draw command a node.
    bool mBlockIndices = false;
    std::optional<BlockTriangles> mBlockTriangles;
    std::vector<std::uint32_t> mFrameIndices;
    std::vector<std::uint16_t> mFrameShortIndices;
    gl::Buffer mCommandsBuffer;
    struct DrawCommand {  // DrawElementsIndirectCommand
        GLuint count;
        GLuint instances;
        GLuint firstIndex;
        GLint baseVertex;
        GLuint baseInstance;
    };
    std::vector<DrawCommand> mCommands;
    // The frame's nodes in drawing order: the draw list's, near ones first, grouped by program and arrays.
    struct FrameNode {
        const DrawnNode* drawn;
        int program;
    };
    std::vector<FrameNode> mFrameNodes;
    std::optional<TriangleFeedback> mFeedback;  ///< draw(..., feedback)
    std::optional<PixelCounter> mCounter;       ///< PoolOptions::pixelCounts
    std::uint64_t mFrame = 0;                   ///< frames drawn
};
}  // namespace terrain
