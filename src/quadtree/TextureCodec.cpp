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

template <class Visit>
void forEachTexel(int size, Visit visit)
{
    for (int c = 0; c < 3; ++c) {
        for (int y = 0; y < size; ++y) {
            for (int x = 0; x < size; ++x) {
                visit(c, x, y);
            }
        }
    }
}

std::uint8_t predictAt(std::span<const std::uint8_t> rgb, int size, int c, int x, int y)
{
    auto at = [&](int xx, int yy) -> int { return rgb[(static_cast<std::size_t>(yy) * size + xx) * 3 + c]; };
    if (y == 0) {
        return x == 0 ? 0 : static_cast<std::uint8_t>(at(x - 1, 0));
    }
    if (x == 0) {
        return static_cast<std::uint8_t>(at(0, y - 1));
    }
    return medPredict(at(x - 1, y), at(x, y - 1), at(x - 1, y - 1));
}

}  // namespace

std::vector<std::uint8_t> encodeTexture(std::span<const std::uint8_t> rgb, int size, int zlibLevel)
{
    TERRAIN_EXPECTS(rgb.size() == static_cast<std::size_t>(size) * size * 3, "texture must have size*size RGB texels");
    std::vector<std::uint8_t> residuals;
    residuals.reserve(rgb.size());
    forEachTexel(size, [&](int c, int x, int y) {
        auto value = rgb[(static_cast<std::size_t>(y) * size + x) * 3 + c];
        residuals.push_back(static_cast<std::uint8_t>(value - predictAt(rgb, size, c, x, y)));
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
    std::size_t i = 0;
    forEachTexel(size, [&](int c, int x, int y) {
        rgb[(static_cast<std::size_t>(y) * size + x) * 3 + c] =
            static_cast<std::uint8_t>(residuals.value()[i++] + predictAt(rgb, size, c, x, y));
    });
    return {};
}

}  // namespace terrain
