#include "lod/NodeTextures.h"

#include "core/Check.h"

#include <algorithm>
#include <cmath>

#include <string.h>  // stb_dxt uses memcpy without including it

// stb_dxt (public domain; Debian libstb-dev) compiled here, with its functions static to this file. Its own
// code is not held to our warning flags.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wsign-conversion"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wpedantic"
#define STB_DXT_STATIC
#define STB_DXT_IMPLEMENTATION
#include <stb/stb_dxt.h>
#pragma GCC diagnostic pop

namespace terrain {

int blockLayerSize(int textureSize)
{
    TERRAIN_EXPECTS(textureSize >= 1, "a texture has at least one texel");
    return (textureSize + 3) / 4 * 4;
}

std::vector<std::uint8_t> compressDxt1(std::span<const std::uint8_t> rgb, int textureSize)
{
    const int t = textureSize;
    TERRAIN_EXPECTS(rgb.size() == static_cast<std::size_t>(t) * static_cast<std::size_t>(t) * 3,
                    "the texture must hold T x T RGB texels");
    const int blocks = blockLayerSize(t) / 4;
    std::vector<std::uint8_t> out(static_cast<std::size_t>(blocks) * blocks * 8);
    unsigned char block[16 * 4];
    for (int by = 0; by < blocks; ++by) {
        for (int bx = 0; bx < blocks; ++bx) {
            for (int y = 0; y < 4; ++y) {
                for (int x = 0; x < 4; ++x) {
                    const int i = std::min(4 * bx + x, t - 1), j = std::min(4 * by + y, t - 1);
                    const std::uint8_t* texel = rgb.data() + (static_cast<std::size_t>(j) * t + i) * 3;
                    unsigned char* to = block + (y * 4 + x) * 4;
                    to[0] = texel[0];
                    to[1] = texel[1];
                    to[2] = texel[2];
                    to[3] = 255;
                }
            }
            stb_compress_dxt_block(out.data() + (static_cast<std::size_t>(by) * blocks + bx) * 8, block, 0,
                                   STB_DXT_HIGHQUAL);
        }
    }
    return out;
}

std::vector<std::uint8_t> compressRgtc2(std::span<const std::int8_t> rg, int textureSize)
{
    const int t = textureSize;
    TERRAIN_EXPECTS(t >= 1 && rg.size() == static_cast<std::size_t>(t) * static_cast<std::size_t>(t) * 2,
                    "the normal map must hold T x T (x, y) pairs");
    const int blocks = blockLayerSize(t) / 4;
    std::vector<std::uint8_t> out(static_cast<std::size_t>(blocks) * blocks * 16);
    unsigned char block[16 * 2];
    for (int by = 0; by < blocks; ++by) {
        for (int bx = 0; bx < blocks; ++bx) {
            for (int y = 0; y < 4; ++y) {
                for (int x = 0; x < 4; ++x) {
                    const int i = std::min(4 * bx + x, t - 1), j = std::min(4 * by + y, t - 1);
                    const std::int8_t* texel = rg.data() + (static_cast<std::size_t>(j) * t + i) * 2;
                    // Offset binary: the unsigned encoder's order and steps are the signed values' own.
                    block[(y * 4 + x) * 2] = static_cast<unsigned char>(texel[0] + 128);
                    block[(y * 4 + x) * 2 + 1] = static_cast<unsigned char>(texel[1] + 128);
                }
            }
            std::uint8_t* to = out.data() + (static_cast<std::size_t>(by) * blocks + bx) * 16;
            stb_compress_bc5_block(to, block);
            // The endpoints back to two's complement (the indices are the same for signed blocks).
            for (const int endpoint : {0, 1, 8, 9}) {
                to[endpoint] = static_cast<std::uint8_t>(to[endpoint] ^ 0x80u);
            }
        }
    }
    return out;
}

std::vector<std::int8_t> parentNormalsRg8(std::span<const float> window, int chunkSize, double spacing)
{
    const int n = chunkSize;
    const int w = n + 4;
    TERRAIN_EXPECTS(n >= 3 && n % 2 == 1, "a node has an odd number of samples a side, at least 3");
    TERRAIN_EXPECTS(window.size() == static_cast<std::size_t>(w) * w, "window must be (N + 4)^2 heights");
    TERRAIN_EXPECTS(spacing > 0.0, "the spacing must be > 0");
    const int m = (n + 1) / 2;
    std::vector<std::int8_t> out(static_cast<std::size_t>(m) * m * 2);
    auto h = [&](int i, int j) -> double { return window[static_cast<std::size_t>(j + 2) * w + i + 2]; };
    auto snorm8 = [](double v) { return static_cast<std::int8_t>(std::lround(std::clamp(v, -1.0, 1.0) * 127.0)); };
    for (int b = 0; b < m; ++b) {
        for (int a = 0; a < m; ++a) {
            const int i = 2 * a, j = 2 * b;
            const double x = -(h(i + 2, j) - h(i - 2, j)) * 0.25 / spacing;
            const double y = -(h(i, j + 2) - h(i, j - 2)) * 0.25 / spacing;
            const double length = std::sqrt(x * x + y * y + 1.0);
            out[(static_cast<std::size_t>(b) * m + a) * 2] = snorm8(x / length);
            out[(static_cast<std::size_t>(b) * m + a) * 2 + 1] = snorm8(y / length);
        }
    }
    return out;
}

std::vector<std::uint16_t> packWeightsRgba4(std::span<const std::uint8_t> weights)
{
    TERRAIN_EXPECTS(weights.size() % 4 == 0, "material weights come in fours");
    std::vector<std::uint16_t> out(weights.size() / 4);
    auto nibble = [](std::uint8_t w) { return static_cast<std::uint16_t>((w * 15 + 127) / 255); };
    for (std::size_t k = 0; k < out.size(); ++k) {
        const std::uint8_t* w = weights.data() + 4 * k;
        out[k] = static_cast<std::uint16_t>(nibble(w[0]) << 12 | nibble(w[1]) << 8 | nibble(w[2]) << 4 | nibble(w[3]));
    }
    return out;
}

QuantizedHeights quantizeHeightsR16(std::span<const float> window, int chunkSize)
{
    const int n = chunkSize, w = n + 4, inner = n + 2;
    TERRAIN_EXPECTS(window.size() == static_cast<std::size_t>(w) * static_cast<std::size_t>(w),
                    "the window must hold (N + 4)^2 heights");
    QuantizedHeights out;
    float lo = window[static_cast<std::size_t>(w + 1)], hi = lo;
    for (int j = 1; j <= inner; ++j) {
        for (int i = 1; i <= inner; ++i) {
            const float h = window[static_cast<std::size_t>(j) * w + i];
            lo = std::min(lo, h);
            hi = std::max(hi, h);
        }
    }
    out.lo = lo;
    out.range = hi - lo;
    out.codes.resize(static_cast<std::size_t>(inner) * inner);
    const double scale = out.range > 0.0f ? 65535.0 / out.range : 0.0;
    for (int j = 0; j < inner; ++j) {
        for (int i = 0; i < inner; ++i) {
            const double h = window[static_cast<std::size_t>(j + 1) * w + i + 1];
            out.codes[static_cast<std::size_t>(j) * inner + i] =
                static_cast<std::uint16_t>(std::clamp(std::lround((h - lo) * scale), 0l, 65535l));
        }
    }
    return out;
}

}  // namespace terrain
