// 8-bit images (textures, weight maps, captured frames) and their PNG reader/writer.
#pragma once

#include "core/Expected.h"

#include <cstdint>
#include <filesystem>
#include <vector>

namespace terrain {

/// An 8-bit-per-channel image, rows top to bottom as stored in image files (row 0 = top = north for maps).
struct Image {
    int width = 0;
    int height = 0;
    int channels = 0;                  ///< 1 (gray), 3 (RGB) or 4 (RGBA)
    std::vector<std::uint8_t> pixels;  ///< width * height * channels bytes, row-major, channel-interleaved

    std::uint8_t* pixel(int x, int y) { return pixels.data() + (static_cast<std::size_t>(y) * width + x) * channels; }
    const std::uint8_t* pixel(int x, int y) const
    {
        return pixels.data() + (static_cast<std::size_t>(y) * width + x) * channels;
    }
};

/// Reads any PNG and converts it to `channels` channels (1: luminance; 3: RGB; 4: RGBA), 16-bit reduced to 8.
Expected<Image> readPngImage(const std::filesystem::path& path, int channels);

/// How hard PNG writers compress: Small for files kept (height fields, textures), Fast for many large
/// images written as they are made (video frames).
enum class PngCompression { Small, Fast };

/// Writes an 8-bit PNG (gray, RGB or RGBA by image.channels) to a temporary name and renames it.
Status writePngImage(const std::filesystem::path& path, const Image& image,
                     PngCompression compression = PngCompression::Small);

}  // namespace terrain
