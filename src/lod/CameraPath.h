// Camera paths as data (demo mode, "record camera"): keyframes `time x y z yaw pitch` in a text file,
// evaluated at any time with a centripetal Catmull-Rom spline on position and shortest-arc
// interpolation of yaw.
//
// File format, one keyframe per line:
//     # comment (a '#' starts a comment anywhere on a line); blank lines are ignored
//     time x y z yaw pitch
// time in seconds, strictly increasing; x y z in world metres (x east, y north, z up); yaw and pitch in
// degrees as in Camera.h (yaw 0 = north, positive turns east; pitch in [-90, 90], positive up).
// At least two keyframes.
#pragma once

#include "core/Camera.h"
#include "core/Expected.h"

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace terrain {

/// A camera pose at a time. Angles in radians here (the file stores degrees).
struct CameraKeyframe {
    double time = 0.0;  ///< seconds
    glm::dvec3 position{0.0};
    double yaw = 0.0;    ///< radians
    double pitch = 0.0;  ///< radians
};

/// Where the camera is and where it looks; apply with applyTo().
struct CameraPose {
    glm::dvec3 position{0.0};
    double yaw = 0.0;    ///< radians, in (-pi, pi]
    double pitch = 0.0;  ///< radians, in [-pi/2, pi/2]

    void applyTo(Camera& camera) const
    {
        camera.position = position;
        camera.yaw = yaw;
        camera.pitch = pitch;
    }
};

class CameraPath {
public:
    /// Parses the text of a path file; `name` (usually the path) prefixes every message, with the line:
    /// "demo.path:7: time 3 is not after the previous keyframe's time 4".
    static Expected<CameraPath> parse(std::string_view text, const std::string& name);
    /// Reads and parses a path file.
    static Expected<CameraPath> load(const std::filesystem::path& path);
    /// A path from keyframes already in memory; same rules as the file (>= 2, times strictly increasing,
    /// finite values, pitch in [-pi/2, pi/2]) reported as errors naming `name` and the keyframe index.
    static Expected<CameraPath> fromKeyframes(std::vector<CameraKeyframe> keyframes, const std::string& name);

    const std::vector<CameraKeyframe>& keyframes() const { return mKeys; }
    double startTime() const { return mKeys.front().time; }
    double endTime() const { return mKeys.back().time; }
    double duration() const { return endTime() - startTime(); }

    /// The pose at `time` seconds, clamped to [startTime(), endTime()]. Passes exactly through every
    /// keyframe at its time; position and angles are continuous in time (C1 within a segment; the
    /// velocity may change at a keyframe where neighbouring segments have very different durations).
    CameraPose evaluate(double time) const;
    /// The pose with time wrapped into [startTime(), endTime()): for demo mode running forever. The path
    /// closes smoothly only if its last keyframe repeats the first; otherwise the camera jumps back.
    CameraPose evaluateLooping(double time) const;

private:
    explicit CameraPath(std::vector<CameraKeyframe> keys);

    std::vector<CameraKeyframe> mKeys;
    std::vector<double> mUnwrappedYaw;  ///< yaw per keyframe, unwrapped so neighbours differ by <= pi
};

/// One line of the file format for `key` (no newline), numbers in shortest round-trip form.
std::string formatKeyframe(const CameraKeyframe& key);

/// Appends `key` as a line to the path file at `path`, creating the file with a header comment if it does
/// not exist (the viewer's "record camera" key). The caller keeps times increasing (e.g. the time since
/// recording started); parse() rejects a file where they are not.
Status appendKeyframe(const std::filesystem::path& path, const CameraKeyframe& key);

/// A span of a camera path's time, seconds.
struct TimeSpan {
    double begin = 0.0;
    double end = 0.0;
};

/// Where `path` passes below the ground: the spans of time, sampled every `step` seconds (> 0) from the
/// start to the end, where the camera's height is less than `clearance` metres above `groundAt(x, y)`
/// (which returns empty outside the terrain: not counted). A span is reported from its first to its last
/// sample below.
std::vector<TimeSpan> findPathBelowGround(const CameraPath& path,
                                          const std::function<std::optional<double>(double, double)>& groundAt,
                                          double step, double clearance = 0.0);

/// "12.3-14.1 s, 20 s": spans for a message, at most `most` of them and "... (N more)".
std::string formatTimeSpans(const std::vector<TimeSpan>& spans, std::size_t most = 6);

}  // namespace terrain
