// The atmosphere model (light/Atmosphere.h) against numerical integration: the closed-form density integral and
// transmittance, the phase functions' normalisation, and the tables' sample counts against many samples; the
// colours that single scattering must give (blue zenith, reddened low sun, whiter and brighter haze with
// distance).
#include "light/Atmosphere.h"

#include "TestSupport.h"

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include <cmath>
#include <limits>
#include <numbers>

namespace terrain {
namespace {

using test::direction;

constexpr double kPi = std::numbers::pi;

TEST(AtmosphereTest, TheDensityIntegralIsTheIntegralOfTheExponentialAlongTheSegment)
{
    struct Case {
        double altitude, rise, length, height;
    };
    for (const Case& c : {Case{0.0, 0.0, 50000.0, 8000.0}, Case{2500.0, 3000.0, 20000.0, 8000.0},
                          Case{4000.0, -3500.0, 9000.0, 1200.0}, Case{100.0, 1e-3, 150000.0, 1200.0},
                          Case{-400.0, 60000.0, 60000.0, 8000.0}, Case{3000.0, -1e-7, 1000.0, 8000.0}}) {
        constexpr int kSteps = 200000;  // midpoint sum
        double sum = 0.0;
        for (int k = 0; k < kSteps; ++k) {
            const double t = (k + 0.5) * c.length / kSteps;
            sum += std::exp(-(c.altitude + c.rise * t / c.length) / c.height);
        }
        sum *= c.length / kSteps;
        EXPECT_NEAR(densityIntegral(c.altitude, c.rise, c.length, c.height), sum, 1e-8 * sum)
            << c.altitude << " " << c.rise << " " << c.length;
    }
    EXPECT_EQ(densityIntegral(1000.0, 0.0, 0.0, 8000.0), 0.0);
}

TEST(AtmosphereTest, ThePhaseFunctionsIntegrateToOneOverTheSphere)
{
    constexpr int kSteps = 100000;
    double rayleigh = 0.0, mie = 0.0;
    for (int k = 0; k < kSteps; ++k) {
        const double mu = -1.0 + (k + 0.5) * 2.0 / kSteps;
        rayleigh += rayleighPhase(mu);
        mie += miePhase(mu, 0.8);
    }
    // d(omega) = 2 pi d(mu).
    EXPECT_NEAR(rayleigh * 2.0 * kPi * 2.0 / kSteps, 1.0, 1e-6);
    EXPECT_NEAR(mie * 2.0 * kPi * 2.0 / kSteps, 1.0, 1e-4);
    EXPECT_GT(miePhase(1.0, 0.8), 100.0 * miePhase(-1.0, 0.8)) << "aerosols scatter forwards";
}

TEST(AtmosphereTest, TheAirMassIsOneAtTheZenithAndAboutThirtyEightAtTheHorizon)
{
    EXPECT_NEAR(airMass(kPi / 2.0), 1.0, 1e-3);
    EXPECT_NEAR(airMass(0.0), 37.92, 0.05);  // Kasten & Young's 1989 table
    EXPECT_NEAR(airMass(30.0 * kPi / 180.0), 1.995, 0.01);
    EXPECT_EQ(airMass(-0.2), airMass(0.0)) << "below the horizon it holds the horizon's";
    double previous = 0.0;
    for (double e = 90.0; e >= 0.0; e -= 0.5) {
        const double m = airMass(e * kPi / 180.0);
        EXPECT_GT(m, previous) << e;
        previous = m;
    }
}

TEST(AtmosphereTest, TheTablesSampleCountsAgreeWithManySamples)
{
    const AtmosphereModel air;
    for (double sunElevation : {3.0, 15.0, 35.0, 70.0}) {
        const glm::dvec3 sun = direction(135.0, sunElevation);
        for (double distance : {1000.0, 5000.0, 20000.0, 60000.0, 150000.0}) {
            for (double pitch : {-30.0, -5.0, -0.5, 2.0}) {
                for (double azimuth : {0.0, 135.0, 300.0}) {
                    const glm::dvec3 relative = direction(azimuth, pitch) * distance;
                    if (2500.0 + relative.z < -500.0) {
                        continue;  // through the ground: the terrain ends the ray before
                    }
                    const AerialPerspective few = aerialPerspective(air, 2500.0, relative, sun);
                    const AerialPerspective many = aerialPerspective(air, 2500.0, relative, sun, 4096);
                    for (int c = 0; c < 3; ++c) {
                        EXPECT_EQ(few.transmittance[c], many.transmittance[c]) << "closed form either way";
                        EXPECT_NEAR(few.inscattered[c], many.inscattered[c], 0.01 * many.inscattered[c] + 1e-9)
                            << "sun " << sunElevation << ", " << distance << " m at pitch " << pitch << ", azimuth "
                            << azimuth << ", channel " << c;
                    }
                }
            }
        }
        for (double elevation : {-10.0, 0.0, 1.0, 10.0, 45.0, 90.0}) {
            for (double azimuth : {0.0, 135.0, 300.0}) {
                const glm::dvec3 view = direction(azimuth, elevation);
                const glm::dvec3 few = skyRadiance(air, 2500.0, view, sun);
                const glm::dvec3 many = skyRadiance(air, 2500.0, view, sun, 4096);
                for (int c = 0; c < 3; ++c) {
                    EXPECT_NEAR(few[c], many[c], 0.01 * many[c]) << "sky at " << elevation << ", channel " << c;
                }
            }
        }
    }
}

TEST(AtmosphereTest, TransmittanceFallsWithDistanceAndBlueFadesFirst)
{
    const AtmosphereModel air;
    glm::dvec3 previous(1.0);
    for (double distance : {0.0, 5000.0, 20000.0, 60000.0, 150000.0}) {
        const glm::dvec3 t = transmittance(air, 2500.0, 0.0, distance);
        for (int c = 0; c < 3; ++c) {
            EXPECT_LE(t[c], previous[c]);
            EXPECT_GE(t[c], 0.0);
        }
        EXPECT_LE(t.b, t.r);
        previous = t;
    }
    EXPECT_GT(transmittance(air, 4000.0, 0.0, 60000.0).b, transmittance(air, 0.0, 0.0, 60000.0).b)
        << "thinner air higher up";
    // Sunlight: redder towards the horizon.
    const glm::dvec3 high = sunTransmittance(air, 0.0, 60.0 * kPi / 180.0);
    const glm::dvec3 low = sunTransmittance(air, 0.0, 3.0 * kPi / 180.0);
    EXPECT_GT(low.r / low.b, 2.0 * high.r / high.b);
    EXPECT_LT(low.g, high.g);
}

TEST(AtmosphereTest, TheSkyIsBlueOverheadAndHazeBrightensAndWhitensWithDistance)
{
    const AtmosphereModel air;
    const glm::dvec3 sun = direction(135.0, 35.0);
    const glm::dvec3 zenith = skyRadiance(air, 2500.0, {0.0, 0.0, 1.0}, sun);
    EXPECT_GT(zenith.b, zenith.g);
    EXPECT_GT(zenith.g, zenith.r);
    const glm::dvec3 horizon = skyRadiance(air, 2500.0, direction(315.0, 0.0), sun);
    EXPECT_GT(horizon.b, zenith.b) << "the horizon is brighter";
    EXPECT_GT(horizon.r / horizon.b, zenith.r / zenith.b) << "and whiter";
    double previous = 0.0;
    for (double distance : {1000.0, 5000.0, 20000.0, 60000.0}) {
        const AerialPerspective a = aerialPerspective(air, 2500.0, direction(315.0, -1.0) * distance, sun);
        EXPECT_GT(a.inscattered.g, previous);
        previous = a.inscattered.g;
    }
    const glm::dvec3 sky = skyIrradiance(air, 2500.0, 35.0 * kPi / 180.0, nullptr);
    EXPECT_GT(sky.b, sky.r) << "skylight is blue";
    EXPECT_LT(skyIrradiance(air, 2500.0, -0.1, nullptr).g, 0.5 * sky.g) << "the sun set, only twilight";
}

TEST(AtmosphereTest, SkyIrradianceIsTheSkysRadianceOverTheHemisphere)
{
    // Against the sky's radiance summed over 128 x 256 directions of the upper hemisphere (cos-weighted solid
    // angles: midpoints in sin^2 elevation and azimuth), with light scattered more than once, for a low, a middle
    // and a high sun on the ground and 3 km up; and what the MultipleScattering holds at its altitudes.
    const AtmosphereModel air;
    for (double degrees : {5.0, 35.0, 80.0}) {
        const double elevation = degrees * kPi / 180.0;
        const MultipleScattering multiple = multipleScattering(air, elevation);
        const glm::dvec3 sun(std::cos(elevation), 0.0, std::sin(elevation));
        for (double altitude : {0.0, 3000.0}) {
            constexpr int kBands = 128, kAzimuths = 256;
            glm::dvec3 reference(0.0);
            for (int e = 0; e < kBands; ++e) {
                const double s = (e + 0.5) / kBands;
                for (int a = 0; a < kAzimuths; ++a) {
                    const double phi = 2.0 * kPi * (a + 0.5) / kAzimuths;
                    const glm::dvec3 view(std::sqrt(1.0 - s) * std::cos(phi), std::sqrt(1.0 - s) * std::sin(phi),
                                          std::sqrt(s));
                    reference += skyRadiance(air, altitude, view, sun, kSkySamples, &multiple);
                }
            }
            reference *= kPi / (kBands * kAzimuths);
            const glm::dvec3 fast = skyIrradiance(air, altitude, elevation, &multiple);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(fast[c], reference[c], 0.01 * reference[c])
                    << fast[c] / reference[c] << " of it, sun " << degrees << " degrees, altitude " << altitude
                    << ", channel " << c;
            }
            EXPECT_GT(fast.b, fast.r) << "skylight is blue";
        }
        EXPECT_EQ(multiple.irradianceAt(0.0), skyIrradiance(air, 0.0, elevation, &multiple));
        EXPECT_GT(multiple.irradianceAt(0.0).g, multiple.irradianceAt(5000.0).g) << "less air above, less skylight";
        const glm::dvec3 single = skyIrradiance(air, 0.0, elevation, nullptr);
        EXPECT_GT(multiple.irradianceAt(0.0).g, 1.05 * single.g) << "scattering more than once adds skylight";
    }
}

TEST(AtmosphereTest, MultipleScatteringConvergesWithDirectionsAndSamples)
{
    const AtmosphereModel air;
    for (double degrees : {5.0, 35.0, 80.0}) {
        const double elevation = degrees * kPi / 180.0;
        const MultipleScattering used = multipleScattering(air, elevation);
        const MultipleScattering many = multipleScattering(air, elevation, kGroundAlbedo, 1024, 256);
        for (int i = 0; i < kMultipleScatteringAltitudes; ++i) {
            for (int c = 0; c < 3; ++c) {
                const double reference = many.psi[static_cast<std::size_t>(i)][c];
                EXPECT_GT(reference, 0.0);
                EXPECT_NEAR(used.psi[static_cast<std::size_t>(i)][c], reference, 0.02 * reference)
                    << "sun " << degrees << ", altitude " << i << ", channel " << c;
            }
        }
    }
}

TEST(AtmosphereTest, InThinAirMultipleScatteringIsTheGroundsReflectionOverHalfTheSphere)
{
    // With scattering a millionth of the Earth's, the light that reaches a point on the ground from around it is
    // the sunlit ground's, seen over the lower half of the sphere: psi_ms = (1 / 2) albedo / pi sin(sun) there.
    AtmosphereModel thin;
    thin.rayleighScattering *= 1e-6;
    thin.mieScattering *= 1e-6;
    thin.mieExtinction *= 1e-6;
    for (double albedo : {0.1, 0.3}) {
        const double elevation = 35.0 * kPi / 180.0;
        const glm::dvec3 psi = multipleScattering(thin, elevation, albedo).at(0.0);
        const double expected = 0.5 * albedo / kPi * std::sin(elevation);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(psi[c], expected, 1e-3 * expected) << albedo << ", channel " << c;
        }
    }
}

TEST(AtmosphereTest, MultipleScatteringBrightensTheSkyAndTheHaze)
{
    const AtmosphereModel air;
    for (double degrees : {10.0, 35.0, 70.0}) {
        const double elevation = degrees * kPi / 180.0;
        const glm::dvec3 sun = direction(135.0, degrees);
        const MultipleScattering multiple = multipleScattering(air, elevation);
        for (const glm::dvec3& view : {glm::dvec3(0.0, 0.0, 1.0), direction(315.0, 5.0)}) {
            const glm::dvec3 once = skyRadiance(air, 500.0, view, sun, kSkySamples);
            const glm::dvec3 more = skyRadiance(air, 500.0, view, sun, kSkySamples, &multiple);
            for (int c = 0; c < 3; ++c) {
                // The higher orders add a few percent (red, towards a low sun) to about as much again (blue, away
                // from a high sun) to the single-scattered sky.
                EXPECT_GT(more[c] / once[c], 1.02) << degrees << ", channel " << c;
                EXPECT_LT(more[c] / once[c], 2.5) << degrees << ", channel " << c;
            }
        }
        const AerialPerspective once = aerialPerspective(air, 500.0, direction(315.0, -1.0) * 20000.0, sun);
        const AerialPerspective more =
            aerialPerspective(air, 500.0, direction(315.0, -1.0) * 20000.0, sun, kAerialSamples, &multiple);
        EXPECT_EQ(more.transmittance, once.transmittance);
        EXPECT_GT(more.inscattered.g, once.inscattered.g);
        EXPECT_EQ(multiple.at(-5.0), multiple.psi[0]);
        EXPECT_EQ(multiple.at(std::numeric_limits<double>::quiet_NaN()), multiple.psi[0]);
        EXPECT_EQ(multiple.at(std::numeric_limits<double>::infinity()), multiple.psi.back());
        // A brighter ground bounces more light into the air.
        EXPECT_GT(multipleScattering(air, elevation, 0.4).at(500.0).g, multiple.at(500.0).g);
    }
}

TEST(AtmosphereTest, TheToneMapIsMonotoneFromBlackToWhite)
{
    EXPECT_EQ(toneMap(glm::dvec3(0.0), 1.0), glm::dvec3(0.0));
    EXPECT_GT(toneMap(glm::dvec3(100.0), 1.0).r, 0.99);
    double previous = 0.0;
    for (double x = 0.001; x < 8.0; x *= 1.5) {  // the fit reaches white at about 10
        const double y = toneMap(glm::dvec3(x), 1.0).g;
        EXPECT_GT(y, previous) << x;
        previous = y;
    }
    EXPECT_EQ(toneMap(glm::dvec3(0.5), 2.0), toneMap(glm::dvec3(1.0), 1.0)) << "exposure scales the radiance";
}

}  // namespace
}  // namespace terrain
