// 8-bit image PNG reading (any PNG, converted to 1/3/4 channels) and atomic writing. Sources in odd
// formats (palette, tRNS, 1-bit, 16-bit, gray+alpha, interlaced) are written here straight through
// libpng, independently of the writer under test.
#include "heightfield/Image.h"

#include "heightfield/HeightFieldIo.h"

#include "TestSupport.h"

#include <gtest/gtest.h>
#include <png.h>
#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace terrain {
namespace {

using Bytes = std::vector<std::uint8_t>;

/// What to write with libpng directly. `pixels`: rows top to bottom exactly as PNG stores them
/// (packed for bit depths below 8, big-endian for 16).
struct SourcePng {
    int width = 0;
    int height = 0;
    int colorType = PNG_COLOR_TYPE_GRAY;
    int bitDepth = 8;
    Bytes pixels;
    std::vector<png_color> palette;
    Bytes paletteAlpha;  ///< tRNS for palette images
    bool interlaced = false;
};

bool writeSourcePng(const std::filesystem::path& path, const SourcePng& source)
{
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (!file) {
        return false;
    }
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png_create_info_struct(png);
    const std::size_t rowBytes = source.pixels.size() / static_cast<std::size_t>(source.height);
    std::vector<png_bytep> rows(static_cast<std::size_t>(source.height));
    for (std::size_t y = 0; y < rows.size(); ++y) {
        rows[y] = const_cast<png_bytep>(source.pixels.data() + y * rowBytes);
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        std::fclose(file);
        return false;
    }
    png_init_io(png, file);
    png_set_IHDR(png, info, static_cast<png_uint_32>(source.width), static_cast<png_uint_32>(source.height),
                 source.bitDepth, source.colorType, source.interlaced ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (!source.palette.empty()) {
        png_set_PLTE(png, info, source.palette.data(), static_cast<int>(source.palette.size()));
    }
    if (!source.paletteAlpha.empty()) {
        png_set_tRNS(png, info, source.paletteAlpha.data(), static_cast<int>(source.paletteAlpha.size()), nullptr);
    }
    png_write_info(png, info);
    if (source.interlaced) {
        png_set_interlace_handling(png);
    }
    png_write_image(png, rows.data());
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    return true;
}

void writeBytes(const std::filesystem::path& path, const Bytes& bytes)
{
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

Bytes readBytes(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

Image makeImage(int width, int height, int channels, Bytes pixels)
{
    Image image;
    image.width = width;
    image.height = height;
    image.channels = channels;
    image.pixels = std::move(pixels);
    return image;
}

TEST(ImageTest, WriteThenReadIsExactForEveryChannelCount)
{
    // 3x2 with distinct bytes everywhere, so a swapped row, column or channel shows.
    for (int channels : {1, 3, 4}) {
        SCOPED_TRACE(channels);
        test::ScratchDir dir;
        Bytes pixels(static_cast<std::size_t>(3 * 2 * channels));
        for (std::size_t k = 0; k < pixels.size(); ++k) {
            pixels[k] = static_cast<std::uint8_t>(7 + 11 * k);
        }
        const Image image = makeImage(3, 2, channels, pixels);
        ASSERT_TRUE(writePngImage(dir / "image.png", image).ok());
        EXPECT_EQ(dir.list(), std::vector<std::string>{"image.png"});
        auto read = readPngImage(dir / "image.png", channels);
        ASSERT_TRUE(read.ok()) << read.error().message;
        EXPECT_EQ(read->width, 3);
        EXPECT_EQ(read->height, 2);
        EXPECT_EQ(read->channels, channels);
        EXPECT_EQ(read->pixels, pixels);
        EXPECT_EQ(read->pixel(2, 1)[0], pixels[static_cast<std::size_t>(5 * channels)]);
    }
}

TEST(ImageTest, ConvertsEverySourceFormatToTheRequestedChannels)
{
    struct Case {
        const char* name;
        SourcePng source;
        int channels;
        Bytes expected;
    };
    const SourcePng gray8{3, 1, PNG_COLOR_TYPE_GRAY, 8, {0, 100, 255}, {}, {}, false};
    // Pure gray keeps its level in any luminance formula; red is darker than green.
    const SourcePng rgb8{3, 1, PNG_COLOR_TYPE_RGB, 8, {90, 90, 90, 10, 20, 30, 200, 0, 0}, {}, {}, false};
    const SourcePng rgba8{1, 1, PNG_COLOR_TYPE_RGB_ALPHA, 8, {90, 90, 90, 40}, {}, {}, false};
    const SourcePng grayAlpha{1, 1, PNG_COLOR_TYPE_GRAY_ALPHA, 8, {77, 128}, {}, {}, false};
    const SourcePng palette{2, 1, PNG_COLOR_TYPE_PALETTE, 8, {1, 0}, {{255, 0, 0}, {0, 0, 255}}, {10}, false};
    const SourcePng oneBit{4, 1, PNG_COLOR_TYPE_GRAY, 1, {0b0110'0000}, {}, {}, false};
    const SourcePng gray16{3, 1, PNG_COLOR_TYPE_GRAY, 16, {0x12, 0x34, 0xff, 0xff, 0x00, 0x00}, {}, {}, false};
    const SourcePng rgb16{1, 1, PNG_COLOR_TYPE_RGB, 16, {0x80, 0x00, 0x00, 0x00, 0xff, 0xff}, {}, {}, false};
    const Case cases[] = {
        {"gray8 as gray", gray8, 1, {0, 100, 255}},
        {"gray8 as RGB", gray8, 3, {0, 0, 0, 100, 100, 100, 255, 255, 255}},
        {"gray8 as RGBA", gray8, 4, {0, 0, 0, 255, 100, 100, 100, 255, 255, 255, 255, 255}},
        {"RGB as RGB", rgb8, 3, {90, 90, 90, 10, 20, 30, 200, 0, 0}},
        {"RGB as RGBA", rgb8, 4, {90, 90, 90, 255, 10, 20, 30, 255, 200, 0, 0, 255}},
        {"RGBA as RGB", rgba8, 3, {90, 90, 90}},
        {"RGBA as RGBA", rgba8, 4, {90, 90, 90, 40}},
        {"RGBA as gray", rgba8, 1, {90}},
        {"gray+alpha as gray", grayAlpha, 1, {77}},
        {"gray+alpha as RGBA", grayAlpha, 4, {77, 77, 77, 128}},
        {"palette as RGB", palette, 3, {0, 0, 255, 255, 0, 0}},
        {"palette+tRNS as RGBA", palette, 4, {0, 0, 255, 255, 255, 0, 0, 10}},
        {"1-bit gray as gray", oneBit, 1, {0, 255, 255, 0}},
        {"16-bit gray as gray", gray16, 1, {0x12, 0xff, 0x00}},
        {"16-bit RGB as RGB", rgb16, 3, {0x80, 0x00, 0xff}},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        test::ScratchDir dir;
        ASSERT_TRUE(writeSourcePng(dir / "source.png", c.source));
        auto image = readPngImage(dir / "source.png", c.channels);
        ASSERT_TRUE(image.ok()) << image.error().message;
        EXPECT_EQ(image->width, c.source.width);
        EXPECT_EQ(image->height, c.source.height);
        EXPECT_EQ(image->channels, c.channels);
        EXPECT_EQ(image->pixels, c.expected);
    }
}

TEST(ImageTest, ColourToGrayWeighsGreenAboveRed)
{
    test::ScratchDir dir;
    const SourcePng rgb{3, 1, PNG_COLOR_TYPE_RGB, 8, {90, 90, 90, 255, 0, 0, 0, 255, 0}, {}, {}, false};
    ASSERT_TRUE(writeSourcePng(dir / "rgb.png", rgb));
    auto gray = readPngImage(dir / "rgb.png", 1);
    ASSERT_TRUE(gray.ok()) << gray.error().message;
    ASSERT_EQ(gray->pixels.size(), 3u);
    EXPECT_EQ(gray->pixels[0], 90);
    EXPECT_NEAR(gray->pixels[1], 54, 2);   // 0.2126 * 255
    EXPECT_NEAR(gray->pixels[2], 182, 2);  // 0.7152 * 255
}

TEST(ImageTest, InterlacedPngsAreDeinterlaced)
{
    test::ScratchDir dir;
    SourcePng source{9, 9, PNG_COLOR_TYPE_RGB, 8, Bytes(9 * 9 * 3), {}, {}, true};
    for (std::size_t k = 0; k < source.pixels.size(); ++k) {
        source.pixels[k] = static_cast<std::uint8_t>(k * 37 % 251);
    }
    ASSERT_TRUE(writeSourcePng(dir / "adam7.png", source));
    auto image = readPngImage(dir / "adam7.png", 3);
    ASSERT_TRUE(image.ok()) << image.error().message;
    EXPECT_EQ(image->pixels, source.pixels);
}

TEST(ImageTest, SixteenBitMapRowsMatchTheHeightFieldReader)
{
    // Image rows are top-down, HeightField rows bottom-up: row y of the image is j = height - 1 - y.
    const auto path = test::testDataPath("jacksboro_fault_dem_403x344.png");
    auto image = readPngImage(path, 1);
    ASSERT_TRUE(image.ok()) << image.error().message;
    auto field = readPngHeightField(path);
    ASSERT_TRUE(field.ok()) << field.error().message;
    ASSERT_EQ(image->width, 403);
    ASSERT_EQ(image->height, 344);
    int mismatches = 0;
    for (int y = 0; y < image->height; ++y) {
        for (int x = 0; x < image->width; ++x) {
            const double expected = field->at(x, image->height - 1 - y) / 257.0;
            mismatches += std::abs(image->pixel(x, y)[0] - expected) > 0.51 ? 1 : 0;
        }
    }
    EXPECT_EQ(mismatches, 0);
}

TEST(ImageTest, BadFilesGiveErrorsNamingTheFile)
{
    test::ScratchDir dir;
    const Image image = makeImage(8, 8, 3, Bytes(8 * 8 * 3, 99));
    ASSERT_TRUE(writePngImage(dir / "good.png", image).ok());
    const Bytes good = readBytes(dir / "good.png");
    writeBytes(dir / "truncated.png", Bytes(good.begin(), good.end() - 30));
    writeBytes(dir / "text.png", Bytes{'n', 'o', 't', ' ', 'a', ' ', 'p', 'n', 'g'});
    Bytes flipped = good;
    flipped[20] ^= 0xff;  // inside IHDR: its CRC no longer matches
    writeBytes(dir / "crc.png", flipped);
    struct Case {
        const char* name;
        int channels;
        const char* mention;
    };
    const Case cases[] = {
        {"missing.png", 3, "cannot open"},
        {"text.png", 3, "not a PNG file"},
        {"truncated.png", 3, "corrupt or truncated"},
        {"crc.png", 3, "corrupt PNG header"},
        {"good.png", 2, "2 channels"},
        {"good.png", 0, "0 channels"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        auto read = readPngImage(dir / c.name, c.channels);
        EXPECT_ERROR_MENTIONS(read, dir / c.name, c.mention);
    }
}

TEST(ImageTest, WriterRefusesInconsistentImagesAndLeavesNoFile)
{
    test::ScratchDir dir;
    struct Case {
        const char* name;
        Image image;
        const char* mention;
    };
    const Case cases[] = {
        {"two.png", makeImage(2, 2, 2, Bytes(8)), "2 channels"},
        {"short.png", makeImage(2, 2, 3, Bytes(11)), "11 bytes"},
        {"empty.png", makeImage(0, 0, 3, Bytes()), "0x0x3"},
        {"negative.png", makeImage(-2, 3, 1, Bytes(6)), "-2x3x1"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const Status status = writePngImage(dir / c.name, c.image);
        EXPECT_ERROR_MENTIONS(status, dir / c.name, c.mention);
    }
    EXPECT_TRUE(dir.list().empty());
    const Status unwritable = writePngImage("/nonexistent-dir/x/out.png", makeImage(1, 1, 1, {0}));
    EXPECT_ERROR_MENTIONS(unwritable, std::filesystem::path("/nonexistent-dir/x/out.png"), "cannot create");
}

TEST(ImageTest, RewritingReplacesTheFileWhole)
{
    test::ScratchDir dir;
    ASSERT_TRUE(writePngImage(dir / "frame.png", makeImage(1, 1, 1, {10})).ok());
    ASSERT_TRUE(writePngImage(dir / "frame.png", makeImage(2, 1, 3, {1, 2, 3, 4, 5, 6})).ok());
    EXPECT_EQ(dir.list(), std::vector<std::string>{"frame.png"});
    auto read = readPngImage(dir / "frame.png", 3);
    ASSERT_TRUE(read.ok()) << read.error().message;
    EXPECT_EQ(read->pixels, (Bytes{1, 2, 3, 4, 5, 6}));
}

/// Union-find over the pixels differing by more than `levels`: the size of the largest 4-connected region,
/// independently of compareImages' flood fill.
std::size_t largestRegionByUnionFind(const Image& a, const Image& b, int levels)
{
    const int n = a.width * a.height;
    std::vector<int> parent(static_cast<std::size_t>(n));
    std::vector<bool> far(static_cast<std::size_t>(n));
    for (int p = 0; p < n; ++p) {
        parent[p] = p;
        for (int c = 0; c < a.channels; ++c) {
            far[p] = far[p] || std::abs(a.pixels[p * a.channels + c] - b.pixels[p * a.channels + c]) > levels;
        }
    }
    const auto find = [&](int p) {
        while (parent[p] != p) {
            p = parent[p] = parent[parent[p]];
        }
        return p;
    };
    for (int y = 0; y < a.height; ++y) {
        for (int x = 0; x < a.width; ++x) {
            const int p = y * a.width + x;
            if (far[p] && x + 1 < a.width && far[p + 1]) {
                parent[find(p)] = find(p + 1);
            }
            if (far[p] && y + 1 < a.height && far[p + a.width]) {
                parent[find(p)] = find(p + a.width);
            }
        }
    }
    std::vector<std::size_t> size(static_cast<std::size_t>(n), 0);
    std::size_t largest = 0;
    for (int p = 0; p < n; ++p) {
        if (far[p]) {
            largest = std::max(largest, ++size[find(p)]);
        }
    }
    return largest;
}

TEST(ImageTest, ComparingCountsIdenticalPixelsAndFindsTheLargestRegionOverTheLevels)
{
    std::mt19937 random(16);
    for (int trial = 0; trial < 20; ++trial) {
        SCOPED_TRACE(trial);
        const int width = 5 + trial * 3, height = 4 + trial * 2, channels = trial % 2 == 0 ? 3 : 1;
        Image a = makeImage(width, height, channels, Bytes(static_cast<std::size_t>(width * height * channels)));
        for (auto& v : a.pixels) {
            v = static_cast<std::uint8_t>(random() % 256);
        }
        Image b = a;
        std::size_t changed = 0;
        for (int p = 0; p < width * height; ++p) {
            if (random() % 3 == 0) {  // a third of the pixels change in one channel, by 1 to 20 levels
                auto& v = b.pixels[static_cast<std::size_t>(p * channels) + random() % channels];
                const int step = 1 + static_cast<int>(random() % 20);
                v = static_cast<std::uint8_t>(v >= 128 ? v - step : v + step);
                ++changed;
            }
        }
        auto d = compareImages(a, b, 8);
        ASSERT_TRUE(d.ok()) << d.error().message;
        EXPECT_EQ(d->pixels, static_cast<std::size_t>(width * height));
        EXPECT_EQ(d->identical, d->pixels - changed);
        EXPECT_EQ(d->largestRegion, largestRegionByUnionFind(a, b, 8));
        if (d->largestRegion > 0) {  // the pixel named lies in a region over the levels
            const auto* pa = a.pixel(d->largestRegionX, d->largestRegionY);
            const auto* pb = b.pixel(d->largestRegionX, d->largestRegionY);
            int worst = 0;
            for (int c = 0; c < channels; ++c) {
                worst = std::max(worst, std::abs(pa[c] - pb[c]));
            }
            EXPECT_GT(worst, 8);
        }
    }
    // A 5-pixel plus sign over the levels, two lone pixels within them: one region of 5.
    Image a = makeImage(7, 7, 1, Bytes(49, 100));
    Image b = a;
    for (int p : {3 * 7 + 3, 2 * 7 + 3, 4 * 7 + 3, 3 * 7 + 2, 3 * 7 + 4}) {
        b.pixels[static_cast<std::size_t>(p)] = 120;
    }
    b.pixels[0] = 108;
    b.pixels[48] = 92;
    auto d = compareImages(a, b, 8);
    ASSERT_TRUE(d.ok());
    EXPECT_EQ(d->identical, 42u);
    EXPECT_EQ(d->largestRegion, 5u);
    // Diagonal neighbours are separate regions.
    Image c = a;
    c.pixels[0] = c.pixels[8] = c.pixels[16] = 0;
    d = compareImages(a, c, 8);
    ASSERT_TRUE(d.ok());
    EXPECT_EQ(d->largestRegion, 1u);
    auto wrong = compareImages(a, makeImage(7, 6, 1, Bytes(42)), 8);
    ASSERT_FALSE(wrong.ok());
    EXPECT_NE(wrong.error().message.find("7x7x1 and 7x6x1"), std::string::npos) << wrong.error().message;
}

}  // namespace
}  // namespace terrain
