#include "apps/FreeFlight.h"

#include "core/Check.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace terrain {

void KeyInput::press(Key key, double time)
{
    auto& since = mDownSince[static_cast<std::size_t>(key)];
    if (!since) {  // a repeat of a key held is no new press
        since = time;
    }
    mPresses.push_back(key);
}

void KeyInput::release(Key key, double time)
{
    const auto k = static_cast<std::size_t>(key);
    if (mDownSince[k]) {
        mHeld[k] += std::max(0.0, time - *mDownSince[k]);
        mDownSince[k].reset();
    }
}

KeyInput::Frame KeyInput::endFrame(double time)
{
    Frame frame;
    for (std::size_t k = 0; k < kKeyCount; ++k) {
        if (mDownSince[k]) {
            mHeld[k] += std::max(0.0, time - *mDownSince[k]);
            mDownSince[k] = std::max(*mDownSince[k], time);
        }
        frame.heldSeconds[k] = mHeld[k];
        mHeld[k] = 0.0;
    }
    frame.presses = std::move(mPresses);
    mPresses.clear();
    return frame;
}

void FreeFlight::look(Camera& camera, double dxPixels, double dyPixels) const
{
    constexpr double kMostPitch = 1.55;  // radians: just short of straight up or down, where yaw is undefined
    camera.yaw += dxPixels * mOptions.radiansPerPixel;
    camera.pitch = std::clamp(camera.pitch - dyPixels * mOptions.radiansPerPixel, -kMostPitch, kMostPitch);
}

double FreeFlight::speedAt(double heightAboveGround) const
{
    return mFactor * std::max(mOptions.minSpeed, mOptions.heightsPerSecond * std::max(0.0, heightAboveGround));
}

void FreeFlight::fly(Camera& camera, const KeyInput::Frame& keys, const GroundHeight& ground, double fallbackHeight)
{
    for (Key key : keys.presses) {
        if (key == Key::Faster) {
            mFactor = std::min(mFactor * 2.0, 1024.0);
        } else if (key == Key::Slower) {
            mFactor = std::max(mFactor / 2.0, 1.0 / 1024.0);
        }
    }
    const auto below = ground(camera.position.x, camera.position.y);
    const double speed = speedAt(below ? camera.position.z - *below : fallbackHeight);
    auto held = [&](Key key) { return std::min(keys.held(key), mOptions.maxFrameSeconds); };
    // Horizontal keys move along the view, q and z along the world's up.
    const glm::dvec3 move = camera.forward() * (held(Key::Forward) - held(Key::Back)) +
                            camera.right() * (held(Key::Right) - held(Key::Left)) +
                            glm::dvec3(0.0, 0.0, 1.0) * (held(Key::Up) - held(Key::Down));
    camera.position += move * speed;
    if (const auto floor = ground(camera.position.x, camera.position.y)) {
        camera.position.z = std::max(camera.position.z, *floor + mOptions.minClearance);
    }
}

FrameClock::FrameClock(Drive drive, double pathStart, double framesPerSecond)
    : mDrive(drive), mPathStart(pathStart), mFramesPerSecond(framesPerSecond)
{
    TERRAIN_EXPECTS(framesPerSecond > 0.0, "frames per second must be > 0");
}

FrameTime FrameClock::next(std::size_t frame, double wallSeconds)
{
    FrameTime t;
    const double step = frame == 0 ? 0.0 : std::max(0.0, wallSeconds - mPreviousWall);
    mPreviousWall = std::max(mPreviousWall, wallSeconds);
    switch (mDrive) {
        case Drive::Video:
            t.pathTime = mPathStart + static_cast<double>(frame) / mFramesPerSecond;
            t.clock = t.pathTime;
            t.step = frame == 0 ? 0.0 : 1.0 / mFramesPerSecond;
            break;
        case Drive::Demo:
            t.pathTime = mPathStart + wallSeconds;
            t.clock = t.pathTime;
            t.step = step;
            break;
        case Drive::User:
            t.clock = wallSeconds;
            t.step = step;
            break;
    }
    return t;
}

Camera framingCamera(const Camera& lens, const glm::dvec3& min, const glm::dvec3& max, double pitchRadians)
{
    TERRAIN_EXPECTS(pitchRadians < 0.0, "the framing camera looks down");
    Camera camera = lens;
    camera.pitch = pitchRadians;
    const glm::dvec3 centre = (min + max) * 0.5;
    const glm::dvec3 forward = camera.forward(), right = camera.right(), up = camera.up();
    const double ty = std::tan(camera.verticalFov / 2.0);
    const double tx = ty * camera.aspect();
    // A corner at offset o from the centre lies in the view from centre - d forward when |o.right| <= tx depth and
    // |o.up| <= ty depth, where depth = d + o.forward; and in front of the near plane.
    double d = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 p{(corner & 1) ? max.x : min.x, (corner & 2) ? max.y : min.y, (corner & 4) ? max.z : min.z};
        const glm::dvec3 o = p - centre;
        const double along = glm::dot(o, forward);
        d = std::max({d, std::abs(glm::dot(o, right)) / tx - along, std::abs(glm::dot(o, up)) / ty - along,
                      camera.nearPlane - along});
    }
    camera.position = centre - forward * d;
    return camera;
}

}  // namespace terrain
