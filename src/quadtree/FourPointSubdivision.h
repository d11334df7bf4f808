// Kobbelt's interpolatory 4-point rule on node windows (Kobbelt 1996, "Interpolatory subdivision on open
// quadrilateral nets with arbitrary topology", the regular case; paper 3.3.2, 3.4.3), tensor product: the
// one definition of the stencil. It has two users, and both compute a child's window from its parent's:
//   quadtree/HeightCodec.cpp        predicts a static node from its parent (integers, omega = 1), and
//   synthesis/KobbeltSubdivider.cpp makes a dynamic node's base heights (double, omega =
//                                   detail_subdivision_factor).
// So static and dynamic nodes are two cases of one step: parent -> subdivide -> add (residual | fractal).
//
// Geometry (windows of quadtree/ChunkGeometry.h): child window index c is child coordinate u = c - kBorder
// in [-kBorder, N - 1 + kBorder]. Even u is the parent sample at window index p0 + u / 2 with
// p0 = kBorder + qx (N - 1) / 2 (qx = quadrant & 1); odd u = 2m + 1 combines parent window indices
// p0 + m - 1 .. p0 + m + 2 with weights -w, 1/2 + w, 1/2 + w, -w, w = omega / 16. The same in y with
// qy = quadrant >> 1. Child `quadrant` (bit 0: east half, bit 1: north half) covers a quarter of its parent.
#pragma once

#include "core/Check.h"
#include "quadtree/ChunkGeometry.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

namespace terrain {

/// The rule's weights in the arithmetic `T` of an evaluation, all multiplied by one scale s: outer = -w s
/// (taps 0 and 3), inner = (1/2 + w) s (taps 1 and 2), copy = s (the weight of an even sample).
template <typename T>
struct FourPointWeights {
    T outer;
    T inner;
    T copy;
};

/// The weights for `omega` in double, scale 1: omega = 0 is bilinear, 1 Kobbelt's rule (which reproduces
/// cubics); C1 in the limit for 0 < omega < 2.47.
inline FourPointWeights<double> fourPointWeights(double omega)
{
    const double w = omega / 16.0;
    return {0.0 - w, 0.5 + w, 1.0};  // 0 - w, not -w: omega = 0 then gives +0, never a -0 term
}

/// Kobbelt's rule (omega = 1) scaled by 16: -1, 9, 9, -1 and 16 for a copy, exact in integers. A child sample
/// of the tensor product then carries the scale 16 * 16 = 256.
inline constexpr FourPointWeights<std::int32_t> kKobbeltWeightsTimes16 = {-1, 9, 16};

/// One application of the rule in the one evaluation order every caller uses: ((o a0 + i a1) + i a2) + o a3.
template <typename T>
constexpr T fourPoint(T a0, T a1, T a2, T a3, const FourPointWeights<T>& w)
{
    return ((w.outer * a0 + w.inner * a1) + w.inner * a2) + w.outer * a3;
}

/// Parent window index of child window index c's sample (c even) or of the first of its four taps (c odd),
/// for a child whose u = 0 lies at parent window index p0.
constexpr int fourPointFirstTap(int c, int p0)
{
    const int u = c - kBorder;
    return (u & 1) == 0 ? p0 + u / 2 : p0 + (u - 1) / 2 - 1;
}

/// Child `quadrant`'s (0..3) whole window from its parent's: an x pass over every parent row some child row
/// needs, in `T`, then a y pass over those values in `T`; child[k] = finish(value), where value carries the
/// weights' scale squared. `parent` and `child` hold W * W samples (W = windowSize(chunkSize), rows south
/// to north) and must not overlap; `chunkSize` satisfies isValidChunkSize.
///
/// Determinism: each child sample is computed from the same parent samples with the same operations in the
/// same order whichever child (sibling or cousin) computes it. For floating-point `T`, instantiate this only
/// in files built with -ffp-contract=off, so no fused multiply-add makes one copy round differently.
template <typename T, typename In, typename Out, typename Finish>
void subdivideFourPoint(std::span<const In> parent, int chunkSize, int quadrant, const FourPointWeights<T>& weights,
                        std::span<Out> child, Finish finish)
{
    TERRAIN_EXPECTS(isValidChunkSize(chunkSize), "chunk size must be 2^k + 1 in [3, 1025]");
    TERRAIN_EXPECTS(quadrant >= 0 && quadrant <= 3, "quadrant must be 0..3");
    const int size = windowSize(chunkSize);
    const auto count = static_cast<std::size_t>(size) * size;
    TERRAIN_EXPECTS(parent.size() == count && child.size() == count, "windows must hold W*W samples, W = N + 4");

    const int half = (chunkSize - 1) / 2;
    const int px0 = kBorder + (quadrant & 1) * half;  // parent window index of the child's u = 0
    const int py0 = kBorder + (quadrant >> 1) * half;
    // Parent rows the y pass reads: from the first tap of child row 1 to the last tap of child row W - 2.
    const int firstRow = fourPointFirstTap(1, py0);
    const int lastRow = fourPointFirstTap(size - 2, py0) + 3;
    TERRAIN_ASSERT(firstRow >= 0 && lastRow < size && fourPointFirstTap(1, px0) >= 0 &&
                   fourPointFirstTap(size - 2, px0) + 3 < size);

    // x pass; every element is written below, so no zero fill.
    std::unique_ptr<T[]> rows(new T[static_cast<std::size_t>(lastRow - firstRow + 1) * size]);
    for (int py = firstRow; py <= lastRow; ++py) {
        const In* in = parent.data() + static_cast<std::size_t>(py) * size;
        T* out = rows.get() + static_cast<std::size_t>(py - firstRow) * size;
        for (int c = 0; c < size; c += 2) {
            out[c] = weights.copy * static_cast<T>(in[fourPointFirstTap(c, px0)]);
        }
        for (int c = 1; c < size; c += 2) {
            const In* a = in + fourPointFirstTap(c, px0);
            out[c] = fourPoint(static_cast<T>(a[0]), static_cast<T>(a[1]), static_cast<T>(a[2]), static_cast<T>(a[3]),
                               weights);
        }
    }
    // y pass over the x pass values.
    for (int cy = 0; cy < size; ++cy) {
        Out* out = child.data() + static_cast<std::size_t>(cy) * size;
        const T* r0 = rows.get() + static_cast<std::size_t>(fourPointFirstTap(cy, py0) - firstRow) * size;
        if ((cy & 1) == 0) {
            for (int c = 0; c < size; ++c) {
                out[c] = finish(weights.copy * r0[c]);
            }
            continue;
        }
        const T* r1 = r0 + size;
        const T* r2 = r1 + size;
        const T* r3 = r2 + size;
        for (int c = 0; c < size; ++c) {
            out[c] = finish(fourPoint(r0[c], r1[c], r2[c], r3[c], weights));
        }
    }
}

}  // namespace terrain
