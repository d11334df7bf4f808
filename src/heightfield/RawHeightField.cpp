// Headerless raw 16-bit height fields (.raw, .r16, .bin): width * height samples, row 0 = north edge,
// signed or unsigned, little- or big-endian. The file says nothing about itself, so the size comes from
// the caller and the file must hold exactly width * height * 2 bytes.
#include "heightfield/HeightFieldIo.h"

#include "core/AtomicFile.h"
#include "heightfield/HeightFieldIoSupport.h"

#include <cmath>

namespace terrain {

namespace {

constexpr std::size_t kRawBytesPerSample = 2;
/// Written for NaN in signed files: the SRTM void value, which readers pass as options.noData.
constexpr double kRawSignedNoData = -32768.0;

std::string rawVariant(bool isSigned, bool bigEndian)
{
    return std::string("raw 16-bit ") + (isSigned ? "signed " : "unsigned ") +
           (bigEndian ? "big-endian" : "little-endian");
}

}  // namespace

Expected<HeightField> readRawHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options)
{
    const std::string name = path.string();
    if (options.rawWidth < 1 || options.rawHeight < 1) {
        return makeError(name, ": a raw 16-bit file does not store its size; give it (rawWidth, rawHeight >= 1), got ",
                         options.rawWidth, "x", options.rawHeight);
    }
    auto file = detail::InputFile::open(path);
    TERRAIN_TRY(file);
    const std::uint64_t width = std::uint64_t(options.rawWidth);
    const std::uint64_t height = std::uint64_t(options.rawHeight);
    const std::uint64_t expectedBytes = width * height * kRawBytesPerSample;
    if (file->size() != expectedBytes) {
        return makeError(name, ": a ", width, "x", height, " raw 16-bit file has exactly ", expectedBytes,
                         " bytes, this one has ", file->size());
    }
    TERRAIN_TRY(detail::checkSampleMemory(path, width, height));

    HeightField field;
    field.width = options.rawWidth;
    field.height = options.rawHeight;
    field.integerSamples = true;
    detail::allocateSamples(field);
    const bool isSigned = options.rawSigned;
    const bool bigEndian = options.rawBigEndian;
    const bool ok = detail::forEachSample(
        *file, 0, width * height, kRawBytesPerSample, [&](std::uint64_t k, const std::uint8_t* p) {
            const std::uint16_t bits = bigEndian ? detail::loadU16Be(p) : detail::loadLe<std::uint16_t>(p);
            const int row = static_cast<int>(k / width);
            field.at(static_cast<int>(k % width), field.height - 1 - row) =
                isSigned ? float(static_cast<std::int16_t>(bits)) : float(bits);
        });
    if (!ok) {
        return makeError(name, ": read error in the samples");
    }
    detail::applyNoData(field, options);
    field.description =
        rawVariant(isSigned, bigEndian) + " " + std::to_string(field.width) + "x" + std::to_string(field.height);
    return field;
}

Status writeRawHeightField(const std::filesystem::path& path, const HeightField& field, bool isSigned, bool bigEndian)
{
    TERRAIN_TRY(detail::checkFieldShape(path, field));
    if (!isSigned) {
        TERRAIN_TRY(detail::checkNoNaN(path, field, "unsigned raw 16-bit"));
    }
    const double lo = isSigned ? -32768.0 : 0.0;
    const double hi = isSigned ? 32767.0 : 65535.0;
    auto file = AtomicFile::create(path);
    TERRAIN_TRY(file);
    std::vector<std::uint8_t> row(static_cast<std::size_t>(field.width) * kRawBytesPerSample);
    for (int r = 0; r < field.height; ++r) {
        const int j = field.height - 1 - r;
        for (int i = 0; i < field.width; ++i) {
            const float sample = field.at(i, j);
            const double value = std::isnan(sample) ? kRawSignedNoData : detail::roundClamp(sample, lo, hi);
            const std::uint16_t bits = isSigned ? static_cast<std::uint16_t>(static_cast<std::int16_t>(value))
                                                : static_cast<std::uint16_t>(value);
            std::uint8_t* p = row.data() + i * kRawBytesPerSample;
            if (bigEndian) {
                detail::storeU16Be(p, bits);
            } else {
                p[0] = static_cast<std::uint8_t>(bits);
                p[1] = static_cast<std::uint8_t>(bits >> 8);
            }
        }
        file->write(row.data(), row.size());
    }
    return file->commit();
}

}  // namespace terrain
