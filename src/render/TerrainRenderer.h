// The chunk renderer (paper 3.2.6-3.2.11, 4.2.3): one template mesh for every node, each node drawn
// with its own heights and texture, geomorphed and skirted in the vertex program, front to back in the
// selector's order. GPU copies of node data live as long as the node stays in the cache.
#pragma once

#include "core/Camera.h"
#include "core/Expected.h"
#include "lod/TerrainStreamer.h"
#include "quadtree/MapFormat.h"
#include "render/GlObjects.h"
#include "render/ShaderProgram.h"
#include "render/TemplateMesh.h"
#include "synthesis/Material.h"

#include <glm/vec3.hpp>

#include <filesystem>
#include <memory>
#include <unordered_map>

namespace terrain {

/// How the scene looks (config options draw_sky, sun_*, haze_distance, clear_color, wireframe).
struct SceneStyle {
    glm::vec3 sunDirection{0.5f, -0.5f, 0.7f};  ///< towards the sun; normalised by the renderer
    glm::vec3 sunColour{1.0f, 0.95f, 0.85f};
    glm::vec3 ambient{0.35f, 0.4f, 0.5f};
    glm::vec3 hazeColour{0.68f, 0.76f, 0.86f};
    glm::vec3 zenithColour{0.25f, 0.45f, 0.8f};
    glm::vec3 clearColour{0.68f, 0.76f, 0.86f};
    float hazeDistance = 60000.0f;  ///< metres
    bool drawSky = true;
    bool wireframe = false;
    bool geomorph = true;  ///< false: every node at its own detail, morph factor 1 (shows popping)
};

struct RenderStats {
    std::size_t nodes = 0;
    std::size_t staticNodes = 0;
    std::size_t dynamicNodes = 0;
    std::uint64_t triangles = 0;
    std::size_t uploads = 0;   ///< nodes copied to the GPU this frame
    std::size_t gpuNodes = 0;  ///< nodes with GPU copies after the frame
};

class TerrainRenderer {
public:
    /// Loads the shaders from `shaderDirectory` and builds the template mesh for `header`'s chunk size with
    /// the zigzag order for `vertexCacheSize`. With `materials`, their detail textures are drawn over the
    /// nodes' colours, blended by the nodes' material weights (NodeData::materialWeights): material m's k-th
    /// detail_texture repeats every detail_texture_size / 4^k metres (a finer layer of the same ground).
    /// All detail textures must have the same size (they share one texture array); at most kMaxDetailLayers.
    /// Errors name the file. Needs a current GL context.
    static Expected<std::unique_ptr<TerrainRenderer>> create(const std::filesystem::path& shaderDirectory,
                                                             const MapHeader& header, int vertexCacheSize,
                                                             const MaterialSet* materials = nullptr);

    /// Detail texture layers the shader blends (shaders/terrain.frag, kMaxLayers).
    static constexpr int kMaxDetailLayers = 8;

    /// Clears, draws the sky and every node of `streamer`'s current selection. `camera` must be the one the
    /// selection was made with.
    RenderStats draw(const TerrainStreamer& streamer, const Camera& camera, const SceneStyle& style);

private:
    struct GpuNode {
        NodePtr data;         ///< keeps the CPU copy alive while the GPU copy is in use; identity for eviction
        gl::Buffer vertices;  ///< NodeVertex per template vertex (render/NodeVertexData.h)
        gl::Texture colour;
        std::uint64_t lastFrame = 0;
    };
    TerrainRenderer(const MapHeader& header) : mHeader(header) {}
    GpuNode& upload(const NodePtr& node, RenderStats& stats);
    void releaseEvicted(const TerrainStreamer& streamer);
    void drawSky(const Camera& camera, const SceneStyle& style);

    MapHeader mHeader;
    TemplateMesh mMesh;
    /// The terrain program: [kNear] with the materials' detail layers (or the only one without materials),
    /// [kFar] the same without the layers, for nodes beyond every layer's fade.
    std::vector<ShaderProgram> mPrograms;
    static constexpr std::size_t kNear = 0;
    static constexpr std::size_t kFar = 1;
    /// Uniform locations set per node, one entry per program variant.
    struct NodeUniforms {
        GLint origin, spacing, morph, skirt, parentOffset;
        std::vector<GLint> layerOrigin;  ///< uLayerOrigin[k]
    };
    std::vector<NodeUniforms> mLocations;
    double mCoarsestLayer = 0.0;  ///< metres per repeat of the detail layer that fades out last
    ShaderProgram mSky;
    gl::VertexArray mTemplateVao;
    gl::Buffer mTemplateVertices;
    gl::Buffer mTemplateIndices;
    GLsizei mIndexCount = 0;
    GLenum mIndexType = GL_UNSIGNED_INT;
    std::uint64_t mTrianglesPerNode = 0;
    gl::VertexArray mEmptyVao;       ///< the sky's full-screen triangle needs no attributes
    gl::Texture mDetail;             ///< GL_TEXTURE_2D_ARRAY of the detail layers, or none
    std::vector<double> mLayerSize;  ///< metres per repeat of each detail layer
    /// Repeats of a detail layer beyond which the fragment shader has faded it out (terrain.frag).
    static constexpr double kDetailFadeRepeats = 40.0;
    std::unordered_map<std::uint64_t, GpuNode> mGpuNodes;
    std::uint64_t mFrame = 0;
};

}  // namespace terrain
