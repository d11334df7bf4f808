// zlib compression of whole buffers (node payloads are small and independent).
#pragma once

#include "core/Expected.h"

#include <cstdint>
#include <span>
#include <vector>

namespace terrain {

/// zlib-compresses `bytes` at `level` (0..9).
std::vector<std::uint8_t> zlibCompress(std::span<const std::uint8_t> bytes, int level = 4);

/// Inflates a zlib stream that must decode to exactly `expectedSize` bytes and end there. The error
/// message says what was wrong (corrupt data, too short, trailing data); callers prefix the file and node.
Expected<std::vector<std::uint8_t>> zlibDecompress(std::span<const std::uint8_t> bytes, std::size_t expectedSize);

}  // namespace terrain
