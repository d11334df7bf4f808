// Grayscale PNG height fields, 8 or 16 bits (1/2/4-bit read too), values as stored. PNG row 0 is the
// north edge, so row r becomes j = height - 1 - r (HeightField.h: j = 0 is south).
#include "heightfield/HeightFieldIo.h"

#include "heightfield/HeightFieldIoSupport.h"
#include "heightfield/PngCodec.h"

#include <cmath>

namespace terrain {

Expected<HeightField> readPngHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options)
{
    auto decoded = detail::decodePng(path, detail::PngReadMode::NativeGray, 1, sizeof(float));
    TERRAIN_TRY(decoded);
    HeightField field;
    field.width = decoded->width;
    field.height = decoded->height;
    field.integerSamples = true;
    TERRAIN_TRY(detail::checkSampleMemory(path, std::uint64_t(field.width), std::uint64_t(field.height)));
    detail::allocateSamples(field);

    const std::uint8_t* pixels = decoded->pixels.data();
    const bool sixteen = decoded->bytesPerChannel == 2;
    for (int row = 0; row < field.height; ++row) {
        const int j = field.height - 1 - row;
        const std::uint8_t* p = pixels + static_cast<std::size_t>(row) * field.width * decoded->bytesPerChannel;
        for (int i = 0; i < field.width; ++i) {
            field.at(i, j) = sixteen ? float(detail::loadU16Be(p + 2 * i)) : float(p[i]);
        }
    }
    detail::applyNoData(field, options);
    field.description = "PNG " + std::to_string(decoded->sourceBitDepth) + "-bit gray " + std::to_string(field.width) +
                        "x" + std::to_string(field.height);
    return field;
}

Status writePngHeightField(const std::filesystem::path& path, const HeightField& field, int bitDepth)
{
    if (bitDepth != 8 && bitDepth != 16) {
        return makeError(path.string(), ": PNG height fields are 8 or 16 bits, not ", bitDepth);
    }
    TERRAIN_TRY(detail::checkFieldShape(path, field));
    TERRAIN_TRY(detail::checkNoNaN(path, field, "PNG"));
    const double maxValue = bitDepth == 16 ? 65535.0 : 255.0;
    const std::size_t bytesPerSample = static_cast<std::size_t>(bitDepth / 8);
    std::vector<std::uint8_t> pixels(field.samples.size() * bytesPerSample);
    for (int row = 0; row < field.height; ++row) {
        const int j = field.height - 1 - row;
        std::uint8_t* p = pixels.data() + static_cast<std::size_t>(row) * field.width * bytesPerSample;
        for (int i = 0; i < field.width; ++i) {
            const double value = detail::roundClamp(field.at(i, j), 0.0, maxValue);
            if (bitDepth == 16) {
                detail::storeU16Be(p + 2 * i, static_cast<std::uint16_t>(value));
            } else {
                p[i] = static_cast<std::uint8_t>(value);
            }
        }
    }
    return detail::encodePng(path, field.width, field.height, 1, bitDepth, pixels.data());
}

}  // namespace terrain
