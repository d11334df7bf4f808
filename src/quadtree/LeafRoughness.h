// The roughness law of each static leaf, measured from a field held whole or streamed through in
// bands of whole leaf rows (out-of-core prep): both give the same map bytes.
#pragma once

#include "heightfield/HeightField.h"
#include "heightfield/Roughness.h"
#include "quadtree/MapFormat.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace terrain {

/// Fewer deviations than this at a lag and a leaf's law is not its own (LeafRoughnessMeter::finish).
inline constexpr std::uint64_t kMinRoughnessSamples = 256;

/// Rows of the field a band must hold beyond the leaf rows it measures (the largest lag), where the field
/// has them.
inline constexpr int kRoughnessMargin = kRoughnessLags.back();

/// Measures a map's leaves (header's chunk size and levels, at most 15) on a width x height field: the
/// midpoint deviation at kRoughnessLags over each leaf's input samples (lags reaching into the neighbouring
/// leaves), in metres (heights x metresPerUnit; an offset changes nothing). Leaf (lx, ly) covers samples
/// [lx c, (lx + 1) c) x [ly c, (ly + 1) c), c = N - 1, clipped to the field, the last column and row of
/// leaves up to the field's edge.
class LeafRoughnessMeter {
public:
    LeafRoughnessMeter(int width, int height, double metresPerUnit, const MapHeader& header);

    /// Field rows a leaf row ly covers: [leafRowBegin(ly), leafRowBegin(ly + 1)), the last up to the height.
    int leafRowBegin(int ly) const;
    int leafRows() const { return mSide; }

    /// Measures the leaf rows [ly0, ly1) from `window`: field rows [windowRow0, windowRow0 + windowRows),
    /// full width, which must hold those leaf rows and kRoughnessMargin rows beyond them on each side (as
    /// far as the field goes). Each leaf row once; `threads` >= 1 share the leaves.
    void addLeafRows(int ly0, int ly1, std::span<const float> window, int windowRow0, int windowRows, int threads);

    /// The laws by fitRoughnessLaw. A leaf with fewer than kMinRoughnessSamples deviations at some lag
    /// (padding, a narrow strip of input) takes the law of the nearest measured leaf (ties: the lowest
    /// index); with none measured every leaf gets the law of the sums of all leaves. Deterministic.
    RoughnessGrid finish() const;

private:
    int mWidth, mHeight, mCells, mSide;
    double mMetresPerUnit;
    std::vector<std::array<MidpointSums, kRoughnessLags.size()>> mSums;  ///< per leaf, row-major
};

/// The laws of a whole field: one LeafRoughnessMeter pass over all its leaf rows.
RoughnessGrid measureLeafRoughness(const HeightField& field, double metresPerUnit, const MapHeader& header,
                                   int threads = 1);

}  // namespace terrain
