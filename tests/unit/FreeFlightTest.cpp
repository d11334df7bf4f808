// The viewer's user controls driven with synthetic input and time, no window: key taps shorter than a frame,
// free flight into slopes, speed with height, the frame clock and the first view.
#include "apps/FreeFlight.h"

#include "core/SplitMix64.h"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/vec4.hpp>

#include <cmath>

namespace terrain {
namespace {

TEST(KeyInputTest, ATapShorterThanAFrameIsSeenAsAPressAndAsTheTimeItWasHeld)
{
    KeyInput input;
    input.press(Key::Forward, 1.000);
    input.release(Key::Forward, 1.020);
    const KeyInput::Frame frame = input.endFrame(1.5);  // a 500 ms frame
    EXPECT_NEAR(frame.held(Key::Forward), 0.020, 1e-12);
    ASSERT_EQ(frame.presses.size(), 1u);
    EXPECT_EQ(frame.presses[0], Key::Forward);
    EXPECT_FALSE(input.isDown(Key::Forward));
    const KeyInput::Frame next = input.endFrame(2.0);
    EXPECT_EQ(next.held(Key::Forward), 0.0);
    EXPECT_TRUE(next.presses.empty());
}

TEST(KeyInputTest, AKeyHeldAcrossFramesCountsInEachFrameItWasDownFor)
{
    KeyInput input;
    input.press(Key::Left, 0.9);
    input.press(Key::Left, 0.95);  // a repeat while held: no new hold
    EXPECT_NEAR(input.endFrame(1.0).held(Key::Left), 0.1, 1e-12);
    EXPECT_TRUE(input.isDown(Key::Left));
    EXPECT_NEAR(input.endFrame(1.5).held(Key::Left), 0.5, 1e-12);
    input.release(Key::Left, 1.7);
    input.press(Key::Left, 1.8);
    input.release(Key::Left, 1.85);
    const KeyInput::Frame last = input.endFrame(2.0);
    EXPECT_NEAR(last.held(Key::Left), 0.25, 1e-12);
    EXPECT_EQ(last.presses.size(), 1u);
    EXPECT_EQ(last.held(Key::Right), 0.0);
}

/// A camera over flat ground at z = 0.
Camera cameraAt(double x, double y, double z, double yawDegrees, double pitchDegrees)
{
    Camera camera;
    camera.position = {x, y, z};
    camera.yaw = yawDegrees * kRadiansPerDegree;
    camera.pitch = pitchDegrees * kRadiansPerDegree;
    return camera;
}

KeyInput::Frame holding(Key key, double seconds)
{
    KeyInput::Frame frame;
    frame.heldSeconds[static_cast<std::size_t>(key)] = seconds;
    return frame;
}

TEST(FreeFlightTest, ATapMovesTheCameraByTheTimeItWasHeldAtTheSpeedOfItsHeight)
{
    const GroundHeight flat = [](double, double) { return std::optional<double>(0.0); };
    for (double height : {5.0, 100.0, 10000.0, 400000.0}) {
        FreeFlight flight(FlightOptions{});
        Camera camera = cameraAt(0, 0, height, 0, 0);  // looking north, level
        flight.fly(camera, holding(Key::Forward, 0.02), flat, 0.0);
        const double expected = 0.02 * std::max(1.0, 0.5 * height);
        EXPECT_NEAR(camera.position.y, expected, 1e-9 * expected) << "at " << height << " m";
        EXPECT_NEAR(camera.position.x, 0.0, 1e-9 * expected);
        EXPECT_DOUBLE_EQ(camera.position.z, height);
    }
}

TEST(FreeFlightTest, SpeedScalesWithHeightAndTheSpeedKeys)
{
    FreeFlight flight(FlightOptions{});
    EXPECT_DOUBLE_EQ(flight.speedAt(1000.0), 500.0);
    EXPECT_DOUBLE_EQ(flight.speedAt(100000.0), 50000.0);
    EXPECT_DOUBLE_EQ(flight.speedAt(0.5), 1.0);  // the least speed near the ground
    EXPECT_DOUBLE_EQ(flight.speedAt(-20.0), 1.0);
    const GroundHeight flat = [](double, double) { return std::optional<double>(0.0); };
    Camera camera = cameraAt(0, 0, 1000, 0, 0);
    KeyInput::Frame faster;
    faster.presses = {Key::Faster, Key::Faster, Key::Slower};
    flight.fly(camera, faster, flat, 0.0);
    EXPECT_DOUBLE_EQ(flight.speedFactor(), 2.0);
    EXPECT_DOUBLE_EQ(flight.speedAt(1000.0), 1000.0);
    // Where nothing is drawn below, the fallback height sets the speed.
    const GroundHeight none = [](double, double) { return std::optional<double>(); };
    Camera off = cameraAt(0, 0, 1000, 90, 0);  // looking east
    flight.fly(off, holding(Key::Forward, 0.1), none, 300.0);
    EXPECT_NEAR(off.position.x, 0.1 * 2.0 * 150.0, 1e-9);
}

TEST(FreeFlightTest, UpAndDownMoveAlongTheWorldsVerticalAndAStalledFrameMovesAtMostAQuarterSecond)
{
    FreeFlight flight(FlightOptions{});
    const GroundHeight flat = [](double, double) { return std::optional<double>(0.0); };
    Camera camera = cameraAt(10, 20, 1000, 30, -89);  // looking nearly straight down
    flight.fly(camera, holding(Key::Up, 0.1), flat, 0.0);
    EXPECT_DOUBLE_EQ(camera.position.x, 10.0);
    EXPECT_DOUBLE_EQ(camera.position.y, 20.0);
    EXPECT_NEAR(camera.position.z, 1000.0 + 0.1 * 500.0, 1e-9);
    Camera stalled = cameraAt(0, 0, 1000, 0, 0);
    flight.fly(stalled, holding(Key::Forward, 3.0), flat, 0.0);  // a 3 s frame
    EXPECT_NEAR(stalled.position.y, 0.25 * 500.0, 1e-9);
}

TEST(FreeFlightTest, FlownIntoSlopesTheCameraKeepsItsClearanceAboveTheSurface)
{
    // Many slopes, headings and frame lengths: the camera held on `w` (and sometimes `z`) towards rising ground
    // never ends a frame below the surface plus the clearance, and does reach the slope.
    SplitMix64 random(7);
    auto uniform = [&](double lo, double hi) {
        return lo + (hi - lo) * static_cast<double>(random.next() >> 11) * 0x1.0p-53;
    };
    for (int trial = 0; trial < 200; ++trial) {
        const double gradient = uniform(0.2, 3.0);       // rise per metre
        const double heading = uniform(0.0, 6.2831853);  // the direction the ground rises
        const double bumps = uniform(0.0, 50.0);
        const glm::dvec2 up{std::sin(heading), std::cos(heading)};
        const GroundHeight ground = [&](double x, double y) {
            return std::optional<double>(gradient * glm::dot(glm::dvec2(x, y), up) +
                                         bumps * std::sin(x / 37.0) * std::cos(y / 53.0));
        };
        FlightOptions options;
        options.minClearance = uniform(0.0, 20.0);
        FreeFlight flight(options);
        Camera camera = cameraAt(0, 0, *ground(0, 0) + uniform(5, 3000), heading / kRadiansPerDegree, uniform(-60, -5));
        double closest = 1e300;
        for (int frame = 0; frame < 400; ++frame) {
            KeyInput::Frame keys = holding(Key::Forward, uniform(1.0 / 120.0, 0.5));
            if (frame % 7 == 0) {
                keys.heldSeconds[static_cast<std::size_t>(Key::Down)] = uniform(0.0, 0.3);
            }
            flight.fly(camera, keys, ground, 0.0);
            const double above = camera.position.z - *ground(camera.position.x, camera.position.y);
            ASSERT_GE(above, options.minClearance - 1e-9 * std::abs(camera.position.z))
                << "trial " << trial << ", frame " << frame;
            closest = std::min(closest, above);
        }
        EXPECT_LT(closest, options.minClearance + 1e-6) << "trial " << trial << ": never lifted off the slope";
    }
}

TEST(FreeFlightTest, MouseLookTurnsAndStopsShortOfStraightUpOrDown)
{
    FreeFlight flight(FlightOptions{});
    Camera camera = cameraAt(0, 0, 0, 0, 0);
    flight.look(camera, 400.0, -100.0);  // right and up
    EXPECT_NEAR(camera.yaw, 1.0, 1e-12);
    EXPECT_NEAR(camera.pitch, 0.25, 1e-12);
    flight.look(camera, 0.0, 1e6);
    EXPECT_NEAR(camera.pitch, -1.55, 1e-12);
}

TEST(FrameClockTest, VideoFramesAreAtTheFixedStepWhateverTheWallClock)
{
    FrameClock clock(Drive::Video, 3.0, 12.0);
    const double walls[] = {0.0, 5.0, 5.001, 40.0};
    for (std::size_t frame = 0; frame < 4; ++frame) {
        const FrameTime t = clock.next(frame, walls[frame]);
        EXPECT_DOUBLE_EQ(t.pathTime, 3.0 + static_cast<double>(frame) / 12.0);
        EXPECT_DOUBLE_EQ(t.clock, t.pathTime);
        EXPECT_DOUBLE_EQ(t.step, frame == 0 ? 0.0 : 1.0 / 12.0);
    }
}

TEST(FrameClockTest, DemoAndUserFramesFollowTheWallClockNeverBackwards)
{
    FrameClock demo(Drive::Demo, 2.0, 12.0);
    EXPECT_DOUBLE_EQ(demo.next(0, 0.01).pathTime, 2.01);
    const FrameTime second = demo.next(1, 0.51);
    EXPECT_DOUBLE_EQ(second.pathTime, 2.51);
    EXPECT_DOUBLE_EQ(second.step, 0.5);
    FrameClock user(Drive::User, 2.0, 12.0);
    EXPECT_DOUBLE_EQ(user.next(0, 1.0).step, 0.0);
    const FrameTime t = user.next(1, 1.25);
    EXPECT_DOUBLE_EQ(t.pathTime, 0.0);
    EXPECT_DOUBLE_EQ(t.clock, 1.25);
    EXPECT_DOUBLE_EQ(t.step, 0.25);
    EXPECT_DOUBLE_EQ(user.next(2, 1.2).step, 0.0);  // a wall clock that steps back gives no negative step
}

/// The largest |x| or |y| of `p` in normalized device coordinates, and whether it is in front of the near plane.
std::pair<double, bool> ndcExtent(const Camera& camera, const glm::dvec3& p)
{
    const glm::dvec4 clip = camera.viewProjection() * glm::dvec4(p, 1.0);
    return {std::max(std::abs(clip.x / clip.w), std::abs(clip.y / clip.w)), clip.w >= camera.nearPlane * 0.999};
}

TEST(FramingCameraTest, TheWholeBoxIsInViewAndTouchesItsEdge)
{
    SplitMix64 random(11);
    auto uniform = [&](double lo, double hi) {
        return lo + (hi - lo) * static_cast<double>(random.next() >> 11) * 0x1.0p-53;
    };
    for (int trial = 0; trial < 500; ++trial) {
        Camera lens;
        lens.verticalFov = uniform(10, 120) * kRadiansPerDegree;
        lens.viewportWidth = static_cast<int>(uniform(100, 4000));
        lens.viewportHeight = static_cast<int>(uniform(100, 4000));
        lens.yaw = uniform(-7, 7);
        lens.nearPlane = uniform(0.1, 1);
        lens.farPlane = 1e12;
        const glm::dvec3 min{uniform(-1e6, 1e6), uniform(-1e6, 1e6), uniform(-500, 3000)};
        const glm::dvec3 max = min + glm::dvec3(uniform(100, 2e5), uniform(100, 2e5), uniform(0, 9000));
        const Camera camera = framingCamera(lens, min, max, -uniform(5, 90) * kRadiansPerDegree);
        double widest = 0.0;
        for (int corner = 0; corner < 8; ++corner) {
            const glm::dvec3 p{(corner & 1) ? max.x : min.x, (corner & 2) ? max.y : min.y,
                               (corner & 4) ? max.z : min.z};
            const auto [extent, inFront] = ndcExtent(camera, p);
            ASSERT_TRUE(inFront) << "trial " << trial << ", corner " << corner;
            ASSERT_LE(extent, 1.0 + 1e-9) << "trial " << trial << ", corner " << corner;
            widest = std::max(widest, extent);
        }
        EXPECT_GT(widest, 1.0 - 1e-6) << "trial " << trial << ": not as near as it could be";
        EXPECT_EQ(camera.viewportWidth, lens.viewportWidth);
        EXPECT_DOUBLE_EQ(camera.yaw, lens.yaw);
    }
}

}  // namespace
}  // namespace terrain
