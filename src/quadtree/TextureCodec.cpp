// LOCO-I / JPEG-LS median edge detector prediction + zlib for node textures.
#include "quadtree/TextureCodec.h"

#include "core/Check.h"
#include "core/Zlib.h"

#include <algorithm>

namespace terrain {

namespace {

// JPEG-LS MED: picks min/max of the left and upper neighbours at an edge, else the planar estimate.
std::uint8_t medPredict(int left, int up, int upLeft)
{
    if (upLeft >= std::max(left, up)) {
        return static_cast<std::uint8_t>(std::min(left, up));
    }
    if (upLeft <= std::min(left, up)) {
        return static_cast<std::uint8_t>(std::max(left, up));
    }
    return static_cast<std::uint8_t>(left + up - upLeft);
}

/// Visits the planes' texels in coding order, passing each texel's value and its MED prediction from
/// already-visited texels. `Code(value, prediction)` returns the texel's final value (encoder: the value;
/// decoder: the value rebuilt from the residual).
template <class Code>
void forEachTexel(std::span<std::uint8_t> rgb, int size, Code code)
{
    const std::size_t row = static_cast<std::size_t>(size) * 3;
    for (int c = 0; c < 3; ++c) {
        std::uint8_t* p = rgb.data() + c;
        // Row 0: west neighbour.
        p[0] = code(p[0], 0);
        for (int x = 1; x < size; ++x) {
            p[x * 3] = code(p[x * 3], p[(x - 1) * 3]);
        }
        for (int y = 1; y < size; ++y) {
            std::uint8_t* cur = p + y * row;
            const std::uint8_t* below = cur - row;
            cur[0] = code(cur[0], below[0]);
            for (int x = 1; x < size; ++x) {
                cur[x * 3] = code(cur[x * 3], medPredict(cur[(x - 1) * 3], below[x * 3], below[(x - 1) * 3]));
            }
        }
    }
}

}  // namespace

std::vector<std::uint8_t> encodeTexture(std::span<const std::uint8_t> rgb, int size, int zlibLevel)
{
    TERRAIN_EXPECTS(rgb.size() == static_cast<std::size_t>(size) * size * 3, "texture must have size*size RGB texels");
    std::vector<std::uint8_t> texels(rgb.begin(), rgb.end());
    std::vector<std::uint8_t> residuals;
    residuals.reserve(rgb.size());
    forEachTexel(texels, size, [&](std::uint8_t value, std::uint8_t prediction) {
        residuals.push_back(static_cast<std::uint8_t>(value - prediction));
        return value;
    });
    return zlibCompress(residuals, zlibLevel);
}

Status decodeTexture(std::span<const std::uint8_t> stream, int size, std::span<std::uint8_t> rgb)
{
    TERRAIN_EXPECTS(rgb.size() == static_cast<std::size_t>(size) * size * 3, "texture must have size*size RGB texels");
    auto residuals = zlibDecompress(stream, rgb.size());
    if (!residuals.ok()) {
        return makeError("texture stream: ", residuals.error().message);
    }
    const std::uint8_t* next = residuals->data();
    forEachTexel(rgb, size, [&](std::uint8_t, std::uint8_t prediction) {
        return static_cast<std::uint8_t>(*next++ + prediction);
    });
    return {};
}

}  // namespace terrain
