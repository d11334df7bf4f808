// The air as tables, made once a frame so that a pixel reads its air in one fetch instead of summing it
// (Hillaire 2020's sky-view table and aerial-perspective volume, indexed by direction rather than by screen).
// Over a flat ground with densities that fall with height, the light the air scatters towards the viewer along a
// ray depends only on the viewer's altitude, the sun, the ray's direction relative to the sun and its length, so
// for one frame (one altitude, one sun) it is a function of three numbers:
// - the azimuth a between the ray and the sun, in [0, pi] (the air is symmetric about the sun's vertical plane),
//   as sqrt(tan(a / 4)): spaced finely near the sun, where Mie's peak is;
// - the ray's elevation e, as 0.5 + 0.5 sign(e) sqrt(tan(|e| / 2)): spaced finely near the horizon, where the light
//   changes fastest (like Hillaire's 0.5 + 0.5 sign(e) sqrt(|e| / (pi / 2))), evenly near the zenith.
// Neither needs an inverse trigonometric function to look up (the vertex programs do it for every vertex): with
// a and b the horizontal unit directions of the ray and the sun, tan(a / 4) = |a - b| / (2 + |a + b|), and
// tan(|e| / 2) = |z| / (length + horizontal length) of the ray;
// - the distance, as sqrt(distance / range): dense near the viewer, where the light builds up.
// The aerial table holds the in-scattered light of segments (aerialPerspective's .inscattered, phase functions
// included) over those three, divided by the distance coordinate squared (distance / range): the light per
// metre, which is smooth where the light itself starts from 0 in a straight line (a lookup multiplies it back); the sky
// table the sky's radiance (skyRadiance) over the first two. The view ray's transmittance and the sunlight stay in
// closed form (eight exponentials, cheaper than a fetch on a CPU rasterizer: per vertex for the quadtree, per pixel
// for the clipmap).
//
// Cells sit on the coordinates' grid points: cell i of n is coordinate i / (n - 1), so the first and last
// cells are the ends of each range exactly (OpenGL's texture coordinate (c (n - 1) + 0.5) / n). The renderer's
// tables (render/AtmosphereTables.h) are filled by shaders/atmosphere_table.frag with the same layout; this file
// is their reference, used by the tests to bound what a lookup costs in accuracy. Pure: no GL.
#pragma once

#include "core/Camera.h"
#include "light/Atmosphere.h"

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <vector>

namespace terrain {

/// The aerial table's cells along azimuth, elevation and distance, and the sky table's along azimuth and
/// elevation. Part of the C++/GLSL contract (AERIAL_TABLE_SIZE, SKY_TABLE_SIZE).
inline constexpr int kAerialTableAzimuths = 32;
inline constexpr int kAerialTableElevations = 64;
inline constexpr int kAerialTableDistances = 32;
inline constexpr int kSkyTableAzimuths = 64;
inline constexpr int kSkyTableElevations = 128;

/// The coordinates in [0, 1]^2 of unit view direction `view` with the sun in unit direction `sun`: x the
/// azimuth's between them, y the elevation's (see above). Defined for every pair of unit vectors,
/// vertical ones included (azimuth 0).
glm::dvec2 directionCoordinate(const glm::dvec3& view, const glm::dvec3& sun);
/// A unit view direction at coordinates `coordinate` (directionCoordinate's inverse; of the two mirror images
/// about the sun's vertical plane, which the air does not tell apart, the one clockwise from the sun).
glm::dvec3 directionAt(const glm::dvec2& coordinate, const glm::dvec3& sun);
/// sqrt(distance / range), clamped to [0, 1]; `range` > 0.
double distanceCoordinate(double distance, double range);
/// range coordinate^2 (distanceCoordinate's inverse).
double distanceAt(double coordinate, double range);

/// The aerial table's range for `camera`: the distance to the far plane's corners (nothing drawn is farther).
double aerialTableRange(const Camera& camera);

/// The renderer fills its tables at altitudes that are multiples of a step and makes the frame's by interpolating
/// linearly between the two around the viewer (render/AtmosphereTextures.h): a flight fills a table when it
/// crosses a step, not every frame. The light depends on the viewer's altitude h through densities exp(-h / H), so
/// the interpolation is off by a share of it that grows with (step / H)^2: the step is kTableAltitudeShare of the
/// smaller scale height (60 m for the default haze's 1.2 km): AtmosphereTablesTest measures 0.05% (its limit 0.2%).
inline constexpr double kTableAltitudeShare = 0.05;
struct TableAltitudes {
    double lower = 0.0;   ///< metres, a multiple of the step
    double upper = 0.0;   ///< lower + the step
    double weight = 0.0;  ///< of the upper table, in [0, 1]
};
/// The two altitudes around `altitude` for `air`. An altitude not finite, or too large for its step, is its own:
/// lower = upper = altitude, weight 0.
TableAltitudes tableAltitudes(double altitude, const AtmosphereModel& air);

/// The tables for one viewer altitude and sun, made on the CPU as the shaders make them, looked up with
/// linear interpolation as OpenGL does.
class AtmosphereTables {
public:
    /// Distances beyond `range` metres read the last cell (what is seen there is at least that far).
    /// With `multiple`, the light scattered more than once is in both tables (as the renderer's have it).
    AtmosphereTables(const AtmosphereModel& air, double altitude, const glm::dvec3& sun, double range,
                     const MultipleScattering* multiple = nullptr);

    /// The in-scattered light of the segment `distance` metres along unit `view`.
    glm::dvec3 inscattered(const glm::dvec3& view, double distance) const;
    /// The sky's radiance in unit direction `view`.
    glm::dvec3 sky(const glm::dvec3& view) const;

private:
    glm::dvec3 aerialCell(int azimuth, int elevation, int distance) const;
    glm::dvec3 skyCell(int azimuth, int elevation) const;

    glm::dvec3 mSun;
    double mRange;
    std::vector<glm::dvec3> mAerial;  ///< azimuth fastest, then elevation, then distance
    std::vector<glm::dvec3> mSky;     ///< azimuth fastest
};

}  // namespace terrain
