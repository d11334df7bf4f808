// Kobbelt's interpolatory 4-point subdivision on a regular grid (Kobbelt 1996, "Interpolatory subdivision
// on open quadrilateral nets with arbitrary topology", the regular case; paper 3.3.2): the base height
// field of a dynamic node from its parent's (3.4.3).
#pragma once

#include "synthesis/Subdivider.h"

#include <span>

namespace terrain {

/// Child `quadrant`'s window from its parent's by the tensor-product 4-point rule, weights
/// -w, 1/2 + w, 1/2 + w, -w with w = omega / 16 (omega = `detail_subdivision_factor`: 0 is bilinear,
/// 1 is Kobbelt's rule, which reproduces cubics; C1 in the limit for 0 < omega < 2.47).
///
/// The stencil and its geometry are quadtree/FourPointSubdivision.h's subdivideFourPoint, the one the static
/// nodes' integer predictor (quadtree/HeightCodec.h's predictChildWindow) uses with omega = 1. Samples with
/// even u and even v are copied exactly.
///
/// `parent` and `child` hold W * W heights in metres (W = chunkSize + 4), rows south to north; they must
/// not overlap. `chunkSize` is isValidChunkSize (2^k + 1 in [3, 1025]), `quadrant` in 0..3, `omega` finite.
///
/// Precision: heights are float (24-bit mantissa: 1 mm steps up to 8 km, plenty for terrain relative to
/// the detail's centimetres, half the memory of double in the node cache). Every sample is accumulated in
/// double (the x pass is kept in double too) and rounded to float once.
///
/// Determinism: each child sample is evaluated from the same parent samples with the same operations in
/// the same order whichever child (sibling or cousin) computes it: the x pass on parent rows, each value
/// from the same 4 parent samples as ((w0 a0 + w1 a1) + w1 a2) + w0 a3 (fourPoint), then the y pass over
/// those values in the same form. KobbeltSubdivider.cpp, where the double form is instantiated, is compiled
/// with -ffp-contract=off, so no fused multiply-add can make one copy of the loop round differently from
/// another; x86-64 SSE2 has no excess precision.
void subdivideChildWindow(std::span<const float> parent, int chunkSize, int quadrant, double omega,
                          std::span<float> child);

/// The Subdivider for `detail_subdivision_scheme = kobbelt`.
class KobbeltSubdivider final : public Subdivider {
public:
    /// `chunkSize` is isValidChunkSize; `omega` is finite.
    KobbeltSubdivider(int chunkSize, double omega);

    int chunkSize() const override { return mChunkSize; }
    double omega() const { return mOmega; }
    void subdivide(std::span<const float> parent, int quadrant, std::span<float> child) const override;

private:
    int mChunkSize;
    double mOmega;
};

}  // namespace terrain
