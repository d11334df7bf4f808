// tengine: the viewer (paper 4.2, 4.4.2). Wires the options, the viewer session (apps/ViewerSession.h: map,
// synthesis, streamer), the renderer and the window together; three ways to drive the camera: the user (mouse and
// keys, apps/FreeFlight.h), demo_mode (camera_path in real time, looping) and video_mode (camera_path once at a
// fixed time step, every frame (or every video_save_every-th) saved as a PNG, plus a CSV of per-frame statistics
// and, when ffmpeg is installed, an MP4).
#include "DataDirectories.h"
#include "DetailSetup.h"
#include "FrameRateMeter.h"
#include "FreeFlight.h"
#include "TengineOptions.h"
#include "VideoRecorder.h"
#include "ViewerSession.h"

#include "core/Memory.h"
#include "core/StopSignals.h"
#include "lod/CameraPath.h"
#include "lod/HeightQuery.h"
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
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace terrain;

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
    style.exposure = static_cast<float>(o.exposure);
    return style;
}

/// The viewer's key for a GLFW key; empty for keys it does not act on.
std::optional<Key> viewerKey(int glfwKey)
{
    switch (glfwKey) {
        case GLFW_KEY_W:
            return Key::Forward;
        case GLFW_KEY_S:
            return Key::Back;
        case GLFW_KEY_A:
            return Key::Left;
        case GLFW_KEY_D:
            return Key::Right;
        case GLFW_KEY_Q:
            return Key::Up;
        case GLFW_KEY_Z:
            return Key::Down;
        case GLFW_KEY_1:
            return Key::Faster;
        case GLFW_KEY_2:
            return Key::Slower;
        case GLFW_KEY_L:
            return Key::Wireframe;
        case GLFW_KEY_K:
            return Key::RecordKeyframe;
        case GLFW_KEY_ESCAPE:
            return Key::Quit;
        default:
            return std::nullopt;
    }
}

/// The window's input as the viewer's: key events (GLFW's key callback) timed on the viewer's clock into a
/// KeyInput, so a tap shorter than a frame is seen however slow the frame, and the mouse's movement.
class WindowInput {
public:
    /// `window` null (headless): no input. `look`: the cursor is captured for mouse look. `start`: the viewer's
    /// clock's zero.
    WindowInput(GLFWwindow* window, bool look, std::chrono::steady_clock::time_point start)
        : mWindow(window), mStart(start)
    {
        if (!window) {
            return;
        }
        glfwSetWindowUserPointer(window, this);
        glfwSetKeyCallback(window, [](GLFWwindow* w, int glfwKey, int, int action, int) {
            auto* self = static_cast<WindowInput*>(glfwGetWindowUserPointer(w));
            const auto key = viewerKey(glfwKey);
            if (!key || action == GLFW_REPEAT) {
                return;
            }
            const double now = self->seconds(std::chrono::steady_clock::now());
            if (action == GLFW_PRESS) {
                self->mKeys.press(*key, now);
            } else {
                self->mKeys.release(*key, now);
            }
        });
        if (look) {
            glfwSetInputMode(window, GLFW_CURSOR, GLFW_CURSOR_DISABLED);
            mLooking = true;
        }
    }
    ~WindowInput()
    {
        if (!mWindow) {
            return;
        }
        glfwSetKeyCallback(mWindow, nullptr);
        glfwSetWindowUserPointer(mWindow, nullptr);
    }
    WindowInput(const WindowInput&) = delete;
    WindowInput& operator=(const WindowInput&) = delete;

    double seconds(std::chrono::steady_clock::time_point t) const
    {
        return std::chrono::duration<double>(t - mStart).count();
    }
    /// Ends the frame at `time` (call after pollEvents).
    KeyInput::Frame keys(double time) { return mKeys.endFrame(time); }
    /// The mouse's movement in pixels since the last call; none the first time (the first position after the
    /// cursor is captured is where GLFW centred it: turning by it would throw away camera_yaw and camera_pitch).
    glm::dvec2 mouseMoved()
    {
        if (!mLooking) {
            return {0.0, 0.0};
        }
        glm::dvec2 at{0.0, 0.0};
        glfwGetCursorPos(mWindow, &at.x, &at.y);
        const glm::dvec2 moved = mLast ? at - *mLast : glm::dvec2(0.0);
        mLast = at;
        return moved;
    }

private:
    GLFWwindow* mWindow;
    std::chrono::steady_clock::time_point mStart;
    KeyInput mKeys;
    bool mLooking = false;
    std::optional<glm::dvec2> mLast;
};

/// Video mode's frames.csv columns. Per frame: cache_hits, cache_misses, requests_made, requests_completed
/// and requests_failed (groups that could not be loaded); now: cache_nodes, requests_pending (queued plus
/// loading), resident_bytes (the process's resident set), deepest_level (of the nodes drawn; below the
/// map's levels - 1 they are dynamic) and draw_calls (the terrain's: one per program in chunks mode, runs of
/// nodes times ranges of patches in tessellation mode, TerrainRenderer::drawPatchRanges); since the start:
/// requests_pending_peak (the most queued plus loading at once, NodeServerStats::peakPending). With visibility_lod
/// (else 0): nodes_hidden (drawn as they are, hidden), requests_skipped_hidden (of those, the ones whose children were
/// not resident), nodes_revealing (morphing in after a reveal). dynamic_groups_made: groups of four dynamic nodes the
/// workers synthesized that arrived this frame (FrameStats::synthesized). New columns go at the end: readers cut
/// columns by position. blocks_occluded: tessellation mode with visibility_lod, blocks of drawn nodes made
/// coarsest, behind the previous frame's depth. error_max_px, error_p99_px: with video_measure_error_every, the
/// measured screen-space error of what the frame shows (empty in frames not measured). cache_short: groups of
/// children the selection wanted that the node cache had no room for (FrameStats::deferred; memory_budget).
/// advance_ms: of milliseconds, the time the session took to advance (selection, and in video mode the wait for
/// the loads and synthesis the frame needs); the rest is drawing.
constexpr const char* kCsvHeader =
    "frame,time_s,milliseconds,triangles,nodes_static,nodes_dynamic,cache_nodes,cache_hits,cache_misses,"
    "requests_made,requests_completed,requests_pending,requests_failed,requests_pending_peak,resident_bytes,"
    "deepest_level,draw_calls,nodes_hidden,requests_skipped_hidden,nodes_revealing,dynamic_groups_made,blocks_occluded,"
    "error_max_px,error_p99_px,cache_short,advance_ms";

/// Everything the viewer draws with, opened from the options in dependency order. Not movable: the renderers
/// refer to the window's context.
struct Scene {
    std::optional<CameraPath> path;
    std::unique_ptr<GlWindow> window;
    std::unique_ptr<TerrainRenderer> renderer;         ///< quadtree mode
    std::unique_ptr<ClipmapRenderer> clipmapRenderer;  ///< lod_mode = clipmap
    std::unique_ptr<TextOverlay> overlay;
    std::unique_ptr<ViewerSession> session;

    const MapHeader& header() const { return session->header(); }
    const TerrainStreamer& streamer() const { return session->streamer(); }
};

/// What the node pools and the GL offer the session, asked of the current context.
GlCapabilities glCapabilities()
{
    GlCapabilities gl;
    gl.tessellation = TerrainRenderer::tessellationSupported();
    gl.multiDrawIndirect = TerrainRenderer::multiDrawIndirectSupported();
    gl.pixelCounts = TerrainRenderer::pixelCountsSupported();
    gl.s3tc = epoxy_has_gl_extension("GL_EXT_texture_compression_s3tc");
    gl.softwareRasterizer = TerrainRenderer::softwareRasterizer();
    gl.maxSlots = TerrainRenderer::maxSlots();
    return gl;
}

/// The renderer of `scene`'s session (the clipmap's rings or the quadtree's nodes, a pool slot per cache slot),
/// logged.
Status openRenderer(Scene& scene, const TengineOptions& o, const std::filesystem::path& shaders, Log& log)
{
    ViewerSession& session = *scene.session;
    const MapHeader& header = session.header();
    const LightingModel lighting{o.atmosphere};
    if (session.clipmap()) {
        const ClipmapLayout& layout = *session.clipmapLayout();
        auto renderer = ClipmapRenderer::create(shaders, header, layout, session.materials(),
                                                session.clipmap()->normalTexelsPerCell(), lighting);
        TERRAIN_TRY(renderer);
        scene.clipmapRenderer = std::move(renderer).value();
        const int finest = layout.window(0).level;
        log("clipmap: " + std::to_string(layout.ringCount()) + " rings of " + std::to_string(o.clipmapSamples) + " x " +
            std::to_string(o.clipmapSamples) + " samples, levels 0 to " + std::to_string(finest) + " (finest spacing " +
            std::to_string(header.spacingAt(finest)) + " m), " +
            std::to_string(scene.clipmapRenderer->textureBytes() + session.clipmap()->bytes()) +
            " bytes of ring data (GPU and CPU)");
        return {};
    }
    auto renderer =
        TerrainRenderer::create(shaders, header, o.vertexCacheSize,
                                PoolOptions{session.cache().nodes, o.nodeTextureCompression, session.tessellation(),
                                            o.dynamicTextureSize > 0 ? normalMapTexels(o.dynamicTextureSize) : 0,
                                            session.compressedNormalMaps(), session.countsPixels(), session.shadows(),
                                            0, session.blockIndices()},
                                session.materials(), lighting);
    TERRAIN_TRY(renderer);
    scene.renderer = std::move(renderer).value();
    const SlotBytes& b = scene.renderer->slotBytes();
    log("node pools: " + std::to_string(scene.renderer->slots()) + " slots of " + std::to_string(b.total()) +
        " bytes (heights " + std::to_string(b.heights) + ", parent normals " + std::to_string(b.normals) + ", colour " +
        std::to_string(b.colour) + ", material weights " + std::to_string(b.weights) + ", normal map " +
        std::to_string(b.normalMap) + ", light " + std::to_string(b.light) + ", constants " +
        std::to_string(b.constants) + ")");
    return {};
}

/// Opens the session (map, materials), the camera path, the window, the streaming for its GL, the renderer and
/// the overlay; errors are logged and end the program with status 1. `materialsDirectory`: the built-in
/// materials (programDataDirectory).
std::unique_ptr<Scene> openScene(const ParsedCommandLine& parsed, const std::filesystem::path& materialsDirectory,
                                 Log& log)
{
    const TengineOptions& o = parsed.options;
    auto scene = std::make_unique<Scene>();
    auto fail = [&](const std::string& message) {
        log(message);
        return nullptr;
    };
    auto session = ViewerSession::open(o, materialsDirectory, SessionUse::View,
                                       [&log](const std::string& message) { log(message); });
    if (!session.ok()) {
        return fail(session.error().message);
    }
    scene->session = std::move(session).value();
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
    windowOptions.displayLost = [&log](const std::string& message) { log(message); };
    auto window = GlWindow::create(windowOptions);
    if (!window.ok()) {
        return fail(window.error().message);
    }
    scene->window = std::move(window).value();
    log(scene->window->description());
    if (auto started = scene->session->startStreaming(glCapabilities()); !started.ok()) {
        return fail(started.error().message);
    }
    log(scene->session->cache().description);
    const std::filesystem::path shaders =
        o.shaderPath.empty() ? programDataDirectory("shaders", TERRAIN_SHADER_DIR) : o.shaderPath;
    if (auto opened = openRenderer(*scene, o, shaders, log); !opened.ok()) {
        return fail(opened.error().message);
    }
    auto overlay = TextOverlay::create(shaders);
    if (!overlay.ok()) {
        return fail(overlay.error().message);
    }
    scene->overlay = std::move(overlay).value();
    return scene;
}

/// Demo and video mode fly the path as given; where it passes below the finest static surface the frames
/// show the terrain from below, so say once where (sampled every 0.1 s).
void warnWherePathIsBelowGround(const Scene& scene, const std::filesystem::path& pathFile, Log& log)
{
    constexpr double kStepSeconds = 0.1;
    const auto spans = findPathBelowGround(
        *scene.path,
        [&](double x, double y) -> std::optional<double> {
            auto sample = staticHeightAt(scene.session->map(), x, y);
            return sample.ok() ? std::optional<double>(sample->height) : std::nullopt;
        },
        kStepSeconds);
    if (!spans.empty()) {
        log("warning: " + pathFile.string() + " passes below the terrain at " + formatTimeSpans(spans) +
            ": the camera is flown there as given and shows the terrain from below");
    }
}

/// The camera at the start: camera_position, camera_yaw and camera_pitch; without camera_position, looking at
/// camera_yaw and camera_pitch (at least 5 degrees down) at the whole terrain, as near as shows all of it.
Camera initialCamera(const TengineOptions& o, const Scene& scene, Log& log)
{
    const MapHeader& header = scene.header();
    Camera camera;
    camera.viewportWidth = scene.window->width();
    camera.viewportHeight = scene.window->height();
    camera.verticalFov = o.cameraFov * kRadiansPerDegree;
    camera.nearPlane = o.cameraZNear;
    camera.farPlane = o.cameraZFar;
    camera.yaw = o.cameraYaw * kRadiansPerDegree;
    camera.pitch = o.cameraPitch * kRadiansPerDegree;
    if (o.cameraPosition) {
        camera.position = *o.cameraPosition;
        return camera;
    }
    constexpr double kLeastFramingPitch = -5.0;  // degrees: from above
    const double extent = header.nodeSizeAt(0);
    const DirectoryEntry& root = scene.session->map().directory().front();
    const glm::dvec3 min{header.originX, header.originY, header.heightOf(root.minCode)};
    const glm::dvec3 max{header.originX + extent, header.originY + extent, header.heightOf(root.maxCode)};
    camera = framingCamera(camera, min, max, std::min(o.cameraPitch, kLeastFramingPitch) * kRadiansPerDegree);
    const double farthest = glm::length(camera.position - (min + max) * 0.5) + glm::length(max - min) * 0.5;
    if (farthest > camera.farPlane) {
        log("warning: camera_z_far " + std::to_string(camera.farPlane) + " m cuts the first view, which shows the " +
            "terrain up to " + std::to_string(farthest) + " m away");
    }
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
    if (const ClipmapLayout* clipmapLayout = scene.session->clipmapLayout()) {
        const ClipmapLayout& layout = *clipmapLayout;
        const int firstRing = scene.session->clipmapFirstRing();
        std::snprintf(line, sizeof line,
                      "clipmap: rings from level %d (%d rings), %zu footprints, %zu culled, %zu nodes upsampled",
                      layout.window(firstRing).level, layout.ringCount() - firstRing, render.blocks,
                      render.culledBlocks, scene.session->clipmap()->upsampledNodes());
    } else if (scene.session->tessellation()) {
        std::snprintf(line, sizeof line, "nodes %zu static, %zu dynamic, %zu blocks tessellated", render.staticNodes,
                      render.dynamicNodes, render.blocks);
    } else {
        std::snprintf(line, sizeof line, "nodes %zu static, %zu dynamic", render.staticNodes, render.dynamicNodes);
    }
    lines.emplace_back(line);
    if (scene.session->countsPixels()) {
        std::snprintf(line, sizeof line,
                      "visibility: %zu hidden, %zu requests skipped, %zu revealing, %zu blocks occluded",
                      selection.hidden, selection.requestsSkippedHidden, selection.revealing, render.occludedBlocks);
        lines.emplace_back(line);
    }
    const auto server = scene.streamer().serverStats();
    std::snprintf(
        line, sizeof line, "cache %zu / %zu nodes, requests pending %zu%s", scene.streamer().cache().size(),
        scene.streamer().cache().capacity(), server.queued + server.inFlight,
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
        const auto server = scene.streamer().serverStats();
        const auto& cache = scene.streamer().cache();
        int deepestLevel = scene.session->clipmap()
                               ? scene.session->clipmapLayout()->window(scene.session->clipmapFirstRing()).level
                               : 0;
        for (const SelectedNode& node : scene.streamer().selection().nodes) {
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
        const auto server = scene.streamer().serverStats();
        mHits = scene.streamer().cache().hits();
        mMisses = scene.streamer().cache().misses();
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

/// One frame's figures.
struct DrawnFrame {
    FrameStats selection;
    RenderStats render;
    double advanceMilliseconds = 0.0;  ///< the session's advance: selection, loads and synthesis waited for
};

/// Advances the session for `camera` and draws what it selected.
DrawnFrame advanceAndDraw(Scene& scene, const Camera& camera, const FrameTime& time, double speed, Settle settle,
                          const SceneStyle& style)
{
    DrawnFrame drawn;
    ViewerSession& session = *scene.session;
    const auto start = std::chrono::steady_clock::now();
    drawn.selection = session.advance(camera, time.clock, speed, settle, scene.renderer.get());
    drawn.advanceMilliseconds =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (scene.clipmapRenderer) {
        const ClipmapStats rings = scene.clipmapRenderer->draw(*session.clipmapLayout(), *session.clipmap(),
                                                               session.clipmapFirstRing(), camera, style);
        drawn.render.triangles = rings.triangles;
        drawn.render.drawCalls = rings.pieces;
        drawn.render.blocks = rings.pieces;
        drawn.render.culledBlocks = rings.culledPieces;
        return drawn;
    }
    drawn.render = scene.renderer->draw(session.drawList(), style);
    return drawn;
}

/// The screen-space error of what the frame just drawn shows (video_measure_error_every): the meter of
/// tengine-tool error over the drawn surface, only at points the frame's own depth shows.
Expected<FrameError> measureShownError(Scene& scene, const Camera& camera)
{
    const DepthSurface surface(TerrainRenderer::readDepth(camera.viewportWidth, camera.viewportHeight),
                               camera.viewportWidth, camera.viewportHeight, camera);
    MeasuredVisibility visibility;
    visibility.shows = [&surface](const glm::dvec3& point) { return surface.shows(point); };
    return scene.session->measureDrawn(camera, visibility);
}

/// The measured error of what video mode's frames show, over the frames measured.
class ShownError {
public:
    void add(std::size_t frame, const FrameError& error, double tau)
    {
        ++mFrames;
        mOverTau += error.maxPixels > tau ? 1 : 0;
        if (error.maxPixels > mWorst) {
            mWorst = error.maxPixels;
            mWorstFrame = frame;
        }
        mPixels.insert(mPixels.end(), error.pixels.begin(), error.pixels.end());
    }
    /// The summary line; empty when no frame was measured.
    std::string summary(double tau)
    {
        if (mFrames == 0) {
            return {};
        }
        std::sort(mPixels.begin(), mPixels.end());
        const double p99 =
            mPixels.empty() ? 0.0 : mPixels[static_cast<std::size_t>(0.99 * static_cast<double>(mPixels.size() - 1))];
        char line[200];
        std::snprintf(line, sizeof line,
                      "measured error of what is shown: max %.3f px (frame %zu), p99 %.3f px over %zu frames; "
                      "%zu frames over lod_error %g",
                      mWorst, mWorstFrame, p99, mFrames, mOverTau, tau);
        return line;
    }

private:
    std::size_t mFrames = 0, mOverTau = 0, mWorstFrame = 0;
    double mWorst = 0.0;
    std::vector<float> mPixels;  // every measured point's error
};

/// Video mode's outputs: a PNG (every video_save_every-th), a frames.csv row and, with video_measure_error_every,
/// the measured error of each frame.
class Recording {
public:
    Recording(std::unique_ptr<VideoRecorder> recorder, const TengineOptions& o) : mRecorder(std::move(recorder)), mO(o)
    {
    }
    /// Records the frame just drawn, `milliseconds` after it began.
    Status add(Scene& scene, std::size_t frame, double time, double milliseconds, const DrawnFrame& drawn,
               const Camera& camera)
    {
        Image pixels;
        if (mRecorder->savesImage(frame)) {
            pixels = captureFrame(camera.viewportWidth, camera.viewportHeight);
        }
        std::string measured = ",,";  // error_max_px, error_p99_px
        if (scene.session->meter() && frame % static_cast<std::size_t>(mO.videoMeasureErrorEvery) == 0) {
            auto error = measureShownError(scene, camera);
            TERRAIN_TRY(error);
            char columns[64];
            std::snprintf(columns, sizeof columns, ",%.3f,%.3f", error->maxPixels, error->p99Pixels);
            measured = columns;
            mShown.add(frame, *error, mO.lodError);
        }
        return mRecorder->add(frame, std::move(pixels),
                              mCounters.row(frame, time, milliseconds, drawn.render, drawn.selection, scene) +
                                  measured + "," + std::to_string(drawn.selection.deferred) + "," +
                                  std::to_string(drawn.advanceMilliseconds));
    }
    Status finish(bool interrupted) { return mRecorder->finish(interrupted); }
    std::string errorSummary() { return mShown.summary(mO.lodError); }

private:
    std::unique_ptr<VideoRecorder> mRecorder;
    const TengineOptions& mO;
    FrameCounters mCounters;
    ShownError mShown;
};

/// How the frames were ended.
struct Ending {
    bool windowClosed = false;  ///< escape or the window's close button
    std::size_t frames = 0;     ///< frames drawn
    double seconds = 0.0;       ///< from the first frame's start to the last's
};

/// A key press with an effect per press in free flight: l toggles wireframe, k appends the camera's pose at
/// `seconds` to `recordPath` (1 and 2, the speed, are FreeFlight's).
void userKeyPressed(Key key, const Camera& camera, SceneStyle& style, double seconds,
                    const std::filesystem::path& recordPath, Log& log)
{
    if (key == Key::Wireframe) {
        style.wireframe = !style.wireframe;
        log(style.wireframe ? "wireframe on" : "wireframe off");
    } else if (key == Key::RecordKeyframe) {
        const CameraKeyframe keyframe{seconds, camera.position, camera.yaw, camera.pitch};
        auto appended = appendKeyframe(recordPath, keyframe);
        log(appended.ok() ? "camera keyframe appended to " + recordPath.string() : appended.error().message);
    }
}

/// The frame loop: until the path's frames are done (video), escape, the window closing or a stop signal. Each
/// frame: input, the camera (by the user, the demo path in real time or the video path at its step), the session
/// advanced and drawn, the overlay, the recording. A recording error is logged and ends the loop with status 1.
Expected<Ending> runFrames(Scene& scene, const TengineOptions& o, Drive drive, std::size_t videoFrames,
                           Recording* recording, const StopSignals& stop, Log& log)
{
    const auto start = std::chrono::steady_clock::now();
    WindowInput input(scene.window->handle(), drive == Drive::User, start);
    FrameClock clock(drive, scene.path ? scene.path->startTime() : 0.0, o.framesPerSecond);
    FreeFlight flight(FlightOptions{o.cameraMinClearance});
    Camera camera = initialCamera(o, scene, log);
    SceneStyle style = styleFrom(o);
    const ViewerSession& session = *scene.session;
    const double lowest = scene.header().heightOf(session.map().directory().front().minCode);
    const GroundHeight ground = [&session](double x, double y) { return session.drawnHeightAt(x, y); };
    const std::filesystem::path recordPath = recordedCameraPathFile(o);
    FrameRateMeter rate;
    Ending ending;
    glm::dvec3 previousPosition = camera.position;
    for (std::size_t frame = 0;; ++frame) {
        const double wall = input.seconds(std::chrono::steady_clock::now());
        const FrameTime time = clock.next(frame, wall);
        scene.window->pollEvents();
        const KeyInput::Frame keys = input.keys(wall);
        const bool quit = std::find(keys.presses.begin(), keys.presses.end(), Key::Quit) != keys.presses.end();
        if (scene.window->shouldClose() || quit) {
            ending.windowClosed = true;
            break;
        }
        if (stop.received() != 0 || (drive == Drive::Video && frame >= videoFrames)) {
            break;
        }
        ending.frames = frame + 1;
        ending.seconds = wall;
        if (drive == Drive::Video) {
            scene.path->evaluate(time.pathTime).applyTo(camera);
        } else if (drive == Drive::Demo) {
            scene.path->evaluateLooping(time.pathTime).applyTo(camera);
        } else {
            for (Key key : keys.presses) {
                userKeyPressed(key, camera, style, wall, recordPath, log);
            }
            const glm::dvec2 moved = input.mouseMoved();
            flight.look(camera, moved.x, moved.y);
            flight.fly(camera, keys, ground, camera.position.z - lowest);
        }
        // The camera's speed for the velocity limit (3.4.4): over the fixed time step in video mode, so a
        // recording does not depend on how fast it was made.
        const double speed =
            frame == 0 || time.step <= 0.0 ? 0.0 : glm::length(camera.position - previousPosition) / time.step;
        previousPosition = camera.position;
        const auto frameStart = std::chrono::steady_clock::now();
        // A recording shows every frame complete, independent of thread timing: identical runs give identical
        // frames.
        const DrawnFrame drawn = advanceAndDraw(scene, camera, time, speed,
                                                drive == Drive::Video ? Settle::Complete : Settle::Arrived, style);
        if (o.drawUserInterface) {
            scene.overlay->draw(overlayLines(drive == Drive::Video, frame, time.pathTime, rate.framesPerSecond(),
                                             drawn.render, drawn.selection, scene, camera, o.lodError, style.wireframe),
                                camera.viewportWidth, camera.viewportHeight);
        }
        if (recording) {
            glFinish();
            const double milliseconds =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frameStart).count();
            if (auto added = recording->add(scene, frame, time.pathTime, milliseconds, drawn, camera); !added.ok()) {
                return added.error();
            }
        }
        scene.window->swapBuffers();
        rate.frameEnded(input.seconds(std::chrono::steady_clock::now()));
    }
    return ending;
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
    const Drive drive = o.demoMode ? Drive::Demo : o.videoMode ? Drive::Video : Drive::User;
    if (scene->path && drive != Drive::User) {
        warnWherePathIsBelowGround(*scene, o.cameraPath, log);
    }
    const std::size_t lastVideoFrame =
        scene->path ? static_cast<std::size_t>(std::floor(scene->path->duration() * o.framesPerSecond + 1e-9)) : 0;
    const std::size_t videoFrames =
        o.videoFrames > 0 ? std::min<std::size_t>(static_cast<std::size_t>(o.videoFrames), lastVideoFrame + 1)
                          : lastVideoFrame + 1;
    std::unique_ptr<Recording> recording;
    if (drive == Drive::Video) {
        auto created = VideoRecorder::create(recorderOptions(o, videoFrames, log));
        if (!created.ok()) {
            log(created.error().message);
            return 1;
        }
        recording = std::make_unique<Recording>(std::move(created).value(), o);
    }
    const auto ended = runFrames(*scene, o, drive, videoFrames, recording.get(), stop, log);
    if (!ended.ok()) {
        log(ended.error().message);
        if (recording) {
            (void)recording->finish(true);
        }
        return 1;
    }
    if (drive != Drive::Video && ended->frames > 1) {
        char line[96];
        std::snprintf(line, sizeof line, "%zu frames drawn in %.1f s, mean frame time %.1f ms", ended->frames,
                      ended->seconds, 1000.0 * ended->seconds / static_cast<double>(ended->frames));
        log(line);
    }
    const bool interrupted = stop.received() != 0 || (drive == Drive::Video && ended->windowClosed);
    if (recording) {
        if (const std::string summary = recording->errorSummary(); !summary.empty()) {
            log(summary);
        }
        if (interrupted) {
            log(std::string("recording stopped by ") +
                (stop.received() != 0 ? strsignal(stop.received()) : "closing the window") + " after " +
                std::to_string(ended->frames) + " of " + std::to_string(videoFrames) + " frames");
        }
        if (auto finished = recording->finish(interrupted); !finished.ok()) {
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
