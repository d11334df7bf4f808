// The whole terrain as one padded square grid of 16-bit height codes at the finest static level: what prep
// builds every node from. Coarser levels are subsamples of it (3.2.3: a parent's samples are exactly its
// children's even samples).
#pragma once

#include "core/Expected.h"
#include "heightfield/HeightField.h"
#include "quadtree/HeightCodec.h"
#include "quadtree/MapFormat.h"

#include <cstdint>
#include <span>
#include <vector>

namespace terrain {

/// How metres map to 16-bit codes: metres = offset + step * code.
struct Quantization {
    double offset = 0.0;
    double step = 1.0;
    std::uint32_t bin = 1;       ///< residual quantizer bin in codes, 2 * E + 1
    double errorBound = 0.0;     ///< guaranteed max |stored - input| in metres
    std::uint32_t margin = 0;    ///< codes kept free below and above the data so lossy values stay in range
    double nativeMin = 0.0;      ///< the native value that maps to code `margin`
    double nativePerCode = 1.0;  ///< native units per code
};

/// Chooses the quantization of `field` (no NaN left) with metres = baseOffset + scale * native. Integer
/// input whose range fits 16 bits is stored losslessly with one code per native unit; otherwise (float
/// samples or a range over 65535 units) the step is the finest that fits. `maxError` (metres, >= 0) is the
/// L-infinity bound the map may add on top. Fails if scale is not positive and finite.
Expected<Quantization> chooseQuantization(const HeightField& field, double scale, double baseOffset, double maxError);

class QuantizedGrid {
public:
    /// Quantizes `field` into a size x size grid (size >= field's sides), replicating the last column and row
    /// into the padding. Checks the allocation against available memory first.
    static Expected<QuantizedGrid> build(const HeightField& field, const Quantization& quantization,
                                         std::uint32_t size);

    std::uint32_t size() const { return mSize; }
    std::uint16_t at(std::uint64_t x, std::uint64_t y) const { return mCodes[y * mSize + x]; }
    std::uint16_t& at(std::uint64_t x, std::uint64_t y) { return mCodes[y * mSize + x]; }
    std::span<const std::uint16_t> codes() const { return mCodes; }

    /// Copies node `id`'s window (static levels) out of the grid and fills its outside samples.
    void extractWindow(const MapHeader& header, const NodeId& id, std::span<std::uint16_t> window) const;

    /// Replaces the codes by what the decoder will reconstruct with residuals quantized to `bin`
    /// (odd, > 1): top-down, each level predicted from the reconstructed level above, so every stored
    /// sample ends within (bin - 1) / 2 codes of its original and every node's residuals are multiples of
    /// `bin`. Runs on `threads` threads; the result does not depend on their number.
    void reconstructLossy(const MapHeader& header, std::uint32_t bin, int threads);

private:
    explicit QuantizedGrid(std::uint32_t size);

    std::uint32_t mSize = 0;
    std::vector<std::uint16_t> mCodes;
};

}  // namespace terrain
