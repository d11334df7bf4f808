// The air's tables (light/AtmosphereTables.h): their coordinates against their inverses at every direction,
// and what a lookup costs in accuracy against the model summed over many samples, over viewers, suns,
// directions and distances none of the tables' cells sit on.
#include "light/AtmosphereTables.h"

#include "core/SplitMix64.h"

#include "TestSupport.h"

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace terrain {
namespace {

using test::direction;

constexpr double kPi = std::numbers::pi;

double uniform(SplitMix64& random)
{
    return static_cast<double>(random.next() >> 11) * 0x1.0p-53;
}

TEST(AtmosphereTablesTest, CoordinatesAreInTheUnitSquareAndInvertible)
{
    SplitMix64 random(7);
    for (int k = 0; k < 20000; ++k) {
        const glm::dvec3 sun = direction(360.0 * uniform(random), 180.0 * uniform(random) - 90.0);
        const glm::dvec3 view = direction(360.0 * uniform(random), 180.0 * uniform(random) - 90.0);
        const glm::dvec2 c = directionCoordinate(view, sun);
        ASSERT_TRUE(c.x >= 0.0 && c.x <= 1.0 && c.y >= 0.0 && c.y <= 1.0) << k;
        const glm::dvec3 back = directionAt(c, sun);
        EXPECT_NEAR(glm::length(back), 1.0, 1e-12);
        EXPECT_NEAR(back.z, view.z, 1e-9) << k;
        // The same angle to the sun: the same air.
        EXPECT_NEAR(glm::dot(back, sun), glm::dot(view, sun), 1e-9) << k;
        const glm::dvec2 again = directionCoordinate(back, sun);
        EXPECT_NEAR(again.x, c.x, 1e-9);
        EXPECT_NEAR(again.y, c.y, 1e-9);
    }
    // Vertical rays and suns, where the azimuth is undefined, and the ends of each range.
    const glm::dvec3 up(0.0, 0.0, 1.0), down(0.0, 0.0, -1.0), east(1.0, 0.0, 0.0), west(-1.0, 0.0, 0.0);
    EXPECT_EQ(directionCoordinate(up, up), glm::dvec2(0.0, 1.0));
    EXPECT_EQ(directionCoordinate(down, up), glm::dvec2(0.0, 0.0));
    EXPECT_EQ(directionCoordinate(east, down), glm::dvec2(0.0, 0.5));
    EXPECT_EQ(directionCoordinate(west, east), glm::dvec2(1.0, 0.5));
    EXPECT_EQ(distanceCoordinate(0.0, 1000.0), 0.0);
    EXPECT_EQ(distanceCoordinate(250.0, 1000.0), 0.5);
    EXPECT_EQ(distanceCoordinate(1e300, 1000.0), 1.0);
    EXPECT_EQ(distanceCoordinate(-5.0, 1000.0), 0.0);
    EXPECT_DOUBLE_EQ(distanceAt(distanceCoordinate(640.0, 1000.0), 1000.0), 640.0);
}

// The largest error of a lookup relative to the model with 4096 samples, as a fraction of the light the pixel
// receives: `inscattered` and the ground's own light seen through the air (a ground of reflectance 0.1 in the
// sun: the aerial perspective's error matters against what it is added to).
struct LookupErrors {
    double aerial = 0.0;
    double sky = 0.0;
};

LookupErrors measure(double altitude, double sunElevation, std::uint64_t seed)
{
    const AtmosphereModel air;
    const glm::dvec3 sun = direction(135.0, sunElevation);
    constexpr double kRange = 150000.0;
    const AtmosphereTables tables(air, altitude, sun, kRange);
    SplitMix64 random(seed);
    LookupErrors errors;
    for (int k = 0; k < 150; ++k) {
        // Downwards to the ground, or slightly up to a mountain; 100 m to the range.
        const double elevation = -89.0 + 95.0 * uniform(random);
        const double distance =
            std::min(100.0 * std::pow(kRange / 100.0, uniform(random)),
                     elevation < 0.0 ? (altitude + 400.0) / std::sin(-elevation * kPi / 180.0) : kRange);
        const glm::dvec3 view = direction(360.0 * uniform(random), elevation);
        const AerialPerspective reference = aerialPerspective(air, altitude, view * distance, sun, 4096);
        const glm::dvec3 ground = 0.1 / kPi *
                                  sunTransmittance(air, altitude + view.z * distance, sunElevation * kPi / 180.0) *
                                  std::max(sun.z, 0.05) * reference.transmittance;
        const glm::dvec3 looked = tables.inscattered(view, distance);
        for (int c = 0; c < 3; ++c) {
            errors.aerial = std::max(
                errors.aerial, std::abs(looked[c] - reference.inscattered[c]) / (reference.inscattered[c] + ground[c]));
        }
        const glm::dvec3 skyView = direction(360.0 * uniform(random), 90.0 * uniform(random));
        const glm::dvec3 sky = skyRadiance(air, altitude, skyView, sun, 4096);
        const glm::dvec3 skyLooked = tables.sky(skyView);
        for (int c = 0; c < 3; ++c) {
            errors.sky = std::max(errors.sky, std::abs(skyLooked[c] - sky[c]) / sky[c]);
        }
    }
    return errors;
}

TEST(AtmosphereTablesTest, LookupsAreTheModelWithinAFewPercent)
{
    LookupErrors worst;
    std::uint64_t seed = 1;
    for (double altitude : {30.0, 900.0, 4200.0, 12000.0}) {
        for (double sunElevation : {3.0, 12.0, 40.0, 80.0}) {
            const LookupErrors e = measure(altitude, sunElevation, ++seed);
            std::printf("altitude %6.0f m, sun %4.0f deg: aerial %.4f, sky %.4f\n", altitude, sunElevation, e.aerial,
                        e.sky);
            worst.aerial = std::max(worst.aerial, e.aerial);
            worst.sky = std::max(worst.sky, e.sky);
        }
    }
    EXPECT_LT(worst.aerial, 0.02);
    EXPECT_LT(worst.sky, 0.01);
}

/// The renderer's tables between fills: the linear interpolation of the tables at the two altitudes around the
/// viewer (tableAltitudes) against the tables at the viewer's own, over directions, distances, suns and altitudes
/// (the lowest just above the ground's haze, where the light changes with altitude fastest), and a thin haze whose
/// scale height makes the step small.
TEST(AtmosphereTablesTest, TablesInterpolatedBetweenAltitudeStepsAreTheViewersOwn)
{
    SplitMix64 random(11);
    double worst = 0.0;
    for (const double mieHeight : {1200.0, 300.0}) {
        AtmosphereModel air;
        air.mieHeight = mieHeight;
        for (const double altitude : {7.0, 1830.0, 4321.0}) {
            const TableAltitudes at = tableAltitudes(altitude, air);
            ASSERT_LE(at.lower, altitude);
            ASSERT_GE(at.upper, altitude);
            EXPECT_NEAR(at.upper - at.lower, kTableAltitudeShare * mieHeight, 1e-9);
            EXPECT_NEAR(at.lower + at.weight * (at.upper - at.lower), altitude, 1e-9);
            const glm::dvec3 sun = direction(25.0, 15.0 + altitude / 1000.0);
            const double range = 200000.0;
            const AtmosphereTables own(air, altitude, sun, range), lower(air, at.lower, sun, range),
                upper(air, at.upper, sun, range);
            auto relative = [](const glm::dvec3& mixed, const glm::dvec3& exact) {
                const glm::dvec3 d = glm::abs(mixed - exact);
                return std::max({d.x, d.y, d.z}) / std::max({exact.x, exact.y, exact.z, 1e-12});
            };
            for (int k = 0; k < 400; ++k) {
                const glm::dvec3 view = direction(360.0 * uniform(random), (uniform(random) - 0.3) * 90.0);
                const double distance = range * uniform(random) * uniform(random);
                const glm::dvec3 mixedAerial =
                    glm::mix(lower.inscattered(view, distance), upper.inscattered(view, distance), at.weight);
                const glm::dvec3 mixedSky = glm::mix(lower.sky(view), upper.sky(view), at.weight);
                worst = std::max(
                    {worst, relative(mixedAerial, own.inscattered(view, distance)), relative(mixedSky, own.sky(view))});
            }
        }
    }
    std::printf("largest relative difference of the interpolated tables: %.5f\n", worst);
    EXPECT_LT(worst, 0.002);
    const TableAltitudes nan = tableAltitudes(std::nan(""), AtmosphereModel{});
    EXPECT_EQ(nan.weight, 0.0);
    EXPECT_TRUE(std::isnan(nan.lower) && std::isnan(nan.upper));
    for (const double huge : {1e300, -1e300, std::numeric_limits<double>::infinity()}) {
        const TableAltitudes own = tableAltitudes(huge, AtmosphereModel{});
        EXPECT_EQ(own.lower, huge);
        EXPECT_EQ(own.upper, huge);
        EXPECT_EQ(own.weight, 0.0);
    }
    const TableAltitudes below = tableAltitudes(-250.0, AtmosphereModel{});
    EXPECT_LE(below.lower, -250.0);
    EXPECT_GT(below.upper, -250.0);
}

}  // namespace
}  // namespace terrain
