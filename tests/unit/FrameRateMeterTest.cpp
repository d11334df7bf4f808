// The overlay's frame rate (apps/FrameRateMeter.h) against the frame times it was given: it never shows
// more frames per second than were drawn, whatever the first interval.
#include "apps/FrameRateMeter.h"

#include <gtest/gtest.h>

#include <vector>

namespace terrain {
namespace {

TEST(FrameRateMeterTest, EmptyUntilTwoFramesEnded)
{
    FrameRateMeter meter;
    EXPECT_FALSE(meter.framesPerSecond());
    meter.frameEnded(0.5);
    EXPECT_FALSE(meter.framesPerSecond()) << "one frame end measures no interval";
    meter.frameEnded(0.75);
    ASSERT_TRUE(meter.framesPerSecond());
    EXPECT_DOUBLE_EQ(*meter.framesPerSecond(), 4.0);
}

TEST(FrameRateMeterTest, MatchesTheMeasuredFrameTimes)
{
    // A near-zero first interval (the start-up case that showed "6366.2 fps") followed by 250 ms frames:
    // within a second the rate is the measured 4 fps, and it is never above the frames actually drawn.
    const std::vector<double> frameSeconds = {1e-6, 0.25, 0.25, 0.25, 0.25, 0.25, 0.25, 0.25, 0.25, 0.25};
    FrameRateMeter meter;
    double t = 10.0;
    meter.frameEnded(t);
    int drawn = 1;
    for (double dt : frameSeconds) {
        t += dt;
        meter.frameEnded(t);
        ++drawn;
        ASSERT_TRUE(meter.framesPerSecond());
        // Never more than the frames that ended over the span measured.
        EXPECT_LE(*meter.framesPerSecond(), (drawn - 1) / (t - 10.0) + 1e-9);
    }
    EXPECT_NEAR(*meter.framesPerSecond(), 4.0, 1e-9);
    EXPECT_NEAR(*meter.meanFrameSeconds(), 0.25, 1e-12);
}

TEST(FrameRateMeterTest, FollowsAChangeWithinTheWindow)
{
    FrameRateMeter meter;
    double t = 0.0;
    for (int i = 0; i < 100; ++i) {  // 100 fps for a second
        meter.frameEnded(t += 0.01);
    }
    EXPECT_NEAR(*meter.framesPerSecond(), 100.0, 1e-6);
    for (int i = 0; i < 20; ++i) {  // then 10 fps for two seconds
        meter.frameEnded(t += 0.1);
    }
    EXPECT_NEAR(*meter.framesPerSecond(), 10.0, 1e-6);
    meter.frameEnded(t += 3.0);  // a frame slower than the window still measures
    EXPECT_NEAR(*meter.framesPerSecond(), 1.0 / 3.0, 1e-9) << "one frame in the last 3 s";
}

}  // namespace
}  // namespace terrain
