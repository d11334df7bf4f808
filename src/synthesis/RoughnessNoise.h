// The terrain's own roughness continued below its data: noise whose amplitude follows the power
// law prep measured around each static leaf (heightfield/Roughness.h, quadtree/MapFormat.h RoughnessGrid),
// from the data's spacing s0 downwards.
//
// Octave k (k = 0, 1, ...) is Perlin gradient noise on a lattice of spacing s0 2^-k aligned with the map's
// sample grid, with amplitude a_k = c(H) A (2^-k)^H, A and H the law interpolated at the point. Gradient
// noise is zero at its lattice points, so:
//  - at the static samples every octave is zero: the real data is left exactly as it is;
//  - at the samples of level l below the leaves (spacing s0 2^-l) octaves k >= l are zero: each dynamic
//    level adds the next octave, the one its spacing resolves (random midpoint displacement, made
//    deterministic), and nothing aliases;
//  - the value depends only on the sample's position and the stored laws: every node, level and thread
//    gets the same bits, so shared edges stay bit-identical and a child's even samples equal its parent's.
// c(H) calibrates the sum so that the RMS midpoint deviation of the synthesized samples at lags of one and
// two of their spacings, s0 2^-j and s0 2^(1-j), follows the law A (r / s0)^H: with g_m (h_m) the RMS midpoint
// deviation of one octave at a lag of 2^-m (2^(1-m)) of its wavelength, measured at the positions a level's
// samples take on it, the octaves k < j contribute with m = j - k, c1^-2 = sum_{m >= 1} 2^(2 H m) g_m^2 makes
// the one-sample lag exact, c2^-2 = 2^(-2H) sum_m 2^(2 H m) h_m^2 the two-sample lag, and c = sqrt(c1 c2)
// (they differ by 10 to 20 %: the top octave is not self-similar).
//
// The law varies smoothly: log A and H are interpolated bilinearly between leaf centres (clamped at the
// map's edges), so no leaf border shows.
#pragma once

#include "quadtree/MapFormat.h"
#include "synthesis/Material.h"
#include "synthesis/PerlinNoise.h"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace terrain {

/// The noise's seed unless told otherwise (octave k uses seed + k).
inline constexpr std::uint64_t kRoughnessSeed = 0x5eed5eedull;
/// Most octaves (a 2^-24 of the data's spacing is below any use).
inline constexpr int kMaxRoughnessOctaves = 24;
/// Exponent step of the calibration table (c(H) is interpolated linearly between its entries).
inline constexpr double kRoughnessCalibrationStep = 0.01;

class RoughnessNoise {
public:
    /// `grid` from the map; `leafCells` = N - 1 (samples per leaf side, minus one); `dataSpacing` s0, metres
    /// between the finest static samples; `octaves` in [0, kMaxRoughnessOctaves]: octave k has wavelength
    /// s0 2^-k. Preconditions: grid has leavesPerSide^2 laws, dataSpacing > 0.
    RoughnessNoise(RoughnessGrid grid, int leafCells, double dataSpacing, int octaves,
                   std::uint64_t seed = kRoughnessSeed);

    /// The octaves with wavelength s0 2^-k >= `finestWavelength` (metres), for data of spacing `dataSpacing`:
    /// the octaves synthesized before the materials' own take over. At most kMaxRoughnessOctaves.
    static int octavesDownTo(double dataSpacing, double finestWavelength);

    int octaves() const { return static_cast<int>(mNoise.size()); }
    int leafCells() const { return mLeafCells; }
    double dataSpacing() const { return mDataSpacing; }
    /// Levels below the static leaves of nodes with sample spacing `spacing` (negative above them):
    /// round(log2(s0 / spacing)).
    int levelsBelow(double spacing) const;
    const RoughnessGrid& grid() const { return mGrid; }

    /// The law at (u, v), in samples of the finest static level from the map's grid origin (any real value).
    RoughnessLaw lawAt(double u, double v) const;
    /// c(H), for exponents in [kMinRoughnessExponent, kMaxRoughnessExponent] (clamped).
    double calibration(double exponent) const;
    /// The law's RMS midpoint deviation at `lag` metres at (u, v) (as lawAt): A (lag / s0)^H, metres, with log A
    /// and H interpolated as lawAt does (so log D is bilinear between leaf centres too).
    double deviationAt(double u, double v, double lag) const;
    /// out[j * width + i] = deviationAt at global sample (gx0 + i, gy0 + j) of the level with sample spacing
    /// `spacing` (s0 2^-k for any integer k), as float: exactly at and above the finest static level; below
    /// it interpolated bilinearly from deviationAt at the finest static samples around (a function of the
    /// position only; within (d log D)^2 / 8 of it relative, d log D its change from one finest sample to the
    /// next: 1.3e-4 for a law 8x rougher one 64-sample leaf away). Precondition: out holds width * height values.
    void deviationGrid(std::int64_t gx0, std::int64_t gy0, int width, int height, double spacing, double lag,
                       std::span<float> out) const;
    /// The largest deviationAt(., ., lag) anywhere: at a leaf centre, log D being bilinear between them.
    double maxDeviation(double lag) const;

    /// The noise at global sample (gx, gy) of the level `below` levels below the static leaves (spacing s0
    /// 2^-below): sum over k < min(below, octaves()) of a_k P_k, in float; exactly 0 for below <= 0.
    /// Precondition: below <= 30.
    float at(std::int64_t gx, std::int64_t gy, int below) const;
    /// out[j * width + i] += at(gx0 + i, gy0 + j, below) (bit for bit), only where mask[k] != 0 when a mask
    /// is given. Preconditions: out (and mask) hold width * height values.
    void add(std::int64_t gx0, std::int64_t gy0, int width, int height, int below, std::span<float> out,
             std::span<const std::uint8_t> mask = {}) const;

    /// The most the octaves k >= `from` can add anywhere in the leaf square [x0, x1] x [y0, y1] (leaf
    /// indices, inclusive, clamped to the grid) and around it as far as the interpolation reaches: sum of
    /// the largest a_k there (|P| <= 1). metres, >= 0.
    double bound(int from, int x0, int y0, int x1, int y1) const;
    /// bound() over the whole map.
    double bound(int from) const;
    /// The same over the rectangle [u0, u1] x [v0, v1] (samples of the finest static level, as lawAt), from
    /// the law there: log A and H are bilinear between leaf centres, so their extremes over the rectangle lie
    /// at its corners, where the centres' lines cross its edges, and at the centres inside it. At most
    /// bound() of the leaves it touches.
    double boundOver(int from, double u0, double v0, double u1, double v1) const;
    /// What the octaves a node does not have yet can add anywhere below it: boundOver() from its level below
    /// the leaves (0 above them) over its square. The node has sample spacing `spacing` and `cells` cells a
    /// side from global sample (firstX, firstY) of its level.
    double nodeBound(double spacing, std::int64_t firstX, std::int64_t firstY, int cells) const;
    /// How far the noise can lie inside each cell of a level (spacing `spacing`; the square: `cells` cells a
    /// side from global sample (firstX, firstY) of that level) from the template triangulation of its values at
    /// the level's samples, into out[j * cells + i] for cell (firstX + i, firstY + j): the octaves that vanish at
    /// those samples (k >= the level's levels below the leaves) up to their largest |P|, and those present
    /// there up to their interpolation error at the samples (tailWeight), each times its largest amplitude
    /// over the square (as boundOver). The octaves closest to the level's spacing are taken by the cell's own
    /// corner gradients (PerlinNoise::extremes' per-cell tables): the first two the samples lack (the cell,
    /// and its four cells of the next octave, up to their own peaks) and the two coarser ones they hold (their
    /// interpolation error in the part of their lattice cell the cell covers). metres, >= 0. Precondition: out
    /// holds cells^2 values.
    void cellTails(double spacing, std::int64_t firstX, std::int64_t firstY, int cells, std::span<float> out) const;

private:
    /// Sum over octaves k >= from of the largest c(H) 2^(-kH) for H in [lo, hi], times 1.01 (the curvature
    /// between calibration entries) and `amplitude`.
    double octaveSum(int from, double amplitude, double lo, double hi) const;
    /// Sum over every octave k of weight(k) x the largest c(H) 2^(-kH) for H in [lo, hi], times 1.01 and
    /// `amplitude`.
    template <typename Weight>
    double weightedOctaveSum(const Weight& weight, double amplitude, double lo, double hi) const;
    /// A level's square (cellTails' arguments): its levels below the leaves and the law's largest amplitude
    /// and exponents' range over it.
    struct SquareLaw {
        int below = 0;
        double amplitude = 0.0, lo = 0.0, hi = 0.0;
    };
    SquareLaw squareLaw(double spacing, std::int64_t firstX, std::int64_t firstY, int cells) const;
    /// Octave k's factor in the tail at samples `below` levels below the leaves: the noise's peak for an
    /// octave they lack (k >= below), its interpolation error at 2^(k - below) lattice cells for one they hold.
    static double tailWeight(int k, int below);
    /// The largest amplitude and the exponents' range of the law over the rectangle (as boundOver).
    void lawRange(double u0, double v0, double u1, double v1, double& amplitude, double& lo, double& hi) const;
    /// a_k at the interpolated law: c(H) A 2^(-k H), for k = 0 .. count - 1, into amplitudes.
    void amplitudes(double u, double v, int count, double* out) const;

    RoughnessGrid mGrid;
    int mLeafCells;
    double mDataSpacing;
    std::vector<PerlinNoise> mNoise;
    std::vector<double> mLogAmplitude;  ///< per leaf: log(max(A, tiny))
    std::vector<double> mCalibration;   ///< c(H) at kMinRoughnessExponent + i * kRoughnessCalibrationStep
};

/// Where the roughness octaves stop without materials: a metre (finer relief is the materials' business).
inline constexpr double kRoughnessFinestWavelength = 1.0;

/// The roughness synthesized below the leaves of the map with `header`: its RoughnessGrid, octaves from the
/// data's spacing down to the coarsest material wavelength (octave 0, where the materials' own octaves take
/// over), or to kRoughnessFinestWavelength without materials. Null when the map has no roughness block.
/// The one rule shared by the viewer, the height queries and prep's leaf errors.
std::shared_ptr<const RoughnessNoise> makeRoughnessNoise(const MapHeader& header, const MaterialSet* materials);

}  // namespace terrain
