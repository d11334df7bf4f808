// Filling no-data samples (NaN) before a height field is quantized, the same whether the field is held
// whole or streamed through in bands of rows (out-of-core prep).
//
// A hole at Chebyshev distance d <= kFillRings from valid data takes, ring by ring, the mean of its
// 8-neighbours that are valid or of an earlier ring (a hole is filled smoothly from its rim). A hole farther
// than that (the inside of a sea or a large void) takes the bilinear interpolation of the FarFillGrid: the
// mean of the valid samples of each kFillBlock x kFillBlock block, its empty blocks filled ring by ring in
// the same way. Both rules see only samples within kFillRings of the hole, so a band of rows with
// kFillRings rows of margin on each side fills its inner rows exactly as the whole field would.
#pragma once

#include "heightfield/HeightField.h"

#include <cstdint>
#include <span>
#include <vector>

namespace terrain {

/// Rings filled from the valid samples; holes farther away take the far fill.
inline constexpr int kFillRings = 64;
/// Side, in samples, of the blocks whose means make the far fill.
inline constexpr int kFillBlock = 64;

/// The block means the far fill interpolates: blocksX x blocksY values, block (bx, by) covering samples
/// [bx B, bx B + B) x [by B, by B + B) of the field (B = kFillBlock), its value at sample position
/// ((bx + 0.5) B - 0.5, (by + 0.5) B - 0.5).
struct FarFillGrid {
    int blocksX = 0;
    int blocksY = 0;
    std::vector<float> means;

    /// The far fill at sample (x, y): bilinear between block centres, clamped at the outer blocks.
    float at(int x, int y) const;
};

/// Accumulates the block sums of a field fed row by row (rows in increasing order, each row once).
class FarFillBuilder {
public:
    FarFillBuilder(int width, int height);
    /// Rows [j0, j0 + rows) of the field, width samples each.
    void addRows(int j0, int rows, std::span<const float> samples);
    /// The means, empty blocks filled from their neighbours. Precondition: some sample was valid.
    FarFillGrid finish() const;

private:
    int mWidth, mHeight, mBlocksX, mBlocksY;
    std::vector<double> mSums;
    std::vector<std::uint32_t> mCounts;
};

/// Fills the NaN samples of the full-width rows [firstRow, firstRow + rows) of a field, `samples` holding
/// them row by row (width each), as the header says: exact for the rows at least kFillRings from a cut edge
/// of the window (an edge that is not the field's). Returns the samples filled; when `filled` is given it
/// receives a width x rows mask, 1 where a sample was filled (left empty when none was).
std::uint64_t fillNoDataRows(std::span<float> samples, int width, int rows, int firstRow, const FarFillGrid& far,
                             std::vector<std::uint8_t>* filled = nullptr);

/// The whole field at once (FarFillBuilder over every row, then fillNoDataRows). A field with no valid
/// sample is left unchanged and returns 0; callers check countValid() first.
std::uint64_t fillNoData(HeightField& field, std::vector<std::uint8_t>* filled = nullptr);

/// Samples that are not NaN.
std::uint64_t countValid(const HeightField& field);

}  // namespace terrain
