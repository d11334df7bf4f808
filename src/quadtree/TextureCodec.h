// Lossless coding of node textures: RGB8, each plane predicted by the LOCO-I median edge detector
// (Weinberger et al., JPEG-LS), residual bytes modulo 256, zlib.
#pragma once

#include "core/Expected.h"

#include <cstdint>
#include <span>
#include <vector>

namespace terrain {

/// `rgb` holds size*size interleaved RGB texels, rows south to north (as node heights).
std::vector<std::uint8_t> encodeTexture(std::span<const std::uint8_t> rgb, int size, int zlibLevel = 4);

/// Decodes into `rgb` (size*size*3 bytes). Errors say what was wrong with the stream.
Status decodeTexture(std::span<const std::uint8_t> stream, int size, std::span<std::uint8_t> rgb);

}  // namespace terrain
