// tengine: the viewer (paper 4.2, 4.4.2). Wires options, map, streamer, renderer and window together;
// three ways to drive the camera: the user (mouse and keys), demo_mode (camera_path in real time, looping)
// and video_mode (camera_path once at a fixed time step, every frame (or every video_save_every-th) saved
// as a PNG, plus a CSV of per-frame statistics and, when ffmpeg is installed, an MP4).
#include "DetailSetup.h"
#include "TengineOptions.h"

#include "core/AtomicFile.h"
#include "core/Memory.h"
#include "lod/CameraPath.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "render/FrameCapture.h"
#include "render/GlWindow.h"
#include "render/TerrainRenderer.h"
#include "render/TextOverlay.h"

#include <GLFW/glfw3.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

namespace {

using namespace terrain;

constexpr double kDegrees = std::numbers::pi / 180.0;

/// Messages to stderr and, when log_file is set, to the log.
class Log {
public:
    explicit Log(const std::filesystem::path& file)
    {
        if (!file.empty()) {
            mFile.open(file, std::ios::app);
        }
    }
    bool ok() const { return !mFile.is_open() || mFile.good(); }
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
};

SceneStyle styleFrom(const TengineOptions& o)
{
    SceneStyle style;
    const double az = o.sunAzimuth * kDegrees, el = o.sunElevation * kDegrees;
    style.sunDirection = glm::vec3(static_cast<float>(std::sin(az) * std::cos(el)),
                                   static_cast<float>(std::cos(az) * std::cos(el)), static_cast<float>(std::sin(el)));
    style.hazeDistance = o.hazeDistance > 0 ? static_cast<float>(o.hazeDistance) : 1e30f;
    style.clearColour = o.clearColor;
    style.drawSky = o.drawSky;
    style.wireframe = o.wireframe;
    style.geomorph = o.geomorph;
    return style;
}

/// Mouse look and w/s/a/d/q/z movement (paper 4.4.2); 1/2 faster/slower; l wireframe; k records a keyframe.
class FreeFlight {
public:
    FreeFlight(GLFWwindow* window, double speed) : mWindow(window), mSpeed(speed)
    {
        glfwSetInputMode(window, GLFW_CURSOR, GLFW_CURSOR_DISABLED);
        glfwGetCursorPos(window, &mLastX, &mLastY);
    }

    void update(Camera& camera, double dt)
    {
        double x = 0, y = 0;
        glfwGetCursorPos(mWindow, &x, &y);
        constexpr double kRadiansPerPixel = 0.0025;
        camera.yaw += (x - mLastX) * kRadiansPerPixel;
        camera.pitch = std::clamp(camera.pitch - (y - mLastY) * kRadiansPerPixel, -1.55, 1.55);
        mLastX = x;
        mLastY = y;
        auto down = [&](int key) { return glfwGetKey(mWindow, key) == GLFW_PRESS ? 1.0 : 0.0; };
        const glm::dvec3 move = camera.forward() * (down(GLFW_KEY_W) - down(GLFW_KEY_S)) +
                                camera.right() * (down(GLFW_KEY_D) - down(GLFW_KEY_A)) +
                                camera.up() * (down(GLFW_KEY_Q) - down(GLFW_KEY_Z));
        camera.position += move * (mSpeed * dt);
    }
    /// Keys with an effect per press rather than while held.
    bool pressed(int key)
    {
        const bool now = glfwGetKey(mWindow, key) == GLFW_PRESS;
        const bool was = mHeld[key];
        mHeld[key] = now;
        return now && !was;
    }
    double& speed() { return mSpeed; }

private:
    GLFWwindow* mWindow;
    double mSpeed;
    double mLastX = 0, mLastY = 0;
    bool mHeld[GLFW_KEY_LAST + 1] = {};
};

/// Video mode's frames.csv columns. Per frame: cache_hits, cache_misses, requests_made, requests_completed
/// and requests_failed (groups that could not be loaded); now: cache_nodes, requests_pending (queued plus
/// loading), resident_bytes (the process's resident set) and deepest_level (of the nodes drawn; below the
/// map's levels - 1 they are dynamic); since the start: requests_pending_peak (the most queued plus loading
/// at once, NodeServerStats::peakPending). New columns go at the end: readers cut columns by position.
std::string csvHeader()
{
    return "frame,time_s,milliseconds,triangles,nodes_static,nodes_dynamic,cache_nodes,cache_hits,cache_misses,"
           "requests_made,requests_completed,requests_pending,requests_failed,requests_pending_peak,resident_bytes,"
           "deepest_level\n";
}

bool commandExists(const char* name)
{
    std::string command = std::string("command -v ") + name + " >/dev/null 2>&1";
    return std::system(command.c_str()) == 0;
}

int run(const ParsedCommandLine& parsed)
{
    const TengineOptions& o = parsed.options;
    Log log(o.logFile);
    if (!log.ok()) {
        std::fprintf(stderr, "tengine: %s: cannot open the log file\n", o.logFile.c_str());
        return 1;
    }
    for (const auto& warning : parsed.warnings) {
        log("warning: " + warning);
    }
    if (o.mapFile.empty()) {
        log("no map: give a .map file on the command line or map_file in a config (see tengine --help)");
        return 2;
    }
    auto map = MapFile::open(o.mapFile, o.reader);
    if (!map.ok()) {
        log(map.error().message);
        return 1;
    }
    const MapHeader& header = (*map)->header();

    // Detail synthesis (3.4): the synthesizer dynamic nodes are made with, null when it is off.
    std::vector<std::string> materialWarnings;
    auto synthesizer = makeDetailSynthesizer(o, static_cast<int>(header.chunkSize), TERRAIN_MATERIALS_DIR, materialWarnings);
    for (const auto& warning : materialWarnings) {
        log("warning: " + warning);
    }
    if (!synthesizer.ok()) {
        log(synthesizer.error().message);
        return 1;
    }
    if (*synthesizer && !header.hasDetailErrors()) {
        log("warning: " + (*map)->name() +
            " has no estimates of the detail error below its leaves (made by an older prep): no dynamic nodes; "
            "run prep again to get them");
    }
    const MaterialSet* materials = *synthesizer ? (*synthesizer)->settings().materials.get() : nullptr;

    const bool demo = o.demoMode;
    const bool video = o.videoMode && !demo;
    std::optional<CameraPath> path;
    if (!o.cameraPath.empty()) {
        auto loaded = CameraPath::load(o.cameraPath);
        if (!loaded.ok()) {
            log(loaded.error().message);
            return 1;
        }
        path = std::move(loaded.value());
    }

    WindowOptions windowOptions;
    windowOptions.width = o.windowWidth;
    windowOptions.height = o.windowHeight;
    windowOptions.visible = !video;
    windowOptions.title = "tengine - " + o.mapFile.filename().string();
    auto window = GlWindow::create(windowOptions);
    if (!window.ok()) {
        log(window.error().message);
        return 1;
    }
    log((*window)->description());
    const std::filesystem::path shaders = o.shaderPath.empty() ? std::filesystem::path(TERRAIN_SHADER_DIR) : o.shaderPath;
    auto renderer = TerrainRenderer::create(shaders, header, o.vertexCacheSize, materials);
    if (!renderer.ok()) {
        log(renderer.error().message);
        return 1;
    }
    auto overlay = TextOverlay::create(shaders);
    if (!overlay.ok()) {
        log(overlay.error().message);
        return 1;
    }

    TerrainNodeSource source(**map, {synthesizer->get(), o.lodMinimumSpacing});
    StreamerOptions streamerOptions;
    streamerOptions.cacheSize = static_cast<std::size_t>(o.quadCacheSize);
    streamerOptions.queueLimit = static_cast<std::size_t>(o.requestQueueSize);
    streamerOptions.workers = o.workerThreads;
    streamerOptions.velocityLimit = o.detailVelocityLimit;
    auto streamer = TerrainStreamer::create(source, extentOf(header), streamerOptions);
    if (!streamer.ok()) {
        log(streamer.error().message);
        return 1;
    }
    (*streamer)->onLoadError([&](const std::string& message) { log(message); });

    Camera camera;
    camera.viewportWidth = (*window)->width();
    camera.viewportHeight = (*window)->height();
    camera.verticalFov = o.cameraFov * kDegrees;
    camera.nearPlane = o.cameraZNear;
    camera.farPlane = o.cameraZFar;
    const double extent = header.nodeSizeAt(0);
    if (o.cameraPosition) {
        camera.position = *o.cameraPosition;
    } else {
        const double top = header.heightOf((*map)->directory().front().maxCode);
        camera.position = {header.originX + extent / 2, header.originY + extent / 2 - extent * 0.6, top + extent * 0.25};
    }
    camera.yaw = o.cameraYaw * kDegrees;
    camera.pitch = o.cameraPitch * kDegrees;
    const SceneStyle baseStyle = styleFrom(o);
    SceneStyle style = baseStyle;

    std::ofstream csv;
    std::string csvText;
    if (video) {
        std::error_code ec;
        std::filesystem::create_directories(o.imagePath, ec);
        if (ec) {
            log(o.imagePath.string() + ": cannot create the image directory: " + ec.message());
            return 1;
        }
        csvText = csvHeader();
    }
    std::unique_ptr<FreeFlight> flight;
    if (!demo && !video) {
        flight = std::make_unique<FreeFlight>((*window)->handle(), std::max(20.0, header.sampleSpacing * 2));
    }

    const std::size_t lastVideoFrame =
        path ? static_cast<std::size_t>(std::floor(path->duration() * o.framesPerSecond + 1e-9)) : 0;
    const std::size_t videoFrames = o.videoFrames > 0 ? std::min<std::size_t>(static_cast<std::size_t>(o.videoFrames), lastVideoFrame + 1)
                                                      : lastVideoFrame + 1;
    const auto start = std::chrono::steady_clock::now();
    auto previous = start;
    double fps = 0.0;
    std::uint64_t hitsBefore = 0, missesBefore = 0, requestedBefore = 0, completedBefore = 0, failedBefore = 0;
    std::size_t frame = 0;
    glm::dvec3 previousPosition = camera.position;
    std::string recordPath = o.cameraPath.empty() ? "recorded.path" : o.cameraPath.string() + ".recorded";
    for (;; ++frame) {
        const auto now = std::chrono::steady_clock::now();
        const double dt = std::chrono::duration<double>(now - previous).count();
        previous = now;
        fps = fps == 0.0 ? 1.0 / std::max(dt, 1e-6) : 0.9 * fps + 0.1 / std::max(dt, 1e-6);
        (*window)->pollEvents();
        if ((*window)->shouldClose() || glfwGetKey((*window)->handle(), GLFW_KEY_ESCAPE) == GLFW_PRESS) {
            break;
        }
        double time = 0.0;
        if (video) {
            if (frame >= videoFrames) {
                break;
            }
            time = path->startTime() + static_cast<double>(frame) / o.framesPerSecond;
            path->evaluate(time).applyTo(camera);
        } else if (demo) {
            time = path->startTime() + std::chrono::duration<double>(now - start).count();
            path->evaluateLooping(time).applyTo(camera);
        } else {
            flight->update(camera, std::min(dt, 0.25));
            if (flight->pressed(GLFW_KEY_1)) {
                flight->speed() *= 2.0;
            }
            if (flight->pressed(GLFW_KEY_2)) {
                flight->speed() /= 2.0;
            }
            if (flight->pressed(GLFW_KEY_L)) {
                style.wireframe = !style.wireframe;
            }
            if (flight->pressed(GLFW_KEY_K)) {
                CameraKeyframe key{std::chrono::duration<double>(now - start).count(), camera.position, camera.yaw,
                                   camera.pitch};
                auto appended = appendKeyframe(recordPath, key);
                log(appended.ok() ? "camera keyframe appended to " + recordPath : appended.error().message);
            }
        }

        // The camera's speed for the velocity limit (3.4.4): over the fixed time step in video mode, so a
        // recording does not depend on how fast it was made.
        const double step = video ? 1.0 / o.framesPerSecond : dt;
        const double speed = frame == 0 || step <= 0.0 ? 0.0 : glm::length(camera.position - previousPosition) / step;
        previousPosition = camera.position;
        const auto frameStart = std::chrono::steady_clock::now();
        FrameStats frameStats = (*streamer)->update(camera, o.lodError, speed);
        if (video) {
            // A recording shows every frame complete: load what it wants, select again, until it wants
            // nothing more (or the cache is full). Independent of thread timing: identical runs give
            // identical frames.
            for (int round = 0; round < 64 && frameStats.requested > frameStats.deferred + frameStats.tooFast; ++round) {
                (*streamer)->drain();
                frameStats = (*streamer)->update(camera, o.lodError, speed);
            }
        }
        RenderStats renderStats = (*renderer)->draw(**streamer, camera, style);
        const auto server = (*streamer)->serverStats();
        const auto& cache = (*streamer)->cache();
        if (o.drawUserInterface) {
            char line[160];
            std::vector<std::string> lines;
            if (video) {  // wall-clock rates mean nothing in frames rendered at a fixed time step
                std::snprintf(line, sizeof line, "frame %zu  t %.2f s  %.2f Mtriangles", frame, time,
                              static_cast<double>(renderStats.triangles) / 1e6);
            } else {
                std::snprintf(line, sizeof line, "%.1f fps  %.2f Mtriangles", fps,
                              static_cast<double>(renderStats.triangles) / 1e6);
            }
            lines.emplace_back(line);
            std::snprintf(line, sizeof line, "nodes %zu static, %zu dynamic", renderStats.staticNodes, renderStats.dynamicNodes);
            lines.emplace_back(line);
            std::snprintf(line, sizeof line, "cache %zu / %zu nodes, requests pending %zu", cache.size(), cache.capacity(),
                          server.queued + server.inFlight);
            lines.emplace_back(line);
            std::snprintf(line, sizeof line, "camera %.0f %.0f %.0f m  tau %.1f px%s", camera.position.x, camera.position.y,
                          camera.position.z, o.lodError, style.wireframe ? "  wireframe" : "");
            lines.emplace_back(line);
            (*overlay)->draw(lines, camera.viewportWidth, camera.viewportHeight);
        }
        if (video) {
            glFinish();
            const double milliseconds =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frameStart).count();
            if (o.videoSaveEvery > 0 && frame % static_cast<std::size_t>(o.videoSaveEvery) == 0) {
                char name[32];
                std::snprintf(name, sizeof name, "frame_%05zu.png", frame);
                auto written =
                    writePngImage(o.imagePath / name, captureFrame(camera.viewportWidth, camera.viewportHeight));
                if (!written.ok()) {
                    log(written.error().message);
                    return 1;
                }
            }
            int deepestLevel = 0;
            for (const SelectedNode& node : (*streamer)->selection().nodes) {
                deepestLevel = std::max(deepestLevel, node.id.level);
            }
            std::ostringstream row;
            row << frame << ',' << time << ',' << milliseconds << ',' << renderStats.triangles << ','
                << renderStats.staticNodes << ',' << renderStats.dynamicNodes << ',' << cache.size() << ','
                << cache.hits() - hitsBefore << ',' << cache.misses() - missesBefore << ','
                << server.requested - requestedBefore << ',' << server.completed - completedBefore << ','
                << server.queued + server.inFlight << ',' << server.failed - failedBefore << ',' << server.peakPending
                << ',' << currentResidentBytes() << ',' << deepestLevel << '\n';
            csvText += row.str();
        }
        hitsBefore = cache.hits();
        missesBefore = cache.misses();
        requestedBefore = server.requested;
        completedBefore = server.completed;
        failedBefore = server.failed;
        (*window)->swapBuffers();
    }

    if (video) {
        const auto csvPath = o.imagePath / "frames.csv";
        auto written = writeFileAtomically(
            csvPath, std::span(reinterpret_cast<const std::uint8_t*>(csvText.data()), csvText.size()));
        if (!written.ok()) {
            log(written.error().message);
            return 1;
        }
        if (o.videoSaveEvery == 1) {
            std::printf("tengine: %zu frames written to %s (statistics in %s)\n", frame, o.imagePath.c_str(),
                        csvPath.c_str());
        } else {
            const std::size_t every = static_cast<std::size_t>(o.videoSaveEvery);
            std::printf("tengine: %zu frames rendered, %zu of them written to %s (statistics in %s)\n", frame,
                        every > 0 ? (frame + every - 1) / every : 0, o.imagePath.c_str(), csvPath.c_str());
        }
        if (o.videoFfmpeg && o.videoSaveEvery != 1) {
            log("no MP4: video_save_every is " + std::to_string(o.videoSaveEvery) + ", not every frame was saved");
        } else if (o.videoFfmpeg && commandExists("ffmpeg")) {
            const auto mp4 = o.imagePath / "video.mp4";
            const auto partial = o.imagePath / "video.partial.mp4";
            std::string command = "ffmpeg -loglevel error -y -framerate " + std::to_string(o.framesPerSecond) + " -i '" +
                                  (o.imagePath / "frame_%05d.png").string() +
                                  "' -c:v libx264 -pix_fmt yuv420p -crf 20 '" + partial.string() + "'";
            std::error_code ec;  // non-throwing forms: a failed rename is reported, not an uncaught exception
            if (std::system(command.c_str()) != 0) {
                std::filesystem::remove(partial, ec);
                log("ffmpeg failed; the frames are still in " + o.imagePath.string());
            } else if (std::filesystem::rename(partial, mp4, ec); ec) {
                const std::string why = ec.message();
                std::filesystem::remove(partial, ec);
                log(mp4.string() + ": cannot name the video: " + why + "; the frames are still in " +
                    o.imagePath.string());
                return 1;
            } else {
                std::printf("tengine: video written to %s\n", mp4.c_str());
            }
        }
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv)
{
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
    return run(*parsed);
}
