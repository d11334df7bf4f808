// Terrain shadows and sky visibility from horizons (Timonen & Westerholm 2010's horizon-based self-shadowing
// of height fields, on a plain grid): at a point on the surface, the horizon in a direction is the highest
// elevation angle under which the surface around is seen along it, out to a distance. With the horizons over a
// few azimuths kept, the sun's visibility for any sun follows without looking at the surface again (the sun is
// seen where it stands above the horizon at its azimuth, softly over its disc and the penumbra), and so does the
// sky's (the share of the cosine-weighted sky above every horizon: ambient occlusion).
//
// The march steps grow with distance (each a fixed fraction of the distance reached, at least the grid's
// spacing), so a horizon costs a few dozen height lookups however far it reaches: near the point the steps are
// fine where small relief matters, far away coarse where only large relief can rise above the horizon.
// Pure: no GL, no threads.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace terrain {

/// A height grid placed in the world: `width` x `height` samples, row-major south to north, sample (i, j) at
/// (originX + i spacing, originY + j spacing) metres. Heights in metres.
struct HeightGrid {
    int width = 0;
    int height = 0;
    double originX = 0.0;
    double originY = 0.0;
    double spacing = 1.0;
    std::vector<float> heights;

    /// The bilinear height at world (x, y), clamped to the grid's edge outside it.
    double at(double x, double y) const;
};

/// How horizons are searched.
struct HorizonOptions {
    int azimuths = 8;              ///< directions, evenly spaced from east counterclockwise; >= 1
    double maxDistance = 20000.0;  ///< metres searched along each direction, > 0
    double stepGrowth = 0.15;      ///< each step this fraction of the distance reached, > 0
};

/// The horizons at world (x, y) on a surface `z` metres high: per azimuth k (direction angle 2 pi k / azimuths
/// from +x towards +y), the tangent of the highest elevation of the grid seen from there, at least -1 (the
/// horizon of a flat ground is 0 in every direction; a point under a cliff has a large tangent towards it).
std::vector<float> horizonTangents(const HeightGrid& grid, double x, double y, double z, const HorizonOptions& options);

/// The sun's visibility in [0, 1] over horizons `tangents` (horizonTangents, azimuths evenly spaced) for the sun at
/// direction angle `sunAzimuth` (radians from +x towards +y) and elevation `sunElevation` (radians): 1 where the
/// sun stands `softness` radians or more above the horizon at its azimuth (linearly interpolated between the two
/// nearest azimuths), 0 that far below, smooth between.
double sunVisibility(std::span<const float> tangents, double sunAzimuth, double sunElevation, double softness);

/// The share of a horizontal surface's cosine-weighted sky irradiance that comes from above the horizons: the
/// mean over azimuths of cos^2(horizon elevation) = 1 / (1 + tangent^2), horizons below 0 counting as 0 (1 on
/// open ground, 0.5 at the foot of a wall that hides half the azimuths).
double skyVisibility(std::span<const float> tangents);

}  // namespace terrain
