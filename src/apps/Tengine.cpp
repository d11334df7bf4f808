// tengine: the viewer (paper 4.2, 4.4.2). Wires options, map, streamer, renderer and window together;
// three ways to drive the camera: the user (mouse and keys), demo_mode (camera_path in real time, looping)
// and video_mode (camera_path once at a fixed time step, every frame (or every video_save_every-th) saved
// as a PNG, plus a CSV of per-frame statistics and, when ffmpeg is installed, an MP4).
#include "DataDirectories.h"
#include "DetailSetup.h"
#include "FrameRateMeter.h"
#include "NodeBudget.h"
#include "TengineOptions.h"
#include "VideoRecorder.h"

#include "core/Memory.h"
#include "core/StopSignals.h"
#include "lod/CameraPath.h"
#include "lod/ClipmapLayout.h"
#include "lod/ClipmapTerrain.h"
#include "lod/ErrorMeter.h"
#include "lod/HeightQuery.h"
#include "lod/NodeVisibility.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "render/ClipmapRenderer.h"
#include "render/FrameCapture.h"
#include "render/GlWindow.h"
#include "render/TerrainRenderer.h"
#include "render/TextOverlay.h"
#include "synthesis/NormalMap.h"

#include <GLFW/glfw3.h>
#include <glm/geometric.hpp>

#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace terrain;

/// How far around a box the previous frame's depth must hide it (DepthOcclusion): the image moves in the frames
/// between that depth and the one drawn with it (kPixelCountLag), most at silhouettes a low flight crosses.
constexpr int kOcclusionMarginPixels = 8;

/// Messages to stderr and, when log_file is set, to the log.
class Log {
public:
    explicit Log(const std::filesystem::path& file)
    {
        if (!file.empty()) {
            errno = 0;
            mFile.open(file, std::ios::app);
            if (!mFile.is_open()) {
                mError = errno != 0 ? std::strerror(errno) : "it cannot be opened for appending";
            }
        }
    }
    bool ok() const { return mError.empty() && (!mFile.is_open() || mFile.good()); }
    /// Why the file could not be opened (the system's reason).
    const std::string& error() const { return mError; }
    void operator()(const std::string& message)
    {
        std::fprintf(stderr, "tengine: %s\n", message.c_str());
        if (mFile.is_open()) {
            mFile << message << '\n';
            mFile.flush();
        }
    }

private:
    std::ofstream mFile;
    std::string mError;
};

SceneStyle styleFrom(const TengineOptions& o)
{
    SceneStyle style;
    const double az = o.sunAzimuth * kRadiansPerDegree, el = o.sunElevation * kRadiansPerDegree;
    style.sunDirection = glm::vec3(static_cast<float>(std::sin(az) * std::cos(el)),
                                   static_cast<float>(std::cos(az) * std::cos(el)), static_cast<float>(std::sin(el)));
    style.hazeDistance = o.hazeDistance > 0 ? static_cast<float>(o.hazeDistance) : 1e30f;
    style.clearColour = o.clearColor;
    style.drawSky = o.drawSky;
    style.wireframe = o.wireframe;
    style.geomorph = o.geomorph;
    return style;
}

/// Key presses as events (GLFW's key callback), so a tap shorter than a frame is never lost however slow
/// the frame; held keys are still read with glfwGetKey for smooth movement.
class KeyPresses {
public:
    /// `window` null (headless): no keys.
    explicit KeyPresses(GLFWwindow* window) : mWindow(window)
    {
        if (!window) {
            return;
        }
        glfwSetWindowUserPointer(window, this);
        glfwSetKeyCallback(window, [](GLFWwindow* w, int key, int, int action, int) {
            if (action == GLFW_PRESS) {
                static_cast<KeyPresses*>(glfwGetWindowUserPointer(w))->mPressed.push_back(key);
            }
        });
    }
    ~KeyPresses()
    {
        if (!mWindow) {
            return;
        }
        glfwSetKeyCallback(mWindow, nullptr);
        glfwSetWindowUserPointer(mWindow, nullptr);
    }
    KeyPresses(const KeyPresses&) = delete;
    KeyPresses& operator=(const KeyPresses&) = delete;

    /// The keys pressed since the last call, in order (call after pollEvents).
    std::vector<int> take() { return std::exchange(mPressed, {}); }

private:
    GLFWwindow* mWindow;
    std::vector<int> mPressed;
};

/// Mouse look and w/s/a/d/q/z movement (paper 4.4.2), kept camera_min_clearance above the drawn surface.
class FreeFlight {
public:
    FreeFlight(GLFWwindow* window, double speed) : mWindow(window), mSpeed(speed)
    {
        glfwSetInputMode(window, GLFW_CURSOR, GLFW_CURSOR_DISABLED);
        glfwGetCursorPos(window, &mLastX, &mLastY);
    }

    /// Moves the camera by the mouse and the held keys over `dt` seconds; then lifts it to `floor` metres
    /// when it is below (the drawn surface plus the clearance; empty where nothing is drawn).
    void update(Camera& camera, double dt, const std::function<std::optional<double>(double, double)>& floor)
    {
        double x = 0, y = 0;
        glfwGetCursorPos(mWindow, &x, &y);
        // The first position after disabling the cursor is where GLFW centred it, not a mouse movement:
        // turning by it would throw away camera_yaw and camera_pitch.
        if (mLooking) {
            constexpr double kRadiansPerPixel = 0.0025;
            camera.yaw += (x - mLastX) * kRadiansPerPixel;
            camera.pitch = std::clamp(camera.pitch - (y - mLastY) * kRadiansPerPixel, -1.55, 1.55);
        }
        mLooking = true;
        mLastX = x;
        mLastY = y;
        auto down = [&](int key) { return glfwGetKey(mWindow, key) == GLFW_PRESS ? 1.0 : 0.0; };
        const glm::dvec3 move = camera.forward() * (down(GLFW_KEY_W) - down(GLFW_KEY_S)) +
                                camera.right() * (down(GLFW_KEY_D) - down(GLFW_KEY_A)) +
                                camera.up() * (down(GLFW_KEY_Q) - down(GLFW_KEY_Z));
        camera.position += move * (mSpeed * dt);
        if (const auto lowest = floor(camera.position.x, camera.position.y); lowest && camera.position.z < *lowest) {
            camera.position.z = *lowest;
        }
    }
    /// A key press with an effect per press: 1/2 double or halve the speed, l toggles wireframe, k appends
    /// the camera's pose at `seconds` to `recordPath`.
    void pressed(int key, const Camera& camera, SceneStyle& style, double seconds,
                 const std::filesystem::path& recordPath, Log& log)
    {
        if (key == GLFW_KEY_1) {
            mSpeed *= 2.0;
        } else if (key == GLFW_KEY_2) {
            mSpeed /= 2.0;
        } else if (key == GLFW_KEY_L) {
            style.wireframe = !style.wireframe;
            log(style.wireframe ? "wireframe on" : "wireframe off");
        } else if (key == GLFW_KEY_K) {
            const CameraKeyframe keyframe{seconds, camera.position, camera.yaw, camera.pitch};
            auto appended = appendKeyframe(recordPath, keyframe);
            log(appended.ok() ? "camera keyframe appended to " + recordPath.string() : appended.error().message);
        }
    }

private:
    GLFWwindow* mWindow;
    double mSpeed;
    double mLastX = 0, mLastY = 0;
    bool mLooking = false;
};

/// Video mode's frames.csv columns. Per frame: cache_hits, cache_misses, requests_made, requests_completed
/// and requests_failed (groups that could not be loaded); now: cache_nodes, requests_pending (queued plus
/// loading), resident_bytes (the process's resident set), deepest_level (of the nodes drawn; below the
/// map's levels - 1 they are dynamic) and draw_calls (for the terrain: 1); since the start: requests_pending_peak (the
/// most queued plus loading at once, NodeServerStats::peakPending). With visibility_lod (else 0): nodes_hidden
/// (drawn as they are, hidden), requests_skipped_hidden (of those, the ones whose children were not resident),
/// nodes_revealing (morphing in after a reveal). dynamic_groups_made: groups of four dynamic nodes the workers
/// synthesized that arrived this frame (FrameStats::synthesized). New columns go at the end: readers cut
/// columns by position. blocks_occluded: tessellation mode with visibility_lod, blocks of drawn nodes made
/// coarsest, behind the previous frame's depth. error_max_px, error_p99_px: with video_measure_error_every, the
/// measured screen-space error of what the frame shows (empty in frames not measured). cache_short: groups of
/// children the selection wanted that the node cache had no room for (FrameStats::deferred; memory_budget).
constexpr const char* kCsvHeader =
    "frame,time_s,milliseconds,triangles,nodes_static,nodes_dynamic,cache_nodes,cache_hits,cache_misses,"
    "requests_made,requests_completed,requests_pending,requests_failed,requests_pending_peak,resident_bytes,"
    "deepest_level,draw_calls,nodes_hidden,requests_skipped_hidden,nodes_revealing,dynamic_groups_made,blocks_occluded,"
    "error_max_px,error_p99_px,cache_short";

/// Everything the viewer draws with, opened from the options in dependency order. Not movable: the source
/// refers to the map and the synthesizer, the streamer to the source.
struct Scene {
    std::unique_ptr<MapFile> map;
    std::unique_ptr<const DetailSynthesizer> synthesizer;
    std::optional<CameraPath> path;
    std::unique_ptr<GlWindow> window;
    std::unique_ptr<TerrainRenderer> renderer;
    std::unique_ptr<TextOverlay> overlay;
    std::unique_ptr<TerrainNodeSource> source;
    std::unique_ptr<TerrainStreamer> streamer;
    bool tessellation = false;  ///< render_mode = tessellation, and the GL has it
    /// visibility_lod, and the GL counts pixels: what the renderer's pixel counts say is hidden; else null.
    std::unique_ptr<NodeVisibility> visibility;
    PixelCounts pixelCounts;                  ///< reused for each frame's counts
    std::optional<DepthOcclusion> occlusion;  ///< the depth of the latest frame measured
    double nodePixels = 2.0;                  ///< the selection's tau: all of lod_error, or what the blocks leave of it
    double blockPixels = 0.0;                 ///< tessellation: the blocks' part of lod_error
    /// video_measure_error_every: the reference the frames are measured against (tengine-tool error's), last
    /// so that it goes first.
    std::unique_ptr<TerrainNodeSource> referenceSource;
    std::unique_ptr<ErrorMeter> meter;
    /// lod_mode = clipmap (seed 002): the rings' layout and data and their renderer; the quadtree renderer
    /// is not made.
    std::optional<ClipmapLayout> clipmapLayout;
    std::unique_ptr<ClipmapTerrain> clipmap;
    std::unique_ptr<ClipmapRenderer> clipmapRenderer;
    int clipmapFirstRing = 0;  ///< the finest ring drawn this frame

    const MapHeader& header() const { return map->header(); }
};

/// lod_mode = clipmap: the finest ring's quadtree level, the deepest whose spacing is at least
/// clipmap_finest_spacing (and lod_minimum_spacing), below the map's data only with synthesis.
int clipmapFinestLevel(const TengineOptions& o, const MapHeader& header, bool synthesis)
{
    const double limit = std::max(o.clipmapFinestSpacing, o.lodMinimumSpacing);
    const int deepest = synthesis ? NodeId::kMaxLevel : static_cast<int>(header.levels) - 1;
    int level = 0;
    while (level < deepest && header.spacingAt(level + 1) >= limit) {
        ++level;
    }
    return level;
}

/// Opens the map, the materials, the camera path, the window, the renderer and the streamer; errors are
/// logged and end the program with status 1.
/// `materialsDirectory`: the built-in materials (programDataDirectory).
/// The node cache for `scene`'s map and source: what memory_budget pays for at a GPU slot of the pools the
/// options ask for (RGTC2 normal maps where `rgtc2`) plus the CPU bytes of the root (a static node, which holds
/// its height codes too, costs at least what a dynamic one does).
Expected<CacheChoice> nodeCacheFor(Scene& scene, const TengineOptions& o, const MaterialSet* materials, bool rgtc2)
{
    auto root = scene.source->loadRoot();
    TERRAIN_TRY(root);
    const bool s3tc = epoxy_has_gl_extension("GL_EXT_texture_compression_s3tc");
    return chooseCacheSize(o, scene.header(), materials, s3tc, rgtc2, residentBytes(**root),
                           o.clipmap ? SIZE_MAX : TerrainRenderer::maxSlots());
}

std::unique_ptr<Scene> openScene(const ParsedCommandLine& parsed, const std::filesystem::path& materialsDirectory,
                                 Log& log)
{
    const TengineOptions& o = parsed.options;
    auto scene = std::make_unique<Scene>();
    auto fail = [&](const std::string& message) {
        log(message);
        return nullptr;
    };
    auto map = MapFile::open(o.mapFile, o.reader);
    if (!map.ok()) {
        return fail(map.error().message);
    }
    scene->map = std::move(map).value();
    const MapHeader& header = scene->header();
    if (o.dynamicTextureSize > 0 && normalMapCells(o.dynamicTextureSize) > (static_cast<int>(header.chunkSize) - 1)
                                                                               << kMaxNormalMapDepth) {
        return fail("dynamic_texture_size " + std::to_string(o.dynamicTextureSize) + " is more than " +
                    std::to_string(1 << kMaxNormalMapDepth) + "x the " + std::to_string(header.chunkSize - 1) +
                    " cells of " + scene->map->name() +
                    "'s nodes: normal maps sample the surface at most that many levels below a node, and more "
                    "texels would only interpolate it (at most " +
                    std::to_string((header.chunkSize - 1) << kMaxNormalMapDepth) + ")");
    }

    // Detail synthesis (3.4): the synthesizer dynamic nodes are made with, null when it is off.
    std::vector<std::string> materialWarnings;
    auto synthesizer = makeDetailSynthesizer(o, header, materialsDirectory, materialWarnings);
    for (const auto& warning : materialWarnings) {
        log("warning: " + warning);
    }
    if (!synthesizer.ok()) {
        return fail(synthesizer.error().message);
    }
    scene->synthesizer = std::move(synthesizer).value();
    if (scene->synthesizer && !header.hasDetailErrors()) {
        log("warning: " + scene->map->name() +
            " has no estimates of the detail error below its leaves (made by an older prep): no dynamic nodes; "
            "run prep again to get them");
    }
    if (scene->synthesizer && header.hasDetailErrors()) {
        auto recipe = viewerDetailRecipe(o, *scene->synthesizer, materialsDirectory);
        if (!recipe.ok()) {
            return fail(recipe.error().message);
        }
        const auto files = synthesizedMaterialFiles(o, *scene->synthesizer, materialsDirectory);
        if (auto mismatch = detailRecipeMismatch(header, scene->map->name(), *recipe, files)) {
            log("warning: " + *mismatch);
        }
    }
    const MaterialSet* materials = scene->synthesizer ? scene->synthesizer->settings().materials.get() : nullptr;

    if (!o.cameraPath.empty()) {
        auto loaded = CameraPath::load(o.cameraPath);
        if (!loaded.ok()) {
            return fail(loaded.error().message);
        }
        scene->path = std::move(loaded.value());
    }

    WindowOptions windowOptions;
    windowOptions.width = o.windowWidth;
    windowOptions.height = o.windowHeight;
    windowOptions.visible = !(o.videoMode && !o.demoMode);
    windowOptions.title = "tengine - " + o.mapFile.filename().string();
    auto window = GlWindow::create(windowOptions);
    if (!window.ok()) {
        return fail(window.error().message);
    }
    scene->window = std::move(window).value();
    log(scene->window->description());
    const std::filesystem::path shaders =
        o.shaderPath.empty() ? programDataDirectory("shaders", TERRAIN_SHADER_DIR) : o.shaderPath;
    scene->tessellation = o.tessellation;
    if (o.tessellation && !TerrainRenderer::tessellationSupported()) {
        log("render_mode = tessellation needs OpenGL 4.0 tessellation shaders, which this GL lacks: drawing chunks");
        scene->tessellation = false;
    }
    const bool countPixels = o.visibilityLod && TerrainRenderer::pixelCountsSupported();
    if (o.visibilityLod && !countPixels) {
        log("visibility_lod needs OpenGL 4.3 (or GL_ARB_shader_storage_buffer_object and "
            "GL_ARB_shader_image_load_store) to count visible pixels, which this GL lacks: refining all in view");
    }
    if (countPixels) {
        scene->visibility = std::make_unique<NodeVisibility>(o.visibilityHiddenFrames);
    }
    if (o.clipmap) {
        if (o.visibilityLod) {
            log("warning: lod_mode = clipmap draws no quadtree selection: visibility_lod has no effect");
        }
        scene->tessellation = false;
        scene->visibility.reset();
        const bool synthesis = scene->synthesizer && header.hasDetailErrors();
        const int finest = clipmapFinestLevel(o, header, synthesis);
        scene->clipmapLayout.emplace(extentOf(header), static_cast<int>(header.chunkSize), o.clipmapSamples, finest, 0);
        const int normalTexels = o.dynamicTextureSize > 0 ? normalMapTexels(o.dynamicTextureSize) : 0;
        scene->clipmap = std::make_unique<ClipmapTerrain>(
            *scene->clipmapLayout, static_cast<int>(header.chunkSize), static_cast<int>(header.textureSize),
            materials && std::any_of(materials->materials().begin(), materials->materials().end(),
                                     [](const Material& m) { return !m.detailTextures.empty(); }),
            normalTexels, o.clipmapMorphSeconds);
        auto clipmapRenderer = ClipmapRenderer::create(shaders, header, *scene->clipmapLayout, materials,
                                                       scene->clipmap->normalTexelsPerCell());
        if (!clipmapRenderer.ok()) {
            return fail(clipmapRenderer.error().message);
        }
        scene->clipmapRenderer = std::move(clipmapRenderer).value();
        log("clipmap: " + std::to_string(scene->clipmapLayout->ringCount()) + " rings of " +
            std::to_string(o.clipmapSamples) + " x " + std::to_string(o.clipmapSamples) + " samples, levels 0 to " +
            std::to_string(finest) + " (finest spacing " + std::to_string(header.spacingAt(finest)) + " m), " +
            std::to_string(scene->clipmapRenderer->textureBytes() + scene->clipmap->bytes()) +
            " bytes of ring data (GPU and CPU)");
    }
    const bool rgtc2 = compressNormalMaps(o, TerrainRenderer::softwareRasterizer()) && !o.clipmap;
    scene->source =
        std::make_unique<TerrainNodeSource>(*scene->map, DetailPolicy{scene->synthesizer.get(), o.lodMinimumSpacing,
                                                                      scene->tessellation ? kTessellationBlockQuads : 0,
                                                                      o.dynamicTextureSize, true, rgtc2});
    auto cache = nodeCacheFor(*scene, o, materials, rgtc2);
    if (!cache.ok()) {
        return fail(cache.error().message);
    }
    log(cache->description);
    scene->nodePixels = scene->tessellation ? o.lodError * (1.0 - o.tessellationShare) : o.lodError;
    scene->blockPixels = scene->tessellation ? o.lodError * o.tessellationShare : 0.0;
    auto renderer =
        o.clipmap
            ? Expected<std::unique_ptr<TerrainRenderer>>(std::unique_ptr<TerrainRenderer>())
            : TerrainRenderer::create(
                  shaders, header, o.vertexCacheSize,
                  PoolOptions{cache->nodes, o.nodeTextureCompression, scene->tessellation,
                              o.dynamicTextureSize > 0 ? normalMapTexels(o.dynamicTextureSize) : 0, rgtc2, countPixels},
                  materials);
    if (!renderer.ok()) {
        return fail(renderer.error().message);
    }
    scene->renderer = std::move(renderer).value();
    if (scene->renderer) {
        const SlotBytes& b = scene->renderer->slotBytes();
        log("node pools: " + std::to_string(scene->renderer->slots()) + " slots of " + std::to_string(b.total()) +
            " bytes (heights " + std::to_string(b.heights) + ", parent normals " + std::to_string(b.normals) +
            ", colour " + std::to_string(b.colour) + ", material weights " + std::to_string(b.weights) +
            ", normal map " + std::to_string(b.normalMap) + ", constants " + std::to_string(b.constants) + ")");
    }
    auto overlay = TextOverlay::create(shaders);
    if (!overlay.ok()) {
        return fail(overlay.error().message);
    }
    scene->overlay = std::move(overlay).value();

    StreamerOptions streamerOptions;
    streamerOptions.cacheSize = cache->nodes;
    streamerOptions.queueLimit = static_cast<std::size_t>(o.requestQueueSize);
    streamerOptions.workers = o.workerThreads;
    streamerOptions.velocityLimit = o.detailVelocityLimit;
    streamerOptions.revealSeconds = o.visibilityRevealSeconds;
    auto streamer = TerrainStreamer::create(*scene->source, extentOf(header), streamerOptions);
    if (!streamer.ok()) {
        return fail(streamer.error().message);
    }
    scene->streamer = std::move(streamer).value();
    scene->streamer->onLoadError([&log](const std::string& message) { log(message); });
    if (scene->renderer) {
        scene->streamer->onEvict(
            [renderer = scene->renderer.get()](const NodeData& node) { renderer->release(node.id); });
    }
    if (o.videoMeasureErrorEvery > 0) {
        // The reference nodes are the viewer's surfaces without the bounds, normal maps and tessellation
        // errors they do not need.
        scene->referenceSource = std::make_unique<TerrainNodeSource>(
            *scene->map, DetailPolicy{scene->synthesizer.get(), o.lodMinimumSpacing, 0, 0, false});
        scene->meter = std::make_unique<ErrorMeter>(header, *scene->referenceSource,
                                                    ErrorMeterOptions{o.lodError / 8.0, 1024, 16});
    }
    return scene;
}

/// The screen-space error of what the frame just drawn shows (video_measure_error_every): the meter of
/// tengine-tool error over the drawn selection, only at points the frame's own depth shows.
Expected<FrameError> measureShownError(Scene& scene, const Camera& camera, const TengineOptions& o,
                                       const BoxOccluded& occluded)
{
    const DepthSurface surface(TerrainRenderer::readDepth(camera.viewportWidth, camera.viewportHeight),
                               camera.viewportWidth, camera.viewportHeight, camera);
    if (scene.clipmap) {
        // lod_mode = clipmap: the rings' surface as drawn, against the same reference.
        MeasuredVisibility visibility;
        visibility.shows = [&surface](const glm::dvec3& point) { return surface.shows(point); };
        return scene.meter->measureSurface(
            [&scene](double x, double y) {
                return scene.clipmap->drawnHeight(*scene.clipmapLayout, scene.clipmapFirstRing, x, y);
            },
            camera, visibility);
    }
    const TerrainStreamer& streamer = *scene.streamer;
    LodSelection atOwnDetail;
    const LodSelection* drawn = &streamer.selection();
    if (!o.geomorph) {  // the renderer then draws every node at its own detail
        atOwnDetail = unmorphed(streamer.selection());
        drawn = &atOwnDetail;
    }
    MeasuredVisibility visibility;
    visibility.occluded = occluded;
    visibility.shows = [&surface](const glm::dvec3& point) { return surface.shows(point); };
    return scene.meter->measure(
        *drawn, [&streamer](const NodeId& id) { return streamer.node(id); }, camera, o.lodError,
        scene.tessellation ? scene.blockPixels : 0.0, visibility);
}

/// Demo and video mode fly the path as given; where it passes below the finest static surface the frames
/// show the terrain from below, so say once where (sampled every 0.1 s).
void warnWherePathIsBelowGround(const Scene& scene, const std::filesystem::path& pathFile, Log& log)
{
    constexpr double kStepSeconds = 0.1;
    const auto spans = findPathBelowGround(
        *scene.path,
        [&](double x, double y) -> std::optional<double> {
            auto sample = staticHeightAt(*scene.map, x, y);
            return sample.ok() ? std::optional<double>(sample->height) : std::nullopt;
        },
        kStepSeconds);
    if (!spans.empty()) {
        log("warning: " + pathFile.string() + " passes below the terrain at " + formatTimeSpans(spans) +
            ": the camera is flown there as given and shows the terrain from below");
    }
}

Camera initialCamera(const TengineOptions& o, const Scene& scene)
{
    const MapHeader& header = scene.header();
    Camera camera;
    camera.viewportWidth = scene.window->width();
    camera.viewportHeight = scene.window->height();
    camera.verticalFov = o.cameraFov * kRadiansPerDegree;
    camera.nearPlane = o.cameraZNear;
    camera.farPlane = o.cameraZFar;
    const double extent = header.nodeSizeAt(0);
    if (o.cameraPosition) {
        camera.position = *o.cameraPosition;
    } else {
        const double top = header.heightOf(scene.map->directory().front().maxCode);
        camera.position = {header.originX + extent / 2, header.originY + extent / 2 - extent * 0.6,
                           top + extent * 0.25};
    }
    camera.yaw = o.cameraYaw * kRadiansPerDegree;
    camera.pitch = o.cameraPitch * kRadiansPerDegree;
    return camera;
}

/// The overlay's lines: rate (measured) or frame and time (video), triangles, nodes (and tessellated blocks),
/// cache, camera.
std::vector<std::string> overlayLines(bool video, std::size_t frame, double time, std::optional<double> fps,
                                      const RenderStats& render, const FrameStats& selection, const Scene& scene,
                                      const Camera& camera, double tau, bool wireframe)
{
    char line[160];
    std::vector<std::string> lines;
    const double mtriangles = static_cast<double>(render.triangles) / 1e6;
    if (video) {  // wall-clock rates mean nothing in frames rendered at a fixed time step
        std::snprintf(line, sizeof line, "frame %zu  t %.2f s  %.2f Mtriangles", frame, time, mtriangles);
    } else if (fps) {
        std::snprintf(line, sizeof line, "%.1f fps  %.2f Mtriangles", *fps, mtriangles);
    } else {
        std::snprintf(line, sizeof line, "-- fps  %.2f Mtriangles", mtriangles);
    }
    lines.emplace_back(line);
    if (scene.clipmap) {
        const ClipmapLayout& layout = *scene.clipmapLayout;
        std::snprintf(line, sizeof line,
                      "clipmap: rings from level %d (%d rings), %zu footprints, %zu culled, %zu nodes upsampled",
                      layout.window(scene.clipmapFirstRing).level, layout.ringCount() - scene.clipmapFirstRing,
                      render.blocks, render.culledBlocks, scene.clipmap->upsampledNodes());
    } else if (scene.tessellation) {
        std::snprintf(line, sizeof line, "nodes %zu static, %zu dynamic, %zu blocks tessellated", render.staticNodes,
                      render.dynamicNodes, render.blocks);
    } else {
        std::snprintf(line, sizeof line, "nodes %zu static, %zu dynamic", render.staticNodes, render.dynamicNodes);
    }
    lines.emplace_back(line);
    if (scene.visibility) {
        std::snprintf(line, sizeof line,
                      "visibility: %zu hidden, %zu requests skipped, %zu revealing, %zu blocks occluded",
                      selection.hidden, selection.requestsSkippedHidden, selection.revealing, render.occludedBlocks);
        lines.emplace_back(line);
    }
    const auto server = scene.streamer->serverStats();
    std::snprintf(
        line, sizeof line, "cache %zu / %zu nodes, requests pending %zu%s", scene.streamer->cache().size(),
        scene.streamer->cache().capacity(), server.queued + server.inFlight,
        selection.deferred > 0 ? ("  cache short: " + std::to_string(selection.deferred) + " groups").c_str() : "");
    lines.emplace_back(line);
    std::snprintf(line, sizeof line, "camera %.0f %.0f %.0f m  tau %.1f px%s", camera.position.x, camera.position.y,
                  camera.position.z, tau, wireframe ? "  wireframe" : "");
    lines.emplace_back(line);
    return lines;
}

/// Per-frame counters as differences of the streamer's running totals.
class FrameCounters {
public:
    /// The frames.csv row of this frame (kCsvHeader's columns), then remembers the totals.
    std::string row(std::size_t frame, double time, double milliseconds, const RenderStats& render,
                    const FrameStats& selection, const Scene& scene)
    {
        const auto server = scene.streamer->serverStats();
        const auto& cache = scene.streamer->cache();
        int deepestLevel = scene.clipmap ? scene.clipmapLayout->window(scene.clipmapFirstRing).level : 0;
        for (const SelectedNode& node : scene.streamer->selection().nodes) {
            deepestLevel = std::max(deepestLevel, node.id.level);
        }
        std::ostringstream row;
        row << frame << ',' << time << ',' << milliseconds << ',' << render.triangles << ',' << render.staticNodes
            << ',' << render.dynamicNodes << ',' << cache.size() << ',' << cache.hits() - mHits << ','
            << cache.misses() - mMisses << ',' << server.requested - mRequested << ',' << server.completed - mCompleted
            << ',' << server.queued + server.inFlight << ',' << server.failed - mFailed << ',' << server.peakPending
            << ',' << currentResidentBytes() << ',' << deepestLevel << ',' << render.drawCalls << ','
            << selection.hidden << ',' << selection.requestsSkippedHidden << ',' << selection.revealing << ','
            << selection.synthesized << ',' << render.occludedBlocks;
        remember(scene);
        return row.str();
    }
    void remember(const Scene& scene)
    {
        const auto server = scene.streamer->serverStats();
        mHits = scene.streamer->cache().hits();
        mMisses = scene.streamer->cache().misses();
        mRequested = server.requested;
        mCompleted = server.completed;
        mFailed = server.failed;
    }

private:
    std::uint64_t mHits = 0, mMisses = 0, mRequested = 0, mCompleted = 0, mFailed = 0;
};

/// Video mode's recorder settings from the options: `frames` frames, progress in place on a terminal.
VideoRecorderOptions recorderOptions(const TengineOptions& o, std::size_t frames, Log& log)
{
    VideoRecorderOptions recording;
    recording.directory = o.imagePath;
    recording.frames = frames;
    recording.framesPerSecond = o.framesPerSecond;
    recording.saveEvery = o.videoSaveEvery;
    recording.ffmpeg = o.videoFfmpeg;
    recording.csvHeader = kCsvHeader;
    recording.progressInPlace = ::isatty(STDERR_FILENO) != 0;
    recording.log = [&log](const std::string& message) { log(message); };
    return recording;
}

/// lod_mode = clipmap, one frame: the windows follow the camera, the finest ring worth drawing from its
/// height above the ground, the nodes the windows want are asked for and what arrived fills the rings. In
/// video mode it loads until the windows want nothing more (as the quadtree's rounds do): identical runs give
/// identical frames.
FrameStats updateClipmap(Scene& scene, const Camera& camera, bool video, double clock)
{
    ClipmapLayout& layout = *scene.clipmapLayout;
    ClipmapTerrain& clipmap = *scene.clipmap;
    TerrainStreamer& streamer = *scene.streamer;
    const ResidentNodeLookup resident = [&streamer](const NodeId& id) { return streamer.node(id); };
    const auto entered = layout.moveTo(camera.position.x, camera.position.y);
    // The ground below from the rings as they are (the finest one covers the viewer).
    auto firstRing = [&] {
        const double ground =
            scene.header().heightOffset + clipmap.heightAt(layout, 0, camera.position.x, camera.position.y);
        return layout.finestActiveRing(std::max(0.0, camera.position.z - ground));
    };
    scene.clipmapFirstRing = firstRing();
    FrameStats stats = streamer.updateFor(clipmap.wanted(layout, scene.clipmapFirstRing));
    clipmap.update(layout, entered, resident, clock);
    const std::vector<std::vector<LatticeRect>> none(static_cast<std::size_t>(layout.ringCount()));
    for (int round = 0; video && round < 64; ++round) {
        // The rings just filled may put the ground nearer than it seemed (the first frame's were empty).
        const int first = firstRing();
        if (stats.requested <= stats.deferred && first == scene.clipmapFirstRing) {
            break;
        }
        scene.clipmapFirstRing = first;
        const std::size_t synthesized = stats.synthesized + streamer.drain().synthesized;
        stats = streamer.updateFor(clipmap.wanted(layout, scene.clipmapFirstRing));
        stats.synthesized += synthesized;
        clipmap.update(layout, none, resident, clock);
    }
    return stats;
}

int run(const ParsedCommandLine& parsed, const StopSignals& stop)
{
    const TengineOptions& o = parsed.options;
    // Before anything is opened for writing, the log included: no output may be one of the inputs.
    const std::filesystem::path materialsDirectory = programDataDirectory("materials", TERRAIN_MATERIALS_DIR);
    if (auto refused = checkOutputsAreNotInputs(parsed, o.detailCreateNewNodes && o.detailAddMaterial
                                                            ? detailMaterialFiles(o, materialsDirectory)
                                                            : std::vector<std::filesystem::path>{});
        !refused.ok()) {
        std::fprintf(stderr, "tengine: %s\n", refused.error().message.c_str());
        return 2;
    }
    Log log(o.logFile);
    if (!log.ok()) {
        std::fprintf(stderr, "tengine: %s: cannot open the log file: %s\n", o.logFile.c_str(), log.error().c_str());
        return 1;
    }
    for (const auto& warning : parsed.warnings) {
        log("warning: " + warning);
    }
    if (o.mapFile.empty()) {
        log("no map: give a .map file on the command line or map_file in a config (see tengine --help)");
        return 2;
    }
    const auto scene = openScene(parsed, materialsDirectory, log);
    if (!scene) {
        return 1;
    }
    const MapHeader& header = scene->header();
    const bool demo = o.demoMode;
    const bool video = o.videoMode && !demo;
    if (scene->path && (demo || video)) {
        warnWherePathIsBelowGround(*scene, o.cameraPath, log);
    }
    Camera camera = initialCamera(o, *scene);
    SceneStyle style = styleFrom(o);

    KeyPresses keys(scene->window->handle());
    std::unique_ptr<FreeFlight> flight;
    if (!demo && !video) {
        flight = std::make_unique<FreeFlight>(scene->window->handle(), std::max(20.0, header.sampleSpacing * 2));
    }
    const std::size_t lastVideoFrame =
        scene->path ? static_cast<std::size_t>(std::floor(scene->path->duration() * o.framesPerSecond + 1e-9)) : 0;
    const std::size_t videoFrames =
        o.videoFrames > 0 ? std::min<std::size_t>(static_cast<std::size_t>(o.videoFrames), lastVideoFrame + 1)
                          : lastVideoFrame + 1;
    std::unique_ptr<VideoRecorder> recorder;
    if (video) {
        auto created = VideoRecorder::create(recorderOptions(o, videoFrames, log));
        if (!created.ok()) {
            log(created.error().message);
            return 1;
        }
        recorder = std::move(created).value();
    }

    const auto start = std::chrono::steady_clock::now();
    auto previous = start;
    FrameRateMeter rate;
    FrameCounters counters;
    struct {
        std::size_t frames = 0, overTau = 0, worstFrame = 0;
        double worst = 0.0;
        std::vector<float> pixels;  // every measured point's error
    } shownError;
    bool windowClosed = false;
    std::size_t frame = 0;
    glm::dvec3 previousPosition = camera.position;
    const std::filesystem::path recordPath = recordedCameraPathFile(o);
    for (;; ++frame) {
        const auto now = std::chrono::steady_clock::now();
        const double dt = std::chrono::duration<double>(now - previous).count();
        previous = now;
        scene->window->pollEvents();
        bool quit = false;
        for (int key : keys.take()) {
            quit = quit || key == GLFW_KEY_ESCAPE;
            if (flight) {
                flight->pressed(key, camera, style, std::chrono::duration<double>(now - start).count(), recordPath,
                                log);
            }
        }
        if (scene->window->shouldClose() || quit) {
            windowClosed = true;
            break;
        }
        if (stop.received() != 0) {
            break;
        }
        double time = 0.0;
        if (video) {
            if (frame >= videoFrames) {
                break;
            }
            time = scene->path->startTime() + static_cast<double>(frame) / o.framesPerSecond;
            scene->path->evaluate(time).applyTo(camera);
        } else if (demo) {
            time = scene->path->startTime() + std::chrono::duration<double>(now - start).count();
            scene->path->evaluateLooping(time).applyTo(camera);
        } else {
            flight->update(camera, std::min(dt, 0.25), [&](double x, double y) -> std::optional<double> {
                if (scene->clipmap) {
                    return header.heightOffset + scene->clipmap->heightAt(*scene->clipmapLayout, 0, x, y) +
                           o.cameraMinClearance;
                }
                const auto ground = drawnHeightAt(*scene->streamer, header, x, y);
                return ground ? std::optional<double>(*ground + o.cameraMinClearance) : std::nullopt;
            });
        }

        // The camera's speed for the velocity limit (3.4.4): over the fixed time step in video mode, so a
        // recording does not depend on how fast it was made.
        const double step = video ? 1.0 / o.framesPerSecond : dt;
        const double speed = frame == 0 || step <= 0.0 ? 0.0 : glm::length(camera.position - previousPosition) / step;
        previousPosition = camera.position;
        const auto frameStart = std::chrono::steady_clock::now();
        // Seconds on the viewer's clock, never decreasing (video mode: the frame's time).
        const double clock = video || demo ? time : std::chrono::duration<double>(now - start).count();
        // Visibility: the pixel counts of the frames drawn long enough ago, then what they hide.
        FrameVisibility visibility;
        double moved = 0.0;  // metres from where the depth tested against was drawn
        if (scene->visibility) {
            while (scene->renderer->takePixelCounts(scene->pixelCounts)) {
                const PixelCounts& counts = scene->pixelCounts;
                scene->visibility->record(counts.frame, counts.nodes, counts.pixels);
                scene->occlusion.reset();
                if (!counts.depth.empty()) {
                    scene->occlusion.emplace(counts.depth, counts.camera.viewportWidth, counts.camera.viewportHeight,
                                             counts.camera, kOcclusionMarginPixels);
                }
            }
            const TerrainStreamer& streamer = *scene->streamer;
            moved = scene->occlusion ? glm::length(camera.position - scene->occlusion->eye()) : 0.0;
            visibility.hidden = hiddenFrom(
                *scene->visibility, scene->occlusion ? &*scene->occlusion : nullptr, streamer.tree(),
                [&streamer](const NodeId& id) { return streamer.childrenResident(id); }, moved);
            visibility.time = clock;
        }
        BoxOccluded occluded;
        if (scene->occlusion) {
            occluded = [&occlusion = *scene->occlusion, moved](const Aabb& box) {
                return occlusion.occluded(box, moved);
            };
        }
        FrameStats frameStats;
        RenderStats renderStats;
        if (scene->clipmap) {
            frameStats = updateClipmap(*scene, camera, video, clock);
            const ClipmapStats drawn = scene->clipmapRenderer->draw(*scene->clipmapLayout, *scene->clipmap,
                                                                    scene->clipmapFirstRing, camera, style);
            renderStats.triangles = drawn.triangles;
            renderStats.drawCalls = drawn.pieces;
            renderStats.blocks = drawn.pieces;
            renderStats.culledBlocks = drawn.culledPieces;
        } else {
            frameStats = scene->streamer->update(camera, scene->nodePixels, speed, visibility);
            if (video) {
                // A recording shows every frame complete: load what it wants, select again, until it wants
                // nothing more (or the cache is full). Independent of thread timing: identical runs give
                // identical frames.
                for (int round = 0; round < 64 && frameStats.requested > frameStats.deferred + frameStats.tooFast;
                     ++round) {
                    std::size_t synthesized = frameStats.synthesized + scene->streamer->drain().synthesized;
                    frameStats = scene->streamer->update(camera, scene->nodePixels, speed, visibility);
                    frameStats.synthesized += synthesized;  // the frame's, all rounds together
                }
            }
            const TerrainStreamer& streamer = *scene->streamer;
            renderStats = scene->renderer->draw(
                streamer.selection(), [&streamer](const NodeId& id) { return streamer.node(id); }, camera, style,
                scene->blockPixels, nullptr, occluded);
        }
        if (o.drawUserInterface) {
            scene->overlay->draw(overlayLines(video, frame, time, rate.framesPerSecond(), renderStats, frameStats,
                                              *scene, camera, o.lodError, style.wireframe),
                                 camera.viewportWidth, camera.viewportHeight);
        }
        if (recorder) {
            glFinish();
            const double milliseconds =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frameStart).count();
            Image pixels;
            if (recorder->savesImage(frame)) {
                pixels = captureFrame(camera.viewportWidth, camera.viewportHeight);
            }
            std::string measured = ",,";  // error_max_px, error_p99_px
            if (scene->meter && frame % static_cast<std::size_t>(o.videoMeasureErrorEvery) == 0) {
                auto error = measureShownError(*scene, camera, o, occluded);
                if (!error.ok()) {
                    log(error.error().message);
                    (void)recorder->finish(true);
                    return 1;
                }
                char columns[64];
                std::snprintf(columns, sizeof columns, ",%.3f,%.3f", error->maxPixels, error->p99Pixels);
                measured = columns;
                shownError.frames += 1;
                shownError.overTau += error->maxPixels > o.lodError ? 1 : 0;
                if (error->maxPixels > shownError.worst) {
                    shownError.worst = error->maxPixels;
                    shownError.worstFrame = frame;
                }
                shownError.pixels.insert(shownError.pixels.end(), error->pixels.begin(), error->pixels.end());
            }
            if (auto added = recorder->add(frame, std::move(pixels),
                                           counters.row(frame, time, milliseconds, renderStats, frameStats, *scene) +
                                               measured + "," + std::to_string(frameStats.deferred));
                !added.ok()) {
                log(added.error().message);
                (void)recorder->finish(true);
                return 1;
            }
        } else {
            counters.remember(*scene);
        }
        scene->window->swapBuffers();
        rate.frameEnded(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }

    if (!video && frame > 1) {
        const double seconds = std::chrono::duration<double>(previous - start).count();
        char line[96];
        std::snprintf(line, sizeof line, "%zu frames drawn in %.1f s, mean frame time %.1f ms", frame, seconds,
                      1000.0 * seconds / static_cast<double>(frame));
        log(line);
    }
    if (shownError.frames > 0) {
        std::sort(shownError.pixels.begin(), shownError.pixels.end());
        const double p99 =
            shownError.pixels.empty()
                ? 0.0
                : shownError.pixels[static_cast<std::size_t>(0.99 * static_cast<double>(shownError.pixels.size() - 1))];
        char line[200];
        std::snprintf(line, sizeof line,
                      "measured error of what is shown: max %.3f px (frame %zu), p99 %.3f px over %zu frames; "
                      "%zu frames over lod_error %g",
                      shownError.worst, shownError.worstFrame, p99, shownError.frames, shownError.overTau, o.lodError);
        log(line);
    }
    const bool interrupted = stop.received() != 0 || (video && windowClosed);
    if (recorder) {
        if (interrupted) {
            log(std::string("recording stopped by ") +
                (stop.received() != 0 ? strsignal(stop.received()) : "closing the window") + " after " +
                std::to_string(frame) + " of " + std::to_string(videoFrames) + " frames");
        }
        auto finished = recorder->finish(interrupted);
        if (!finished.ok()) {
            log(finished.error().message);
            return 1;
        }
    }
    if (stop.received() != 0) {
        return stop.exitStatus();
    }
    return interrupted ? 128 + SIGINT : 0;
}

}  // namespace

int main(int argc, char** argv)
{
    // Before any other thread exists (GLFW, Mesa and the node server start theirs): SIGINT and SIGTERM
    // then end a recording cleanly instead of killing the process.
    const StopSignals stop;
    auto parsed = parseTengineCommandLine(argc, argv);
    if (!parsed.ok()) {
        std::fprintf(stderr, "tengine: %s\n", parsed.error().message.c_str());
        return 2;
    }
    if (parsed->help) {
        std::fputs(tengineUsage().c_str(), stdout);
        return 0;
    }
    if (parsed->printConfig) {
        std::fputs(tengineConfigText(parsed->options).c_str(), stdout);
        return 0;
    }
    return run(*parsed, stop);
}
