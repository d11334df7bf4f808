// The viewer over a damaged map, end to end under Xvfb + Mesa llvmpipe (video mode): a node with flipped
// bits, and the map file cut to half while tengine runs on it with the memory-mapped reader. tengine must
// finish the flight (exit 0), name the file and node in its output, and draw the parents instead: no frame
// shows the clear colour where a view ray must hit the ground.
#include "GlTestSupport.h"
#include "TestSupport.h"

#include "core/Camera.h"
#include "heightfield/HeightFieldIo.h"
#include "heightfield/Image.h"
#include "lod/CameraPath.h"
#include "lod/LodSelector.h"
#include "quadtree/MapFile.h"
#include "quadtree/QuadtreeBuilder.h"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <thread>

namespace terrain {
namespace {

using test::isHole;
using test::mustHitTerrain;

constexpr double kFramesPerSecond = 4.0;
constexpr double kFarPlane = 150000.0;
constexpr int kWidth = 320, kHeight = 180;

std::string frameName(int index)
{
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", index);
    return name;
}

/// The camera tengine flies at frame `f` of `path` in video mode with the settings below.
Camera flightCamera(const CameraPath& path, int f)
{
    Camera camera;
    camera.viewportWidth = kWidth;
    camera.viewportHeight = kHeight;
    camera.verticalFov = 60.0 * std::numbers::pi / 180;
    camera.farPlane = kFarPlane;
    path.evaluate(f / kFramesPerSecond).applyTo(camera);
    return camera;
}

/// The bundled terrain as a map and a flight over it (as TengineGLTest flies), built once for all tests.
class FaultGLTest : public ::testing::Test {
protected:
    static void SetUpTestSuite()
    {
        sDir = new test::ScratchDir();
        auto built = test::buildDemoMap(map());
        ASSERT_TRUE(built.ok()) << built.error().message;
        // Up a valley from the south-west, over a ridge, then a steep look down in the north-east.
        std::ofstream(flight()) << "0 15000 12000 2496 47.7 -8\n"
                                   "2 36000 33000 2700 41.6 -10\n"
                                   "4 46500 45500 4400 39.8 -15\n"
                                   "6 58000 60000 3900 29.1 -30\n"
                                   "8 60000 70000 7000 -50 -60\n";
    }
    static void TearDownTestSuite()
    {
        delete sDir;
        sDir = nullptr;
    }

    static std::filesystem::path map() { return *sDir / "trinidad.map"; }
    static std::filesystem::path flight() { return *sDir / "flight.path"; }
    static int flightFrames() { return static_cast<int>(8 * kFramesPerSecond) + 1; }

    /// tengine's arguments for the flight in video mode over `mapFile`, frames into `frames`: no sky, no
    /// text, no haze, clear colour magenta, the static map only (no synthesized detail).
    static std::vector<std::string> videoArgs(const std::filesystem::path& mapFile, const std::filesystem::path& frames,
                                              std::vector<std::string> settings)
    {
        std::vector<std::string> base = {"camera_path=" + flight().string(),
                                         "video_mode=true",
                                         "video_ffmpeg=false",
                                         "image_path=" + frames.string(),
                                         "window_width=" + std::to_string(kWidth),
                                         "window_height=" + std::to_string(kHeight),
                                         "frames_per_second=4",
                                         "draw_sky=false",
                                         "draw_user_interface=false",
                                         "clear_color=1,0,1",
                                         "haze_distance=0",
                                         "camera_z_far=150000",
                                         "detail_create_new_nodes=false"};
        base.insert(base.end(), settings.begin(), settings.end());
        std::vector<std::string> args = {mapFile.string()};
        for (auto& s : base) {
            args.push_back("--set");
            args.push_back(s);
        }
        return args;
    }

    static test::ScratchDir* sDir;
};

test::ScratchDir* FaultGLTest::sDir = nullptr;

/// Checks every frame of the flight in `frames` for holes; returns the pixels checked.
int expectNoHoles(const std::filesystem::path& frames, const MapHeader& header, double zMin, const CameraPath& path,
                  int frameCount)
{
    int pixelsChecked = 0;
    for (int f = 0; f < frameCount; ++f) {
        auto image = readPngImage(frames / frameName(f), 3);
        if (!image.ok()) {
            ADD_FAILURE() << image.error().message;
            continue;
        }
        const Camera view = flightCamera(path, f);
        int holes = 0, firstX = -1, firstY = -1;
        for (int y = 0; y < image->height; ++y) {
            for (int x = 0; x < image->width; ++x) {
                if (!mustHitTerrain(view, header, zMin, x, y)) {
                    continue;
                }
                ++pixelsChecked;
                if (isHole(image->pixel(x, y)) && holes++ == 0) {
                    firstX = x;
                    firstY = y;
                }
            }
        }
        EXPECT_EQ(holes, 0) << "frame " << f << ": " << holes
                            << " pixels show the clear colour below the horizon, first at (" << firstX << ", " << firstY
                            << ")";
    }
    return pixelsChecked;
}

int countOf(const std::string& text, const std::string& what)
{
    int n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
        ++n;
    }
    return n;
}

TEST_F(FaultGLTest, NodeWithFlippedBitsIsReportedAndItsParentDrawnInstead)
{
    auto sound = MapFile::open(map(), ReaderKind::Stream);
    ASSERT_TRUE(sound.ok()) << sound.error().message;
    const MapHeader& header = (*sound)->header();
    auto path = CameraPath::load(flight());
    ASSERT_TRUE(path.ok()) << path.error().message;
    // The victim: the deepest node the flight draws in the most frames (selected with everything resident
    // at lod_error 2, as tengine selects), so the viewer certainly asks for it.
    MapLodTree tree(**sound);
    std::map<std::uint64_t, std::pair<NodeId, int>> drawn;
    LodSelection selection;
    for (int f = 0; f < flightFrames(); ++f) {
        selectNodes(tree, flightCamera(*path, f), 2.0, {}, selection);
        for (const auto& node : selection.nodes) {
            auto& [id, frames] = drawn[node.id.key()];
            id = node.id;
            ++frames;
        }
    }
    NodeId victim;
    int victimFrames = 0;
    for (const auto& [key, seen] : drawn) {
        if (seen.first.level > victim.level || (seen.first.level == victim.level && seen.second > victimFrames)) {
            victim = seen.first;
            victimFrames = seen.second;
        }
    }
    ASSERT_GE(victim.level, 2);
    const DirectoryEntry* entry = (*sound)->find(victim);
    ASSERT_NE(entry, nullptr);

    test::ScratchDir work;
    const auto damaged = work / "damaged.map";
    std::filesystem::copy_file(map(), damaged);
    ASSERT_TRUE(test::flipBits(damaged, entry->offset + entry->payloadBytes() / 3, 0x10));
    const auto frames = work / "frames";
    auto run = test::runProgram(TERRAIN_TENGINE_EXE, videoArgs(damaged, frames, {"worker_threads=2"}));
    ASSERT_EQ(run.exitCode, 0) << run.output;
    const std::string report = damaged.string() + ": node " + victim.toString() + ": checksum mismatch";
    EXPECT_EQ(countOf(run.output, report), 1) << "expected '" << report << "' once in:\n" << run.output;
    const double zMin = header.heightOf((*sound)->directory().front().minCode);
    const int pixels = expectNoHoles(frames, header, zMin, *path, flightFrames());
    EXPECT_GT(pixels, flightFrames() * kWidth * kHeight / 4) << "the flight should look at the ground";
    EXPECT_FALSE(std::filesystem::exists(frames / frameName(flightFrames()))) << "more frames than the flight has";
    RecordProperty("checked", "node " + victim.toString() + " (drawn in " + std::to_string(victimFrames) +
                                  " frames of the sound map) with a flipped bit: tengine exits 0, reports it once, " +
                                  std::to_string(flightFrames()) + " frames without holes (" + std::to_string(pixels) +
                                  " ground pixels checked)");
}

TEST_F(FaultGLTest, MapTruncatedWhileTheViewerRunsIsReportedAndTheFlightCompletes)
{
    // tengine flies over a copy of the map with the memory-mapped reader; once the first frame is written
    // the copy is cut to half (every node past the middle, and the directory, are gone). Touching those
    // pages would be SIGBUS; instead the loads fail, naming the file, and the resident parents are drawn.
    auto sound = MapFile::open(map(), ReaderKind::Stream);
    ASSERT_TRUE(sound.ok()) << sound.error().message;
    const MapHeader& header = (*sound)->header();
    auto path = CameraPath::load(flight());
    ASSERT_TRUE(path.ok()) << path.error().message;

    test::ScratchDir work, logs;
    const auto copy = work / "running.map";
    std::filesystem::copy_file(map(), copy);
    const auto frames = work / "frames";
    const pid_t child = test::spawnProgram(TERRAIN_TENGINE_EXE, videoArgs(copy, frames, {"reader=memory_mapped"}),
                                           logs / "tengine.txt");
    ASSERT_GT(child, 0);
    // Poll for the first frame (written atomically: it exists only when complete), then cut.
    const auto start = std::chrono::steady_clock::now();
    int status = 0;
    bool exited = false;
    while (!std::filesystem::exists(frames / frameName(0)) && !(exited = ::waitpid(child, &status, WNOHANG) == child) &&
           std::chrono::steady_clock::now() - start < std::chrono::seconds(120)) {
        std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    ASSERT_FALSE(exited) << "tengine ended before its first frame: " << test::describeWaitStatus(status) << "\n"
                         << test::readTextFile(logs / "tengine.txt");
    ASSERT_TRUE(std::filesystem::exists(frames / frameName(0))) << "no first frame within 120 s";
    std::filesystem::resize_file(copy, std::filesystem::file_size(copy) / 2);
    int framesBeforeCut = 0;
    while (std::filesystem::exists(frames / frameName(framesBeforeCut))) {
        ++framesBeforeCut;
    }
    const auto waited = test::waitForProgram(child, 300);
    const std::string output = test::readTextFile(logs / "tengine.txt");
    ASSERT_TRUE(waited) << "tengine did not finish within 300 s:\n" << output;
    ASSERT_TRUE(WIFEXITED(*waited) && WEXITSTATUS(*waited) == 0) << test::describeWaitStatus(*waited) << "\n" << output;
    const std::string report = copy.string() + ": node ";
    EXPECT_GT(countOf(output, report), 0) << "no load failed naming " << copy << ":\n" << output;
    EXPECT_GT(countOf(output, "file is truncated"), 0) << output;
    const double zMin = header.heightOf((*sound)->directory().front().minCode);
    const int pixels = expectNoHoles(frames, header, zMin, *path, flightFrames());
    EXPECT_GT(pixels, flightFrames() * kWidth * kHeight / 4) << "the flight should look at the ground";
    RecordProperty("checked", "cut to half after " + std::to_string(framesBeforeCut) + " of " +
                                  std::to_string(flightFrames()) + " frames: tengine exits 0, " +
                                  std::to_string(countOf(output, report)) + " failed loads reported naming the file, " +
                                  "no holes in any frame");
}

}  // namespace
}  // namespace terrain
