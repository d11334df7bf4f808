// A node's textures as the renderer's texture arrays store them (node data in GPU pools): the colour as DXT1
// (S3TC) blocks, 4 bits a texel, the normal map as RGTC2 blocks, 8 bits a texel, and the weights as 4 bits
// per material. Pure CPU code: no GL here.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace terrain {

/// Texels per side of a block-compressed layer (DXT1, RGTC2) for a T x T texture: T rounded up to a multiple
/// of 4 (both code 4 x 4 blocks). The texels beyond T repeat the last row and column.
int blockLayerSize(int textureSize);

/// The DXT1 blocks (8 bytes each, rows of blocks south to north, as GL_COMPRESSED_RGB_S3TC_DXT1_EXT wants
/// them) of a T x T RGB texture (3 bytes a texel, rows south to north), padded to blockLayerSize(T). Encoded
/// with stb_dxt's high-quality mode.
std::vector<std::uint8_t> compressDxt1(std::span<const std::uint8_t> rgb, int textureSize);

/// The RGTC2 blocks (16 bytes each: x's BC4 block, then y's; rows of blocks south to north, as
/// GL_COMPRESSED_SIGNED_RG_RGTC2 wants them) of a T x T normal map of signed 8-bit (x, y) pairs
/// (GL_RG8_SNORM, rows south to north; NodeData::normalMap), padded to blockLayerSize(T). Each block keeps
/// its own smallest and largest value exactly and puts every texel on the nearest of the 8 steps between
/// them (stb_dxt's BC4 encoder): a texel is off by at most 1/14 of its block's range, plus a half step of
/// rounding.
std::vector<std::uint8_t> compressRgtc2(std::span<const std::int8_t> rg, int textureSize);

/// The parent's unit normals at its samples, the node's even samples: ((N + 1) / 2)^2 pairs (x, y) as signed
/// 8-bit normalised integers (GL_RG8_SNORM; z = sqrt(1 - x^2 - y^2)), rows south to north. The parent's
/// normal at a sample is its own central difference, over the node's samples two away on each side, from
/// the node's (N + 4)^2 surface `window` (2-sample border); `spacing` is the node's (metres).
std::vector<std::int8_t> parentNormalsRg8(std::span<const float> window, int chunkSize, double spacing);

/// A node's surface as the pools' 16-bit height layer holds it (GL_R16, unsigned normalised): the (N + 2)^2
/// inner part of the (N + 4)^2 `window` (a 1-sample border, for the own normals at the edges), each height h
/// as round((h - lo) / range * 65535), rows south to north. The shaders read lo + range * code / 65535,
/// which is within range / 131070 metres of h (plus float rounding); a flat window has range 0.
struct QuantizedHeights {
    std::vector<std::uint16_t> codes;
    float lo = 0.0f;
    float range = 0.0f;
};
QuantizedHeights quantizeHeightsR16(std::span<const float> window, int chunkSize);

/// N x N x 4 material weights (0..255) as GL_RGBA4 texels (GL_UNSIGNED_SHORT_4_4_4_4: red in the top 4 bits),
/// each weight rounded to the nearest of 0, 1/15, ..., 1.
std::vector<std::uint16_t> packWeightsRgba4(std::span<const std::uint8_t> weights);

}  // namespace terrain
