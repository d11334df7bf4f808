// Displacement functions of the detail synthesis (paper 3.3.1, 3.3.3): fBm and Musgrave's ridged
// multifractal ("Texturing and Modeling" [6], ch. 16) over a basis function: Perlin gradient noise or a
// tileable bitmap. With the paper's two speed-ups as options: a cached basis (the noise tabulated once
// and interpolated) and a cached fractal (the whole fractal tabulated over a tile and interpolated).
//
// The value depends only on the world position (x, y) in metres, given as double, so every node,
// level and thread that asks for the same point gets the same bits (3.3.1, "the same area ... calculated
// several times with the same result"), and stays exact hundreds of km from the origin: each octave's
// lattice coordinate is computed and split into cell and fraction in double; the noise inside the cell
// and the octave sum run in float.
//
// The exact Perlin fractal of a grid is evaluated in batches of 64 samples (any rows, only the masked
// ones), octave by octave: the lattice split in double (a loop the compiler vectorises), the noise of the
// 64 cells in float (PerlinNoise::cells), the fBm or ridged update in float. Two builds of it: baseline
// (SSE2) and AVX2, chosen at run time. Every path and the point form do the same IEEE operations in the
// same order (no FMA: -ffp-contract=off), so they agree bit for bit. tests/bench/FractalBench, 69 x 69
// samples, 8 octaves, 500 km out, one thread of a 2-core AMD EPYC (Zen 3, 2.45 GHz), best of 1500 runs:
// the scalar double code before took 455 us (fBm) / 538 us (ridged); now 96 / 101 us with AVX2 and
// 305 / 315 us on the SSE2 baseline (2-lane doubles and emulated 32-bit multiplies).
#pragma once

#include "synthesis/PerlinNoise.h"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace terrain {

struct Image;

enum class FractalType {
    Fbm,     ///< sum of gain^i * basis(lacunarity^i * p), [6] "fBm"
    Ridged,  ///< Musgrave's ridged multifractal: (offset - |basis|)^2, each octave weighted by the last
};

/// The paper's speed-ups (3.3.3, "Real-time Fractals"). Errors measured in FractalTest, costs in FractalBench
/// (69 x 69 window, 8 octaves, AVX2 machine): exact 96 us (fBm) / 101 us (ridged), cached basis 310 / 390 us,
/// cached fractal 39 us. Since the exact path is vectorised, the cached basis is no longer a speed-up.
enum class FractalCache {
    None,     ///< exact: the basis evaluated for every octave of every sample
    Basis,    ///< Perlin basis tabulated (kCachedBasisPeriod cells, kCachedBasisSamplesPerCell per cell),
              ///< bilinear: |error| <= kCachedBasisMaxError{Fbm,Ridged} * amplitude. No effect on a
              ///< bitmap basis (already a table).
    Fractal,  ///< a tileable version of the fractal (no octave rotation, whole cells per tile) tabulated
              ///< over kCachedFractalTileWavelengths base wavelengths, bilinear: |error| <=
              ///< kCachedFractalMaxError{Fbm,Ridged} * amplitude against that tileable fractal; the
              ///< surface repeats every tile.
};

/// Cached basis: period of the tabulated noise in lattice cells (each octave is rotated and offset, so
/// the repetition does not line up between octaves) and samples per cell: 256 x 256 floats = 256 KB,
/// which stays in L2. 8 samples per cell over 32 cells had 4x the error for the same size.
inline constexpr int kCachedBasisPeriod = 16;
inline constexpr int kCachedBasisSamplesPerCell = 16;
/// Bilinear interpolation error of the cached basis relative to the amplitude, against the same fractal
/// over the exact periodic noise (Fractal::uncachedValue), 8 octaves, lacunarity 2, gain 0.5, 10^5
/// points: measured max 0.0058 (fBm) and 0.0248 (ridged: squaring and feedback amplify the basis
/// error); pinned with margin.
inline constexpr double kCachedBasisMaxErrorFbm = 0.01;
inline constexpr double kCachedBasisMaxErrorRidged = 0.04;
/// Cached fractal: tile size in base wavelengths, and table samples per cell of the finest octave.
inline constexpr int kCachedFractalTileWavelengths = 4;
inline constexpr int kCachedFractalSamplesPerFinestCell = 2;
/// Largest table side: 2048^2 floats = 16 MB per material; more octaves than fit are cut off.
inline constexpr int kCachedFractalMaxTable = 2048;
/// Interpolation error of the cached fractal relative to the amplitude, against the exact tileable
/// fractal, same setting: measured max 0.0025 (fBm) and 0.0154 (ridged); pinned with margin. The finest
/// octave is smoothed (2 samples per cell), and the surface repeats every tile.
inline constexpr double kCachedFractalMaxErrorFbm = 0.005;
inline constexpr double kCachedFractalMaxErrorRidged = 0.03;

/// The sample positions of a node window (or any regular grid): sample (i, j), i < width, j < height, lies
/// at world x = originX + double(gx0 + i) * spacing, y = originY + double(gy0 + j) * spacing metres. The
/// same expression for the same global sample index in every node makes neighbouring nodes agree bit for
/// bit; and since a child's spacing is its parent's halved (exact) and its indices doubled, a parent
/// sample and the child sample on top of it get the same position too.
struct SampleGrid {
    double originX = 0.0;
    double originY = 0.0;
    std::int64_t gx0 = 0;
    std::int64_t gy0 = 0;
    double spacing = 1.0;  ///< > 0
    int width = 0;         ///< >= 0
    int height = 0;        ///< >= 0

    double x(int i) const { return originX + static_cast<double>(gx0 + i) * spacing; }
    double y(int j) const { return originY + static_cast<double>(gy0 + j) * spacing; }
    std::size_t count() const { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
};

struct FractalParams {
    FractalType type = FractalType::Fbm;
    int octaves = 8;             ///< number of basis samples summed, [1, 24]
    double lacunarity = 2.0;     ///< frequency ratio between successive octaves, [1.1, 8]
    double gain = 0.5;           ///< amplitude ratio between successive octaves, (0, 1]
    double wavelength = 32.0;    ///< metres: a lattice cell (Perlin) or one bitmap tile at octave 0, > 0
    double amplitude = 1.0;      ///< metres: every value lies in [-amplitude, amplitude], >= 0
    std::uint64_t seed = 1;      ///< picks the noise and each octave's rotation and offset
    double ridgeOffset = 1.0;    ///< ridged: Musgrave's offset, [0.5, 1.5]; 1 puts the ridges at basis 0
    double ridgeFeedback = 2.0;  ///< ridged: Musgrave's gain, how much a low octave damps the next, [0, 8]
    FractalCache cache = FractalCache::None;
};

/// Checks the ranges documented on FractalParams; returns an empty string or what is wrong.
std::string validateFractalParams(const FractalParams& params);

/// A tileable grid of basis values in [-1, 1], sampled with wrap-around. One unit of the sampling
/// coordinates covers texelsPerUnit texels.
class BasisTable {
public:
    enum class Filter { Bilinear, Bicubic };  ///< bicubic is Catmull-Rom (C1), clamped to [-1, 1]

    /// Takes `values` (width * height, row-major). Preconditions: width, height > 0, sizes agree.
    BasisTable(int width, int height, std::vector<float> values, double texelsPerUnit, Filter filter);
    /// A gray image (1 channel) as a basis: 0 -> -1, 255 -> 1; one unit = the whole image (texelsPerUnit =
    /// width; the image must be square). Preconditions: channels == 1, width == height > 0.
    static BasisTable fromImage(const Image& gray, Filter filter = Filter::Bicubic);
    /// A periodic noise tabulated at `samplesPerCell` per lattice cell over its period, bilinear.
    /// Preconditions: noise.period() > 0, samplesPerCell > 0.
    static BasisTable fromNoise(const PerlinNoise& noise, int samplesPerCell);

    /// The interpolated value at (u, v) units; any finite u, v (wraps).
    double operator()(double u, double v) const;

    int width() const { return mWidth; }
    int height() const { return mHeight; }
    const std::vector<float>& values() const { return mValues; }

private:
    float at(std::int64_t x, std::int64_t y) const;  ///< x, y already wrapped
    /// i mod size in [0, size); a mask (size - 1) for powers of two, else -1 and a division.
    static std::int64_t wrap(std::int64_t i, int size, std::int64_t mask);

    int mWidth;
    int mHeight;
    std::vector<float> mValues;
    double mTexelsPerUnit;
    Filter mFilter;
    std::int64_t mMaskX = -1;
    std::int64_t mMaskY = -1;
};

/// A displacement function: the fractal of FractalParams over a Perlin or bitmap basis. Immutable after
/// construction, so one instance may be evaluated from any number of threads.
class Fractal {
public:
    /// Perlin basis. Precondition: validateFractalParams(params) is empty.
    explicit Fractal(const FractalParams& params);
    /// Bitmap basis: `bitmap` (from BasisTable::fromImage) spans one base wavelength and repeats.
    /// Preconditions: as above, bitmap not null.
    Fractal(const FractalParams& params, std::shared_ptr<const BasisTable> bitmap);

    /// Displacement in metres at world (x, y) metres; in [-amplitude, amplitude].
    double operator()(double x, double y) const;

    /// Fills out[j * width + i] = float((*this)(grid.x(i), grid.y(j))): bit-identical to the point form.
    /// With a non-empty `mask` (grid.count() entries) only samples with mask[k] != 0 are written; the rest
    /// of `out` is left as it was. Preconditions: grid valid (SampleGrid), out.size() >= grid.count().
    /// Exact Perlin fractals (FractalCache::None) run vectorised on bestSimdPath(); a lattice coordinate of
    /// 2^30 cells or more (far beyond any terrain) falls back to the point form, sample by sample.
    void evaluateGrid(const SampleGrid& grid, std::span<float> out, std::span<const std::uint8_t> mask = {}) const;
    /// evaluateGrid on a given instruction set path, for the tests and benchmarks that compare them: the
    /// same bits on every path. Precondition: simdPathSupported(path).
    void evaluateGrid(const SampleGrid& grid, std::span<float> out, std::span<const std::uint8_t> mask,
                      SimdPath path) const;

    /// The function a cache approximates, evaluated exactly (metres): the fractal over the periodic noise
    /// for a cached basis, the tileable fractal for a cached fractal, else (*this)(x, y). The reference
    /// of kCachedBasisMaxError and kCachedFractalMaxError; slow, for tests.
    double uncachedValue(double x, double y) const;
    /// Cached fractal only: the tile size in metres (the surface repeats with this period), else 0.
    double tileSize() const { return mTileSize; }

    const FractalParams& params() const { return mParams; }

private:
    friend struct FractalKernels;  // the vectorised exact path (Fractal.cpp)

    /// Per-octave transform from world metres to basis units: u = cu * x - su * y + ou, v = su * x + cu * y + ov.
    struct Octave {
        double cu, su, ou, ov;
        double weight;      ///< gain^i, for the cached and tileable sums (double)
        float exactWeight;  ///< gain^i in float, for the exact Perlin sum (float)
    };
    template <class Basis>
    double sum(const std::vector<Octave>& octaves, double x, double y, const Basis& basis) const;
    double tileSum(double u, double v) const;
    template <class Basis>
    void grid(const SampleGrid& grid, std::span<float> out, std::span<const std::uint8_t> mask,
              const Basis& basis) const;
    void buildCachedFractal();
    /// The exact Perlin fractal at (x, y): the point form of the vectorised grid path.
    double exactValue(double x, double y) const;
    /// Whether every lattice coordinate of every octave over `grid` stays below 2^30 cells, so the
    /// vectorised path may split it with a 32-bit conversion. Precondition: grid not empty.
    bool fitsVectorPath(const SampleGrid& grid) const;
    void exactGrid(const SampleGrid& grid, std::span<float> out, std::span<const std::uint8_t> mask,
                   SimdPath path) const;

    FractalParams mParams;
    PerlinNoise mNoise;
    PerlinNoise mPeriodicNoise;  ///< the noise a cached basis tabulates
    std::vector<Octave> mOctaves;
    double mScale = 1.0;  ///< maps the raw sum to [-amplitude, amplitude] (see Fractal.cpp)
    double mOffset = 0.0;
    std::shared_ptr<const BasisTable> mTable;         ///< bitmap or cached basis; null for exact Perlin
    std::vector<PerlinNoise> mTileNoise;              ///< cached fractal: one periodic noise per octave
    std::vector<Octave> mTileOctaves;                 ///< cached fractal: transforms from tile units
    std::shared_ptr<const BasisTable> mFractalTable;  ///< cached fractal, in tile units
    double mTileSize = 0.0;                           ///< cached fractal: metres per tile
};

}  // namespace terrain
