// The chunk renderer (paper 3.2.6-3.2.11, 4.2.3): one template mesh for every node, geomorphed and skirted
// in the vertex program, front to back in the selector's order. Node data lives in pools allocated once for
// the cache's capacity (4.2.3): a slot per resident node, a layer of one of each pool's texture arrays, taken
// when the node is first drawn and given back when the cache evicts it. A frame's nodes go in one instanced
// draw per program and pair of arrays (the node's and its parent's; one pair while the pools fit one array).
#pragma once

#include "core/Camera.h"
#include "core/Expected.h"
#include "lod/LodSelector.h"
#include "lod/NodeData.h"
#include "lod/NodeMemory.h"
#include "lod/TessellationLevels.h"
#include "quadtree/MapFormat.h"
#include "render/DetailLayers.h"
#include "render/GlObjects.h"
#include "render/ShaderProgram.h"
#include "render/Sky.h"
#include "render/TemplateMesh.h"
#include "synthesis/Material.h"

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <unordered_map>
#include <vector>

namespace terrain {

struct RenderStats {
    std::size_t nodes = 0;
    std::size_t staticNodes = 0;
    std::size_t dynamicNodes = 0;
    std::uint64_t triangles = 0;
    std::size_t uploads = 0;   ///< nodes copied into their slots this frame
    std::size_t gpuNodes = 0;  ///< slots holding a node after the frame
    /// Draw calls for the terrain (the sky not counted): one per program and pair of pool arrays (the nodes',
    /// their parents') that has nodes in view; 1 when the pools fit one array and no detail layers split it.
    std::size_t drawCalls = 0;
    std::size_t blocks = 0;                ///< tessellation mode: blocks drawn (not culled)
    std::size_t culledBlocks = 0;          ///< tessellation mode: blocks of drawn nodes outside the frustum
    std::size_t occludedBlocks = 0;        ///< tessellation mode: blocks drawn at their coarsest, hidden (`occluded`)
    std::uint64_t generatedTriangles = 0;  ///< with transform feedback: the triangles the GL says it made
};

/// The node pools' size and formats.
struct PoolOptions {
    std::size_t slots = 512;      ///< nodes: the cache's capacity (memory_budget or quad_cache_size)
    bool compressColour = false;  ///< DXT1 colour layers (node_texture_compression), where the GL has S3TC
    /// render_mode = tessellation: blocks of kTessellationBlockQuads quads tessellated at the levels
    /// chooseBlockLevels picks (lod/TessellationLevels.h); needs GL 4.0 (tessellationSupported()) and nodes
    /// with tessellation errors.
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
    /// Layers of each texture array (0: GL_MAX_ARRAY_TEXTURE_LAYERS): more slots take more arrays per pool.
    /// Tests set a few to draw with several arrays.
    std::size_t layersPerArray = 0;
};

/// The visible pixels of the nodes drawn in one frame (PoolOptions::pixelCounts), and its depth.
struct PixelCounts {
    std::uint64_t frame = 0;            ///< draw()'s frame number: 1 for the first frame drawn
    std::vector<NodeId> nodes;          ///< the nodes drawn, in drawing order
    std::vector<std::uint32_t> pixels;  ///< per node, its fragments that passed the depth test
    /// The frame's depth buffer after the terrain (DepthOcclusion's input), row 0 at the bottom, and the
    /// camera it was drawn with; empty when nothing was drawn.
    std::vector<float> depth;
    Camera camera;
};

class TerrainRenderer {
public:
    /// Loads the shaders from `shaderDirectory`, builds the template mesh for `header`'s chunk size with the
    /// zigzag order for `vertexCacheSize`, and allocates the node pools: `pools.slots` nodes' heights,
    /// normals, colour textures and material weights in texture arrays. With
    /// `materials`, their detail textures (render/DetailLayers.h) are drawn over the nodes' colours, blended by
    /// the nodes' material weights (NodeData::materialWeights). Errors name the file, or the GL limit that the
    /// slots exceed. Needs a current GL context.
    static Expected<std::unique_ptr<TerrainRenderer>> create(const std::filesystem::path& shaderDirectory,
                                                             const MapHeader& header, int vertexCacheSize,
                                                             const PoolOptions& pools,
                                                             const MaterialSet* materials = nullptr);

    /// Clears, draws the sky and every node of `selection` (made for `camera`) in one instanced draw (two
    /// with detail layers: nodes beyond every layer's fade go in a second one, drawn by a program without
    /// the layers), the nodes' data from `resident` (the node cache: every selected node and its parent must be
    /// resident). A node gets a slot the first time it is drawn and keeps it until release().
    /// In tessellation mode the blocks spend `blockPixels` of error (the selection was made for the rest of tau).
    /// With `feedback` (tessellation mode, for tests), the camera-relative corners of every triangle the
    /// tessellator made are read back by transform feedback, three a triangle, in drawing order (node by node
    /// as drawn, patch by patch: blocks, then skirts). With `occluded` (tessellation mode, visibility_lod: the
    /// previous frame's depth), hidden blocks with no visible neighbour are drawn at their coarsest level
    /// (drawnBlockLevels).
    RenderStats draw(const LodSelection& selection, const ResidentNodeLookup& resident, const Camera& camera,
                     const SceneStyle& style, double blockPixels = 0.0, std::vector<glm::vec3>* feedback = nullptr,
                     const BoxOccluded& occluded = {});

    /// Whether this context runs tessellation shaders (OpenGL 4.0).
    static bool tessellationSupported();
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
    bool takePixelCounts(PixelCounts& out, std::uint64_t lag = kPixelCountLag);
    /// The depth buffer of the frame just drawn (the bound framebuffer's, `width` x `height` from its
    /// origin), rows bottom to top, read at once: waits for the GL. For measuring (tengine
    /// measure_error_every), not for drawing: the pixel counts' depth comes late and does not wait.
    static std::vector<float> readDepth(int width, int height);
    /// Frames whose pixel counts were dropped untaken.
    std::uint64_t droppedPixelCounts() const { return mDroppedCounts; }

    /// The node cache evicted `id` (TerrainStreamer::onEvict): its slot is free for another node. Nothing
    /// is freed on the GPU. Unknown ids are ignored (a node evicted before it was ever drawn).
    void release(const NodeId& id);

    const SlotBytes& slotBytes() const { return mSlotBytes; }
    std::size_t slots() const { return mSlotData.size(); }

private:
    TerrainRenderer(const MapHeader& header) : mHeader(header) {}
    /// The node's slot, copying it there when it is new; a new node takes a free slot in `preferredArray`'s
    /// layers when there is one (its parent's: a node and its parent in one array draw together).
    int slotFor(const NodePtr& node, RenderStats& stats, int preferredArray = -1);
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
        gl::Texture colour;         ///< DXT1 (or GL_RGB8), mColourLayerSize^2 per layer
        gl::Texture weights;        ///< GL_RGBA4, N^2 per layer; none without materials
        gl::Texture normalMaps;     ///< RGTC2 (or GL_RG8_SNORM), mNormalLayerSize^2 per layer; or none
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
    std::vector<NodePtr> mSlotData;                  ///< per slot: the node it holds (identity for reloads), or null
    std::vector<std::vector<int>> mFreeSlots;        ///< per array, a stack
    std::unordered_map<std::uint64_t, int> mSlotOf;  ///< by node key
    // The frame's per-node constants (terrain.vert's per-instance attributes: mNodeTexels vec4s a node).
    int mNodeTexels = 3;
    std::vector<float> mConstants;
    gl::Buffer mConstantsBuffer;
    // Tessellation mode: patches (blocks, then border skirts) and the frame's block codes.
    bool mTessellation = false;
    QuadtreeExtent mExtent;
    int mBlocks = 0;  ///< per side
    gl::VertexArray mPatchVao;
    gl::Buffer mPatchIds;
    gl::Buffer mLevelsBuffer;
    gl::Texture mLevelsTexture;  ///< GL_TEXTURE_BUFFER over mLevelsBuffer, R16UI
    std::vector<std::uint16_t> mCodes;
    // The frame's nodes before they are ordered into draws, and the draws.
    struct FrameNode {
        const SelectedNode* selected;
        const NodeData* node;    ///< held by the cache for the frame
        const NodeData* parent;  ///< the node itself for the root
        int slot;
        int parentSlot;
        int program;
    };
    std::vector<FrameNode> mFrameNodes;
    gl::Buffer mFeedback;  ///< transform feedback of draw(..., feedback)
    // Pixel counts: three frames' buffers in turn (frame % 3), each a uint a drawn node.
    struct CountFrame {
        gl::Buffer buffer;
        std::size_t capacity = 0;  ///< nodes the buffer holds
        gl::Fence fence;           ///< after the frame's draws; none when nothing was drawn
        std::uint64_t frame = 0;   ///< 0: nothing waiting to be taken
        std::vector<NodeId> nodes;
        gl::Buffer depth;             ///< pixel pack buffer the depth is read into
        std::size_t depthPixels = 0;  ///< its size
        bool hasDepth = false;        ///< this frame's depth was read
        Camera camera;
    };
    bool mPixelCounts = false;
    std::array<CountFrame, 3> mCountFrames;
    std::uint64_t mFrame = 0;  ///< frames drawn
    std::uint64_t mDroppedCounts = 0;
};
}  // namespace terrain
