// Improved Perlin noise in 2D (Perlin 2002; [6] ch. 2), keyed by a seed; see PerlinNoise.h.
#include "synthesis/PerlinNoise.h"

#include "core/Check.h"

namespace terrain {

namespace {
constexpr double kSqrt2 = 1.41421356237309504880;

/// splitmix64's finaliser: turns consecutive seeds into unrelated keys.
std::uint64_t mixSeed(std::uint64_t z)
{
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
}  // namespace

const double PerlinNoise::kGradients[8][2] = {{kSqrt2, 0.0}, {1.0, 1.0},   {0.0, kSqrt2},  {-1.0, 1.0},
                                              {-kSqrt2, 0.0}, {-1.0, -1.0}, {0.0, -kSqrt2}, {1.0, -1.0}};

PerlinNoise::PerlinNoise(std::uint64_t seed, std::int64_t period) : mSeed(seed), mKey(mixSeed(seed)), mPeriod(period)
{
    TERRAIN_EXPECTS(period >= 0, "the noise period must be 0 (none) or a positive number of lattice cells");
}

}  // namespace terrain
