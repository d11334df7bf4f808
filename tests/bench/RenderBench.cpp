// Triangle throughput of the chunk renderer against a brute-force single mesh with the same triangle
// count, on the same OpenGL context and camera path: per camera, the brute-force mesh is the
// engine's own triangles of that frame merged into one static mesh (positions and normals, one draw
// call, a plain lit shader), so the ratio is what the engine's per-node machinery (template mesh, node
// pools, morphing and normals in the vertex program, textures, one instanced draw) costs. Needs a display: run under
// Xvfb,
//
//   xvfb-run -a -s "-screen 0 1280x720x24" build/tests/RenderBench
//
// and read `ratio` (engine Mtriangles/s over brute force Mtriangles/s; target >= 0.8).
#include "gpudata/NodeVertexData.h"
#include "gpudata/TemplateMesh.h"
#include "gpudata/ZigzagIndexBuffer.h"
#include "heightfield/HeightFieldIo.h"
#include "lod/CameraPath.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "quadtree/QuadtreeBuilder.h"
#include "render/GlWindow.h"
#include "render/ShaderProgram.h"
#include "render/TerrainRenderer.h"

#include <benchmark/benchmark.h>
#include <glm/gtc/type_ptr.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace {

using namespace terrain;

constexpr int kFrames = 48;  ///< camera positions along the demo path
constexpr int kRepeats = 2;  ///< each frame drawn this often per measurement

/// Everything both measurements share: the context, the map, the cameras.
struct Scene {
    std::unique_ptr<GlWindow> window;
    std::unique_ptr<MapFile> map;
    std::vector<Camera> cameras;
    double spacing = 90.0;
    double engineTrianglesPerFrame = 0;
    double engineMtrisPerSecond = 0;
    double bruteMtrisPerSecond = 0;
};

Scene& scene()
{
    static Scene s = [] {
        Scene made;
        WindowOptions options;
        options.visible = false;
        auto window = GlWindow::create(options);
        if (!window.ok()) {
            std::fprintf(stderr, "%s\n", window.error().message.c_str());
            std::exit(1);
        }
        made.window = std::move(window.value());
        auto field = readHeightField(std::filesystem::path(TERRAIN_DEMO_DATA_DIR) / "trinidad_co_srtm3_crop_1025.png");
        const auto mapPath = std::filesystem::temp_directory_path() / "render-bench.map";
        BuildOptions build;
        build.spacing = made.spacing;
        build.threads = 2;
        if (!buildMap(std::move(field.value()), build, mapPath).ok()) {
            std::exit(1);
        }
        made.map = std::move(MapFile::open(mapPath, ReaderKind::MemoryMapped).value());
        auto path = CameraPath::load(std::filesystem::path(TERRAIN_DEMO_DIR) / "trinidad.path").value();
        for (int f = 0; f < kFrames; ++f) {
            Camera camera;
            camera.nearPlane = 1.0;
            camera.farPlane = 200000.0;
            path.evaluate(path.startTime() + path.duration() * f / (kFrames - 1)).applyTo(camera);
            made.cameras.push_back(camera);
        }
        return made;
    }();
    return s;
}

void BM_ChunkRenderer(benchmark::State& state)
{
    Scene& s = scene();
    // render_mode = tessellation (Arg 2 = 1): the selection at 1 px, the blocks at the other 1 px of tau 2.
    const bool tessellation = state.range(1) != 0;
    const double nodePixels = tessellation ? 1.0 : 2.0, blockPixels = tessellation ? 1.0 : 0.0;
    // Arg 3: normal maps of 129 texels a node (dynamic_texture_size 128, made by subdivision alone here) as
    // RG8 (1) or RGTC2 blocks (2); 0: none, lit by vertex normals.
    const int normalMaps = static_cast<int>(state.range(2));
    TerrainNodeSource source(*s.map, {nullptr, 0.0, tessellation ? kTessellationBlockQuads : 0,
                                      normalMaps > 0 ? 128 : 0, true, normalMaps == 2});
    StreamerOptions options;
    options.cacheSize = s.map->directory().size();
    options.workers = 2;
    auto renderer = TerrainRenderer::create(TERRAIN_SHADER_DIR, s.map->header(), 16,
                                            {options.cacheSize, state.range(0) != 0, tessellation,
                                             normalMaps > 0 ? 129 : 0, normalMaps == 2})
                        .value();
    auto streamer = TerrainStreamer::create(source, extentOf(s.map->header()), options).value();
    std::size_t drawCalls = 0;
    SceneStyle style;
    style.drawSky = false;  // triangles only: the brute-force side draws no sky either
    double seconds = 0, triangles = 0;
    for (auto _ : state) {
        for (const Camera& camera : s.cameras) {
            // Load everything the view wants first: the measurement is drawing only.
            streamer->settle(Settle::Complete, camera, nodePixels);
            const DrawList frame = makeDrawList(streamer->selection(), *streamer, camera, blockPixels);
            for (int r = 0; r < kRepeats; ++r) {
                auto start = std::chrono::steady_clock::now();
                RenderStats stats = renderer->draw(frame, style);
                drawCalls = std::max(drawCalls, stats.drawCalls);
                glFinish();
                seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
                triangles += static_cast<double>(stats.triangles);
            }
        }
    }
    if (!tessellation) {  // the brute-force mesh draws the chunks' triangles
        s.engineTrianglesPerFrame = triangles / (static_cast<double>(state.iterations()) * kFrames * kRepeats);
        s.engineMtrisPerSecond = triangles / seconds / 1e6;
    }
    state.counters["triangles_per_frame"] = triangles / (static_cast<double>(state.iterations()) * kFrames * kRepeats);
    state.counters["Mtriangles_per_s"] = triangles / seconds / 1e6;
    state.counters["ms_per_frame"] = 1e3 * seconds / (static_cast<double>(state.iterations()) * kFrames * kRepeats);
    state.counters["draw_calls"] = static_cast<double>(drawCalls);
    state.counters["gpu_bytes_per_node"] = static_cast<double>(renderer->slotBytes().total());
}
// Args: node_texture_compression (DXT1 colour layers) on or off, render_mode chunks (0) or tessellation (1),
// normal maps (none 0, RG8 1, RGTC2 2); the brute-force ratio is against the last (chunks, uncompressed, no
// normal maps).
BENCHMARK(BM_ChunkRenderer)
    ->Args({0, 0, 1})
    ->Args({0, 0, 2})
    ->Args({1, 0, 0})
    ->Args({0, 1, 0})
    ->Args({0, 0, 0})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

constexpr const char* kBruteVertex = R"(#version 330 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
uniform mat4 uViewProjection;
out vec3 vNormal;
out vec3 vRelative;
void main()
{
    vRelative = aPosition;  // camera-relative already
    vNormal = aNormal;
    gl_Position = uViewProjection * vec4(vRelative, 1.0);
}
)";
constexpr const char* kBruteFragment = R"(#version 330 core
in vec3 vNormal;
in vec3 vRelative;
uniform vec3 uSun;
out vec4 fragColour;
void main()
{
    vec3 albedo = vec3(0.4, 0.45, 0.3);
    vec3 colour = albedo * (0.35 + max(dot(normalize(vNormal), uSun), 0.0));
    float haze = 1.0 - exp(-length(vRelative) / 60000.0);
    fragColour = vec4(mix(colour, vec3(0.68, 0.76, 0.86), haze), 1.0);
}
)";

void BM_BruteForceMesh(benchmark::State& state)
{
    Scene& s = scene();
    // Per camera, the very triangles the engine drew (selected nodes, morphed, with skirts) merged into
    // one static mesh with positions and normals, drawn with one call and a plain lit shader: the raw
    // throughput of those triangles on this context. Building and uploading it is not timed.
    TerrainNodeSource source(*s.map, {});
    StreamerOptions options;
    options.cacheSize = s.map->directory().size();
    options.workers = 2;
    auto streamer = TerrainStreamer::create(source, extentOf(s.map->header()), options).value();
    const MapHeader& header = s.map->header();
    const TemplateMesh mesh = buildTemplateMesh(static_cast<int>(header.chunkSize));
    const std::vector<std::uint32_t> templateIndices = buildZigzagIndices(static_cast<int>(header.chunkSize), 16, true);
    auto program = ShaderProgram::fromSource("brute", kBruteVertex, kBruteFragment).value();
    auto vao = gl::VertexArray::create();
    auto vbo = gl::Buffer::create();
    auto ibo = gl::Buffer::create();
    glBindVertexArray(vao.name());
    glBindBuffer(GL_ARRAY_BUFFER, vbo.name());
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                          reinterpret_cast<const void*>(3 * sizeof(float)));
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo.name());
    double seconds = 0, triangles = 0;
    for (auto _ : state) {
        for (const Camera& camera : s.cameras) {
            streamer->settle(Settle::Complete, camera, 2.0);
            std::vector<float> vertices;
            std::vector<std::uint32_t> indices;
            for (const SelectedNode& selected : streamer->selection().nodes) {
                NodePtr node = streamer->node(selected.id);
                const double spacing = node->spacing;
                std::vector<float> surface(node->heights.base.size());
                node->heights.surface(surface);
                const auto data = buildNodeVertices(mesh, surface, node->spacing, node->materialWeights);
                NodePtr parent = selected.id.isRoot() ? node : streamer->node(selected.id.parent());
                const double skirt = std::max(parent->deltaC, node->deltaC) + header.heightStep;
                const float morph = selected.id.isRoot() ? 1.0f : selected.morph;
                const auto base = static_cast<std::uint32_t>(vertices.size() / 6);
                for (std::size_t k = 0; k < mesh.vertices.size(); ++k) {
                    const TemplateVertex& t = mesh.vertices[k];
                    const NodeVertex& v = data[k];
                    const double z = header.heightOffset - camera.position.z + v.parent + morph * (v.own - v.parent) -
                                     t.skirt * skirt;
                    const float nx = (v.parentNormal[0] + morph * (v.ownNormal[0] - v.parentNormal[0])) / 32767.0f;
                    const float ny = (v.parentNormal[1] + morph * (v.ownNormal[1] - v.parentNormal[1])) / 32767.0f;
                    vertices.insert(vertices.end(),
                                    {static_cast<float>(selected.cameraRelativeOrigin.x + t.i * spacing),
                                     static_cast<float>(selected.cameraRelativeOrigin.y + t.j * spacing),
                                     static_cast<float>(z), nx, ny, std::sqrt(std::max(0.0f, 1 - nx * nx - ny * ny))});
                }
                for (std::uint32_t index : templateIndices) {
                    indices.push_back(base + index);
                }
            }
            glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)), vertices.data(),
                         GL_STATIC_DRAW);
            glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * 4), indices.data(),
                         GL_STATIC_DRAW);
            glFinish();
            for (int r = 0; r < kRepeats; ++r) {
                auto start = std::chrono::steady_clock::now();
                glViewport(0, 0, camera.viewportWidth, camera.viewportHeight);
                glClearColor(0.68f, 0.76f, 0.86f, 1.0f);
                glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
                glEnable(GL_DEPTH_TEST);
                glEnable(GL_CULL_FACE);
                program.use();
                const glm::mat4 viewProjection(camera.projection() * camera.viewRotation());
                glUniformMatrix4fv(program.uniform("uViewProjection"), 1, GL_FALSE, glm::value_ptr(viewProjection));
                glUniform3f(program.uniform("uSun"), 0.5f, -0.5f, 0.7f);
                glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(indices.size()), GL_UNSIGNED_INT, nullptr);
                glFinish();
                seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
                triangles += static_cast<double>(indices.size() / 3);
            }
        }
    }
    s.bruteMtrisPerSecond = triangles / seconds / 1e6;
    state.counters["triangles_per_frame"] = triangles / (static_cast<double>(state.iterations()) * kFrames * kRepeats);
    state.counters["Mtriangles_per_s"] = s.bruteMtrisPerSecond;
    state.counters["ms_per_frame"] = 1e3 * seconds / (static_cast<double>(state.iterations()) * kFrames * kRepeats);
    if (s.engineMtrisPerSecond > 0) {
        state.counters["ratio"] = s.engineMtrisPerSecond / s.bruteMtrisPerSecond;
    }
}
BENCHMARK(BM_BruteForceMesh)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
