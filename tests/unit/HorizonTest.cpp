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

// The search stops where even the grid's highest sample could not rise above the horizon found (HeightGrid::top):
// the same horizons as searching to the end, for points in valleys, on peaks and above the whole grid.
TEST(HorizonTest, StoppingAtTheGridsTopFindsTheSameHorizons)
{
    auto field = readHeightField(test::demoDataPath("trinidad_co_srtm3_crop_1025.png"));
    ASSERT_TRUE(field.ok()) << field.error().message;
    const HeightGrid full{field->width, field->height, 0.0, 0.0, 90.0, field->samples};
    HeightGrid topped = full;
    topped.setTop();
    ASSERT_LT(topped.top, 1e6);
    const HorizonOptions options{16, 20000.0, 0.2};
    int points = 0;
    for (int j = 0; j < full.height; j += 97) {
        for (int i = 0; i < full.width; i += 89) {
            const double x = i * 90.0 + 13.0, y = j * 90.0 + 29.0;
            for (double lift : {0.0, 40.0, 3000.0}) {
                const double z = full.at(x, y) + lift;
                ASSERT_EQ(horizonTangents(full, x, y, z, options), horizonTangents(topped, x, y, z, options))
                    << x << ", " << y << " lifted " << lift;
                ++points;
            }
        }
    }
    EXPECT_GT(points, 300);
}

TEST(HorizonTest, CodesKeepTheHorizonsAngleWithinHalfAStep)
{
    const double step = 0.75 * kPi / 255.0;
    for (double angle = -0.25 * kPi; angle < 0.4999 * kPi; angle += 0.0007) {
        const double back = std::atan(decodeHorizon(encodeHorizon(std::tan(angle))));
        ASSERT_NEAR(back, angle, 0.5 * step + 1e-9) << angle;
    }
    EXPECT_EQ(encodeHorizon(-5.0), 0) << "below -1: the lowest code";
    EXPECT_EQ(encodeHorizon(1e9), 255);
    EXPECT_EQ(encodeHorizon(std::nan("")), 0);
    EXPECT_TRUE(std::isfinite(decodeHorizon(255)));
}

/// A lattice of `size` points whose codes are a function of the point and azimuth.
HorizonLattice patternLattice(int size, int azimuths)
{
    HorizonLattice lattice{size, azimuths, {}};
    for (int j = 0; j < size; ++j) {
        for (int i = 0; i < size; ++i) {
            for (int k = 0; k < azimuths; ++k) {
                lattice.codes.push_back(static_cast<std::uint8_t>((i * 7 + j * 13 + k * 29) % 200 + 20));
            }
        }
    }
    return lattice;
}

TEST(HorizonTest, AQuadrantIsTheLatticesPointsOverTheChildsSquare)
{
    const HorizonLattice lattice = patternLattice(9, 4);
    for (int q = 0; q < 4; ++q) {
        const HorizonLattice quarter = latticeQuadrant(lattice, q);
        ASSERT_EQ(quarter.size, 5);
        ASSERT_EQ(quarter.azimuths, 4);
        for (int j = 0; j < 5; ++j) {
            for (int i = 0; i < 5; ++i) {
                for (int k = 0; k < 4; ++k) {
                    const int pi = i + (q & 1) * 4, pj = j + (q >> 1) * 4;
                    ASSERT_EQ(quarter.codes[static_cast<std::size_t>((j * 5 + i) * 4 + k)],
                              lattice.codes[static_cast<std::size_t>((pj * 9 + pi) * 4 + k)])
                        << q << " " << i << " " << j;
                }
            }
        }
    }
}

// The visibilities written for a node's samples: at the samples on lattice points, the visibility of that point's
// horizons; between them, between their values.
TEST(HorizonTest, LatticeVisibilityIsThePointsVisibilityBilinearlyBetweenThem)
{
    const int size = 5, azimuths = 8, n = 17;  // a lattice point every 4 samples
    const HorizonLattice lattice = patternLattice(size, azimuths);
    const double sunAzimuth = 0.7, sunElevation = 0.3, softness = 0.05;
    std::vector<std::uint8_t> out(static_cast<std::size_t>(n) * n * 4, 7);
    latticeVisibility(lattice, sunAzimuth, sunElevation, softness, n, out, 4, 2);
    auto point = [&](int i, int j) {
        std::vector<float> t(azimuths);
        for (int k = 0; k < azimuths; ++k) {
            t[static_cast<std::size_t>(k)] = static_cast<float>(
                decodeHorizon(lattice.codes[static_cast<std::size_t>((j * size + i) * azimuths + k)]));
        }
        return std::pair{sunVisibility(t, sunAzimuth, sunElevation, softness), skyVisibility(t)};
    };
    int shaded = 0;
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const std::size_t at = (static_cast<std::size_t>(j) * n + static_cast<std::size_t>(i)) * 4;
            ASSERT_EQ(out[at], 7) << "channels outside the offset are left alone";
            ASSERT_EQ(out[at + 1], 7);
            const int li = i / 4, lj = j / 4;
            if (i % 4 == 0 && j % 4 == 0) {
                const auto [sun, sky] = point(li, lj);
                ASSERT_NEAR(out[at + 2] / 255.0, sun, 0.5 / 255.0 + 1e-6) << i << " " << j;
                ASSERT_NEAR(out[at + 3] / 255.0, sky, 0.5 / 255.0 + 1e-6) << i << " " << j;
                shaded += sun < 0.5;
            } else {
                const int hi = std::min(li + 1, size - 1), hj = std::min(lj + 1, size - 1);
                const double lo =
                    std::min({point(li, lj).first, point(hi, lj).first, point(li, hj).first, point(hi, hj).first});
                const double up =
                    std::max({point(li, lj).first, point(hi, lj).first, point(li, hj).first, point(hi, hj).first});
                ASSERT_GE(out[at + 2] / 255.0, lo - 0.5 / 255.0 - 1e-6) << i << " " << j;
                ASSERT_LE(out[at + 2] / 255.0, up + 0.5 / 255.0 + 1e-6) << i << " " << j;
            }
        }
    }
    EXPECT_GT(shaded, 0) << "the pattern hides the sun somewhere";
    EXPECT_LT(shaded, size * size) << "and shows it somewhere";
}

}  // namespace
}  // namespace terrain
