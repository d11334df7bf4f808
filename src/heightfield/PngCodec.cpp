// libpng reading and writing with errors as values. Each function that calls libpng sets its own setjmp
// point and holds only trivially destructible locals, so libpng's longjmp never skips a destructor.
#include "heightfield/PngCodec.h"

#include "core/AtomicFile.h"
#include "core/Check.h"
#include "core/Memory.h"

#include <png.h>
#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <sstream>

namespace terrain::detail {

namespace {

/// Deflate's largest compression ratio: a 258-byte match coded in 2 bits (RFC 1951; zlib's tech notes).
constexpr std::uint64_t kDeflateMaxRatio = 1032;

/// Where libpng's error callback leaves its message before jumping back.
struct PngErrorState {
    char message[256] = {};
};

[[noreturn]] void onPngError(png_structp png, png_const_charp message)
{
    auto* state = static_cast<PngErrorState*>(png_get_error_ptr(png));
    std::snprintf(state->message, sizeof state->message, "%s", message ? message : "unknown libpng error");
    png_longjmp(png, 1);
}

void onPngWarning(png_structp, png_const_charp)
{
    // Warnings (bad ancillary chunks, sRGB profile quirks) do not affect the pixels we use.
}

void onPngWrite(png_structp png, png_bytep data, png_size_t size)
{
    static_cast<AtomicFile*>(png_get_io_ptr(png))->write(data, size);
}

void onPngFlush(png_structp) {}

// ---- Functions that call libpng. Each returns false when libpng reported an error. ----

bool pngReadInfo(png_structp png, png_infop info)
{
    if (setjmp(png_jmpbuf(png))) {
        return false;
    }
    png_read_info(png, info);
    return true;
}

bool pngSetTransforms(png_structp png, png_infop info, PngReadMode mode, int channels)
{
    if (setjmp(png_jmpbuf(png))) {
        return false;
    }
    const int colorType = png_get_color_type(png, info);
    const int bitDepth = png_get_bit_depth(png, info);
    if (mode == PngReadMode::NativeGray) {
        if (bitDepth < 8) {
            png_set_packing(png);  // one byte per sample, value unchanged (no scaling to 0..255)
        }
    } else {
        const bool hasTrns = png_get_valid(png, info, PNG_INFO_tRNS) != 0;
        const bool isColor = (colorType & PNG_COLOR_MASK_COLOR) != 0;
        // palette_to_rgb also expands tRNS to alpha; for other types we ask for it only when keeping alpha.
        const bool hasAlpha = (colorType & PNG_COLOR_MASK_ALPHA) != 0 ||
                              (hasTrns && (colorType == PNG_COLOR_TYPE_PALETTE || channels == 4));
        if (colorType == PNG_COLOR_TYPE_PALETTE) {
            png_set_palette_to_rgb(png);
        }
        if (colorType == PNG_COLOR_TYPE_GRAY && bitDepth < 8) {
            png_set_expand_gray_1_2_4_to_8(png);
        }
        if (hasTrns && channels == 4) {
            png_set_tRNS_to_alpha(png);
        }
        if (bitDepth == 16) {
#ifdef PNG_READ_SCALE_16_TO_8_SUPPORTED
            png_set_scale_16(png);  // rounds, where strip_16 truncates
#else
            png_set_strip_16(png);
#endif
        }
        if (channels == 1 && isColor) {
            png_set_rgb_to_gray_fixed(png, 1, -1, -1);  // 1: convert silently; -1: default (Rec. 709) weights
        }
        if (channels >= 3 && !isColor) {
            png_set_gray_to_rgb(png);
        }
        if (channels == 4 && !hasAlpha) {
            png_set_add_alpha(png, 0xff, PNG_FILLER_AFTER);
        }
        if (channels != 4 && hasAlpha) {
            png_set_strip_alpha(png);
        }
    }
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    return true;
}

bool pngReadImage(png_structp png, png_bytepp rows)
{
    if (setjmp(png_jmpbuf(png))) {
        return false;
    }
    png_read_image(png, rows);
    // No png_read_end: the pixels are complete, and chunks after the image data do not change them.
    return true;
}

/// zlib levels of PngCompression: libpng's default (6) for files kept, 1 for video frames. Measured on five
/// 1280 x 720 frames of the demo flight, one core: level 6 109 ms and 304 KB per frame, level 1 31 ms and
/// 406 KB (3.6x faster for files a third larger).
constexpr int kSmallZlibLevel = 6;
constexpr int kFastZlibLevel = 1;

bool pngWrite(png_structp png, png_infop info, png_uint_32 width, png_uint_32 height, int colorType, int bitDepth,
              png_bytepp rows, int zlibLevel)
{
    if (setjmp(png_jmpbuf(png))) {
        return false;
    }
    png_set_compression_level(png, zlibLevel);
    png_set_IHDR(png, info, width, height, bitDepth, colorType, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, nullptr);
    return true;
}

/// Owns the libpng read structures.
struct PngReadHandles {
    png_structp png = nullptr;
    png_infop info = nullptr;
    ~PngReadHandles() { png_destroy_read_struct(&png, info ? &info : nullptr, nullptr); }
};

struct PngWriteHandles {
    png_structp png = nullptr;
    png_infop info = nullptr;
    ~PngWriteHandles() { png_destroy_write_struct(&png, info ? &info : nullptr); }
};

struct FileCloser {
    void operator()(std::FILE* file) const { std::fclose(file); }
};

}  // namespace

std::string pngColorTypeName(int colorType)
{
    switch (colorType) {
        case PNG_COLOR_TYPE_GRAY:
            return "gray";
        case PNG_COLOR_TYPE_GRAY_ALPHA:
            return "gray+alpha";
        case PNG_COLOR_TYPE_RGB:
            return "RGB";
        case PNG_COLOR_TYPE_RGB_ALPHA:
            return "RGBA";
        case PNG_COLOR_TYPE_PALETTE:
            return "palette";
        default:
            return "colour type " + std::to_string(colorType);
    }
}

Expected<DecodedPng> decodePng(const std::filesystem::path& path, PngReadMode mode, int channels,
                               std::uint64_t extraBytesPerPixel)
{
    const std::string name = path.string();
    if (mode == PngReadMode::Convert8 && channels != 1 && channels != 3 && channels != 4) {
        return makeError(name, ": cannot convert a PNG to ", channels, " channels (1, 3 or 4 are supported)");
    }
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        return makeError(name, ": cannot open: is a directory");
    }
    std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
    if (!file) {
        return makeError(name, ": cannot open: ", std::strerror(errno));
    }
    png_byte signature[8] = {};
    const std::size_t signatureSize = std::fread(signature, 1, sizeof signature, file.get());
    if (signatureSize != sizeof signature || png_sig_cmp(signature, 0, sizeof signature) != 0) {
        return makeError(name, ": not a PNG file (the first 8 bytes are not the PNG signature)");
    }

    PngErrorState errorState;
    PngReadHandles handles;
    handles.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &errorState, onPngError, onPngWarning);
    if (!handles.png || !(handles.info = png_create_info_struct(handles.png))) {
        return makeError(name, ": cannot initialise libpng (out of memory?)");
    }
    png_init_io(handles.png, file.get());
    png_set_sig_bytes(handles.png, sizeof signature);
    // libpng's own default limit (1000000 pixels a side) would refuse a larger image with a message that
    // gives no size; allow what the format allows and refuse below, naming the size and the reason.
    png_set_user_limits(handles.png, PNG_UINT_31_MAX, PNG_UINT_31_MAX);
    if (!pngReadInfo(handles.png, handles.info)) {
        return makeError(name, ": corrupt PNG header: ", errorState.message);
    }
    DecodedPng decoded;
    decoded.width = static_cast<int>(png_get_image_width(handles.png, handles.info));
    decoded.height = static_cast<int>(png_get_image_height(handles.png, handles.info));
    decoded.sourceBitDepth = png_get_bit_depth(handles.png, handles.info);
    decoded.sourceColorType = png_get_color_type(handles.png, handles.info);
    if (mode == PngReadMode::NativeGray && decoded.sourceColorType != PNG_COLOR_TYPE_GRAY) {
        return makeError(name, ": expected a grayscale PNG, found ", pngColorTypeName(decoded.sourceColorType));
    }

    // Sizes are checked here, from the header alone: png_read_update_info (in pngSetTransforms) already
    // allocates row buffers as wide as the image.
    const std::uint64_t pixelCount = std::uint64_t(decoded.width) * std::uint64_t(decoded.height);
    std::ostringstream what;
    what << name << ": a " << decoded.width << "x" << decoded.height << " PNG";
    // A header that claims more than the file can hold: the image data as stored (a filter byte plus the
    // packed samples per row; interlaced images store a little more) compresses at most 1032:1 with
    // deflate (a 258-byte match in 2 bits), so the file must have at least a 1032th of it.
    const std::uint64_t storedRowBytes = png_get_rowbytes(handles.png, handles.info);
    const std::uint64_t storedBytes = std::uint64_t(decoded.height) * (storedRowBytes + 1);
    const std::uint64_t fileBytes = std::filesystem::file_size(path, ec);
    const std::uint64_t leastCompressed = storedBytes / kDeflateMaxRatio;
    if (!ec && fileBytes < leastCompressed) {
        return makeError(what.str(), " needs at least ", leastCompressed,
                         " bytes of compressed image data (deflate compresses at most ", kDeflateMaxRatio,
                         ":1), but the file has ", fileBytes, " bytes: its header is wrong or the file is truncated");
    }
    // The pixels after the transforms below (NativeGray: 1 or 2 bytes a sample; Convert8: `channels`
    // bytes), the caller's own buffer, and libpng's two rows as stored (current and previous).
    const std::uint64_t bytesPerPixel =
        mode == PngReadMode::NativeGray ? (decoded.sourceBitDepth == 16 ? 2 : 1) : std::uint64_t(channels);
    TERRAIN_TRY(
        checkAllocation(pixelCount * (bytesPerPixel + extraBytesPerPixel) + 2 * (storedRowBytes + 1), what.str()));

    if (!pngSetTransforms(handles.png, handles.info, mode, channels)) {
        return makeError(name, ": unsupported PNG: ", errorState.message);
    }
    decoded.channels = png_get_channels(handles.png, handles.info);
    const int bitDepth = png_get_bit_depth(handles.png, handles.info);
    decoded.bytesPerChannel = bitDepth == 16 ? 2 : 1;
    if ((mode == PngReadMode::Convert8 && (decoded.channels != channels || bitDepth != 8)) ||
        (mode == PngReadMode::NativeGray && decoded.channels != 1)) {
        return makeError(name, ": cannot convert this ", decoded.sourceBitDepth, "-bit ",
                         pngColorTypeName(decoded.sourceColorType), " PNG to ", channels, " 8-bit channels");
    }

    const std::uint64_t rowBytes = png_get_rowbytes(handles.png, handles.info);
    const std::uint64_t imageBytes = rowBytes * std::uint64_t(decoded.height);
    TERRAIN_ASSERT(imageBytes <= pixelCount * bytesPerPixel);  // the memory check above was an upper bound
    decoded.pixels.resize(static_cast<std::size_t>(imageBytes));
    std::vector<png_bytep> rows(static_cast<std::size_t>(decoded.height));
    for (std::size_t y = 0; y < rows.size(); ++y) {
        rows[y] = decoded.pixels.data() + y * rowBytes;
    }
    if (!pngReadImage(handles.png, rows.data())) {
        return makeError(name, ": corrupt or truncated PNG image data: ", errorState.message);
    }
    return decoded;
}

Status encodePng(const std::filesystem::path& path, int width, int height, int channels, int bitDepth,
                 const std::uint8_t* pixels, PngCompression compression)
{
    const std::string name = path.string();
    static constexpr int kColorTypes[] = {0, PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                          PNG_COLOR_TYPE_RGB_ALPHA};
    if (width < 1 || height < 1 || channels < 1 || channels > 4 || (bitDepth != 8 && bitDepth != 16)) {
        return makeError(name, ": cannot write a ", width, "x", height, " PNG with ", channels, " channels of ",
                         bitDepth, " bits");
    }
    auto file = AtomicFile::create(path);
    TERRAIN_TRY(file);

    PngErrorState errorState;
    PngWriteHandles handles;
    handles.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &errorState, onPngError, onPngWarning);
    if (!handles.png || !(handles.info = png_create_info_struct(handles.png))) {
        return makeError(name, ": cannot initialise libpng (out of memory?)");
    }
    png_set_write_fn(handles.png, &file.value(), onPngWrite, onPngFlush);

    const std::size_t rowBytes = static_cast<std::size_t>(width) * channels * (bitDepth / 8);
    std::vector<png_bytep> rows(static_cast<std::size_t>(height));
    for (std::size_t y = 0; y < rows.size(); ++y) {
        rows[y] = const_cast<png_bytep>(pixels + y * rowBytes);  // libpng's API is not const-correct
    }
    if (!pngWrite(handles.png, handles.info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height),
                  kColorTypes[channels], bitDepth, rows.data(),
                  compression == PngCompression::Fast ? kFastZlibLevel : kSmallZlibLevel)) {
        return makeError(name, ": cannot encode PNG: ", errorState.message);
    }
    return file->commit();
}

}  // namespace terrain::detail
