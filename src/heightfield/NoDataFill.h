// Filling no-data samples (NaN) from valid neighbours before a height field is quantized.
#pragma once

#include "heightfield/HeightField.h"

#include <cstdint>
#include <vector>

namespace terrain {

/// Replaces every NaN sample by the mean of its already-valid 8-neighbours, growing inwards from the
/// valid samples one ring at a time (so a hole is filled smoothly from its rim). Returns the number of
/// samples filled. A field with no valid sample at all is left unchanged and returns 0; callers must
/// check for that case first (see countValid()). When `filled` is given and some sample was filled, it
/// receives a width * height mask (index j * width + i), 1 where a sample was filled.
std::uint64_t fillNoData(HeightField& field, std::vector<std::uint8_t>* filled = nullptr);

/// Samples that are not NaN.
std::uint64_t countValid(const HeightField& field);

}  // namespace terrain
