#include "core/Parse.h"
#include "lod/CameraPath.h"

#include "TestSupport.h"

#include <gtest/gtest.h>
#include <cmath>
#include <numbers>

namespace terrain {
namespace {

constexpr double kPi = std::numbers::pi;
double deg(double d)
{
    return d * kPi / 180.0;
}

/// Smallest angle between two directions, radians in [0, pi].
double angleBetween(double a, double b)
{
    return std::abs(std::remainder(a - b, 2.0 * kPi));
}

CameraPath parseOk(const std::string& text)
{
    auto path = CameraPath::parse(text, "test.path");
    EXPECT_TRUE(path.ok()) << path.error().message;
    return std::move(path).value();
}

struct BadPathCase {
    const char* name;
    const char* text;
    const char* expectedMessage;
};

class CameraPathParseErrors : public ::testing::TestWithParam<BadPathCase> {};

TEST_P(CameraPathParseErrors, NameFileAndLine)
{
    auto path = CameraPath::parse(GetParam().text, "demo.path");
    ASSERT_FALSE(path.ok());
    EXPECT_EQ(path.error().message, GetParam().expectedMessage);
}

INSTANTIATE_TEST_SUITE_P(
    CameraPath, CameraPathParseErrors,
    ::testing::Values(
        BadPathCase{"TooFewFields", "0 0 0 0 0 0\n\n1 2 3 4 5\n",
                    "demo.path:3: expected 6 numbers 'time x y z yaw pitch', found 5 fields"},
        BadPathCase{"TooManyFields", "0 0 0 0 0 0 7\n",
                    "demo.path:1: expected 6 numbers 'time x y z yaw pitch', found 7 fields"},
        BadPathCase{"NotANumber", "# header\n0 0 0 0 0 0\n1 0 0 0 north 0\n",
                    "demo.path:3: yaw: 'north' is not a number"},
        BadPathCase{"TrailingGarbage", "0 0 0 0 0 0\n1 0 0 10m 0 0\n", "demo.path:2: z: '10m' is not a number"},
        BadPathCase{"TimeNotIncreasing", "0 0 0 0 0 0\n# c\n2 0 0 0 0 0\n2 1 0 0 0 0\n",
                    "demo.path:4: time 2 is not after the previous keyframe's time 2 (line 3)"},
        BadPathCase{"TimeGoingBack", "0 0 0 0 0 0\n5 0 0 0 0 0\n4 1 0 0 0 0\n",
                    "demo.path:3: time 4 is not after the previous keyframe's time 5 (line 2)"},
        BadPathCase{"PitchOutOfRange", "0 0 0 0 0 0\n1 0 0 0 0 91\n",
                    "demo.path:2: pitch 91 is outside [-90, 90] degrees"},
        // Found by fuzzing: finite but huge values overflowed the spline to inf/NaN poses.
        BadPathCase{"CoordinateBeyondAMillionKilometres", "0 0 0 0 0 0\n1 5.9e105 0 0 0 0\n",
                    "demo.path:2: x 5.9e+105 m is outside [-1e9, 1e9]"},
        BadPathCase{"TimeBeyondThirtyYears", "0 0 0 0 0 0\n2e9 0 0 0 0 0\n",
                    "demo.path:2: time 2000000000 s is outside [-1e9, 1e9]"},
        BadPathCase{"InfiniteHeight", "0 0 0 0 0 0\n1 0 0 inf 0 0\n", "demo.path:2: z: 'inf' is not a number"},
        BadPathCase{"OneKeyframe", "# only one\n0 0 0 0 0 0 # here\n",
                    "demo.path: a camera path needs at least 2 keyframes, found 1"},
        BadPathCase{"Empty", "", "demo.path: a camera path needs at least 2 keyframes, found 0"},
        BadPathCase{"OnlyComments", "# nothing\n   \n\t# more\n",
                    "demo.path: a camera path needs at least 2 keyframes, found 0"}),
    [](const auto& testInfo) { return std::string(testInfo.param.name); });

TEST(CameraPathTest, MissingFileNamesTheFile)
{
    test::ScratchDir dir;
    auto path = CameraPath::load(dir / "missing.path");
    ASSERT_FALSE(path.ok());
    EXPECT_NE(path.error().message.find("missing.path"), std::string::npos) << path.error().message;
}

TEST(CameraPathTest, CommentsBlankLinesAndWhitespaceAreIgnored)
{
    CameraPath path = parseOk("# demo\n\n  0\t1 2 3  90 -10   # start\n\n10 4 5 6 180 20\r\n");
    ASSERT_EQ(path.keyframes().size(), 2u);
    EXPECT_EQ(path.keyframes()[1].time, 10.0);
    EXPECT_EQ(path.keyframes()[0].position, glm::dvec3(1, 2, 3));
    EXPECT_NEAR(path.keyframes()[0].yaw, deg(90), 1e-15);
    EXPECT_NEAR(path.keyframes()[0].pitch, deg(-10), 1e-15);
    EXPECT_NEAR(path.keyframes()[1].pitch, deg(20), 1e-15);
}

const char* kWindingPath =
    "0    0    0   10   0    0\n"
    "2  100    0   12  90   -5\n"
    "3  105   40   30 170   10\n"  // short segment next to long ones: centripetal must not loop
    "9  -50  300   15 -100  -30\n"
    "10 -60  310   15 -90    0\n";

TEST(CameraPathTest, PassesThroughEveryKeyframe)
{
    CameraPath path = parseOk(kWindingPath);
    for (const CameraKeyframe& k : path.keyframes()) {
        CameraPose pose = path.evaluate(k.time);
        EXPECT_NEAR(glm::length(pose.position - k.position), 0.0, 1e-9) << "t = " << k.time;
        EXPECT_NEAR(angleBetween(pose.yaw, k.yaw), 0.0, 1e-12) << "t = " << k.time;
        EXPECT_NEAR(pose.pitch, k.pitch, 1e-12) << "t = " << k.time;
    }
}

TEST(CameraPathTest, ClampsTimeToThePath)
{
    CameraPath path = parseOk(kWindingPath);
    EXPECT_EQ(path.evaluate(-5.0).position, path.keyframes().front().position);
    EXPECT_EQ(path.evaluate(100.0).position, path.keyframes().back().position);
    EXPECT_EQ(path.evaluate(std::nan("")).position, path.keyframes().front().position);
}

TEST(CameraPathTest, SmallTimeStepsGiveSmallChanges)
{
    CameraPath path = parseOk(kWindingPath);
    const double dt = 1e-4;
    // Fastest segment: ~230 m in 6 s along a curve; 1000 m/s and 20 rad/s are generous bounds that a
    // jump (discontinuity) of even a metre would break.
    CameraPose previous = path.evaluate(0.0);
    for (double t = dt; t <= path.endTime() + dt; t += dt) {
        CameraPose pose = path.evaluate(t);
        ASSERT_LT(glm::length(pose.position - previous.position), 1000.0 * dt) << "t = " << t;
        ASSERT_LT(angleBetween(pose.yaw, previous.yaw), 20.0 * dt) << "t = " << t;
        ASSERT_LT(std::abs(pose.pitch - previous.pitch), 20.0 * dt) << "t = " << t;
        previous = pose;
    }
}

TEST(CameraPathTest, CentripetalSegmentsStayNearTheirChord)
{
    // The short segment 2 -> 3 sits between long ones; uniform Catmull-Rom overshoots here, the
    // centripetal form stays within a fraction of the chord.
    CameraPath path = parseOk(kWindingPath);
    const auto& k = path.keyframes();
    glm::dvec3 a = k[1].position, b = k[2].position;
    double chord = glm::length(b - a);
    for (double t = k[1].time; t <= k[2].time; t += 0.01) {
        glm::dvec3 p = path.evaluate(t).position;
        EXPECT_LT(glm::length(p - a) + glm::length(p - b), 1.5 * chord) << "t = " << t;
    }
}

TEST(CameraPathTest, YawTakesTheShortestArcAcrossNorth)
{
    CameraPath path = parseOk("0 0 0 0 350 0\n1 10 0 0 10 0\n");
    EXPECT_NEAR(angleBetween(path.evaluate(0.5).yaw, 0.0), 0.0, 1e-12);
    for (double t = 0.0; t <= 1.0; t += 0.01) {
        double yaw = path.evaluate(t).yaw;
        EXPECT_LE(angleBetween(yaw, 0.0), deg(10) + 1e-12) << "t = " << t;  // never swings through south
        EXPECT_GT(yaw, -kPi);
        EXPECT_LE(yaw, kPi);
    }
}

TEST(CameraPathTest, YawTakesTheShortestArcAcrossSouth)
{
    CameraPath path = parseOk("0 0 0 0 -170 0\n1 1 0 0 170 0\n2 2 0 0 150 0\n");
    EXPECT_NEAR(angleBetween(path.evaluate(0.5).yaw, kPi), 0.0, deg(1));
    for (double t = 0.0; t <= 1.0; t += 0.01) {
        EXPECT_GE(angleBetween(path.evaluate(t).yaw, 0.0), deg(160)) << "t = " << t;
    }
}

TEST(CameraPathTest, RotatingInPlaceKeepsThePosition)
{
    CameraPath path = parseOk("0 5 5 5 0 0\n1 5 5 5 90 0\n2 6 5 5 90 0\n");
    EXPECT_EQ(path.evaluate(0.5).position, glm::dvec3(5, 5, 5));
    EXPECT_NEAR(path.evaluate(0.5).yaw, deg(45), deg(10));
    glm::dvec3 p = path.evaluate(1.5).position;
    EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
}

TEST(CameraPathTest, LoopingWrapsTime)
{
    CameraPath path = parseOk(kWindingPath);
    for (double t : {0.3, 2.5, 7.0, 9.9}) {
        for (int k : {-2, -1, 1, 3}) {
            CameraPose a = path.evaluate(t), b = path.evaluateLooping(t + k * path.duration());
            EXPECT_NEAR(glm::length(a.position - b.position), 0.0, 1e-6) << t << " " << k;
        }
    }
}

TEST(CameraPathTest, AppendedKeyframesReadBackExactly)
{
    test::ScratchDir dir;
    std::vector<CameraKeyframe> keys = {{0.0, {1000.125, -2.5, 33.3}, deg(12.345), deg(-7.5)},
                                        {0.1, {1001.0, -2.0, 33.0}, deg(359.9), deg(0.0)},
                                        {1.0 / 3.0, {1e6 + 0.1, 2e6, -400.0}, deg(-90.0), deg(89.0)}};
    for (const CameraKeyframe& k : keys) {
        ASSERT_TRUE(appendKeyframe(dir / "rec.path", k).ok());
    }
    auto path = CameraPath::load(dir / "rec.path");
    ASSERT_TRUE(path.ok()) << path.error().message;
    ASSERT_EQ(path->keyframes().size(), keys.size());
    for (std::size_t i = 0; i < keys.size(); ++i) {
        EXPECT_EQ(path->keyframes()[i].time, keys[i].time);
        EXPECT_EQ(path->keyframes()[i].position, keys[i].position);
        EXPECT_NEAR(path->keyframes()[i].yaw, keys[i].yaw, 1e-14);
        EXPECT_NEAR(path->keyframes()[i].pitch, keys[i].pitch, 1e-14);
    }
}

TEST(CameraPathTest, FromKeyframesChecksTheRules)
{
    auto one = CameraPath::fromKeyframes({{0.0, {}, 0.0, 0.0}}, "mem");
    ASSERT_FALSE(one.ok());
    EXPECT_EQ(one.error().message, "mem: a camera path needs at least 2 keyframes, found 1");
    auto back = CameraPath::fromKeyframes({{1.0, {}, 0.0, 0.0}, {0.5, {}, 0.0, 0.0}}, "mem");
    ASSERT_FALSE(back.ok());
    EXPECT_EQ(back.error().message, "mem: keyframe 1: time 0.5 is not after the previous keyframe's time 1");
    auto far = CameraPath::fromKeyframes({{0.0, {}, 0.0, 0.0}, {1.0, {0.0, -2e9, 0.0}, 0.0, 0.0}}, "mem");
    ASSERT_FALSE(far.ok());
    EXPECT_EQ(far.error().message, "mem: keyframe 1: y -2000000000 m is outside [-1e9, 1e9]");
    // The largest allowed values still give finite poses everywhere.
    auto edge = CameraPath::fromKeyframes(
        {{-1e9, {-1e9, -1e9, -1e9}, 0.0, 0.0}, {0.0, {1e9, 1e9, 1e9}, 3.0, 1.5}, {1e9, {-1e9, 1e9, -1e9}, -3.0, -1.5}},
        "mem");
    ASSERT_TRUE(edge.ok()) << edge.error().message;
    for (double t = -1e9; t <= 1e9; t += 1.25e8) {
        const CameraPose pose = edge->evaluate(t);
        EXPECT_TRUE(std::isfinite(pose.position.x + pose.position.y + pose.position.z + pose.yaw + pose.pitch)) << t;
    }
}

}  // namespace
}  // namespace terrain

namespace terrain {
namespace {

TEST(CameraPathTest, FindsWhereThePathPassesBelowTheGround)
{
    // A straight flight east at 100 m over a hill of height 150 m - |x - 500| / 2 (above 100 m for
    // x in (400, 600)): at 10 m/s it is below from t = 40 s to 60 s. Brute force over the same samples.
    auto path = CameraPath::parse("0 0 0 100 90 0\n100 1000 0 100 90 0\n", "hill.path");
    ASSERT_TRUE(path.ok()) << path.error().message;
    auto ground = [](double x, double) -> std::optional<double> {
        if (x > 900) {
            return std::nullopt;  // outside the terrain
        }
        return 150.0 - std::abs(x - 500.0) / 2.0;
    };
    const auto spans = findPathBelowGround(*path, ground, 0.5);
    ASSERT_EQ(spans.size(), 1u);
    double first = -1, last = -1;
    for (int i = 0; i <= 200; ++i) {
        const CameraPose pose = path->evaluate(i * 0.5);
        const auto g = ground(pose.position.x, pose.position.y);
        if (g && pose.position.z < *g) {
            first = first < 0 ? i * 0.5 : first;
            last = i * 0.5;
        }
    }
    EXPECT_DOUBLE_EQ(spans[0].begin, first);
    EXPECT_DOUBLE_EQ(spans[0].end, last);
    EXPECT_NEAR(spans[0].begin, 40.0, 1.0);
    EXPECT_NEAR(spans[0].end, 60.0, 1.0);
    EXPECT_EQ(formatTimeSpans(spans), formatNumber(first) + "-" + formatNumber(last) + " s");

    // A clearance lifts the ground: the span grows; a path above it all has none.
    EXPECT_GT(
        findPathBelowGround(*path, ground, 0.5, 20.0)[0].end - findPathBelowGround(*path, ground, 0.5, 20.0)[0].begin,
        spans[0].end - spans[0].begin);
    auto high = CameraPath::parse("0 0 0 500 90 0\n100 1000 0 500 90 0\n", "high.path");
    ASSERT_TRUE(high.ok());
    EXPECT_TRUE(findPathBelowGround(*high, ground, 0.5).empty());
}

TEST(CameraPathTest, TimeSpansFormatShortly)
{
    EXPECT_EQ(formatTimeSpans({}), "");
    EXPECT_EQ(formatTimeSpans({{1.0, 1.0}, {2.5, 3.25}}), "1 s, 2.5-3.25 s");
    EXPECT_EQ(formatTimeSpans({{1, 2}, {3, 4}, {5, 6}}, 2), "1-2 s, 3-4 s ... (1 more)");
}

}  // namespace
}  // namespace terrain
