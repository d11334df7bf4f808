// The viewer as a user drives it, under Xvfb: a recording stopped by SIGINT or SIGTERM keeps every frame
// it made (PNG, CSV row and MP4 frame alike); a key tap shorter than a frame takes effect however slow the
// frame (key events sent with xdotool); the free-flight camera held on `w` into a slope stays above the
// ground; a camera path through a hill is reported once.
#include "GlTestSupport.h"
#include "TestSupport.h"

#include "core/Subprocess.h"
#include "heightfield/HeightFieldIo.h"
#include "lod/CameraPath.h"
#include "lod/HeightQuery.h"
#include "quadtree/MapFile.h"
#include "quadtree/QuadtreeBuilder.h"
#include "render/GlWindow.h"

#include <cstdlib>
#include "synthesis/DetailRecipeSetup.h"
#include "synthesis/LeafErrorEstimator.h"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <chrono>
#include <csignal>
#include <fstream>
#include <sstream>
#include <thread>

namespace terrain {
namespace {

using namespace std::chrono_literals;

bool contains(const std::string& text, const std::string& what)
{
    return text.find(what) != std::string::npos;
}

std::size_t countOf(const std::string& text, const std::string& what)
{
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
        ++n;
    }
    return n;
}

/// Waits up to `seconds` for `ready()`.
bool waitFor(const std::function<bool()>& ready, double seconds)
{
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
        if (ready()) {
            return true;
        }
        std::this_thread::sleep_for(50ms);
    }
    return ready();
}

std::size_t lineCount(const std::filesystem::path& file)
{
    std::ifstream in(file);
    std::size_t n = 0;
    for (std::string line; std::getline(in, line);) {
        ++n;
    }
    return n;
}

std::size_t pngCount(const std::filesystem::path& dir)
{
    std::size_t n = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        n += entry.path().extension() == ".png" ? 1 : 0;
    }
    return n;
}

/// xdotool with `args`; its exit code.
int xdotool(const std::vector<std::string>& args)
{
    auto run = test::runProgram("/usr/bin/xdotool", args);
    if (run.exitCode != 0) {
        std::string command;
        for (const auto& a : args) {
            command += " " + a;
        }
        ADD_FAILURE() << "xdotool" << command << ": " << run.output;
    }
    return run.exitCode;
}

/// The X window id of the viewer's window ("tengine - NAME.map"), empty if none appeared in `seconds`.
std::string viewerWindow(double seconds)
{
    std::string id;
    waitFor(
        [&] {
            auto found = test::runProgram("/usr/bin/xdotool", {"search", "--name", "^tengine - "});
            std::istringstream lines(found.output);
            std::getline(lines, id);
            return found.exitCode == 0 && !id.empty();
        },
        seconds);
    return id;
}

/// A press and release `holdSeconds` apart, sent to the window: a tap far shorter than a slow frame.
void tap(const std::string& window, const std::string& key, double holdSeconds = 0.02)
{
    EXPECT_EQ(xdotool({"keydown", "--window", window, key}), 0);
    std::this_thread::sleep_for(std::chrono::duration<double>(holdSeconds));
    if (key == "Escape") {  // the viewer may be gone already: the release has nowhere to go
        test::runProgram("/usr/bin/xdotool", {"keyup", "--window", window, key});
    } else {
        EXPECT_EQ(xdotool({"keyup", "--window", window, key}), 0);
    }
}

class InteractionGLTest : public ::testing::Test {
protected:
    static void SetUpTestSuite()
    {
        sDir = new test::ScratchDir();
        auto built = test::buildDemoMap(*sDir / "trinidad.map");
        ASSERT_TRUE(built.ok()) << built.error().message;
        // The same terrain with detail errors estimated for grass.mat alone, and the recipe saying so.
        auto grass =
            test::buildDemoMap(*sDir / "grass.map", {std::filesystem::path(TERRAIN_MATERIALS_DIR) / "grass.mat"});
        ASSERT_TRUE(grass.ok()) << grass.error().message;
        std::ofstream path(*sDir / "flight.path");
        path << "0 15000 12000 2496 47.7 -8\n"
                "8 36000 33000 2700 41.6 -10\n";
    }
    static void TearDownTestSuite()
    {
        delete sDir;
        sDir = nullptr;
    }
    static std::filesystem::path map() { return *sDir / "trinidad.map"; }

    /// Viewer arguments: the map, small window, plus `settings` as --set.
    static std::vector<std::string> arguments(const std::vector<std::string>& settings)
    {
        std::vector<std::string> args = {map().string(), "--set", "window_width=320", "--set", "window_height=180"};
        for (const auto& s : settings) {
            args.push_back("--set");
            args.push_back(s);
        }
        return args;
    }

    static test::ScratchDir* sDir;
};

test::ScratchDir* InteractionGLTest::sDir = nullptr;

TEST_F(InteractionGLTest, RecordingStoppedBySignalKeepsEveryFrameItMade)
{
    ASSERT_FALSE(findOnPath("ffmpeg").empty()) << "ffmpeg is installed by .ci/install-deps";
    // With no display at all: video mode renders through EGL, and no X server shares the signal.
    struct NoDisplay {
        std::string saved;
        bool had = false;
        NoDisplay()
        {
            if (const char* d = std::getenv("DISPLAY")) {
                saved = d;
                had = true;
            }
            ::unsetenv("DISPLAY");
        }
        ~NoDisplay()
        {
            if (had) {
                ::setenv("DISPLAY", saved.c_str(), 1);
            }
        }
    } noDisplay;
    for (int signal : {SIGTERM, SIGINT}) {
        test::ScratchDir out;
        const auto frames = out / "frames";
        const pid_t pid =
            test::spawnProgram(TERRAIN_TENGINE_EXE,
                               arguments({"camera_path=" + (*sDir / "flight.path").string(), "video_mode=true",
                                          "frames_per_second=30", "image_path=" + frames.string()}),
                               out / "tengine.log");
        ASSERT_GT(pid, 0);
        // Stop it part-way, once a dozen frames are on disk (the whole path is 241 frames).
        ASSERT_TRUE(waitFor([&] { return lineCount(frames / "frames.csv") > 12; }, 120))
            << test::readTextFile(out / "tengine.log");
        ASSERT_EQ(::kill(pid, signal), 0);
        const auto status = test::waitForProgram(pid, 120);
        ASSERT_TRUE(status.has_value()) << "did not end after " << strsignal(signal);
        const std::string log = test::readTextFile(out / "tengine.log");
        ASSERT_TRUE(WIFEXITED(*status)) << test::describeWaitStatus(*status) << "\n" << log;
        EXPECT_EQ(WEXITSTATUS(*status), 128 + signal) << log;
        const std::size_t made = pngCount(frames);
        EXPECT_GT(made, 12u);
        EXPECT_LT(made, 241u) << "stopped part-way";
        EXPECT_EQ(lineCount(frames / "frames.csv"), made + 1) << "a header and exactly one row per frame";
        for (std::size_t i = 0; i < made; ++i) {
            char name[32];
            std::snprintf(name, sizeof name, "frame_%05zu.png", i);
            EXPECT_TRUE(std::filesystem::exists(frames / name)) << name;
        }
        auto probe =
            test::runProgram("ffprobe", {"-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                                         "stream=nb_read_frames", "-of", "csv=p=0", (frames / "video.mp4").string()});
        ASSERT_EQ(probe.exitCode, 0) << probe.output << "\n" << log;
        EXPECT_EQ(std::stoul(probe.output), made) << "the MP4 has every frame made";
        EXPECT_TRUE(contains(log, "recording stopped by")) << log;
        EXPECT_TRUE(contains(log, "headless (EGL)")) << log;
        EXPECT_FALSE(std::filesystem::exists(frames / "video.partial.mp4"));
    }
}

TEST_F(InteractionGLTest, TheViewerEndsSayingSoWhenItsDisplayGoesAway)
{
    const std::filesystem::path xvfb = "/usr/bin/Xvfb";
    ASSERT_TRUE(std::filesystem::exists(xvfb)) << "Xvfb is installed by .ci/install-deps";
    // A display of its own, ended under the running viewer.
    test::ScratchDir out;
    const std::string display = ":" + std::to_string(200 + ::getpid() % 400);
    const pid_t server = test::spawnProgram(xvfb.string(), {display, "-screen", "0", "640x480x24", "-nolisten", "tcp"},
                                            out / "xvfb.log");
    ASSERT_GT(server, 0);
    ASSERT_TRUE(waitFor([&] { return std::filesystem::exists("/tmp/.X11-unix/X" + display.substr(1)); }, 30))
        << test::readTextFile(out / "xvfb.log");
    struct ScopedDisplay {
        std::string saved;
        bool had = false;
        explicit ScopedDisplay(const std::string& value)
        {
            if (const char* d = std::getenv("DISPLAY")) {
                saved = d;
                had = true;
            }
            ::setenv("DISPLAY", value.c_str(), 1);
        }
        ~ScopedDisplay()
        {
            if (had) {
                ::setenv("DISPLAY", saved.c_str(), 1);
            } else {
                ::unsetenv("DISPLAY");
            }
        }
    };
    pid_t viewer = -1;
    {
        const ScopedDisplay scoped(display);
        viewer = test::spawnProgram(TERRAIN_TENGINE_EXE, arguments({"log_file=" + (out / "viewer.log").string()}),
                                    out / "stdout.txt");
    }
    ASSERT_GT(viewer, 0);
    ASSERT_TRUE(waitFor([&] { return contains(test::readTextFile(out / "viewer.log"), "node pools"); }, 60))
        << test::readTextFile(out / "stdout.txt");
    std::this_thread::sleep_for(2s);  // frames are being drawn
    ASSERT_EQ(::kill(server, SIGTERM), 0);
    test::waitForProgram(server, 30);
    const auto status = test::waitForProgram(viewer, 30);
    ASSERT_TRUE(status.has_value()) << "the viewer did not end when its display went away";
    const std::string said = test::readTextFile(out / "viewer.log");
    EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == kDisplayLostStatus)
        << test::describeWaitStatus(*status) << "\n"
        << said;
    EXPECT_TRUE(contains(said, "the display " + display + " went away")) << said;
}

TEST_F(InteractionGLTest, KeyTapsShorterThanAFrameTakeEffect)
{
    if (!displayAvailable()) {
        GTEST_SKIP() << "key events need the viewer's window on a display (ctest runs these under Xvfb)";
    }
    // Full window, detail synthesis and tau 0.5 px: frames of several hundred milliseconds on llvmpipe. A
    // 20 ms tap falls inside one frame; a viewer polling the key state once per frame would miss it.
    test::ScratchDir out;
    const auto log = out / "viewer.log";
    std::vector<std::string> args = {map().string(), "--set", "lod_error=0.5", "--set", "log_file=" + log.string()};
    const pid_t pid = test::spawnProgram(TERRAIN_TENGINE_EXE, args, out / "stdout.txt");
    ASSERT_GT(pid, 0);
    const std::string window = viewerWindow(60);
    ASSERT_FALSE(window.empty()) << test::readTextFile(out / "stdout.txt");
    std::this_thread::sleep_for(2s);  // frames are being drawn
    tap(window, "l");
    EXPECT_TRUE(waitFor([&] { return contains(test::readTextFile(log), "wireframe on"); }, 30))
        << test::readTextFile(log);
    tap(window, "Escape");
    const auto status = test::waitForProgram(pid, 30);
    ASSERT_TRUE(status.has_value()) << "esc did not end the viewer";
    EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << test::describeWaitStatus(*status);
    const std::string said = test::readTextFile(log);
    EXPECT_EQ(countOf(said, "wireframe"), 1u) << "one tap, one toggle";
    // The frames really were longer than the tap.
    const auto at = said.find("mean frame time ");
    ASSERT_NE(at, std::string::npos) << said;
    EXPECT_GT(std::stod(said.substr(at + 16)), 20.0 * 2) << said;
}

TEST_F(InteractionGLTest, FreeFlightHeldIntoASlopeStaysAboveTheSurface)
{
    if (!displayAvailable()) {
        GTEST_SKIP() << "key events need the viewer's window on a display (ctest runs these under Xvfb)";
    }
    // 150 m above a mountainside, looking 35 degrees down at it, `1` tapped twice (four times the speed of
    // half the height above the ground per second) and `w` held for six seconds: the camera is driven into the
    // slope and along it. `k` records its pose every
    // 0.4 s; every recorded pose is at least camera_min_clearance above the ground (static detail only, so
    // the drawn surface near the camera is the map's finest level).
    auto mapFile = MapFile::open(map(), ReaderKind::Stream);
    ASSERT_TRUE(mapFile.ok());
    const double x0 = 51000, y0 = 51000;
    auto ground0 = staticHeightAt(**mapFile, x0, y0);
    ASSERT_TRUE(ground0.ok()) << ground0.error().message;
    test::ScratchDir out;
    const auto path = out / "start.path";
    std::ofstream(path) << "0 0 0 0 0 0\n1 1 1 1 0 0\n";  // only names where `k` records: start.path.recorded
    const double clearance = 2.0;
    std::ostringstream position;
    position << "camera_position=" << x0 << "," << y0 << "," << ground0->height + 150;
    const pid_t pid = test::spawnProgram(
        TERRAIN_TENGINE_EXE,
        arguments({position.str(), "camera_yaw=215", "camera_pitch=-35", "camera_path=" + path.string(),
                   "detail_create_new_nodes=false", "camera_min_clearance=2"}),
        out / "stdout.txt");
    ASSERT_GT(pid, 0);
    const std::string window = viewerWindow(60);
    ASSERT_FALSE(window.empty()) << test::readTextFile(out / "stdout.txt");
    std::this_thread::sleep_for(1s);
    tap(window, "1");
    tap(window, "1");
    ASSERT_EQ(xdotool({"keydown", "--window", window, "w"}), 0);
    for (int i = 0; i < 15; ++i) {
        std::this_thread::sleep_for(400ms);
        tap(window, "k", 0.05);
    }
    ASSERT_EQ(xdotool({"keyup", "--window", window, "w"}), 0);
    tap(window, "Escape");
    const auto status = test::waitForProgram(pid, 30);
    ASSERT_TRUE(status.has_value());
    auto recorded = CameraPath::load(out / "start.path.recorded");
    ASSERT_TRUE(recorded.ok()) << recorded.error().message << "\n" << test::readTextFile(out / "stdout.txt");
    ASSERT_GE(recorded->keyframes().size(), 10u);
    double closest = 1e9;
    for (const CameraKeyframe& key : recorded->keyframes()) {
        auto ground = staticHeightAt(**mapFile, key.position.x, key.position.y);
        ASSERT_TRUE(ground.ok()) << ground.error().message;
        const double above = key.position.z - ground->height;
        // The drawn surface is the finest static level here, within the geomorph of the nodes nearby.
        EXPECT_GE(above, clearance - 0.5) << "t " << key.time << " at " << key.position.x << ", " << key.position.y;
        closest = std::min(closest, above);
    }
    EXPECT_LT(closest, 20.0) << "the camera should have been driven down to the slope";
}

TEST_F(InteractionGLTest, APathThroughAHillIsReportedOnceWithItsTimes)
{
    // Straight through the terrain at 1000 m: below the ground for most of the way; reported once.
    test::ScratchDir out;
    std::ofstream(out / "through.path") << "0 20000 20000 1000 45 0\n10 60000 60000 1000 45 0\n";
    auto run = test::runProgram(
        TERRAIN_TENGINE_EXE,
        arguments({"camera_path=" + (out / "through.path").string(), "video_mode=true", "video_frames=2",
                   "video_ffmpeg=false", "image_path=" + (out / "frames").string()}));
    ASSERT_EQ(run.exitCode, 0) << run.output;
    EXPECT_EQ(countOf(run.output, "passes below the terrain"), 1u) << run.output;
    EXPECT_TRUE(contains(run.output, "through.path passes below the terrain at 0-10 s")) << run.output;
    // The bundled demo path stays above it: no warning.
    auto demo = test::runProgram(
        TERRAIN_TENGINE_EXE,
        arguments({"camera_path=" + std::string(TERRAIN_DEMO_DIR) + "/trinidad.path", "video_mode=true",
                   "video_frames=1", "video_ffmpeg=false", "image_path=" + (out / "demo").string()}));
    ASSERT_EQ(demo.exitCode, 0) << demo.output;
    EXPECT_FALSE(contains(demo.output, "passes below")) << demo.output;
}

TEST_F(InteractionGLTest, DetailSettingsUnlikeTheMapsGiveExactlyOneWarning)
{
    auto run = [&](const std::vector<std::string>& settings) {
        test::ScratchDir out;
        std::vector<std::string> all = settings;
        all.insert(all.end(), {"camera_path=" + (*sDir / "flight.path").string(), "video_mode=true", "video_frames=3",
                               "video_ffmpeg=false", "image_path=" + (out / "frames").string()});
        auto args = arguments(all);
        args[0] = (*sDir / "grass.map").string();
        return test::runProgram(TERRAIN_TENGINE_EXE, args);
    };
    auto same = run({});  // the viewer's defaults: grass.mat alone, Kobbelt, omega 1
    ASSERT_EQ(same.exitCode, 0) << same.output;
    EXPECT_EQ(countOf(same.output, "warning"), 0u) << same.output;
    for (const std::string& setting :
         {std::string("detail_material_type=1"), std::string("detail_subdivision_factor=0.5"),
          std::string("detail_add_material=false")}) {
        auto other = run({setting});
        ASSERT_EQ(other.exitCode, 0) << setting << ": " << other.output;
        EXPECT_EQ(countOf(other.output, "warning"), 1u) << setting << ": " << other.output;
        EXPECT_TRUE(contains(other.output, "estimated for kobbelt omega 1, materials grass")) << other.output;
        EXPECT_TRUE(contains(other.output, "to match, run: prep HEIGHTFIELD -h 90")) << other.output;
    }
}

}  // namespace
}  // namespace terrain
