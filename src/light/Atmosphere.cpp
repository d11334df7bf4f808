// Single and multiple scattering in an exponential atmosphere over a flat ground (Atmosphere.h).
#include "light/Atmosphere.h"

#include "core/Check.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

namespace terrain {

namespace {

constexpr double kPi = std::numbers::pi;

/// (1 - e^-x) / x, with its series near 0 where the quotient loses its digits.
double decayFactor(double x)
{
    if (std::abs(x) < 1e-4) {
        return 1.0 - x / 2.0 + x * x / 6.0;
    }
    return -std::expm1(-x) / x;
}

/// Extinction per metre at sea level, per channel.
glm::dvec3 rayleighOpticalDepth(const AtmosphereModel& air, double density)
{
    return air.rayleighScattering * density;
}

}  // namespace

double densityIntegral(double altitude, double rise, double length, double scaleHeight)
{
    TERRAIN_EXPECTS(length >= 0.0 && scaleHeight > 0.0, "a segment of length >= 0 in an atmosphere of height > 0");
    return std::exp(-altitude / scaleHeight) * length * decayFactor(rise / scaleHeight);
}

glm::dvec3 transmittance(const AtmosphereModel& air, double altitude, double rise, double length)
{
    const double rayleigh = densityIntegral(altitude, rise, length, air.rayleighHeight);
    const double mie = densityIntegral(altitude, rise, length, air.mieHeight);
    return glm::exp(-(rayleighOpticalDepth(air, rayleigh) + glm::dvec3(air.mieExtinction * mie)));
}

double airMass(double elevationRadians)
{
    const double degrees = std::max(elevationRadians, 0.0) * 180.0 / kPi;
    return 1.0 / (std::sin(degrees * kPi / 180.0) + 0.50572 * std::pow(degrees + 6.07995, -1.6364));
}

glm::dvec3 sunTransmittance(const AtmosphereModel& air, double altitude, double sunElevation)
{
    // The vertical optical depth above the point, stretched by the air mass.
    const double rayleigh = air.rayleighHeight * std::exp(-altitude / air.rayleighHeight);
    const double mie = air.mieHeight * std::exp(-altitude / air.mieHeight);
    const double m = airMass(sunElevation);
    return glm::exp(-(rayleighOpticalDepth(air, rayleigh) + glm::dvec3(air.mieExtinction * mie)) * m);
}

double rayleighPhase(double mu)
{
    return 3.0 / (16.0 * kPi) * (1.0 + mu * mu);
}

double miePhase(double mu, double g)
{
    const double g2 = g * g;
    return 3.0 / (8.0 * kPi) * (1.0 - g2) * (1.0 + mu * mu) / ((2.0 + g2) * std::pow(1.0 + g2 - 2.0 * g * mu, 1.5));
}

namespace {

/// The in-scattered light of a straight segment from `altitude`, `length` metres rising `slope` metres a metre,
/// with phase functions `rayleighPhaseValue` and `miePhaseValue` (their values at cos(view, sun), or their means
/// over the directions the segment stands for), sun elevation `sunElevation`, summed over `samples` midpoints of u
/// in [0, 1] with t = length u^2: denser near the viewer, where the light that is not yet attenuated comes from
/// (a long sky ray loses most of its light in its first tenth). With `multiple`, each point adds its scattering
/// coefficient times psi_ms there.
glm::dvec3 inscatter(const AtmosphereModel& air, double altitude, double slope, double length,
                     double rayleighPhaseValue, double miePhaseValue, double sunElevation, int samples,
                     const MultipleScattering* multiple)
{
    TERRAIN_EXPECTS(samples >= 1, "at least one sample");
    glm::dvec3 sum(0.0);
    for (int k = 0; k < samples; ++k) {
        const double u = (k + 0.5) / samples;
        const double t = length * u * u;
        const double h = altitude + slope * t;
        const double rayleighDensity = std::exp(-h / air.rayleighHeight), mieDensity = std::exp(-h / air.mieHeight);
        glm::dvec3 light = (air.rayleighScattering * (rayleighDensity * rayleighPhaseValue) +
                            glm::dvec3(air.mieScattering * mieDensity * miePhaseValue)) *
                           sunTransmittance(air, h, sunElevation);
        if (multiple) {
            light += (air.rayleighScattering * rayleighDensity + glm::dvec3(air.mieScattering * mieDensity)) *
                     multiple->at(h);
        }
        // dt = 2 length u du.
        sum += transmittance(air, altitude, slope * t, t) * light * (2.0 * length * u);
    }
    return sum / static_cast<double>(samples);
}

/// The sky ray in a direction of elevation `elevation` (radians): its slope (the air mass's, so that it leaves
/// the air at the horizon too) and its length (to topScaleHeights above the viewer).
std::pair<double, double> skyRay(const AtmosphereModel& air, double elevation)
{
    const double slope = 1.0 / airMass(elevation);
    return {slope, air.topScaleHeights * air.rayleighHeight / slope};
}

}  // namespace

AerialPerspective aerialPerspective(const AtmosphereModel& air, double altitude, const glm::dvec3& relative,
                                    const glm::dvec3& sun, int samples, const MultipleScattering* multiple)
{
    AerialPerspective out;
    const double length = glm::length(relative);
    if (length <= 0.0) {
        return out;
    }
    const glm::dvec3 view = relative / length;
    const double sunElevation = std::asin(std::clamp(sun.z, -1.0, 1.0));
    out.transmittance = transmittance(air, altitude, relative.z, length);
    const double mu = glm::dot(view, sun);
    out.inscattered = inscatter(air, altitude, view.z, length, rayleighPhase(mu), miePhase(mu, air.mieAnisotropy),
                                sunElevation, samples, multiple);
    return out;
}

glm::dvec3 skyRadiance(const AtmosphereModel& air, double altitude, const glm::dvec3& view, const glm::dvec3& sun,
                       int samples, const MultipleScattering* multiple)
{
    const auto [slope, length] = skyRay(air, std::asin(std::clamp(view.z, -1.0, 1.0)));
    const double sunElevation = std::asin(std::clamp(sun.z, -1.0, 1.0));
    const double mu = glm::dot(view, sun);
    return inscatter(air, altitude, slope, length, rayleighPhase(mu), miePhase(mu, air.mieAnisotropy), sunElevation,
                     samples, multiple);
}

namespace {

/// Per elevation band of the upper hemisphere (skyIrradiance), the phase functions' means over its azimuths.
struct BandPhases {
    std::vector<double> rayleigh, mie;
};

BandPhases bandPhases(const AtmosphereModel& air, double sunElevation, int elevations, int azimuths)
{
    TERRAIN_EXPECTS(elevations >= 1 && azimuths >= 1, "at least one elevation and one azimuth");
    const double sunCos = std::cos(sunElevation), sunSin = std::sin(sunElevation);
    BandPhases out{std::vector<double>(static_cast<std::size_t>(elevations)),
                   std::vector<double>(static_cast<std::size_t>(elevations))};
    for (int e = 0; e < elevations; ++e) {
        const double elevation = 0.5 * kPi * (e + 0.5) / elevations;
        const double sinE = std::sin(elevation), cosE = std::cos(elevation);
        double rayleigh = 0.0, mie = 0.0;
        for (int a = 0; a < azimuths; ++a) {
            const double mu = cosE * sunCos * std::cos(2.0 * kPi * (a + 0.5) / azimuths) + sinE * sunSin;
            rayleigh += rayleighPhase(mu);
            mie += miePhase(mu, air.mieAnisotropy);
        }
        out.rayleigh[static_cast<std::size_t>(e)] = rayleigh / azimuths;
        out.mie[static_cast<std::size_t>(e)] = mie / azimuths;
    }
    return out;
}

/// skyIrradiance with the bands' phases made.
glm::dvec3 skyIrradiance(const AtmosphereModel& air, double altitude, double sunElevation,
                         const MultipleScattering* multiple, const BandPhases& phases)
{
    // cos(zenith angle) dw = sin(e) cos(e) de dphi over elevations e in [0, pi / 2]: the irradiance is 2 pi times
    // the sum over the bands (even in elevation: fine at the horizon, where the haze brightens the sky fast) of
    // the radiance's mean over azimuths times sin(e) cos(e) de. Only the phase functions depend on the azimuth:
    // each band's ray is summed once with their means.
    const std::size_t bands = phases.rayleigh.size();
    const double step = 0.5 * kPi / static_cast<double>(bands);
    glm::dvec3 sum(0.0);
    for (std::size_t e = 0; e < bands; ++e) {
        const double elevation = step * (static_cast<double>(e) + 0.5);
        const auto [slope, length] = skyRay(air, elevation);
        sum += inscatter(air, altitude, slope, length, phases.rayleigh[e], phases.mie[e], sunElevation, kSkySamples,
                         multiple) *
               (std::sin(elevation) * std::cos(elevation) * step);
    }
    return 2.0 * kPi * sum;
}

}  // namespace

glm::dvec3 skyIrradiance(const AtmosphereModel& air, double altitude, double sunElevation,
                         const MultipleScattering* multiple, int elevations, int azimuths)
{
    return skyIrradiance(air, altitude, sunElevation, multiple, bandPhases(air, sunElevation, elevations, azimuths));
}

namespace {

/// `values` held at MultipleScattering's altitudes, linear between them at `altitude` (the ground's below 0 and
/// for NaN, the top's above).
glm::dvec3 atAltitude(const std::array<glm::dvec3, kMultipleScatteringAltitudes>& values, double top, double altitude)
{
    // NaN reads the ground's (a NaN index would be undefined).
    const double share = altitude / top;
    const double x = std::sqrt(share >= 0.0 ? std::min(share, 1.0) : 0.0) * (kMultipleScatteringAltitudes - 1);
    const int i = std::min(static_cast<int>(x), kMultipleScatteringAltitudes - 2);
    const double f = x - i;
    return values[static_cast<std::size_t>(i)] * (1.0 - f) + values[static_cast<std::size_t>(i + 1)] * f;
}

}  // namespace

glm::dvec3 MultipleScattering::at(double altitude) const
{
    return atAltitude(psi, top, altitude);
}

glm::dvec3 MultipleScattering::irradianceAt(double altitude) const
{
    return atAltitude(irradiance, top, altitude);
}

MultipleScattering multipleScattering(const AtmosphereModel& air, double sunElevation, double groundAlbedo,
                                      int directions, int samples)
{
    TERRAIN_EXPECTS(directions >= 2 && samples >= 1, "at least two directions and one sample a ray");
    TERRAIN_EXPECTS(groundAlbedo >= 0.0 && groundAlbedo <= 1.0, "a ground reflectance in [0, 1]");
    MultipleScattering out;
    out.top = air.topScaleHeights * air.rayleighHeight;
    const double isotropic = 1.0 / (4.0 * kPi);
    const glm::dvec3 groundLight =
        groundAlbedo / kPi * sunTransmittance(air, 0.0, sunElevation) * std::max(std::sin(sunElevation), 0.0);
    for (int a = 0; a < kMultipleScatteringAltitudes; ++a) {
        const double f = static_cast<double>(a) / (kMultipleScatteringAltitudes - 1);
        const double altitude = out.top * f * f;
        // Over the sphere, p_u dw = dmu / 2 for mu = sin(elevation) uniform in [-1, 1]: the means over mu.
        glm::dvec3 second(0.0), transfer(0.0);
        for (int d = 0; d < directions; ++d) {
            const double mu = -1.0 + 2.0 * (d + 0.5) / directions;
            const double elevation = std::asin(mu);
            // Up: climbing at the air mass's slope, `top` metres (as the sky's rays). Down: to the ground.
            const bool up = mu >= 0.0;
            const double slope = up ? 1.0 / airMass(elevation) : mu;
            const double length = up ? out.top / slope : altitude / -mu;
            glm::dvec3 light(0.0), scattered(0.0);
            for (int k = 0; k < samples; ++k) {
                const double u = (k + 0.5) / samples;
                const double t = length * u * u;
                const double h = std::max(altitude + slope * t, 0.0);
                const glm::dvec3 scattering = air.rayleighScattering * std::exp(-h / air.rayleighHeight) +
                                              glm::dvec3(air.mieScattering * std::exp(-h / air.mieHeight));
                const glm::dvec3 weight = transmittance(air, altitude, slope * t, t) * scattering * (2.0 * length * u);
                light += weight * sunTransmittance(air, h, sunElevation) * isotropic;
                scattered += weight;
            }
            light /= static_cast<double>(samples);
            scattered /= static_cast<double>(samples);
            if (!up) {
                light += transmittance(air, altitude, -altitude, length) * groundLight;
            }
            second += light / static_cast<double>(directions);
            transfer += scattered / static_cast<double>(directions);
        }
        out.psi[static_cast<std::size_t>(a)] = second / (glm::dvec3(1.0) - glm::min(transfer, glm::dvec3(0.99)));
    }
    const BandPhases phases = bandPhases(air, sunElevation, kSkyIrradianceBands, kSkyIrradianceAzimuths);
    for (int a = 0; a < kMultipleScatteringAltitudes; ++a) {
        const double f = static_cast<double>(a) / (kMultipleScatteringAltitudes - 1);
        out.irradiance[static_cast<std::size_t>(a)] = skyIrradiance(air, out.top * f * f, sunElevation, &out, phases);
    }
    return out;
}

glm::dvec3 toneMap(const glm::dvec3& radiance, double exposure)
{
    const glm::dvec3 x = glm::max(radiance * exposure, glm::dvec3(0.0));
    const glm::dvec3 mapped = glm::clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    return glm::sqrt(mapped);
}

}  // namespace terrain
