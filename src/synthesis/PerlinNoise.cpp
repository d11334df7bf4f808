// Improved Perlin noise in 2D (Perlin 2002; [6] ch. 2), keyed by a seed; see PerlinNoise.h.
#include "synthesis/PerlinNoise.h"

#include "core/Check.h"

#include <algorithm>
#include <iterator>

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
