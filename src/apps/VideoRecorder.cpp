#include "apps/VideoRecorder.h"

#include "core/Check.h"
#include "core/Subprocess.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <string_view>

namespace terrain {

namespace {

std::string formatDuration(double seconds)
{
    const long s = std::lround(std::max(0.0, seconds));
    char text[32];
    if (s >= 3600) {
        std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
    } else {
        std::snprintf(text, sizeof text, "%ld:%02ld", s / 60, s % 60);
    }
    return text;
}

}  // namespace

std::string VideoRecorder::frameFileName(std::size_t index)
{
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05zu.png", index);
    return name;
}

bool VideoRecorder::isRecorderFileName(const std::string& name)
{
    // frame_ + at least five digits + .png (frameFileName's pattern)
    constexpr std::string_view kPrefix = "frame_", kSuffix = ".png";
    const std::string_view n = name;
    const bool frame =
        n.size() >= kPrefix.size() + 5 + kSuffix.size() && n.starts_with(kPrefix) && n.ends_with(kSuffix) &&
        std::all_of(n.begin() + kPrefix.size(), n.end() - kSuffix.size(), [](char c) { return c >= '0' && c <= '9'; });
    return name == kCsvName || name == kVideoName || name == kPartialVideoName || frame;
}

Expected<std::unique_ptr<VideoRecorder>> VideoRecorder::create(VideoRecorderOptions options)
{
    TERRAIN_EXPECTS(options.frames >= 1, "VideoRecorder: a recording has at least one frame");
    TERRAIN_EXPECTS(options.framesPerSecond >= 1 && options.saveEvery >= 0, "VideoRecorder: bad options");
    std::error_code ec;
    std::filesystem::create_directories(options.directory, ec);
    if (ec) {
        return makeError(options.directory.string(), ": cannot create the image directory: ", ec.message());
    }
    const auto csvPath = options.directory / kCsvName;
    std::FILE* csv = std::fopen(csvPath.c_str(), "w");
    if (!csv) {
        return makeError(csvPath.string(), ": cannot write the frame statistics: ", std::strerror(errno));
    }
    std::fprintf(csv, "%s\n", options.csvHeader.c_str());
    if (std::fflush(csv) != 0) {
        std::fclose(csv);
        return makeError(csvPath.string(), ": cannot write the frame statistics: ", std::strerror(errno));
    }
    return std::unique_ptr<VideoRecorder>(new VideoRecorder(std::move(options), csv));
}

VideoRecorder::VideoRecorder(VideoRecorderOptions options, std::FILE* csv)
    : mOptions(std::move(options)), mCsv(csv), mStart(std::chrono::steady_clock::now())
{
    mWriter = std::thread([this] { writerLoop(); });
}

void VideoRecorder::stopWriter()
{
    {
        std::lock_guard lock(mMutex);
        mClosing = true;
    }
    mChanged.notify_all();
    if (mWriter.joinable()) {
        mWriter.join();
    }
}

VideoRecorder::~VideoRecorder()
{
    stopWriter();
    if (mCsv) {
        std::fclose(mCsv);
    }
}

bool VideoRecorder::savesImage(std::size_t index) const
{
    return mOptions.saveEvery > 0 && index % static_cast<std::size_t>(mOptions.saveEvery) == 0;
}

void VideoRecorder::say(const std::string& message) const
{
    if (mOptions.log) {
        mOptions.log(message);
    } else {
        std::fprintf(stderr, "%s\n", message.c_str());
    }
}

Status VideoRecorder::add(std::size_t index, Image pixels, std::string csvRow)
{
    TERRAIN_EXPECTS(index == mNextIndex, "VideoRecorder::add: frames are added in order 0, 1, 2, ...");
    TERRAIN_EXPECTS(savesImage(index) == !pixels.pixels.empty(), "VideoRecorder::add: pixels exactly when savesImage");
    {
        std::unique_lock lock(mMutex);
        mChanged.wait(lock, [&] { return mJobs.size() < kQueueFrames || !mError.ok(); });
        if (!mError.ok()) {
            return mError;
        }
        mJobs.push_back({index, std::move(pixels), std::move(csvRow)});
    }
    mChanged.notify_all();
    ++mNextIndex;
    report(mNextIndex);
    return {};
}

void VideoRecorder::report(std::size_t done)
{
    const std::size_t total = mOptions.frames;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - mStart).count();
    const double remaining =
        done > 0 ? elapsed / static_cast<double>(done) * static_cast<double>(total - std::min(done, total)) : 0.0;
    char line[160];
    std::snprintf(line, sizeof line, "recording: frame %zu of %zu, %s elapsed, %s remaining", done, total,
                  formatDuration(elapsed).c_str(), formatDuration(remaining).c_str());
    if (mOptions.progressInPlace) {
        std::fprintf(stderr, "\r%s  ", line);
        std::fflush(stderr);
        mShowedInPlace = true;
        return;
    }
    const int decile = static_cast<int>(done * 10 / std::max<std::size_t>(total, 1));
    if (decile > mLastDecile) {
        mLastDecile = decile;
        say(std::string(line) + " (" + std::to_string(decile * 10) + "%)");
    }
}

void VideoRecorder::writerLoop()
{
    for (;;) {
        Job job;
        {
            std::unique_lock lock(mMutex);
            mChanged.wait(lock, [&] { return !mJobs.empty() || mClosing; });
            if (mJobs.empty()) {
                return;
            }
            job = std::move(mJobs.front());
            mJobs.pop_front();
        }
        Status status;
        if (!job.pixels.pixels.empty()) {
            status = writePngImage(mOptions.directory / frameFileName(job.index), job.pixels, PngCompression::Fast);
        }
        if (status.ok()) {
            std::fprintf(mCsv, "%s\n", job.row.c_str());
            if (std::fflush(mCsv) != 0) {
                status = makeError((mOptions.directory / kCsvName).string(),
                                   ": cannot write the frame statistics: ", std::strerror(errno));
            }
        }
        {
            std::lock_guard lock(mMutex);
            if (status.ok()) {
                ++mWritten;
            } else if (mError.ok()) {
                mError = status;
                mJobs.clear();  // nothing after a lost frame: the CSV and the frames stay consistent
            }
        }
        mChanged.notify_all();
    }
}

std::size_t VideoRecorder::framesWritten() const
{
    std::lock_guard lock(mMutex);
    return mWritten;
}

Status VideoRecorder::finish(bool interrupted)
{
    stopWriter();
    if (mShowedInPlace) {
        std::fprintf(stderr, "\n");
    }
    std::fclose(mCsv);
    mCsv = nullptr;
    const std::size_t frames = framesWritten();
    const auto csvPath = mOptions.directory / kCsvName;
    if (!mError.ok()) {
        say("recording stopped after " + std::to_string(frames) + " frames: " + mError.error().message);
        return mError;
    }
    const std::size_t every = static_cast<std::size_t>(mOptions.saveEvery);
    const std::size_t images = every > 0 ? (frames + every - 1) / every : 0;
    say(std::string(interrupted ? "recording interrupted: " : "recording: ") + std::to_string(frames) + " of " +
        std::to_string(mOptions.frames) + " frames, " + std::to_string(images) + " of them written to " +
        mOptions.directory.string() + " (statistics in " + csvPath.string() + ")");
    if (!mOptions.ffmpeg || frames == 0) {
        return {};
    }
    if (mOptions.saveEvery != 1) {
        say("no MP4: video_save_every is " + std::to_string(mOptions.saveEvery) + ", not every frame was saved");
        return {};
    }
    if (findOnPath("ffmpeg").empty()) {
        say("no MP4: ffmpeg is not installed (the frames are in " + mOptions.directory.string() + ")");
        return {};
    }
    return makeVideo(frames);
}

Status VideoRecorder::makeVideo(std::size_t frames)
{
    const auto mp4 = mOptions.directory / kVideoName;
    const auto partial = mOptions.directory / kPartialVideoName;
    // -frames:v: exactly the frames of this recording, even where an older, longer one left more behind.
    const std::vector<std::string> argv = {"ffmpeg",
                                           "-nostdin",
                                           "-loglevel",
                                           "error",
                                           "-y",
                                           "-framerate",
                                           std::to_string(mOptions.framesPerSecond),
                                           "-i",
                                           (mOptions.directory / "frame_%05d.png").string(),
                                           "-frames:v",
                                           std::to_string(frames),
                                           "-c:v",
                                           "libx264",
                                           "-pix_fmt",
                                           "yuv420p",
                                           "-crf",
                                           "20",
                                           "-f",
                                           "mp4",
                                           partial.string()};
    auto ran = runProcess(argv);
    std::error_code ec;
    if (!ran.ok() || *ran != 0) {
        std::filesystem::remove(partial, ec);
        say((ran.ok() ? "ffmpeg failed (exit status " + std::to_string(*ran) + ")" : ran.error().message) +
            "; no MP4, the frames are still in " + mOptions.directory.string());
        return {};
    }
    std::filesystem::rename(partial, mp4, ec);
    if (ec) {
        const std::string why = ec.message();
        std::filesystem::remove(partial, ec);
        return makeError(mp4.string(), ": cannot name the video: ", why, "; the frames are still in ",
                         mOptions.directory.string());
    }
    say("video written to " + mp4.string() + " (" + std::to_string(frames) + " frames)");
    return {};
}

}  // namespace terrain
