// Camera paths: parsing, centripetal Catmull-Rom evaluation (Barry-Goldman pyramidal form, alpha = 0.5:
// no cusps or self-intersections within a segment, unlike the uniform variant), shortest-arc yaw.
#include "lod/CameraPath.h"

#include "core/Check.h"
#include "core/Parse.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

namespace terrain {

namespace {

constexpr double kPi = std::numbers::pi;
/// Largest |coordinate| in metres and |time| in seconds a keyframe may hold: a million kilometres and
/// thirty years are beyond any terrain or flight, and small enough that the spline arithmetic (squared
/// distances, ghost points 2 p1 - p2) stays finite. Found by fuzzing (tests/data/fuzz/camera_path).
constexpr double kMaxCoordinate = 1e9;
constexpr double kMaxTime = 1e9;

/// Why a keyframe's values are unusable (not finite, out of range), or empty. Angles in radians.
std::string keyframeProblem(const CameraKeyframe& k)
{
    const double values[] = {k.time, k.position.x, k.position.y, k.position.z, k.yaw, k.pitch};
    static constexpr const char* kNames[] = {"time", "x", "y", "z", "yaw", "pitch"};
    for (int f = 0; f < 6; ++f) {
        if (!std::isfinite(values[f])) {
            return std::string(kNames[f]) + " is not finite";
        }
    }
    if (std::abs(k.time) > kMaxTime) {
        return "time " + formatNumber(k.time) + " s is outside [-1e9, 1e9]";
    }
    for (int f = 1; f <= 3; ++f) {
        if (std::abs(values[f]) > kMaxCoordinate) {
            return std::string(kNames[f]) + " " + formatNumber(values[f]) + " m is outside [-1e9, 1e9]";
        }
    }
    if (std::abs(k.pitch) > kPi / 2 + 1e-12) {
        return "pitch " + formatNumber(k.pitch * kDegreesPerRadian) + " degrees is outside [-90, 90]";
    }
    return {};
}

/// Wraps an angle in radians into (-pi, pi].
double wrapAngle(double a)
{
    double w = std::remainder(a, 2.0 * kPi);
    return w <= -kPi ? w + 2.0 * kPi : w;
}

/// Uniform Catmull-Rom through p1 (u = 0) and p2 (u = 1).
double uniformCatmullRom(double p0, double p1, double p2, double p3, double u)
{
    double u2 = u * u, u3 = u2 * u;
    return 0.5 * (2.0 * p1 + (p2 - p0) * u + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * u2 +
                  (3.0 * p1 - p0 - 3.0 * p2 + p3) * u3);
}

/// Centripetal Catmull-Rom between p1 (u = 0) and p2 (u = 1); p0 and p3 must differ from p1 and p2.
glm::dvec3 centripetalCatmullRom(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2, const glm::dvec3& p3,
                                 double u)
{
    double t0 = 0.0;
    double t1 = t0 + std::sqrt(glm::length(p1 - p0));
    double t2 = t1 + std::sqrt(glm::length(p2 - p1));
    double t3 = t2 + std::sqrt(glm::length(p3 - p2));
    double t = t1 + u * (t2 - t1);
    auto mix = [](const glm::dvec3& a, const glm::dvec3& b, double ta, double tb, double tt) {
        return ((tb - tt) * a + (tt - ta) * b) / (tb - ta);
    };
    glm::dvec3 a1 = mix(p0, p1, t0, t1, t);
    glm::dvec3 a2 = mix(p1, p2, t1, t2, t);
    glm::dvec3 a3 = mix(p2, p3, t2, t3, t);
    glm::dvec3 b1 = mix(a1, a2, t0, t2, t);
    glm::dvec3 b2 = mix(a2, a3, t1, t3, t);
    return mix(b1, b2, t1, t2, t);
}

}  // namespace

CameraPath::CameraPath(std::vector<CameraKeyframe> keys) : mKeys(std::move(keys))
{
    mUnwrappedYaw.resize(mKeys.size());
    mUnwrappedYaw[0] = mKeys[0].yaw;
    for (std::size_t i = 1; i < mKeys.size(); ++i) {
        mUnwrappedYaw[i] = mUnwrappedYaw[i - 1] + wrapAngle(mKeys[i].yaw - mKeys[i - 1].yaw);
    }
}

Expected<CameraPath> CameraPath::fromKeyframes(std::vector<CameraKeyframe> keys, const std::string& name)
{
    if (keys.size() < 2) {
        return makeError(name, ": a camera path needs at least 2 keyframes, found ", keys.size());
    }
    for (std::size_t i = 0; i < keys.size(); ++i) {
        const CameraKeyframe& k = keys[i];
        if (const std::string problem = keyframeProblem(k); !problem.empty()) {
            return makeError(name, ": keyframe ", i, ": ", problem);
        }
        if (i > 0 && !(k.time > keys[i - 1].time)) {
            return makeError(name, ": keyframe ", i, ": time ", k.time, " is not after the previous keyframe's time ",
                             keys[i - 1].time);
        }
    }
    return CameraPath(std::move(keys));
}

Expected<CameraPath> CameraPath::parse(std::string_view text, const std::string& name)
{
    static constexpr const char* kFields[] = {"time", "x", "y", "z", "yaw", "pitch"};
    std::vector<CameraKeyframe> keys;
    int previousLine = 0;
    int lineNumber = 0;
    std::size_t pos = 0;
    while (pos < text.size()) {
        std::size_t eol = text.find('\n', pos);
        std::string_view line = text.substr(pos, eol == std::string_view::npos ? std::string_view::npos : eol - pos);
        pos = eol == std::string_view::npos ? text.size() : eol + 1;
        ++lineNumber;
        if (std::size_t hash = line.find('#'); hash != std::string_view::npos) {
            line = line.substr(0, hash);
        }
        std::vector<std::string_view> words;
        std::size_t i = 0;
        while (i < line.size()) {
            while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) {
                ++i;
            }
            std::size_t start = i;
            while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) {
                ++i;
            }
            if (i > start) {
                words.push_back(line.substr(start, i - start));
            }
        }
        if (words.empty()) {
            continue;
        }
        if (words.size() != 6) {
            return makeError(name, ":", lineNumber, ": expected 6 numbers 'time x y z yaw pitch', found ", words.size(),
                             " fields");
        }
        double v[6];
        for (int f = 0; f < 6; ++f) {
            auto number = parseDouble(words[static_cast<std::size_t>(f)]);
            if (!number) {
                return makeError(name, ":", lineNumber, ": ", kFields[f], ": ", number.error().message);
            }
            v[f] = *number;
        }
        if (std::abs(v[5]) > 90.0) {
            return makeError(name, ":", lineNumber, ": pitch ", v[5], " is outside [-90, 90] degrees");
        }
        const CameraKeyframe key{v[0], {v[1], v[2], v[3]}, v[4] / kDegreesPerRadian, v[5] / kDegreesPerRadian};
        if (const std::string problem = keyframeProblem(key); !problem.empty()) {
            return makeError(name, ":", lineNumber, ": ", problem);
        }
        if (!keys.empty() && !(v[0] > keys.back().time)) {
            return makeError(name, ":", lineNumber, ": time ", v[0], " is not after the previous keyframe's time ",
                             keys.back().time, " (line ", previousLine, ")");
        }
        keys.push_back(key);
        previousLine = lineNumber;
    }
    if (keys.size() < 2) {
        return makeError(name, ": a camera path needs at least 2 keyframes, found ", keys.size());
    }
    return fromKeyframes(std::move(keys), name);
}

Expected<CameraPath> CameraPath::load(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        return makeError(path.string(), ": cannot open camera path file");
    }
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) {
        return makeError(path.string(), ": read error");
    }
    return parse(text.str(), path.string());
}

CameraPose CameraPath::evaluate(double time) const
{
    const std::size_t n = mKeys.size();
    if (!(time > mKeys.front().time)) {  // also catches NaN
        time = mKeys.front().time;
    }
    time = std::min(time, mKeys.back().time);
    // Segment i runs from key i to key i + 1.
    auto it = std::upper_bound(mKeys.begin(), mKeys.end(), time,
                               [](double t, const CameraKeyframe& k) { return t < k.time; });
    std::size_t i = static_cast<std::size_t>(it - mKeys.begin());
    i = std::clamp<std::size_t>(i, 1, n - 1) - 1;
    const CameraKeyframe& k1 = mKeys[i];
    const CameraKeyframe& k2 = mKeys[i + 1];
    double u = std::clamp((time - k1.time) / (k2.time - k1.time), 0.0, 1.0);

    CameraPose pose;
    // Position. Missing or coincident outer neighbours are replaced by reflections so that every knot
    // interval of the centripetal parameterization is positive.
    const glm::dvec3& p1 = k1.position;
    const glm::dvec3& p2 = k2.position;
    if (p1 == p2) {
        pose.position = p1;
    } else {
        glm::dvec3 p0 = i > 0 ? mKeys[i - 1].position : p1;
        glm::dvec3 p3 = i + 2 < n ? mKeys[i + 2].position : p2;
        if (p0 == p1) {
            p0 = 2.0 * p1 - p2;
        }
        if (p3 == p2) {
            p3 = 2.0 * p2 - p1;
        }
        pose.position = u == 0.0 ? p1 : u == 1.0 ? p2 : centripetalCatmullRom(p0, p1, p2, p3, u);
    }

    // Angles: uniform Catmull-Rom on the unwrapped yaw (shortest arcs between keyframes) and on pitch,
    // with reflected ghost values at the ends.
    double y1 = mUnwrappedYaw[i], y2 = mUnwrappedYaw[i + 1];
    double y0 = i > 0 ? mUnwrappedYaw[i - 1] : 2.0 * y1 - y2;
    double y3 = i + 2 < n ? mUnwrappedYaw[i + 2] : 2.0 * y2 - y1;
    double q1 = k1.pitch, q2 = k2.pitch;
    double q0 = i > 0 ? mKeys[i - 1].pitch : 2.0 * q1 - q2;
    double q3 = i + 2 < n ? mKeys[i + 2].pitch : 2.0 * q2 - q1;
    pose.yaw = wrapAngle(uniformCatmullRom(y0, y1, y2, y3, u));
    pose.pitch = std::clamp(uniformCatmullRom(q0, q1, q2, q3, u), -kPi / 2, kPi / 2);
    return pose;
}

CameraPose CameraPath::evaluateLooping(double time) const
{
    double d = duration();
    double t = std::fmod(time - startTime(), d);
    if (t < 0.0) {
        t += d;
    }
    return evaluate(startTime() + t);
}

std::string formatKeyframe(const CameraKeyframe& key)
{
    return formatNumber(key.time) + " " + formatNumber(key.position.x) + " " + formatNumber(key.position.y) + " " +
           formatNumber(key.position.z) + " " + formatNumber(key.yaw * kDegreesPerRadian) + " " +
           formatNumber(key.pitch * kDegreesPerRadian);
}

Status appendKeyframe(const std::filesystem::path& path, const CameraKeyframe& key)
{
    std::error_code ec;
    bool exists = std::filesystem::exists(path, ec);
    std::ofstream out(path, std::ios::binary | std::ios::app);
    if (!out) {
        return makeError(path.string(), ": cannot open camera path file for appending");
    }
    if (!exists) {
        out << "# camera path: time(s) x y z(m) yaw pitch(degrees)\n";
    }
    out << formatKeyframe(key) << '\n';
    out.flush();
    if (!out) {
        return makeError(path.string(), ": write error while appending a keyframe");
    }
    return {};
}

std::vector<TimeSpan> findPathBelowGround(const CameraPath& path,
                                          const std::function<std::optional<double>(double, double)>& groundAt,
                                          double step, double clearance)
{
    TERRAIN_EXPECTS(step > 0.0, "findPathBelowGround: step must be positive");
    std::vector<TimeSpan> spans;
    bool inside = false;
    const auto samples = static_cast<std::size_t>(std::ceil(path.duration() / step));
    for (std::size_t i = 0; i <= samples; ++i) {
        const double time = std::min(path.startTime() + static_cast<double>(i) * step, path.endTime());
        const CameraPose pose = path.evaluate(time);
        const std::optional<double> ground = groundAt(pose.position.x, pose.position.y);
        const bool below = ground && pose.position.z < *ground + clearance;
        if (below && !inside) {
            spans.push_back({time, time});
        } else if (below) {
            spans.back().end = time;
        }
        inside = below;
    }
    return spans;
}

std::string formatTimeSpans(const std::vector<TimeSpan>& spans, std::size_t most)
{
    std::ostringstream text;
    for (std::size_t i = 0; i < spans.size() && i < most; ++i) {
        text << (i ? ", " : "") << formatNumber(std::round(spans[i].begin * 100) / 100);
        if (spans[i].end > spans[i].begin) {
            text << "-" << formatNumber(std::round(spans[i].end * 100) / 100);
        }
        text << " s";
    }
    if (spans.size() > most) {
        text << " ... (" << spans.size() - most << " more)";
    }
    return text.str();
}

}  // namespace terrain
