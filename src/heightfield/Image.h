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

/// How two images of the same size differ (frames drawn with and without visibility_lod).
struct ImageDifference {
    std::size_t pixels = 0;     ///< in each image
    std::size_t identical = 0;  ///< pixels whose channels are all equal
    /// The largest 4-connected region of pixels where some channel differs by more than `levels`.
    std::size_t largestRegion = 0;
    int largestRegionX = 0, largestRegionY = 0;  ///< a pixel of it
};

/// Compares `a` and `b` (same size and channels, else an error naming both sizes); `levels` >= 0.
Expected<ImageDifference> compareImages(const Image& a, const Image& b, int levels);

}  // namespace terrain
