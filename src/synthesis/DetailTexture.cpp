// Tileable detail textures from the tileable fractal of Fractal.h (paper 3.4.5).
#include "synthesis/DetailTexture.h"

#include "core/Check.h"

#include <algorithm>
#include <cmath>

namespace terrain {

Image makeDetailTexture(const FractalParams& params, int size)
{
    TERRAIN_EXPECTS(size > 0, "a detail texture needs at least one pixel");
    TERRAIN_EXPECTS(params.amplitude > 0.0, "a detail texture needs a non-zero amplitude");
    FractalParams tileable = params;
    tileable.cache = FractalCache::Fractal;
    Fractal fractal(tileable);
    double step = fractal.tileSize() / size;
    Image image{size, size, 1, std::vector<std::uint8_t>(static_cast<std::size_t>(size) * size)};
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
            double v = fractal.uncachedValue(x * step, y * step) / params.amplitude;
            image.pixel(x, y)[0] = static_cast<std::uint8_t>(std::clamp(std::lround(127.5 + 127.5 * v), 0L, 255L));
        }
    }
    return image;
}

}  // namespace terrain
