// Horizons of a height grid and the visibility they give (light/Horizon.h): exact on surfaces whose horizons are
// known, and the sun's visibility against rays marched towards the sun in fine steps over the bundled terrain.
#include "light/Horizon.h"

#include "TestSupport.h"
#include "heightfield/HeightFieldIo.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

namespace terrain {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDegree = kPi / 180.0;

HeightGrid flatGrid(int size, double spacing, float height)
{
    return {size, size, 0.0, 0.0, spacing, std::vector<float>(static_cast<std::size_t>(size) * size, height)};
}

TEST(HorizonTest, FlatGroundSeesTheWholeSkyAndTheSunAboveTheHorizon)
{
    const HeightGrid grid = flatGrid(65, 30.0, 120.0f);
    const std::vector<float> t = horizonTangents(grid, 960.0, 960.0, 120.0, {});
    ASSERT_EQ(t.size(), 8u);
    for (float v : t) {
        EXPECT_FLOAT_EQ(v, 0.0f);
    }
    EXPECT_DOUBLE_EQ(skyVisibility(t), 1.0);
    EXPECT_DOUBLE_EQ(sunVisibility(t, 1.0, 5.0 * kDegree, 1.0 * kDegree), 1.0);
    EXPECT_DOUBLE_EQ(sunVisibility(t, 1.0, -5.0 * kDegree, 1.0 * kDegree), 0.0);
    EXPECT_DOUBLE_EQ(sunVisibility(t, 1.0, 0.0, 1.0 * kDegree), 0.5);
}

TEST(HorizonTest, AWallRisesToItsAngleOnItsSideOnly)
{
    // A 200 m wall east of x = 1500 m: bilinear between samples, its top edge is at 1520 m.
    HeightGrid grid = flatGrid(129, 20.0, 0.0f);
    for (int j = 0; j < grid.height; ++j) {
        for (int i = 0; i < grid.width; ++i) {
            grid.heights[static_cast<std::size_t>(j) * grid.width + i] = i * grid.spacing > 1500.0 ? 200.0f : 0.0f;
        }
    }
    const HorizonOptions options{16, 5000.0, 0.05};
    for (double d : {100.0, 300.0, 800.0}) {
        const std::vector<float> t = horizonTangents(grid, 1500.0 - d, 1280.0, 0.0, options);
        // East: 200 / (distance to the wall's top edge), sampled at steps of at most 5 % of the distance.
        const double top = d + grid.spacing;
        EXPECT_LE(t[0], 200.0 / top + 1e-6) << d;
        EXPECT_GE(t[0], 200.0 / (top * 1.05 + grid.spacing)) << d;
        EXPECT_FLOAT_EQ(t[8], 0.0f) << "west: open";
        // The sun low in the east is hidden, high in the east or in the west it is not.
        const double wall = std::atan(200.0 / top);
        EXPECT_DOUBLE_EQ(sunVisibility(t, 0.0, wall - 3.0 * kDegree, 1.0 * kDegree), 0.0) << d;
        EXPECT_DOUBLE_EQ(sunVisibility(t, 0.0, wall + 6.0 * kDegree, 1.0 * kDegree), 1.0) << d;
        EXPECT_DOUBLE_EQ(sunVisibility(t, kPi, 2.0 * kDegree, 1.0 * kDegree), 1.0) << d;
        // The sky: the directions that see the wall lose cos^2 of its angle.
        EXPECT_LT(skyVisibility(t), 1.0);
        EXPECT_GT(skyVisibility(t), 0.5);
    }
}

// Sun visibility from 16 horizons against the truth, a ray marched towards the sun in quarter-spacing steps,
// over the bundled terrain (90 m SRTM of the Sangre de Cristo range) under low suns: intersection over union of
// the shadowed points.
TEST(HorizonTest, SunVisibilityMatchesRaysMarchedTowardsTheSunOverRealTerrain)
{
    auto field = readHeightField(test::demoDataPath("trinidad_co_srtm3_crop_1025.png"));
    ASSERT_TRUE(field.ok()) << field.error().message;
    const HeightGrid grid{field->width, field->height, 0.0, 0.0, 90.0, field->samples};
    const HorizonOptions options{16, 20000.0, 0.05};
    for (double elevationDegrees : {6.0, 15.0}) {
        for (double azimuthDegrees : {20.0, 135.0, 250.0}) {
            const double azimuth = azimuthDegrees * kDegree, elevation = elevationDegrees * kDegree;
            const double dx = std::cos(azimuth), dy = std::sin(azimuth), rise = std::tan(elevation);
            int both = 0, either = 0, points = 0;
            for (int j = 100; j < grid.height - 100; j += 16) {
                for (int i = 100; i < grid.width - 100; i += 16) {
                    const double x = i * 90.0 + 37.0, y = j * 90.0 + 61.0;
                    const double z = grid.at(x, y);
                    bool shadowed = false;
                    for (double r = 22.5; r <= options.maxDistance && !shadowed; r += 22.5) {
                        shadowed = grid.at(x + r * dx, y + r * dy) > z + r * rise;
                    }
                    const std::vector<float> t = horizonTangents(grid, x, y, z, options);
                    const bool dark = sunVisibility(t, azimuth, elevation, 0.5 * kDegree) < 0.5;
                    both += shadowed && dark;
                    either += shadowed || dark;
                    ++points;
                }
            }
            const double iou = either > 0 ? static_cast<double>(both) / either : 1.0;
            std::printf("sun %3.0f deg at azimuth %3.0f: %d of %d points shadowed by rays, IoU %.3f\n",
                        elevationDegrees, azimuthDegrees, either, points, iou);
            EXPECT_GE(iou, 0.9);
        }
    }
}

}  // namespace
}  // namespace terrain
