// Terrain shadows and sky visibility from horizons (Timonen & Westerholm 2010's horizon-based self-shadowing
// of height fields, on a plain grid): at a point on the surface, the horizon in a direction is the highest
// elevation angle under which the surface around is seen along it, out to a distance. With the horizons over a
// few azimuths kept, the sun's visibility for any sun follows without looking at the surface again (the sun is
// seen where it stands above the horizon at its azimuth, softly over its disc and the penumbra), and so does the
// sky's (the share of the cosine-weighted sky above every horizon: ambient occlusion).
//
// The march steps grow with distance (each a fixed fraction of the distance reached, at least a quarter of the
// grid's spacing), so a horizon costs a few dozen height lookups however far it reaches: near the point the steps are
// fine where small relief matters, far away coarse where only large relief can rise above the horizon.
// Pure: no GL, no threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
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
    /// At least the highest sample (the search for a horizon stops where nothing further can rise above the
    /// horizon found); +infinity: not known, every step is looked at. setTop() sets it.
    double top = std::numeric_limits<double>::infinity();

    /// The bilinear height at world (x, y), clamped to the grid's edge outside it.
    double at(double x, double y) const;
    /// Sets `top` to the highest sample.
    void setTop();
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
/// horizonTangents into `out` (options.azimuths values).
void horizonTangents(const HeightGrid& grid, double x, double y, double z, const HorizonOptions& options,
                     std::span<float> out);

/// The sun's visibility in [0, 1] over horizons `tangents` (horizonTangents, azimuths evenly spaced) for the sun at
/// direction angle `sunAzimuth` (radians from +x towards +y) and elevation `sunElevation` (radians): 1 where the
/// sun stands `softness` radians or more above the horizon at its azimuth (linearly interpolated between the two
/// nearest azimuths), 0 that far below, smooth between.
double sunVisibility(std::span<const float> tangents, double sunAzimuth, double sunElevation, double softness);

/// The share of a horizontal surface's cosine-weighted sky irradiance that comes from above the horizons: the
/// mean over azimuths of cos^2(horizon elevation) = 1 / (1 + tangent^2), horizons below 0 counting as 0 (1 on
/// open ground, 0.5 at the foot of a wall that hides half the azimuths).
double skyVisibility(std::span<const float> tangents);

/// A horizon kept in a byte: its elevation angle from -pi/4 (tangent -1, the lowest horizonTangents gives) to
/// pi/2 in 255 steps of 0.53 degrees.
std::uint8_t encodeHorizon(double tangent);
/// The tangent of the horizon `code` holds (encodeHorizon's inverse, within half a step of the angle).
double decodeHorizon(std::uint8_t code);

/// The horizons of a node's surface at a square lattice of its samples: `size` x size points evenly over the
/// node's square, corner points on its corners (so neighbours share their edge points), rows south to north, each
/// point `azimuths` codes (encodeHorizon) in horizonTangents' order. size 0: none.
struct HorizonLattice {
    int size = 0;
    int azimuths = 0;
    std::vector<std::uint8_t> codes;  ///< size^2 x azimuths
};

/// The quarter of `lattice` (size 2^k + 1) over a child's square: quadrant 0 south-west, 1 south-east, 2 north-west,
/// 3 north-east (NodeId::child); (size - 1) / 2 + 1 points a side, the same codes.
HorizonLattice latticeQuadrant(const HorizonLattice& lattice, int quadrant);

/// Sun and sky visibility (sunVisibility, skyVisibility) as bytes (0..255) at n x n points evenly over the
/// lattice's square (corner points on its corners), bilinear between the lattice points' visibilities: written
/// to out[(j n + i) stride + offset] (sun) and the byte after it (sky). Precondition: lattice.size >= 2, n >= 2,
/// out holds n^2 stride bytes.
void latticeVisibility(const HorizonLattice& lattice, double sunAzimuth, double sunElevation, double softness, int n,
                       std::span<std::uint8_t> out, int stride, int offset);

/// The sun's softness (radians) of the shadows drawn from horizon lattices: half the width of the penumbra, the
/// sun's disc widened by what the codes and the azimuths between two horizons round.
inline constexpr double kShadowSoftness = 0.02;

}  // namespace terrain
