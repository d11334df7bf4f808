// 8-bit images through libpng (PngCodec.cpp): any PNG in, converted with libpng's own transforms.
#include "heightfield/Image.h"

#include "heightfield/PngCodec.h"

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

}  // namespace terrain
