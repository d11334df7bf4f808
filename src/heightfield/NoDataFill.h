// Filling no-data samples (NaN) from valid neighbours before a height field is quantized.
#pragma once

#include "heightfield/HeightField.h"

#include <cstdint>

namespace terrain {

/// Replaces every NaN sample by the mean of its already-valid 8-neighbours, growing inwards from the
/// valid samples one ring at a time (so a hole is filled smoothly from its rim). Returns the number of
/// samples filled. A field with no valid sample at all is left unchanged and returns 0; callers must
/// check for that case first (see countValid()).
std::uint64_t fillNoData(HeightField& field);

/// Samples that are not NaN.
std::uint64_t countValid(const HeightField& field);

}  // namespace terrain
