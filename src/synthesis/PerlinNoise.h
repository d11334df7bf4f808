// 2D gradient noise: Perlin's "improved noise" (SIGGRAPH 2002; "Texturing and Modeling" [6], ch. 2)
// with the quintic fade 6t^5 - 15t^4 + 10t^3, the basis function of the paper's fractals (3.3.3).
//
// Exact far from the origin: the lattice cell is split off as an int64 before any arithmetic on the
// fraction, so the noise at 500 km is as smooth and as detailed as at 0 (only the double input itself
// limits precision: 2^-52 relative, 1e-10 m at 500 km). The corner gradients come from a seed-keyed
// 64-bit hash of the cell instead of Perlin's 256-entry permutation: the permutation repeats every 256
// cells, which at a 50 m base wavelength is a visible 12.8 km period. An optional explicit period
// (for tabulated, tileable caches) wraps the cell index before hashing.
#pragma once

#include <cmath>
#include <cstdint>

namespace terrain {

class PerlinNoise {
public:
    /// Noise keyed by `seed`. `period` > 0 makes it tileable with that period in lattice cells (both
    /// axes); 0 means not periodic. Precondition: period >= 0.
    explicit PerlinNoise(std::uint64_t seed, std::int64_t period = 0);

    /// The noise at (x, y) in lattice units (one cell = 1), |x|, |y| < 2^62. Range: [-1, 1] (the bound
    /// of 2D gradient noise with unit gradients is sqrt(2)/2, reached at a cell centre; the output is
    /// scaled by sqrt(2)); zero at every lattice point; C2 (quintic fade). Standard deviation about 0.27.
    /// Deterministic: the same (seed, period, x, y) gives the same bits on every thread and machine
    /// that rounds IEEE doubles the same way (compiled with -ffp-contract=off, see CMakeLists.txt).
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

    /// The noise in cell (ix, iy) at fraction (tx, ty) in [0, 1]: the form that keeps large
    /// coordinates exact. operator() is cell(floor(x), floor(y), x - floor(x), y - floor(y)).
    double cell(std::int64_t ix, std::int64_t iy, double tx, double ty) const
    {
        if (mPeriod > 0) {
            ix = wrap(ix);
            iy = wrap(iy);
        }
        std::int64_t ix1 = ix + 1;
        std::int64_t iy1 = iy + 1;
        if (mPeriod > 0) {
            ix1 = ix1 == mPeriod ? 0 : ix1;
            iy1 = iy1 == mPeriod ? 0 : iy1;
        }
        std::uint64_t hx0 = static_cast<std::uint64_t>(ix) * kMulX;
        std::uint64_t hx1 = static_cast<std::uint64_t>(ix1) * kMulX;
        std::uint64_t hy0 = static_cast<std::uint64_t>(iy) * kMulY ^ mKey;
        std::uint64_t hy1 = static_cast<std::uint64_t>(iy1) * kMulY ^ mKey;
        double n00 = grad(hx0 ^ hy0, tx, ty);
        double n10 = grad(hx1 ^ hy0, tx - 1.0, ty);
        double n01 = grad(hx0 ^ hy1, tx, ty - 1.0);
        double n11 = grad(hx1 ^ hy1, tx - 1.0, ty - 1.0);
        double u = fade(tx);
        double v = fade(ty);
        double a = n00 + u * (n10 - n00);
        double b = n01 + u * (n11 - n01);
        return a + v * (b - a);
    }

    std::uint64_t seed() const { return mSeed; }
    std::int64_t period() const { return mPeriod; }

private:
    static constexpr std::uint64_t kMulX = 0x9E3779B97F4A7C15ull;  // odd constants of splitmix64/xxhash
    static constexpr std::uint64_t kMulY = 0xC2B2AE3D27D4EB4Full;
    static constexpr std::uint64_t kMix = 0xD6E8FEB86659FD93ull;

    static double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

    /// Dot product of the corner's gradient with the offset (dx, dy). Eight unit gradients 45 degrees
    /// apart, pre-scaled by sqrt(2) so the output bound is 1.
    static double grad(std::uint64_t h, double dx, double dy)
    {
        h ^= h >> 29;
        h *= kMix;
        h ^= h >> 32;
        const double* g = kGradients[h & 7u];
        return g[0] * dx + g[1] * dy;
    }

    std::int64_t wrap(std::int64_t i) const
    {
        std::int64_t r = i % mPeriod;
        return r < 0 ? r + mPeriod : r;
    }

    static const double kGradients[8][2];

    std::uint64_t mSeed;
    std::uint64_t mKey;
    std::int64_t mPeriod;
};

}  // namespace terrain
