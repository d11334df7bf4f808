// Video mode's recorder (apps/VideoRecorder.h), without GL: frames and CSV rows land on disk in order and
// agree, a stop after N frames leaves exactly N of each, and write errors stop the recording naming the
// file. The GL tests (TengineGLTest) stop the real viewer with SIGINT and SIGTERM and count the MP4.
#include "TestSupport.h"
#include "apps/VideoRecorder.h"
#include "heightfield/Image.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

namespace terrain {
namespace {

Image solid(int width, int height, std::uint8_t value)
{
    Image image;
    image.width = width;
    image.height = height;
    image.channels = 3;
    image.pixels.assign(static_cast<std::size_t>(width) * height * 3, value);
    return image;
}

std::vector<std::string> lines(const std::filesystem::path& file)
{
    std::ifstream in(file);
    std::vector<std::string> out;
    for (std::string line; std::getline(in, line);) {
        out.push_back(line);
    }
    return out;
}

VideoRecorderOptions options(const std::filesystem::path& dir, std::size_t frames, int saveEvery = 1)
{
    VideoRecorderOptions o;
    o.directory = dir;
    o.frames = frames;
    o.saveEvery = saveEvery;
    o.ffmpeg = false;
    o.csvHeader = "frame,value";
    o.log = [](const std::string&) {};
    return o;
}

TEST(VideoRecorderTest, FileNames)
{
    EXPECT_EQ(VideoRecorder::frameFileName(42), "frame_00042.png");
    EXPECT_EQ(VideoRecorder::frameFileName(123456), "frame_123456.png");
    for (const char* name : {"frames.csv", "video.mp4", "video.partial.mp4", "frame_00000.png", "frame_123456.png"}) {
        EXPECT_TRUE(VideoRecorder::isRecorderFileName(name)) << name;
    }
    for (const char* name : {"frame_1.png", "terrain.map", "frames.csv.bak", "frame_00000.png.txt"}) {
        EXPECT_FALSE(VideoRecorder::isRecorderFileName(name)) << name;
    }
}

TEST(VideoRecorderTest, EveryFrameAndRowArriveInOrder)
{
    test::ScratchDir dir;
    auto recorder = VideoRecorder::create(options(dir / "frames", 20));
    ASSERT_TRUE(recorder.ok()) << recorder.error().message;
    for (std::size_t i = 0; i < 20; ++i) {
        ASSERT_TRUE((*recorder)->savesImage(i));
        ASSERT_TRUE((*recorder)->add(i, solid(8, 4, static_cast<std::uint8_t>(i * 10)), std::to_string(i) + ",x").ok());
    }
    ASSERT_TRUE((*recorder)->finish(false).ok());
    EXPECT_EQ((*recorder)->framesWritten(), 20u);
    const auto rows = lines(dir / "frames" / "frames.csv");
    ASSERT_EQ(rows.size(), 21u);
    EXPECT_EQ(rows[0], "frame,value");
    for (std::size_t i = 0; i < 20; ++i) {
        EXPECT_EQ(rows[i + 1], std::to_string(i) + ",x");
        auto image = readPngImage(dir / "frames" / VideoRecorder::frameFileName(i), 3);
        ASSERT_TRUE(image.ok()) << image.error().message;
        EXPECT_EQ(image->pixels, solid(8, 4, static_cast<std::uint8_t>(i * 10)).pixels) << "frame " << i;
    }
}

TEST(VideoRecorderTest, RowsAreOnDiskAsFramesAreWrittenNotAtTheEnd)
{
    // A crash must lose at most the frames in flight: once framesWritten() says N, the CSV on disk holds
    // N rows without finish() (or the destructor) having run.
    test::ScratchDir dir;
    auto recorder = VideoRecorder::create(options(dir.path(), 100));
    ASSERT_TRUE(recorder.ok());
    for (std::size_t i = 0; i < 30; ++i) {
        ASSERT_TRUE((*recorder)->add(i, solid(4, 4, 1), std::to_string(i)).ok());
    }
    for (int spin = 0; spin < 5000 && (*recorder)->framesWritten() < 30; ++spin) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    ASSERT_EQ((*recorder)->framesWritten(), 30u);
    EXPECT_EQ(lines(dir / "frames.csv").size(), 31u);
}

TEST(VideoRecorderTest, StoppedEarlyLeavesExactlyTheFramesMade)
{
    test::ScratchDir dir;
    std::vector<std::string> said;
    auto o = options(dir.path(), 1000);
    o.log = [&](const std::string& m) { said.push_back(m); };
    auto recorder = VideoRecorder::create(o);
    ASSERT_TRUE(recorder.ok());
    for (std::size_t i = 0; i < 7; ++i) {
        ASSERT_TRUE((*recorder)->add(i, solid(4, 4, 1), std::to_string(i)).ok());
    }
    ASSERT_TRUE((*recorder)->finish(true).ok());
    EXPECT_EQ(lines(dir / "frames.csv").size(), 8u);
    std::size_t pngs = 0;
    for (const auto& name : dir.list()) {
        pngs += name.ends_with(".png") ? 1 : 0;
    }
    EXPECT_EQ(pngs, 7u);
    ASSERT_FALSE(said.empty());
    EXPECT_NE(said.back().find("interrupted: 7 of 1000 frames"), std::string::npos) << said.back();
}

TEST(VideoRecorderTest, SaveEveryNthFrameStillRowsEveryFrame)
{
    test::ScratchDir dir;
    auto recorder = VideoRecorder::create(options(dir.path(), 10, 3));
    ASSERT_TRUE(recorder.ok());
    for (std::size_t i = 0; i < 10; ++i) {
        EXPECT_EQ((*recorder)->savesImage(i), i % 3 == 0);
        Image pixels = (*recorder)->savesImage(i) ? solid(4, 4, 2) : Image{};
        ASSERT_TRUE((*recorder)->add(i, std::move(pixels), std::to_string(i)).ok());
    }
    ASSERT_TRUE((*recorder)->finish(false).ok());
    EXPECT_EQ(lines(dir / "frames.csv").size(), 11u);
    EXPECT_EQ(dir.list(), (std::vector<std::string>{"frame_00000.png", "frame_00003.png", "frame_00006.png",
                                                    "frame_00009.png", "frames.csv"}));
}

TEST(VideoRecorderTest, AFrameThatCannotBeWrittenStopsTheRecordingNamingIt)
{
    test::ScratchDir dir;
    auto recorder = VideoRecorder::create(options(dir.path(), 10));
    ASSERT_TRUE(recorder.ok());
    // frame 2's name is taken by a directory: its PNG cannot be written.
    std::filesystem::create_directory(dir / VideoRecorder::frameFileName(2));
    Status failed;
    for (std::size_t i = 0; i < 10 && failed.ok(); ++i) {
        failed = (*recorder)->add(i, solid(4, 4, 1), std::to_string(i));
    }
    const Status finished = (*recorder)->finish(false);
    ASSERT_FALSE(finished.ok());
    EXPECT_NE(finished.error().message.find("frame_00002.png"), std::string::npos) << finished.error().message;
    EXPECT_EQ(lines(dir / "frames.csv").size(), 3u) << "rows for frames 0 and 1 only";
}

TEST(VideoRecorderTest, AnUnwritableDirectoryIsAnError)
{
    test::ScratchDir dir;
    std::ofstream(dir / "file") << "x";
    auto recorder = VideoRecorder::create(options(dir / "file" / "frames", 10));
    ASSERT_FALSE(recorder.ok());
    EXPECT_NE(recorder.error().message.find("file/frames"), std::string::npos) << recorder.error().message;
}

}  // namespace
}  // namespace terrain
