// Shared fixture of the subdivision tests: a block of nodes x nodes parent windows cut from one big height
// array (so neighbouring parents agree on their overlapping border samples, as static nodes do), all their
// children computed by a Subdivider in any order on any number of threads, and a check that every pair of
// children sharing a sample (siblings and cousins, edges, corners and borders) holds the same bits there.
#pragma once

#include "MapTestSupport.h"
#include "core/ParallelFor.h"
#include "synthesis/Subdivider.h"

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <functional>
#include <sstream>
#include <vector>

namespace terrain::test {

/// nodes x nodes parent nodes of chunk size N over one height array. Parent grid coordinates: node (i, j)
/// covers [i (N - 1), (i + 1) (N - 1)] in x; its window index k is grid coordinate i (N - 1) + k - 2.
class ParentBlock {
public:
    /// `height(x, y)` at integer grid coordinates x, y in [-2, nodes (N - 1) + 2].
    ParentBlock(int chunkSize, int nodes, const std::function<float(int, int)>& height)
        : mChunk(chunkSize), mNodes(nodes), mSide(nodes * (chunkSize - 1) + 5)
    {
        mHeights.resize(static_cast<std::size_t>(mSide) * mSide);
        for (int y = 0; y < mSide; ++y) {
            for (int x = 0; x < mSide; ++x) {
                mHeights[static_cast<std::size_t>(y) * mSide + x] = height(x - 2, y - 2);
            }
        }
    }

    int chunkSize() const { return mChunk; }
    int nodes() const { return mNodes; }
    int windowSize() const { return mChunk + 4; }
    float heightAt(int x, int y) const { return mHeights[static_cast<std::size_t>(y + 2) * mSide + x + 2]; }

    std::vector<float> window(int i, int j) const
    {
        const int w = windowSize();
        std::vector<float> out(static_cast<std::size_t>(w) * w);
        for (int y = 0; y < w; ++y) {
            for (int x = 0; x < w; ++x) {
                out[static_cast<std::size_t>(y) * w + x] = heightAt(i * (mChunk - 1) + x - 2, j * (mChunk - 1) + y - 2);
            }
        }
        return out;
    }

    /// Job index of child `quadrant` of node (i, j): (j * nodes + i) * 4 + quadrant.
    int jobCount() const { return mNodes * mNodes * 4; }

    /// All children's windows, indexed by job, computed in `order` (a permutation of the jobs) on `threads`
    /// threads.
    std::vector<std::vector<float>> children(const Subdivider& subdivider, const std::vector<int>& order,
                                             int threads) const
    {
        std::vector<std::vector<float>> out(static_cast<std::size_t>(jobCount()));
        parallelFor(order.size(), threads, [&](std::size_t k) {
            int job = order[k];
            int node = job / 4;
            auto parent = window(node % mNodes, node / mNodes);
            auto& child = out[static_cast<std::size_t>(job)];
            child.resize(parent.size());
            subdivider.subdivide(parent, job % 4, child);
        });
        return out;
    }

    /// The child grid coordinate (twice the parent grid's density) of child window index c along one axis,
    /// for node index `n` and half `q` (0 west/south, 1 east/north).
    int childCoordinate(int n, int q, int c) const { return 2 * n * (mChunk - 1) + q * (mChunk - 1) + c - 2; }

    /// Child grid positions per side that the children's windows cover: coordinates -2 .. side - 3.
    int childGridSide() const { return 2 * mNodes * (mChunk - 1) + 5; }

    /// Calls fn(job, cx, cy, gx, gy) for every sample (cx, cy) of every child's window, with its child grid
    /// coordinates (gx, gy).
    template <class Fn>
    void forEachChildSample(Fn&& fn) const
    {
        const int w = windowSize();
        for (int job = 0; job < jobCount(); ++job) {
            const int node = job / 4;
            const int q = job % 4;
            for (int cy = 0; cy < w; ++cy) {
                for (int cx = 0; cx < w; ++cx) {
                    fn(job, cx, cy, childCoordinate(node % mNodes, q & 1, cx),
                       childCoordinate(node / mNodes, q >> 1, cy));
                }
            }
        }
    }

private:
    int mChunk;
    int mNodes;
    int mSide;
    std::vector<float> mHeights;
};

/// Result of comparing every child sample with every other child's sample at the same position.
struct SharedSampleCheck {
    long compared = 0;    ///< samples that some earlier child also holds
    long mismatched = 0;  ///< of those, how many differ in any bit
    std::string firstMismatch;
};

inline SharedSampleCheck checkSharedSamples(const ParentBlock& block, const std::vector<std::vector<float>>& children)
{
    const int w = block.windowSize();
    const int side = block.childGridSide();
    std::vector<std::uint32_t> bits(static_cast<std::size_t>(side) * side);
    std::vector<int> owner(bits.size(), -1);
    SharedSampleCheck result;
    block.forEachChildSample([&](int job, int cx, int cy, int gx, int gy) {
        auto g = static_cast<std::size_t>(gy + 2) * side + gx + 2;
        auto value = std::bit_cast<std::uint32_t>(
            children[static_cast<std::size_t>(job)][static_cast<std::size_t>(cy) * w + cx]);
        if (owner[g] < 0) {
            owner[g] = job;
            bits[g] = value;
            return;
        }
        ++result.compared;
        if (bits[g] != value && result.mismatched++ == 0) {
            std::ostringstream s;
            s.precision(9);
            s << "child grid (" << gx << ", " << gy << "): job " << owner[g] << " has " << std::bit_cast<float>(bits[g])
              << ", job " << job << " has " << std::bit_cast<float>(value);
            result.firstMismatch = s.str();
        }
    });
    return result;
}

/// How many samples checkSharedSamples must compare, from the geometry alone: all children's samples less
/// one per child grid position, the windows covering the child grid without holes.
inline long expectedSharedCount(const ParentBlock& block)
{
    const long w = block.windowSize();
    const long side = block.childGridSide();
    return block.jobCount() * w * w - side * side;
}

/// Rough, non-smooth heights (independent random values in [100, 1100) m): every rounding shows.
inline std::function<float(int, int)> roughHeights(std::uint32_t seed)
{
    return [seed](int x, int y) { return static_cast<float>(100.0 + 1000.0 * unitNoise(seed, x, y)); };
}

/// The jobs 0..count-1 in a scrambled order.
inline std::vector<int> inOrder(int count);

inline std::vector<int> scrambledOrder(int count, std::uint32_t seed)
{
    std::vector<int> order = inOrder(count);
    for (int i = count - 1; i > 0; --i) {
        auto j = static_cast<int>(hashNoise(seed, i, 0) % static_cast<std::uint32_t>(i + 1));
        std::swap(order[static_cast<std::size_t>(i)], order[static_cast<std::size_t>(j)]);
    }
    return order;
}

inline std::vector<int> inOrder(int count)
{
    std::vector<int> order(static_cast<std::size_t>(count));
    for (int i = 0; i < count; ++i) {
        order[static_cast<std::size_t>(i)] = i;
    }
    return order;
}

}  // namespace terrain::test
