// 2D gradient noise: Perlin's "improved noise" (SIGGRAPH 2002; "Texturing and Modeling" [6], ch. 2)
// with the quintic fade 6t^5 - 15t^4 + 10t^3, the basis function of the paper's fractals (3.3.3).
//
// Exact far from the origin: the lattice cell is split off as an integer in double arithmetic before
// anything is narrowed, so the noise at 500 km is as smooth and as detailed as at 0. Only the fraction
// in [0, 1] goes to float (6e-8 of a cell) together with its fade (computed in double, see fade()), and
// the per-cell gradient arithmetic runs in float: twice the SIMD lanes of double. cells() evaluates a
// batch of 64 cells vectorised (auto-vectorised SSE2, or AVX2 intrinsics chosen at run time), bit for bit
// the same as cell32() on each; Fractal's grids use it.
//
// The corner gradients come from a seed-keyed 32-bit hash of the cell instead of Perlin's 256-entry
// permutation (which repeats every 256 cells: a visible 12.8 km period at a 50 m base wavelength):
// h = ((ix * kMulX) ^ (iy * kMulY) ^ key) * kMix, whose top three bits pick one of eight gradients.
// One 32-bit multiply per corner and no table, so it vectorises (AVX2 vpmulld; SSE2 emulates it with
// pmuludq). Measured over 512^2 cells, the gradient choices of cells up to 16 apart in each direction are
// independent (chi-square of the 8 x 8 pair table at most 99 for 63 degrees of freedom over all 1088
// offsets; PerlinNoiseTest pins five of them). Cells are hashed on the low 32 bits of their index, so the
// noise repeats every 2^32 cells (1000 km at a 0.25 mm cell), and octaves at different frequencies and
// rotations never line up. An optional explicit period (for tabulated, tileable caches) wraps the cell
// index before hashing.
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <vector>

namespace terrain {

/// The instruction sets of the vectorised noise loops (PerlinNoise::cells, Fractal's grids). Every path
/// gives the same bits: the same IEEE operations in the same order, no FMA.
enum class SimdPath {
    Baseline,  ///< the build's baseline (x86-64: SSE2), auto-vectorised
    Avx2,      ///< x86-64 with AVX2: 256-bit vectors, the gradient picked by a lane permute
};

/// Whether this machine can run `path` (Baseline: always; Avx2: CPU and OS support it).
bool simdPathSupported(SimdPath path);
/// The fastest supported path: what the library uses unless told otherwise.
SimdPath bestSimdPath();

/// A batch of lattice samples in structure-of-arrays form, as Fractal's lattice split fills it: the low
/// 32 bits of the cell, the fraction rounded to float, and the fade of the double fraction (PerlinNoise::
/// fade). Aligned for 256-bit loads.
struct LatticeBatch {
    static constexpr int kSize = 64;  ///< a multiple of every vector width; about 2 KB, stays in L1
    alignas(32) std::uint32_t cellX[kSize];
    alignas(32) std::uint32_t cellY[kSize];
    alignas(32) float tx[kSize];
    alignas(32) float ty[kSize];
    alignas(32) float u[kSize];
    alignas(32) float v[kSize];
};

/// What the noise can do within one lattice cell, over every choice of its four corner gradients: the bounds
/// of synthesized detail take these instead of the |P| <= 1 that the gradients' scale guarantees.
struct GradientNoiseExtremes {
    /// Levels of sampling that `interpolation` holds (the finest: 2^-kLevels cells apart).
    static constexpr int kLevels = 4;
    /// The largest |P| anywhere.
    double peak = 1.0;
    /// interpolation[m - 1]: the largest distance between P and the template triangulation
    /// (quadtree/TemplateTriangulation.h) of its samples 2^-m cells apart, for m = 1 .. kLevels; at those
    /// samples' lattice-aligned grid every sample cell lies inside one lattice cell.
    std::array<double, kLevels> interpolation{};

    /// interpolation[m - 1] for m in [1, kLevels]; beyond, interpolation[kLevels - 1] x 4^(kLevels - m) x 2
    /// (the distance of a C2 function from its linear interpolant shrinks by 4 a halving of the spacing;
    /// twice that is the margin for the fade's higher derivatives, on terms that are this small). 0 for m <= 0
    /// (samples on the lattice or coarser: the triangles' corners are lattice points, where P is 0, but
    /// their insides are not) is not defined: precondition m >= 1.
    double interpolationAt(int m) const;

    /// Choices of a cell's four corner gradients: index g00 + 8 g10 + 64 g01 + 512 g11 (PerlinNoise::cellGradients).
    static constexpr int kCombinations = 8 * 8 * 8 * 8;
    /// Levels of sampling with per-cell tables (cellInterpolation).
    static constexpr int kCellLevels = 2;
    /// Per choice of corner gradients: the largest |P| in the cell.
    std::vector<float> cellPeak;
    /// cellInterpolation[m - 1][choice * 4^m + sy * 2^m + sx]: the largest distance of P from the triangulation of
    /// its samples 2^-m cells apart inside sample cell (sx, sy) of the lattice cell (0 the south-west one).
    std::array<std::vector<float>, kCellLevels> cellInterpolation;
};

class PerlinNoise {
public:
    /// Noise keyed by `seed`. `period` > 0 makes it tileable with that period in lattice cells (both
    /// axes); 0 means not periodic. Precondition: period >= 0.
    explicit PerlinNoise(std::uint64_t seed, std::int64_t period = 0);

    /// The noise at (x, y) in lattice units (one cell = 1), |x|, |y| < 2^62. Range: [-1, 1] (2D gradient
    /// noise with unit gradients is bounded by sqrt(2)/2; the gradients are scaled by sqrt(2)); zero at
    /// every lattice point; C2 (quintic fade). Standard deviation about 0.30. A float value returned as
    /// double. Deterministic: the same (seed, period, x, y) gives the same bits on every thread and
    /// machine with IEEE arithmetic (compiled with -ffp-contract=off, see CMakeLists.txt).
    double operator()(double x, double y) const
    {
        std::int64_t ix = floorToInt(x);
        std::int64_t iy = floorToInt(y);
        return cell(ix, iy, x - static_cast<double>(ix), y - static_cast<double>(iy));
    }

    /// floor(x) as an integer, |x| < 2^62. A truncating conversion and a compare: std::floor is a libm
    /// call on baseline x86-64 (no SSE4.1 roundsd) and cost a third of the noise.
    static std::int64_t floorToInt(double x)
    {
        auto i = static_cast<std::int64_t>(x);
        return x < static_cast<double>(i) ? i - 1 : i;
    }

    /// The noise in cell (ix, iy) at fraction (tx, ty) in [0, 1]: the form that keeps large coordinates
    /// exact. operator() is cell(floor(x), floor(y), x - floor(x), y - floor(y)).
    float cell(std::int64_t ix, std::int64_t iy, double tx, double ty) const
    {
        const auto fx = static_cast<float>(tx);
        const auto fy = static_cast<float>(ty);
        if (mPeriod <= 0) {
            return cell32(static_cast<std::uint32_t>(ix), static_cast<std::uint32_t>(iy), fx, fy, fade(tx), fade(ty));
        }
        ix = wrap(ix);
        iy = wrap(iy);
        std::int64_t ix1 = ix + 1 == mPeriod ? 0 : ix + 1;
        std::int64_t iy1 = iy + 1 == mPeriod ? 0 : iy + 1;
        std::uint32_t hy0 = static_cast<std::uint32_t>(iy) * kMulY ^ mKey;
        std::uint32_t hy1 = static_cast<std::uint32_t>(iy1) * kMulY ^ mKey;
        return blend(static_cast<std::uint32_t>(ix) * kMulX, static_cast<std::uint32_t>(ix1) * kMulX, hy0, hy1, fx, fy,
                     fade(tx), fade(ty));
    }

    /// Perlin's fade 6t^5 - 15t^4 + 10t^3 of a fraction t in [0, 1], evaluated in double and rounded to
    /// float. In float, Horner's form loses 20 ulps to cancellation near t = 1 (1e-6: it showed in second
    /// differences, PerlinNoiseTest). fade(0) = 0 and fade(1) = 1 exactly.
    [[gnu::always_inline]] static float fade(double t)
    {
        return static_cast<float>(t * t * t * (t * (t * 6.0 - 15.0) + 10.0));
    }

    /// cell() of a non-periodic noise from the low 32 bits of the cell index (all the hash uses), the
    /// fraction (tx, ty) rounded to float and its fades (u, v) = (fade(tx), fade(ty)) from the double
    /// fraction: the inner loop of Fractal's grids, written so that a loop over it vectorises.
    /// Precondition: period() == 0.
    [[gnu::always_inline]] float cell32(std::uint32_t ix, std::uint32_t iy, float tx, float ty, float u, float v) const
    {
        std::uint32_t hx0 = ix * kMulX;
        std::uint32_t hy0 = iy * kMulY;
        // (i + 1) * k == i * k + k modulo 2^32: the next corner's hash without a second multiply.
        return blend(hx0, hx0 + kMulX, hy0 ^ mKey, (hy0 + kMulY) ^ mKey, tx, ty, u, v);
    }

    /// out[k] = cell32(batch.cellX[k], ..., batch.v[k]) for every k of the batch, bit for bit, on the given
    /// instruction set path. Precondition: period() == 0, simdPathSupported(path).
    void cells(const LatticeBatch& batch, float (&out)[LatticeBatch::kSize], SimdPath path) const;

    std::uint64_t seed() const { return mSeed; }
    std::int64_t period() const { return mPeriod; }

    /// The choice of corner gradients of lattice cell (ix, iy) (GradientNoiseExtremes::kCombinations; its
    /// index in the extremes' per-cell tables). Precondition: period() == 0.
    int cellGradients(std::int64_t ix, std::int64_t iy) const
    {
        const std::uint32_t hx0 = static_cast<std::uint32_t>(ix) * kMulX, hx1 = hx0 + kMulX;
        const std::uint32_t hy = static_cast<std::uint32_t>(iy) * kMulY;
        const std::uint32_t hy0 = hy ^ mKey, hy1 = (hy + kMulY) ^ mKey;
        auto index = [](std::uint32_t x, std::uint32_t y) { return static_cast<int>(((x ^ y) * kMix) >> 29); };
        return index(hx0, hy0) | index(hx1, hy0) << 3 | index(hx0, hy1) << 6 | index(hx1, hy1) << 9;
    }

    /// The noise's extremes over every cell (every one of the 8^4 choices of corner gradients): measured once,
    /// on first use (about 0.2 s), on a grid of 1/64 of a cell, plus the most a C2 function can exceed its
    /// grid maximum between the grid's points (PerlinNoiseTest checks them against a finer grid and the
    /// noise itself). Thread-safe; the same for every seed and period.
    static const GradientNoiseExtremes& extremes();

private:
    void cellsBaseline(const LatticeBatch& batch, float (&out)[LatticeBatch::kSize]) const;
    void cellsAvx2(const LatticeBatch& batch, float (&out)[LatticeBatch::kSize]) const;

    static constexpr std::uint32_t kMulX = 0x9E3779B1u;  // odd constants of xxhash32 / Knuth's golden ratio
    static constexpr std::uint32_t kMulY = 0x85EBCA77u;
    static constexpr std::uint32_t kMix = 0xC2B2AE3Du;
    static constexpr std::uint32_t kSign = 0x80000000u;
    /// The gradients: eight unit vectors 45 degrees apart at 22.5 + 45 k degrees, i.e. (+-c, +-s) and
    /// (+-s, +-c) with c = cos 22.5, s = sin 22.5, scaled by sqrt(2) so the output bound is 1. Built from
    /// the hash bits with integer operations on the float bit patterns: a table lookup would be a gather in
    /// an auto-vectorised loop (the AVX2 path permutes an 8-entry table of the same floats instead).
    static constexpr float kGradC = 1.30656296f;   // sqrt(2) cos(pi / 8)
    static constexpr float kGradS = 0.541196100f;  // sqrt(2) sin(pi / 8)
    static constexpr std::uint32_t kGradCBits = std::bit_cast<std::uint32_t>(kGradC);
    static constexpr std::uint32_t kGradSwap =
        std::bit_cast<std::uint32_t>(kGradC) ^ std::bit_cast<std::uint32_t>(kGradS);

    /// Dot product of the gradient of the corner with hash (hx ^ hy) with the offset (dx, dy).
    [[gnu::always_inline]] static float grad(std::uint32_t hx, std::uint32_t hy, float dx, float dy)
    {
        std::uint32_t h = (hx ^ hy) * kMix;  // top bits: well mixed
        // Bit 29 swaps the components, bits 30 and 31 are their signs.
        std::uint32_t swap = kGradSwap & static_cast<std::uint32_t>(static_cast<std::int32_t>(h << 2) >> 31);
        float gx = std::bit_cast<float>((kGradCBits ^ swap) | ((h << 1) & kSign));
        float gy = std::bit_cast<float>((kGradCBits ^ kGradSwap ^ swap) | (h & kSign));
        return gx * dx + gy * dy;
    }

    /// The gradient noise of one cell from the hashed corner coordinates. The interpolation is written
    /// (1 - u) a + u b, not a + u (b - a): it returns a and b exactly at u = 0 and 1, so neighbouring cells
    /// agree bit for bit on their shared border.
    [[gnu::always_inline]] static float blend(std::uint32_t hx0, std::uint32_t hx1, std::uint32_t hy0,
                                              std::uint32_t hy1, float tx, float ty, float u, float v)
    {
        float n00 = grad(hx0, hy0, tx, ty);
        float n10 = grad(hx1, hy0, tx - 1.0f, ty);
        float n01 = grad(hx0, hy1, tx, ty - 1.0f);
        float n11 = grad(hx1, hy1, tx - 1.0f, ty - 1.0f);
        float a = (1.0f - u) * n00 + u * n10;
        float b = (1.0f - u) * n01 + u * n11;
        return (1.0f - v) * a + v * b;
    }

    std::int64_t wrap(std::int64_t i) const
    {
        std::int64_t r = i % mPeriod;
        return r < 0 ? r + mPeriod : r;
    }

    std::uint64_t mSeed;
    std::uint32_t mKey;
    std::int64_t mPeriod;
};

}  // namespace terrain
