// The viewer's user controls as plain code (paper 4.4.2): keys as timed events, mouse look, free flight kept above
// the drawn surface, the frame clock of the three ways to drive the camera, and the first view of a map. The
// window system only translates its events into these (tengine); unit tests drive them with synthetic input and
// time.
#pragma once

#include "core/Camera.h"

#include <array>
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

namespace terrain {

/// The keys the viewer acts on, whatever the window system calls them.
enum class Key {
    Forward,         ///< w
    Back,            ///< s
    Left,            ///< a
    Right,           ///< d
    Up,              ///< q: up in the world
    Down,            ///< z
    Faster,          ///< 1: doubles the flight speed
    Slower,          ///< 2: halves it
    Wireframe,       ///< l
    RecordKeyframe,  ///< k: appends the camera's pose to the recorded camera path
    Quit,            ///< escape
};
inline constexpr std::size_t kKeyCount = static_cast<std::size_t>(Key::Quit) + 1;

/// Key events between two frames, each with its time in seconds (any clock, never decreasing). A tap shorter than
/// a frame is seen twice over: as a press (presses()) and as the time it was held (heldSeconds()).
class KeyInput {
public:
    void press(Key key, double time);
    void release(Key key, double time);

    /// Ends the frame at `time`: the seconds each key was held since the previous endFrame (or the first event),
    /// then the presses in order; keys still down stay held into the next frame.
    struct Frame {
        std::array<double, kKeyCount> heldSeconds{};
        std::vector<Key> presses;
        double held(Key key) const { return heldSeconds[static_cast<std::size_t>(key)]; }
    };
    Frame endFrame(double time);

    bool isDown(Key key) const { return mDownSince[static_cast<std::size_t>(key)].has_value(); }

private:
    std::array<std::optional<double>, kKeyCount> mDownSince{};
    std::array<double, kKeyCount> mHeld{};
    std::vector<Key> mPresses;
};

struct FlightOptions {
    /// camera_min_clearance: the least height above the drawn surface, metres (>= 0).
    double minClearance = 2.0;
    /// Speed in heights above the ground per second: the ground crosses the view at the same rate at any height.
    double heightsPerSecond = 0.5;
    /// The least speed, metres per second (near the ground).
    double minSpeed = 1.0;
    /// Mouse look, radians per pixel.
    double radiansPerPixel = 0.0025;
    /// The most seconds of movement one frame makes of a key held: a stalled frame does not throw the camera far.
    double maxFrameSeconds = 0.25;
};

/// The height of the drawn surface at (x, y), metres; empty where nothing is drawn.
using GroundHeight = std::function<std::optional<double>(double x, double y)>;

/// Mouse look and w/s/a/d/q/z movement at a speed that scales with the height above the ground, kept
/// FlightOptions::minClearance above the drawn surface.
class FreeFlight {
public:
    explicit FreeFlight(const FlightOptions& options) : mOptions(options) {}

    /// Turns the camera by the mouse's movement in pixels since the last frame (x right, y down).
    void look(Camera& camera, double dxPixels, double dyPixels) const;
    /// Moves the camera for one frame by the keys held (KeyInput::Frame::heldSeconds, at most maxFrameSeconds each) at
    /// the speed of its height above `ground`, applies Faster / Slower presses, then lifts it to the clearance above
    /// `ground` where it is below. Where `ground` has nothing, the speed is that at `fallbackHeight` metres up.
    void fly(Camera& camera, const KeyInput::Frame& keys, const GroundHeight& ground, double fallbackHeight);
    /// Metres per second at `heightAboveGround` metres up.
    double speedAt(double heightAboveGround) const;
    /// The factor Faster and Slower double and halve (1 at first).
    double speedFactor() const { return mFactor; }

private:
    FlightOptions mOptions;
    double mFactor = 1.0;
};

/// How the camera is driven: by the user, along camera_path in real time (demo mode, looping), or along it at a
/// fixed time step (video mode).
enum class Drive { User, Demo, Video };

/// One frame's times.
struct FrameTime {
    double pathTime = 0.0;  ///< seconds on the camera path (demo, video); 0 with Drive::User
    double clock = 0.0;     ///< seconds on the viewer's clock, never decreasing (video: the frame's time)
    double step = 0.0;      ///< seconds since the previous frame (video: 1 / fps), 0 on the first
};

/// The clock of the viewer's frames from the wall time passed in.
class FrameClock {
public:
    /// `pathStart` and `framesPerSecond` (> 0) matter for Drive::Demo and Drive::Video.
    FrameClock(Drive drive, double pathStart, double framesPerSecond);
    /// Frame `frame` (0, 1, ...) begun `wallSeconds` after the first (never decreasing).
    FrameTime next(std::size_t frame, double wallSeconds);

private:
    Drive mDrive;
    double mPathStart;
    double mFramesPerSecond;
    double mPreviousWall = 0.0;
};

/// The first view of a terrain without a camera: from the south, looking down at `pitchRadians` (< 0) towards the
/// centre of the box [min, max], as near as keeps the whole box in the view. The lens (field of view, viewport,
/// planes) is `lens`'s.
Camera framingCamera(const Camera& lens, const glm::dvec3& min, const glm::dvec3& max, double pitchRadians);

}  // namespace terrain
