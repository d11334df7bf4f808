// Detail textures for histogram-preserving tiling (synthesis/DetailTexture.h, gaussianized) against the normal
// distribution, and the test's own autocorrelation measure (TestSupport.h) against patterns whose answer is known.
#include "synthesis/DetailTexture.h"

#include "TestSupport.h"
#include "core/SplitMix64.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace terrain {
namespace {

Image grayImage(int size, const std::function<double(int, int)>& value)
{
    Image image{size, size, 1, std::vector<std::uint8_t>(static_cast<std::size_t>(size) * size)};
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
            *image.pixel(x, y) = static_cast<std::uint8_t>(std::clamp(std::round(value(x, y)), 0.0, 255.0));
        }
    }
    return image;
}

TEST(DetailTextureTest, GaussianizedKeepsOrderMeanAndDeviationAndIsNormal)
{
    SplitMix64 random(11);
    // Skewed (squared uniform) and bimodal inputs.
    const Image skewed = grayImage(128, [&](int, int) {
        const double u = static_cast<double>(random.next() >> 11) * 0x1.0p-53;
        return 40.0 + 200.0 * u * u;
    });
    const Image bimodal = grayImage(128, [&](int x, int) { return (x < 64 ? 70.0 : 180.0) + random.below(21) - 10; });
    for (const Image* input : {&skewed, &bimodal}) {
        const Image out = gaussianized(*input);
        ASSERT_EQ(out.pixels.size(), input->pixels.size());
        double inMean = 0, outMean = 0, inSquare = 0, outSquare = 0;
        const double n = static_cast<double>(out.pixels.size());
        for (std::size_t i = 0; i < out.pixels.size(); ++i) {
            inMean += input->pixels[i] / n;
            outMean += out.pixels[i] / n;
            inSquare += input->pixels[i] * input->pixels[i] / n;
            outSquare += out.pixels[i] * out.pixels[i] / n;
            for (std::size_t j : {i / 2, (i * 7) % out.pixels.size()}) {  // the order is kept
                if (input->pixels[i] < input->pixels[j]) {
                    EXPECT_LE(out.pixels[i], out.pixels[j]);
                }
            }
        }
        const double inDeviation = std::sqrt(inSquare - inMean * inMean);
        const double outDeviation = std::sqrt(outSquare - outMean * outMean);
        EXPECT_NEAR(outMean, inMean, 1.0);
        EXPECT_NEAR(outDeviation, inDeviation, 0.03 * inDeviation);
        EXPECT_NEAR(meanGray(out), outMean / 255.0, 1e-12);
        // Kolmogorov-Smirnov distance to the normal distribution of that mean and deviation (the grays' rounding
        // and the input's ties allow a little).
        std::vector<std::uint8_t> sorted = out.pixels;
        std::sort(sorted.begin(), sorted.end());
        double distance = 0.0;
        for (std::size_t i = 0; i < sorted.size(); ++i) {
            if (i + 1 < sorted.size() && sorted[i + 1] == sorted[i]) {
                continue;  // the empirical function's value after the last of equal grays
            }
            const double z = (sorted[i] + 0.5 - inMean) / inDeviation;
            const double normal = 0.5 * std::erfc(-z / std::sqrt(2.0));
            distance = std::max(distance, std::abs(static_cast<double>(i + 1) / n - normal));
        }
        EXPECT_LT(distance, 0.03);
    }
    // A flat image stays flat.
    const Image flat = grayImage(8, [](int, int) { return 90.0; });
    EXPECT_EQ(gaussianized(flat).pixels, flat.pixels);
}

TEST(DetailTextureTest, AutocorrelationPeakFindsARepeatAndNotNoise)
{
    SplitMix64 random(5);
    const int w = 200, h = 120;
    std::vector<double> tile(37 * 37), tiled(static_cast<std::size_t>(w) * h), noise(tiled.size());
    for (double& v : tile) {
        v = static_cast<double>(random.next() >> 11) * 0x1.0p-53;
    }
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            tiled[static_cast<std::size_t>(y) * w + x] = tile[static_cast<std::size_t>(y % 37) * 37 + x % 37];
            noise[static_cast<std::size_t>(y) * w + x] = static_cast<double>(random.next() >> 11) * 0x1.0p-53;
        }
    }
    const test::AutocorrelationPeak repeat = test::autocorrelationPeak(tiled, w, h, 8, 60);
    EXPECT_NEAR(repeat.value, 1.0, 0.01);
    EXPECT_EQ(repeat.dx * repeat.dx + repeat.dy * repeat.dy, 37 * 37);
    EXPECT_LT(test::autocorrelationPeak(noise, w, h, 8, 60).value, 0.05);
}

}  // namespace
}  // namespace terrain
