// Single and multiple scattering in an exponential atmosphere over a flat ground (Atmosphere.h).
#include "light/Atmosphere.h"

#include "core/Check.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

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

glm::dvec3 skyIrradiance(const AtmosphereModel& air, double altitude, double sunElevation)
{
    const double above = std::max(std::sin(sunElevation), 0.0);
    return 0.5 * above * (glm::dvec3(1.0) - sunTransmittance(air, altitude, sunElevation));
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
/// at cos(view, sun) `mu`, sun elevation `sunElevation`, summed over `samples` midpoints of u in [0, 1] with
/// t = length u^2: denser near the viewer, where the light that is not yet attenuated comes from (a long
/// sky ray loses most of its light in its first tenth). With `multiple`, each point adds its scattering
/// coefficient times psi_ms there.
glm::dvec3 inscatter(const AtmosphereModel& air, double altitude, double slope, double length, double mu,
                     double sunElevation, int samples, const MultipleScattering* multiple)
{
    TERRAIN_EXPECTS(samples >= 1, "at least one sample");
    const double rayleighPhaseValue = rayleighPhase(mu);
    const double miePhaseValue = miePhase(mu, air.mieAnisotropy);
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
    out.inscattered = inscatter(air, altitude, view.z, length, glm::dot(view, sun), sunElevation, samples, multiple);
    return out;
}

glm::dvec3 skyRadiance(const AtmosphereModel& air, double altitude, const glm::dvec3& view, const glm::dvec3& sun,
                       int samples, const MultipleScattering* multiple)
{
    const double elevation = std::asin(std::clamp(view.z, -1.0, 1.0));
    const double slope = 1.0 / airMass(elevation);
    const double length = air.topScaleHeights * air.rayleighHeight / slope;
    const double sunElevation = std::asin(std::clamp(sun.z, -1.0, 1.0));
    return inscatter(air, altitude, slope, length, glm::dot(view, sun), sunElevation, samples, multiple);
}

glm::dvec3 MultipleScattering::at(double altitude) const
{
    // NaN reads the ground's (a NaN index would be undefined).
    const double share = altitude / top;
    const double x = std::sqrt(share >= 0.0 ? std::min(share, 1.0) : 0.0) * (kMultipleScatteringAltitudes - 1);
    const int i = std::min(static_cast<int>(x), kMultipleScatteringAltitudes - 2);
    const double f = x - i;
    return psi[static_cast<std::size_t>(i)] * (1.0 - f) + psi[static_cast<std::size_t>(i + 1)] * f;
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
    return out;
}

glm::dvec3 toneMap(const glm::dvec3& radiance, double exposure)
{
    const glm::dvec3 x = glm::max(radiance * exposure, glm::dvec3(0.0));
    const glm::dvec3 mapped = glm::clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    return glm::sqrt(mapped);
}

}  // namespace terrain
