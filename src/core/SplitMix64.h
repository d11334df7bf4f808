// splitmix64 (Steele, Lea & Flood 2014): a small, fully specified generator, so random choices are the same
// on every platform and standard library.
#pragma once

#include <cstdint>

namespace terrain {

class SplitMix64 {
public:
    explicit SplitMix64(std::uint64_t seed) : mState(seed) {}

    std::uint64_t next()
    {
        std::uint64_t z = (mState += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    /// Uniform in [0, n) for small n (the bias of a 64-bit modulo is far below anything measurable).
    int below(int n) { return static_cast<int>(next() % static_cast<std::uint64_t>(n)); }

private:
    std::uint64_t mState;
};

}  // namespace terrain
