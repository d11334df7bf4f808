// Video mode's outputs (paper 4.4.2): numbered PNG frames, frames.csv with a row of statistics per frame,
// and an MP4 made from the frames by ffmpeg. Built to survive interruption: frames are encoded and written
// on a writer thread (the render thread only hands pixels over), each frame's CSV row is appended and
// flushed as soon as its PNG is on disk, so a crash loses at most the frames in flight, and finish() after
// a stop request (SIGINT, SIGTERM, a closed window) makes the MP4 from exactly the frames written so far.
#pragma once

#include "core/Expected.h"
#include "heightfield/Image.h"

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace terrain {

struct VideoRecorderOptions {
    std::filesystem::path directory;  ///< image_path; created if missing
    std::size_t frames = 0;           ///< frames of the whole recording, >= 1 (for the progress report)
    int framesPerSecond = 30;         ///< of the MP4, [1, 240]
    int saveEvery = 1;                ///< a PNG of every saveEvery-th frame; 0 = none (no MP4 unless 1)
    bool ffmpeg = true;               ///< make video.mp4 when ffmpeg is on PATH and every frame is saved
    std::string csvHeader;            ///< frames.csv's first line, without the newline
    /// Progress: true updates one line in place (a terminal), false prints a line at every 10%.
    bool progressInPlace = false;
    /// Where progress lines and messages go (stderr when empty).
    std::function<void(const std::string&)> log;
};

class VideoRecorder {
public:
    /// File names inside the directory.
    static constexpr const char* kCsvName = "frames.csv";
    static constexpr const char* kVideoName = "video.mp4";
    static constexpr const char* kPartialVideoName = "video.partial.mp4";
    /// "frame_00042.png"
    static std::string frameFileName(std::size_t index);
    /// Whether `name` is one of the files a recording writes (a frame, the CSV, the video).
    static bool isRecorderFileName(const std::string& name);
    /// Frames waiting for the writer at most; add() blocks beyond (2.6 MB each at 1280 x 720).
    static constexpr std::size_t kQueueFrames = 6;

    /// Creates the directory and frames.csv (replacing an old one) and starts the writer thread. Errors
    /// name the path.
    static Expected<std::unique_ptr<VideoRecorder>> create(VideoRecorderOptions options);
    ~VideoRecorder();
    VideoRecorder(const VideoRecorder&) = delete;
    VideoRecorder& operator=(const VideoRecorder&) = delete;

    /// Whether frame `index` is to be saved as a PNG (the caller captures pixels only then).
    bool savesImage(std::size_t index) const;
    /// Hands over frame `index` (0, 1, 2, ... in order): its pixels when savesImage(index) (else an empty
    /// image) and its CSV row without the newline. Blocks while kQueueFrames frames wait. Returns the
    /// writer's first error (a frame that could not be written); later frames are then refused.
    Status add(std::size_t index, Image pixels, std::string csvRow);
    /// Waits for the writer, closes frames.csv and, when every frame was saved and ffmpeg is wanted and on
    /// PATH, makes video.mp4 from the frames written (through a temporary name). `interrupted` only changes
    /// the report. Returns an error when a frame or the video could not be written.
    Status finish(bool interrupted);

    /// Frames whose PNG (when saved) and CSV row are on disk.
    std::size_t framesWritten() const;

private:
    explicit VideoRecorder(VideoRecorderOptions options, std::FILE* csv);
    struct Job {
        std::size_t index = 0;
        Image pixels;
        std::string row;
    };
    void writerLoop();
    /// Lets the writer finish the queued frames and joins it (idempotent).
    void stopWriter();
    void report(std::size_t done);
    void say(const std::string& message) const;
    Status makeVideo(std::size_t frames);

    VideoRecorderOptions mOptions;
    std::FILE* mCsv = nullptr;
    std::chrono::steady_clock::time_point mStart;
    int mLastDecile = 0;
    bool mShowedInPlace = false;

    mutable std::mutex mMutex;
    std::condition_variable mChanged;
    std::deque<Job> mJobs;
    bool mClosing = false;
    std::size_t mWritten = 0;
    std::size_t mNextIndex = 0;
    Status mError;
    std::thread mWriter;
};

}  // namespace terrain
