// The whole terrain as one padded square grid of 16-bit height codes at the finest static level: what prep
// builds every node from. Coarser levels are subsamples of it (3.2.3: a parent's samples are exactly its
// children's even samples).
#pragma once

#include "core/Expected.h"
#include "core/ScratchMapping.h"
#include "heightfield/HeightField.h"
#include "quadtree/HeightCodec.h"
#include "quadtree/MapFormat.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
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

/// What the quantization is chosen from, gathered from a field's rows in order (a whole field or bands of
/// rows streamed from disk give the same): the range of the valid samples, where its ends lie, their count and
/// a subsample of them (every sample whose row-major index is a multiple of a stride, for the lattice test
/// and the bulk's range), and the infinite samples, which are not valid.
class SampleStatistics {
public:
    SampleStatistics(int width, int height);
    /// Rows [j0, j0 + rows), width samples each, rows fed in increasing order. NaN samples are skipped,
    /// infinite ones counted apart.
    void addRows(int j0, int rows, std::span<const float> samples);
    double lo() const { return mLo; }
    double hi() const { return mHi; }
    /// The first sample (column, row; row 0 the south row) holding lo(), and hi().
    std::array<int, 2> loAt() const { return mLoAt; }
    std::array<int, 2> hiAt() const { return mHiAt; }
    std::uint64_t valid() const { return mValid; }
    const std::vector<double>& subsample() const { return mSubsample; }
    /// Samples that are +inf or -inf, and the first of them (value, column, row).
    std::uint64_t infinite() const { return mInfinite; }
    float firstInfinite() const { return mFirstInfinite; }
    std::array<int, 2> firstInfiniteAt() const { return mFirstInfiniteAt; }

private:
    int mWidth;
    std::uint64_t mStride;
    double mLo, mHi;
    std::array<int, 2> mLoAt{}, mHiAt{};
    std::uint64_t mValid = 0;
    std::vector<double> mSubsample;
    std::uint64_t mInfinite = 0;
    float mFirstInfinite = 0.0f;
    std::array<int, 2> mFirstInfiniteAt{};
};

/// The widest an input's heights may range in metres, either side of 0 (10,000 km: more than any planet's
/// relief; finer quantities, the float positions the viewer draws with, stay meaningful within it).
inline constexpr double kMaxHeightMetres = 1e7;

/// Refuses, before anything is quantized, samples that would destroy the quantization, with what to do about
/// them: infinite samples; a lowest or highest sample that lies far outside the rest of the terrain (the
/// subsample's values around its median with no gap wider than 10 median absolute deviations, at least
/// 10 km: an untagged no-data value such as -32768 or float max, or a spike, more than that gap beyond them),
/// naming where it is and suggesting --nodata (its value, as the file holds it) or --clamp; and heights (baseOffset +
/// scale x native) beyond kMaxHeightMetres, naming -v and --offset. Precondition: statistics.valid() > 0, scale > 0.
Status checkSampleRange(const SampleStatistics& statistics, double scale, double baseOffset);

/// The lattice step g of float samples that may all lie on lo + k g (k < 65535) up to float rounding:
/// estimated from the subsample (its smallest gap, refined on values ever farther from lo); empty when the
/// subsample shows they cannot. Every sample must then pass latticeDeviation.
std::optional<double> estimateLattice(const SampleStatistics& statistics);
/// The float rounding the lattice test allows for samples in [lo, hi].
double latticeTolerance(double lo, double hi);
/// The largest distance of the valid `samples` from the lattice lo + k g, or empty when one is farther
/// than the tolerance (they are not on it).
std::optional<double> latticeDeviation(std::span<const float> samples, double lo, double hi, double g);

/// Chooses the quantization with metres = baseOffset + scale * native from the valid samples' statistics.
/// Integer input whose range fits 16 bits is stored losslessly with one code per native unit; float samples
/// on a lattice (estimateLattice, then `latticeWorst(g)`: every sample's latticeDeviation, empty if one is
/// off) losslessly with one code per lattice step; otherwise the step is the finest that fits. `maxError`
/// (metres, >= 0) is the L-infinity bound the map may add on top. Fails if scale is not positive and finite.
Expected<Quantization> chooseQuantization(const SampleStatistics& statistics, bool integerSamples, double scale,
                                          double baseOffset, double maxError,
                                          const std::function<Expected<std::optional<double>>(double)>& latticeWorst);
/// The same for a whole field (NaN samples skipped).
Expected<Quantization> chooseQuantization(const HeightField& field, double scale, double baseOffset, double maxError);

/// The code of native value `native` (not NaN).
std::uint16_t quantizeNative(double native, const Quantization& quantization);

/// The codes of the size x size grid, stored in 64 x 64 tiles (a tile's 8 KiB are contiguous), in memory or,
/// for prep's out-of-core build, in a ScratchMapping whose pages the builder releases when it is done with
/// a region (release): resident memory is then the working set, not the grid. A mapped grid keeps the
/// samples of a coarse lattice (x and y multiples of 2^coarseShift) in memory instead of in their tiles, so
/// nodes above the builder's split level, which read only such samples spread over the whole map, touch no
/// page of the file (each touched sample would make at least a page resident, for one code).
class QuantizedGrid {
public:
    /// Quantizes `field` into a size x size grid in memory (size >= field's sides), replicating the last
    /// column and row into the padding. Checks the allocation against available memory first.
    static Expected<QuantizedGrid> build(const HeightField& field, const Quantization& quantization,
                                         std::uint32_t size);
    /// An all-zero grid in memory (checked against available memory).
    static Expected<QuantizedGrid> create(std::uint32_t size);
    /// An all-zero grid in a temporary file in `directory` (see ScratchMapping), with the samples on the
    /// lattice of step 2^coarseShift (0..kTileShift) held in memory: coarseLatticeBytes(size, coarseShift).
    static Expected<QuantizedGrid> createMapped(std::uint32_t size, const std::filesystem::path& directory,
                                                int coarseShift);
    static std::uint64_t coarseLatticeBytes(std::uint32_t size, int coarseShift);

    std::uint32_t size() const { return mSize; }
    bool mapped() const { return mMapping.has_value(); }
    std::uint16_t at(std::uint64_t x, std::uint64_t y) const { return *slot(x, y); }
    std::uint16_t& at(std::uint64_t x, std::uint64_t y) { return *const_cast<std::uint16_t*>(slot(x, y)); }
    /// Bytes the grid's storage takes for a side of `size`.
    static std::uint64_t storageBytes(std::uint32_t size);

    /// Drops the resident pages of the tiles wholly inside [x0, x1) x [y0, y1) of a mapped grid (their codes
    /// stay); nothing for a grid in memory. Safe while other threads use those tiles.
    void release(std::uint64_t x0, std::uint64_t y0, std::uint64_t x1, std::uint64_t y1) const;
    void releaseAll() const { release(0, 0, mSize, mSize); }

    /// Copies node `id`'s window (static levels) out of the grid and fills its outside samples.
    void extractWindow(const MapHeader& header, const NodeId& id, std::span<std::uint16_t> window) const;

    /// Replaces the codes by what the decoder will reconstruct with residuals quantized to `bin`
    /// (odd, > 1): top-down, each level predicted from the reconstructed level above, so every stored
    /// sample ends within (bin - 1) / 2 codes of its original and every node's residuals are multiples of
    /// `bin`. Runs on `threads` threads; the result does not depend on their number. A mapped grid is
    /// released row of nodes by row of nodes.
    void reconstructLossy(const MapHeader& header, std::uint32_t bin, int threads);

    static constexpr int kTileShift = 6;

private:
    static constexpr std::uint64_t kTileMask = (1u << kTileShift) - 1;
    explicit QuantizedGrid(std::uint32_t size);
    const std::uint16_t* slot(std::uint64_t x, std::uint64_t y) const
    {
        // mNoLattice is 1 without a lattice, so the test never holds and the branch is always predicted.
        if ((((x | y) & mLatticeMask) | mNoLattice) == 0) {
            return mLattice + (y >> mLatticeShift) * mLatticeSide + (x >> mLatticeShift);
        }
        return mData + index(x, y);
    }
    std::size_t index(std::uint64_t x, std::uint64_t y) const
    {
        return static_cast<std::size_t>((((y >> kTileShift) * mTilesX + (x >> kTileShift)) << (2 * kTileShift)) |
                                        ((y & kTileMask) << kTileShift) | (x & kTileMask));
    }

    std::uint32_t mSize = 0;
    std::uint64_t mTilesX = 0;
    std::vector<std::uint16_t> mHeap;
    std::optional<ScratchMapping> mMapping;
    std::uint16_t* mData = nullptr;
    std::vector<std::uint16_t> mLatticeHeap;
    std::uint16_t* mLattice = nullptr;
    int mLatticeShift = 0;
    std::uint64_t mLatticeMask = 0, mLatticeSide = 0, mNoLattice = 1;
};

}  // namespace terrain
