// Improved Perlin noise in 2D (Perlin 2002; [6] ch. 2), keyed by a seed; see PerlinNoise.h.
#include "synthesis/PerlinNoise.h"

#include "core/Check.h"
#include "quadtree/TemplateTriangulation.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <vector>

#if defined(__x86_64__)
#define TERRAIN_X86 1
#include <immintrin.h>
#else
#define TERRAIN_X86 0
#endif

namespace terrain {

namespace {

/// splitmix64's finaliser: turns consecutive seeds into unrelated keys.
std::uint64_t mixSeed(std::uint64_t z)
{
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
}  // namespace

PerlinNoise::PerlinNoise(std::uint64_t seed, std::int64_t period)
    : mSeed(seed), mKey(static_cast<std::uint32_t>(mixSeed(seed) >> 32)), mPeriod(period)
{
    TERRAIN_EXPECTS(period >= 0, "the noise period must be 0 (none) or a positive number of lattice cells");
}

bool simdPathSupported(SimdPath path)
{
    if (path == SimdPath::Baseline) {
        return true;
    }
#if TERRAIN_X86
    // Asked once (a thread-safe local static, constant afterwards). __builtin_cpu_init makes the query safe
    // even before libgcc's constructor ran; libgcc also checks that the OS saves the YMM registers.
    static const bool kAvx2 = [] {
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx2") != 0;
    }();
    return kAvx2;
#else
    return false;
#endif
}

double GradientNoiseExtremes::interpolationAt(int m) const
{
    TERRAIN_EXPECTS(m >= 1, "the samples must be finer than the lattice");
    if (m <= kLevels) {
        return interpolation[static_cast<std::size_t>(m - 1)];
    }
    return 2.0 * interpolation[kLevels - 1] * std::ldexp(1.0, 2 * (kLevels - m));
}

const GradientNoiseExtremes& PerlinNoise::extremes()
{
    static const GradientNoiseExtremes kExtremes = [] {
        // The gradients as grad() assembles them from the hash's top three bits.
        double gradX[8], gradY[8];
        for (std::uint32_t i = 0; i < 8; ++i) {
            const std::uint32_t h = i << 29;
            const std::uint32_t swap = kGradSwap & static_cast<std::uint32_t>(static_cast<std::int32_t>(h << 2) >> 31);
            gradX[i] = std::bit_cast<float>((kGradCBits ^ swap) | ((h << 1) & kSign));
            gradY[i] = std::bit_cast<float>((kGradCBits ^ kGradSwap ^ swap) | (h & kSign));
        }
        constexpr int kSteps = 64;  // grid points a cell side, minus one
        constexpr int kSide = kSteps + 1;
        constexpr double kH = 1.0 / kSteps;
        double fades[kSide];
        for (int i = 0; i < kSide; ++i) {
            fades[i] = static_cast<double>(fade(i * kH));
        }
        GradientNoiseExtremes out;
        out.peak = 0.0;
        out.interpolation.fill(0.0);
        out.cellPeak.assign(GradientNoiseExtremes::kCombinations, 0.0f);
        for (int m = 1; m <= GradientNoiseExtremes::kCellLevels; ++m) {
            out.cellInterpolation[static_cast<std::size_t>(m - 1)].assign(
                static_cast<std::size_t>(GradientNoiseExtremes::kCombinations) << (2 * m), 0.0f);
        }
        double curvature = 0.0;  // the largest second difference over h^2, any direction of the grid
        std::vector<double> p(static_cast<std::size_t>(kSide) * kSide);
        auto at = [&](int i, int j) { return p[static_cast<std::size_t>(j) * kSide + i]; };
        for (int c = 0; c < GradientNoiseExtremes::kCombinations; ++c) {
            const int g00 = c & 7, g10 = (c >> 3) & 7, g01 = (c >> 6) & 7, g11 = (c >> 9) & 7;
            for (int j = 0; j < kSide; ++j) {
                const double ty = j * kH, v = fades[j];
                for (int i = 0; i < kSide; ++i) {
                    const double tx = i * kH, u = fades[i];
                    const double n00 = gradX[g00] * tx + gradY[g00] * ty;
                    const double n10 = gradX[g10] * (tx - 1.0) + gradY[g10] * ty;
                    const double n01 = gradX[g01] * tx + gradY[g01] * (ty - 1.0);
                    const double n11 = gradX[g11] * (tx - 1.0) + gradY[g11] * (ty - 1.0);
                    const double value = (1.0 - v) * ((1.0 - u) * n00 + u * n10) + v * ((1.0 - u) * n01 + u * n11);
                    p[static_cast<std::size_t>(j) * kSide + i] = value;
                    out.peak = std::max(out.peak, std::abs(value));
                }
            }
            for (int j = 1; j + 1 < kSide; ++j) {
                for (int i = 1; i + 1 < kSide; ++i) {
                    const double centre = 2.0 * at(i, j);
                    curvature = std::max({curvature, std::abs(at(i - 1, j) + at(i + 1, j) - centre),
                                          std::abs(at(i, j - 1) + at(i, j + 1) - centre),
                                          0.5 * std::abs(at(i - 1, j - 1) + at(i + 1, j + 1) - centre),
                                          0.5 * std::abs(at(i - 1, j + 1) + at(i + 1, j - 1) - centre)});
                }
            }
            double cellPeak = 0.0;
            for (double v : p) {
                cellPeak = std::max(cellPeak, std::abs(v));
            }
            out.cellPeak[static_cast<std::size_t>(c)] = static_cast<float>(cellPeak);
            for (int m = 1; m <= GradientNoiseExtremes::kLevels; ++m) {
                const int split = 1 << m, step = kSteps >> m;  // sample cells a side, grid points a sample cell
                double& worst = out.interpolation[static_cast<std::size_t>(m - 1)];
                for (int sy = 0; sy < split; ++sy) {
                    for (int sx = 0; sx < split; ++sx) {
                        const int i0 = sx * step, j0 = sy * step;
                        double cellWorst = 0.0;
                        for (int b = 0; b <= step; ++b) {
                            for (int a = 0; a <= step; ++a) {
                                const double surface =
                                    interpolateQuad(at(i0, j0), at(i0 + step, j0), at(i0, j0 + step),
                                                    at(i0 + step, j0 + step), double(a) / step, double(b) / step);
                                cellWorst = std::max(cellWorst, std::abs(at(i0 + a, j0 + b) - surface));
                            }
                        }
                        worst = std::max(worst, cellWorst);
                        if (m <= GradientNoiseExtremes::kCellLevels) {
                            out.cellInterpolation[static_cast<std::size_t>(m - 1)]
                                                 [static_cast<std::size_t>(c) * split * split + sy * split + sx] =
                                static_cast<float>(cellWorst);
                        }
                    }
                }
            }
        }
        // Between the grid's points a function exceeds its largest grid value by at most M2 d^2 / 2, d the
        // distance to the nearest grid point (<= h / sqrt 2) and M2 its largest second derivative, here
        // estimated from the second differences with a margin of 1.5. The interpolation error's second
        // derivative is the noise's (the triangles are linear).
        // With M2 = curvature / h^2 and d^2 = h^2 / 2: M2 d^2 / 2 = curvature / 4.
        const double slack = 1.5 * curvature / 4.0;
        out.peak += slack;
        for (double& e : out.interpolation) {
            e += slack;
        }
        for (float& e : out.cellPeak) {
            e = static_cast<float>(e + slack);
        }
        for (auto& table : out.cellInterpolation) {
            for (float& e : table) {
                e = static_cast<float>(e + slack);
            }
        }
        return out;
    }();
    return kExtremes;
}

SimdPath bestSimdPath()
{
    return simdPathSupported(SimdPath::Avx2) ? SimdPath::Avx2 : SimdPath::Baseline;
}

void PerlinNoise::cells(const LatticeBatch& batch, float (&out)[LatticeBatch::kSize], SimdPath path) const
{
    TERRAIN_EXPECTS(mPeriod == 0, "the batched noise is the non-periodic one");
#if TERRAIN_X86
    if (path == SimdPath::Avx2) {
        cellsAvx2(batch, out);
        return;
    }
#endif
    (void)path;
    cellsBaseline(batch, out);
}

void PerlinNoise::cellsBaseline(const LatticeBatch& batch, float (&out)[LatticeBatch::kSize]) const
{
    // A plain loop over cell32: GCC vectorises it (SSE2: 4 lanes; the 32-bit multiplies are emulated).
    alignas(32) float result[LatticeBatch::kSize];
    for (int k = 0; k < LatticeBatch::kSize; ++k) {
        result[k] = cell32(batch.cellX[k], batch.cellY[k], batch.tx[k], batch.ty[k], batch.u[k], batch.v[k]);
    }
    std::copy(std::begin(result), std::end(result), std::begin(out));
}

#if TERRAIN_X86
namespace {
/// grad() on 8 lanes: the corner hash's top three bits index the gradient tables (gx, gy).
[[gnu::target("avx2"), gnu::always_inline]] inline __m256 grad8(__m256i hx, __m256i hy, __m256 dx, __m256 dy,
                                                                __m256i mix, __m256 gx, __m256 gy)
{
    __m256i index = _mm256_srli_epi32(_mm256_mullo_epi32(_mm256_xor_si256(hx, hy), mix), 29);
    __m256 px = _mm256_mul_ps(_mm256_permutevar8x32_ps(gx, index), dx);
    __m256 py = _mm256_mul_ps(_mm256_permutevar8x32_ps(gy, index), dy);
    return _mm256_add_ps(px, py);
}
}  // namespace

/// cell32 on 8 lanes, written out: the same operations in the same order as blend() and grad(), except
/// that each corner's gradient comes from an 8-entry table by a lane permute (vpermps) of its top three
/// hash bits instead of being assembled from them bit by bit. The table holds exactly the floats grad()
/// assembles, so the products and sums are the same. SimdPathsGiveTheSameBits (FractalTest) checks it.
[[gnu::target("avx2")]] void PerlinNoise::cellsAvx2(const LatticeBatch& batch, float (&out)[LatticeBatch::kSize]) const
{
    alignas(32) float tableX[8];
    alignas(32) float tableY[8];
    for (std::uint32_t i = 0; i < 8; ++i) {
        std::uint32_t h = i << 29;  // the bits grad() reads
        std::uint32_t swap = kGradSwap & static_cast<std::uint32_t>(static_cast<std::int32_t>(h << 2) >> 31);
        tableX[i] = std::bit_cast<float>((kGradCBits ^ swap) | ((h << 1) & kSign));
        tableY[i] = std::bit_cast<float>((kGradCBits ^ kGradSwap ^ swap) | (h & kSign));
    }
    const __m256 gx = _mm256_load_ps(tableX);
    const __m256 gy = _mm256_load_ps(tableY);
    const __m256i mulX = _mm256_set1_epi32(static_cast<int>(kMulX));
    const __m256i mulY = _mm256_set1_epi32(static_cast<int>(kMulY));
    const __m256i mix = _mm256_set1_epi32(static_cast<int>(kMix));
    const __m256i key = _mm256_set1_epi32(static_cast<int>(mKey));
    const __m256 one = _mm256_set1_ps(1.0f);
    for (int k = 0; k < LatticeBatch::kSize; k += 8) {
        __m256i ix = _mm256_load_si256(reinterpret_cast<const __m256i*>(batch.cellX + k));
        __m256i iy = _mm256_load_si256(reinterpret_cast<const __m256i*>(batch.cellY + k));
        __m256 tx = _mm256_load_ps(batch.tx + k);
        __m256 ty = _mm256_load_ps(batch.ty + k);
        __m256 u = _mm256_load_ps(batch.u + k);
        __m256 v = _mm256_load_ps(batch.v + k);
        __m256i hx0 = _mm256_mullo_epi32(ix, mulX);
        __m256i hy = _mm256_mullo_epi32(iy, mulY);
        __m256i hx1 = _mm256_add_epi32(hx0, mulX);
        __m256i hy0 = _mm256_xor_si256(hy, key);
        __m256i hy1 = _mm256_xor_si256(_mm256_add_epi32(hy, mulY), key);
        __m256 tx1 = _mm256_sub_ps(tx, one);
        __m256 ty1 = _mm256_sub_ps(ty, one);
        __m256 n00 = grad8(hx0, hy0, tx, ty, mix, gx, gy);
        __m256 n10 = grad8(hx1, hy0, tx1, ty, mix, gx, gy);
        __m256 n01 = grad8(hx0, hy1, tx, ty1, mix, gx, gy);
        __m256 n11 = grad8(hx1, hy1, tx1, ty1, mix, gx, gy);
        __m256 ou = _mm256_sub_ps(one, u);
        __m256 a = _mm256_add_ps(_mm256_mul_ps(ou, n00), _mm256_mul_ps(u, n10));
        __m256 b = _mm256_add_ps(_mm256_mul_ps(ou, n01), _mm256_mul_ps(u, n11));
        __m256 r = _mm256_add_ps(_mm256_mul_ps(_mm256_sub_ps(one, v), a), _mm256_mul_ps(v, b));
        _mm256_storeu_ps(out + k, r);
    }
}
#endif

}  // namespace terrain
