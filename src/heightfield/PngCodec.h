// Internal libpng wrapper shared by the image and height field PNG code (not part of the layer's API).
// libpng reports errors by longjmp; here every libpng call runs under setjmp in a frame without C++
// objects, so a corrupt file becomes an Error naming the file instead of an abort or a skipped destructor.
#pragma once

#include "core/Expected.h"
#include "heightfield/Image.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace terrain::detail {

enum class PngReadMode {
    /// Grayscale only, values exactly as stored: 1/2/4-bit unpacked to a byte each without scaling,
    /// 16-bit kept as two big-endian bytes. Other colour types fail ("expected a grayscale PNG, found RGB").
    NativeGray,
    /// Any PNG converted to 8-bit `channels` (1 luminance, 3 RGB, 4 RGBA) with libpng's transforms.
    Convert8,
};

struct DecodedPng {
    int width = 0;
    int height = 0;
    int sourceBitDepth = 0;            ///< as stored in the file
    int sourceColorType = 0;           ///< PNG_COLOR_TYPE_* as stored in the file
    int channels = 0;                  ///< after transforms
    int bytesPerChannel = 0;           ///< after transforms: 1, or 2 (big-endian) for 16-bit NativeGray
    std::vector<std::uint8_t> pixels;  ///< rows top to bottom, channel-interleaved
};

/// Decodes a PNG. `channels` is used by Convert8 only. From the header alone, before libpng or this
/// allocates anything as large as a row, refuses (naming the file and the size) an image the file is too
/// small to hold (deflate's 1032:1 limit) and one whose pixels plus `extraBytesPerPixel` per pixel (the
/// caller's own later buffer) do not fit in memory. Any size the format allows (2^31 - 1 a side) is read.
Expected<DecodedPng> decodePng(const std::filesystem::path& path, PngReadMode mode, int channels,
                               std::uint64_t extraBytesPerPixel);

/// Writes a non-interlaced PNG through AtomicFile. `pixels` holds rows top to bottom; 16-bit samples are
/// big-endian. channels 1 (gray), 2 (gray+alpha), 3 (RGB) or 4 (RGBA); bitDepth 8 or 16.
Status encodePng(const std::filesystem::path& path, int width, int height, int channels, int bitDepth,
                 const std::uint8_t* pixels, PngCompression compression = PngCompression::Small);

/// "gray", "RGB", "RGBA", "gray+alpha", "palette".
std::string pngColorTypeName(int colorType);

}  // namespace terrain::detail
