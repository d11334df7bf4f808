// 8-bit images through libpng (PngCodec.cpp): any PNG in, converted with libpng's own transforms.
#include "heightfield/Image.h"

#include "heightfield/PngCodec.h"

#include <algorithm>
#include <cstdlib>
#include <vector>

namespace terrain {

Expected<Image> readPngImage(const std::filesystem::path& path, int channels)
{
    auto decoded = detail::decodePng(path, detail::PngReadMode::Convert8, channels, 0);
    TERRAIN_TRY(decoded);
    Image image;
    image.width = decoded->width;
    image.height = decoded->height;
    image.channels = decoded->channels;
    image.pixels = std::move(decoded->pixels);
    return image;
}

Status writePngImage(const std::filesystem::path& path, const Image& image, PngCompression compression)
{
    if (image.channels != 1 && image.channels != 3 && image.channels != 4) {
        return makeError(path.string(), ": cannot write an image with ", image.channels,
                         " channels as PNG (1, 3 or 4 are supported)");
    }
    if (image.width < 1 || image.height < 1 ||
        image.pixels.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) *
                                   static_cast<std::size_t>(image.channels)) {
        return makeError(path.string(), ": cannot write a ", image.width, "x", image.height, "x", image.channels,
                         " image with ", image.pixels.size(), " bytes of pixels (need width, height >= 1 and ",
                         "width * height * channels bytes)");
    }
    return detail::encodePng(path, image.width, image.height, image.channels, 8, image.pixels.data(), compression);
}

Expected<ImageDifference> compareImages(const Image& a, const Image& b, int levels)
{
    if (a.width != b.width || a.height != b.height || a.channels != b.channels) {
        return makeError("the images differ in size: ", a.width, "x", a.height, "x", a.channels, " and ", b.width, "x",
                         b.height, "x", b.channels);
    }
    TERRAIN_EXPECTS(levels >= 0, "levels >= 0");
    ImageDifference d;
    const auto n = static_cast<std::size_t>(a.width) * a.height;
    d.pixels = n;
    std::vector<std::uint8_t> far(n, 0);  // 1: differs by more than `levels`; 2: counted in a region
    for (std::size_t p = 0; p < n; ++p) {
        int worst = 0;
        for (int c = 0; c < a.channels; ++c) {
            const std::size_t k = p * static_cast<std::size_t>(a.channels) + static_cast<std::size_t>(c);
            worst = std::max(worst, std::abs(static_cast<int>(a.pixels[k]) - static_cast<int>(b.pixels[k])));
        }
        d.identical += worst == 0 ? 1 : 0;
        far[p] = worst > levels ? 1 : 0;
    }
    std::vector<std::size_t> stack;
    for (std::size_t start = 0; start < n; ++start) {
        if (far[start] != 1) {
            continue;
        }
        std::size_t size = 0;
        far[start] = 2;
        stack.assign(1, start);
        while (!stack.empty()) {
            const std::size_t p = stack.back();
            stack.pop_back();
            ++size;
            const int x = static_cast<int>(p % static_cast<std::size_t>(a.width));
            const int y = static_cast<int>(p / static_cast<std::size_t>(a.width));
            const int nx[4] = {x - 1, x + 1, x, x};
            const int ny[4] = {y, y, y - 1, y + 1};
            for (int k = 0; k < 4; ++k) {
                if (nx[k] < 0 || ny[k] < 0 || nx[k] >= a.width || ny[k] >= a.height) {
                    continue;
                }
                const std::size_t q = static_cast<std::size_t>(ny[k]) * static_cast<std::size_t>(a.width) +
                                      static_cast<std::size_t>(nx[k]);
                if (far[q] == 1) {
                    far[q] = 2;
                    stack.push_back(q);
                }
            }
        }
        if (size > d.largestRegion) {
            d.largestRegion = size;
            d.largestRegionX = static_cast<int>(start % static_cast<std::size_t>(a.width));
            d.largestRegionY = static_cast<int>(start / static_cast<std::size_t>(a.width));
        }
    }
    return d;
}

}  // namespace terrain
