// The air between the viewer, the terrain and the sun: scattering by molecules (Rayleigh) and aerosols
// (Mie) in an atmosphere whose densities fall exponentially with height, over a flat ground (Bruneton & Neyret
// 2008's scattering coefficients and phase functions as in Bruneton's 2017 reference implementation; Hillaire
// 2020's sky and aerial perspective as a model of what to compute). The view ray's transmittance is in closed
// form (the integral of an exponential density along a straight line); its in-scattered light is a midpoint sum
// over kAerialSamples points spaced quadratically from the viewer, each lit by the sun through the air above it (the
// Kasten & Young air mass stands in for the Earth's curvature towards a low sun). Light scattered more than once
// enters as Hillaire 2020's multiple-scattering term (section 5.5): per altitude, the isotropic light psi_ms that
// the orders from the second on add to each scattering event (multipleScattering), summed into the in-scattered
// light wherever a MultipleScattering is given. The sky's irradiance on the ground is the sky's radiance over the
// hemisphere, cosine-weighted, held per altitude beside psi_ms. Ozone is left out.
//
// shaders/atmosphere.glsl computes the same in float; this is its reference (AtmosphereGLTest) and what the
// tests measure the frames against. Units: metres, radiance relative to the sun's irradiance at the top of the
// atmosphere (1 in every channel). Pure: no GL.
#pragma once

#include <glm/vec3.hpp>

#include <array>

namespace terrain {

/// The atmosphere's constants (Bruneton's 2017 Earth).
struct AtmosphereModel {
    glm::dvec3 rayleighScattering{5.802e-6, 13.558e-6, 33.1e-6};  ///< per metre at sea level (680, 550, 440 nm)
    double rayleighHeight = 8000.0;                               ///< scale height, metres
    double mieScattering = 3.996e-6;                              ///< per metre at sea level
    double mieExtinction = 4.440e-6;                              ///< per metre at sea level
    double mieHeight = 1200.0;                                    ///< scale height, metres
    double mieAnisotropy = 0.8;                                   ///< Cornette-Shanks g
    /// Where the sky's rays stop: this many Rayleigh scale heights above the viewer (the density left is e^-8).
    double topScaleHeights = 8.0;

    bool operator==(const AtmosphereModel&) const = default;
};

/// The mean reflectance of the ground (grass, rock and soil reflect 0.1 to 0.3 of visible light): the light the
/// ground around bounces onto slopes (shaders/light.glsl) and up into the air (multipleScattering).
inline constexpr double kGroundAlbedo = 0.2;

/// Midpoints the view ray's in-scattered light is summed over, as a cell of the aerial table sums it
/// (light/AtmosphereTables.h): within 1% of many samples over every segment of AtmosphereTest (4096 samples as
/// the reference); 3% with 4, 12% with 2.
inline constexpr int kAerialSamples = 8;
/// Midpoints of a sky ray, as a cell of the sky table sums it: within 1% of many samples (2% with 16, 10% with 8).
inline constexpr int kSkySamples = 32;
/// Elevation bands and azimuths the sky's irradiance is summed over: within 1% of the sky's
/// radiance over 128 x 256 directions (AtmosphereTest). A band costs a ray, an azimuth only the phase functions.
inline constexpr int kSkyIrradianceBands = 32;
inline constexpr int kSkyIrradianceAzimuths = 128;

/// The integral of exp(-h / scaleHeight) along a straight segment from altitude `altitude` rising `rise` metres
/// over its `length` metres (rise in [-length, length]): exp(-h0 / H) L (1 - e^-x) / x with x = rise / H.
double densityIntegral(double altitude, double rise, double length, double scaleHeight);

/// Transmittance (per channel, in [0, 1]) of the air along a straight segment from altitude `altitude`, rising
/// `rise` over `length` metres.
glm::dvec3 transmittance(const AtmosphereModel& air, double altitude, double rise, double length);

/// Relative optical path towards the sun at elevation `elevationRadians` (Kasten & Young 1989's air mass: 1 at
/// the zenith, about 38 at the horizon, held there below it).
double airMass(double elevationRadians);

/// Transmittance of sunlight reaching altitude `altitude` from the sun at elevation `sunElevation` (radians).
glm::dvec3 sunTransmittance(const AtmosphereModel& air, double altitude, double sunElevation);

/// Rayleigh's and Cornette-Shanks's phase functions at cos(angle between view and sun) `mu`, per steradian.
double rayleighPhase(double mu);
double miePhase(double mu, double g);

/// Altitudes multipleScattering holds psi_ms at: top (i / (n - 1))^2, i = 0 .. n - 1, dense near the ground
/// where the air is. Part of the C++/GLSL contract (MULTIPLE_SCATTERING_ALTITUDES).
inline constexpr int kMultipleScatteringAltitudes = 16;

/// Hillaire's psi_ms over altitude, for one sun: radiance per unit of scattering coefficient (times the
/// scattering coefficient at a point, the light that scattering more than once adds there, in every direction).
/// With it, for the same sun and altitudes, the sky's irradiance on a horizontal surface (skyIrradiance with
/// these orders of scattering): what the ground receives from the sky.
struct MultipleScattering {
    std::array<glm::dvec3, kMultipleScatteringAltitudes> psi{};
    std::array<glm::dvec3, kMultipleScatteringAltitudes> irradiance{};
    double top = 1.0;  ///< the highest altitude, metres (AtmosphereModel::topScaleHeights Rayleigh scale heights)
    /// psi_ms at `altitude` metres, linear between the altitudes held (the ground's below 0 and for NaN, the top's
    /// above).
    glm::dvec3 at(double altitude) const;
    /// The sky's irradiance at `altitude` metres, the same way.
    glm::dvec3 irradianceAt(double altitude) const;
    bool operator==(const MultipleScattering&) const = default;
};

/// psi_ms for the sun at elevation `sunElevation` (radians) over a flat ground of reflectance `groundAlbedo`:
/// at each altitude the second order L2 (the single-scattered light of `directions` rays spread evenly over the
/// sphere, the ground's reflection of the sunlight included, with an isotropic phase), and the share f_ms of
/// light that the air around scatters back (the same rays' scattering, summed), psi_ms = L2 / (1 - f_ms): the
/// orders from the second on as a geometric series. Rays climb at the air mass's slope (as the sky's) and
/// descend at the ground's; `samples` midpoints a ray.
/// The sky's irradiance at each altitude follows (skyIrradiance with these orders).
MultipleScattering multipleScattering(const AtmosphereModel& air, double sunElevation,
                                      double groundAlbedo = kGroundAlbedo, int directions = 64, int samples = 32);

/// What the air does to light from a point seen along a segment: the point's light arrives times
/// `transmittance`, plus `inscattered` (radiance, relative to the sun's irradiance above the air).
struct AerialPerspective {
    glm::dvec3 transmittance{1.0};
    glm::dvec3 inscattered{0.0};
};

/// The segment from a viewer at `altitude` to `relative` metres away (z up), lit by the sun in unit direction
/// `sun`, summed over `samples` midpoints (kAerialSamples as the tables; more for a reference).
/// With `multiple`, the light scattered more than once is added (for the same sun).
AerialPerspective aerialPerspective(const AtmosphereModel& air, double altitude, const glm::dvec3& relative,
                                    const glm::dvec3& sun, int samples = kAerialSamples,
                                    const MultipleScattering* multiple = nullptr);

/// The sky's radiance seen from `altitude` in unit direction `view` (rays at or below the horizon see the
/// horizon's), the sun's disc not included: the in-scattered light up to topScaleHeights above the viewer,
/// with the ray climbing at the air mass's slope so that it leaves the air at the horizon too.
glm::dvec3 skyRadiance(const AtmosphereModel& air, double altitude, const glm::dvec3& view, const glm::dvec3& sun,
                       int samples = kSkySamples, const MultipleScattering* multiple = nullptr);

/// The sky's irradiance on a horizontal surface at `altitude` (relative to the sun's irradiance above the air; the
/// sun's disc not included): skyRadiance over the upper hemisphere weighted by cos(zenith angle), with `multiple`
/// the light scattered more than once too. Summed over `elevations` bands even in elevation; each band's ray once,
/// with the phase functions' means over `azimuths` directions around the zenith.
glm::dvec3 skyIrradiance(const AtmosphereModel& air, double altitude, double sunElevation,
                         const MultipleScattering* multiple, int elevations = kSkyIrradianceBands,
                         int azimuths = kSkyIrradianceAzimuths);

/// The filmic tone map (Narkowicz's fit of ACES) of `exposure` times linear radiance, then the display's gamma
/// 2 (a square root, as shaders/atmosphere.glsl): what the frames show of a radiance, each channel in [0, 1].
glm::dvec3 toneMap(const glm::dvec3& radiance, double exposure);

}  // namespace terrain
