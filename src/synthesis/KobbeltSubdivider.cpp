// Kobbelt's interpolatory 4-point rule, regular tensor-product case (Kobbelt 1996; paper 3.3.2, 3.4.3):
// the float version of quadtree/HeightCodec.cpp's integer omega = 1 predictor, same geometry.
// Built with -ffp-contract=off (src/synthesis/CMakeLists.txt): see the header's note on determinism.
#include "synthesis/KobbeltSubdivider.h"

#include "core/Check.h"

#include <cmath>
#include <vector>

namespace terrain {

namespace {

/// The 4-point rule with weights (w0, w1, w1, w0) in the one evaluation order every caller uses.
inline double fourPoint(double a0, double a1, double a2, double a3, double w0, double w1)
{
    return ((w0 * a0 + w1 * a1) + w1 * a2) + w0 * a3;
}

/// Parent window index of child index c's even sample (c even) or of the first of its four taps (c odd),
/// for a child whose u = 0 sits at parent window index p0.
inline int parentIndex(int c, int p0)
{
    int u = c - kBorder;
    return (u & 1) == 0 ? p0 + u / 2 : p0 + (u - 1) / 2 - 1;
}

}  // namespace

void subdivideChildWindow(std::span<const float> parent, int chunkSize, int quadrant, double omega,
                          std::span<float> child)
{
    TERRAIN_EXPECTS(isValidChunkSize(chunkSize), "chunk size must be 2^k + 1 in [3, 1025]");
    TERRAIN_EXPECTS(quadrant >= 0 && quadrant <= 3, "quadrant must be 0..3");
    TERRAIN_EXPECTS(std::isfinite(omega), "omega must be finite");
    const int size = windowSize(chunkSize);
    const auto count = static_cast<std::size_t>(size) * size;
    TERRAIN_EXPECTS(parent.size() == count && child.size() == count, "windows must hold W*W samples, W = N + 4");
    static_assert(kBorder % 2 == 0, "window index parity must equal sample parity");

    const double w = omega / 16.0;
    const double w0 = 0.0 - w;  // 0 - w, not -w: omega = 0 then gives +0, never a -0 term
    const double w1 = 0.5 + w;
    const int half = (chunkSize - 1) / 2;
    const int px0 = kBorder + (quadrant & 1) * half;
    const int py0 = kBorder + (quadrant >> 1) * half;
    // Parent rows the y pass reads: from the first tap of child row 1 to the last tap of child row W - 2.
    const int firstRow = parentIndex(1, py0);
    const int lastRow = parentIndex(size - 2, py0) + 3;
    TERRAIN_ASSERT(firstRow >= 0 && lastRow < size && parentIndex(1, px0) >= 0 &&
                   parentIndex(size - 2, px0) + 3 < size);

    // x pass on every parent row needed, kept in double so each child sample is rounded to float once.
    std::vector<double> rows(static_cast<std::size_t>(lastRow - firstRow + 1) * size);
    for (int py = firstRow; py <= lastRow; ++py) {
        const float* in = parent.data() + static_cast<std::size_t>(py) * size;
        double* out = rows.data() + static_cast<std::size_t>(py - firstRow) * size;
        for (int c = 0; c < size; c += 2) {
            out[c] = in[parentIndex(c, px0)];
        }
        for (int c = 1; c < size; c += 2) {
            const float* a = in + parentIndex(c, px0);
            out[c] = fourPoint(a[0], a[1], a[2], a[3], w0, w1);
        }
    }
    // y pass over the x pass values.
    for (int cy = 0; cy < size; ++cy) {
        float* out = child.data() + static_cast<std::size_t>(cy) * size;
        const int first = parentIndex(cy, py0) - firstRow;
        const double* r0 = rows.data() + static_cast<std::size_t>(first) * size;
        if ((cy & 1) == 0) {
            for (int c = 0; c < size; ++c) {
                out[c] = static_cast<float>(r0[c]);  // exact for even-even samples: a float widened and back
            }
            continue;
        }
        const double* r1 = r0 + size;
        const double* r2 = r1 + size;
        const double* r3 = r2 + size;
        for (int c = 0; c < size; ++c) {
            out[c] = static_cast<float>(fourPoint(r0[c], r1[c], r2[c], r3[c], w0, w1));
        }
    }
}

KobbeltSubdivider::KobbeltSubdivider(int chunkSize, double omega) : mChunkSize(chunkSize), mOmega(omega)
{
    TERRAIN_EXPECTS(isValidChunkSize(chunkSize), "chunk size must be 2^k + 1 in [3, 1025]");
    TERRAIN_EXPECTS(std::isfinite(omega), "omega must be finite");
}

void KobbeltSubdivider::subdivide(std::span<const float> parent, int quadrant, std::span<float> child) const
{
    subdivideChildWindow(parent, mChunkSize, quadrant, mOmega, child);
}

}  // namespace terrain
