// VTP Binary Terrain (.bt) versions 1.0 to 1.3, after the VTP specification
// (vterrain.org/Implementation/Formats/BT.html and the BT10/BT11/BT12 pages for the older versions).
//
// A 256-byte little-endian header, then columns * rows samples stored column by column, west to east,
// each column south to north. Version 1.0 has its own header layout (int32 data size, a UTM flag, float
// extents, the float flag at byte 42); 1.1 and later use int16 data size and float flag, a horizontal
// units field (1.1/1.2 call it "projection": 0 geographic, 1 UTM) and double extents; 1.2 adds the
// external-projection flag and 1.3 the vertical scale (metres per unit, 0 meaning 1).
//
// The extents are taken as the positions of the corner samples (VTP's grid-node convention), so the
// spacing is (right - left) / (columns - 1). No-data is VTP's INVALID_ELEVATION, -32768 (SHRT_MIN), for
// every sample type.
#include "heightfield/HeightFieldIo.h"

#include "core/AtomicFile.h"
#include "heightfield/HeightFieldIoSupport.h"

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace terrain {

namespace {

constexpr std::size_t kBtHeaderSize = 256;
/// VTP's INVALID_ELEVATION (SHRT_MIN), the no-data marker in int16, int32 and float files alike.
constexpr float kBtNoData = -32768.0f;
/// Metres per degree for geographic (degree) extents: the customary equatorial length of a degree of
/// longitude (scaled by cos(latitude)) and the mean length of a degree of latitude.
constexpr double kMetresPerDegreeLongitudeAtEquator = 111320.0;
constexpr double kMetresPerDegreeLatitude = 110574.0;
constexpr double kInternationalFootMetres = 0.3048;
constexpr double kUsSurveyFootMetres = 1200.0 / 3937.0;
constexpr double kInt32Min = std::numeric_limits<std::int32_t>::min();
constexpr double kInt32Max = std::numeric_limits<std::int32_t>::max();
/// x and y spacings further apart than this (relative) are noted in the description.
constexpr double kSpacingMismatchTolerance = 0.01;

enum class BtUnits { Degrees = 0, Metres = 1, InternationalFeet = 2, UsSurveyFeet = 3 };

struct BtHeader {
    int minorVersion = 0;
    std::int32_t columns = 0;
    std::int32_t rows = 0;
    int dataSize = 0;
    bool isFloat = false;
    BtUnits units = BtUnits::Metres;
    double left = 0.0;
    double right = 0.0;
    double bottom = 0.0;
    double top = 0.0;
    double verticalScale = 1.0;
};

const char* sampleTypeName(const BtHeader& header)
{
    return header.isFloat ? "float32" : header.dataSize == 2 ? "int16" : "int32";
}

const char* unitsName(BtUnits units)
{
    switch (units) {
        case BtUnits::Degrees:
            return "degrees";
        case BtUnits::Metres:
            return "metres";
        case BtUnits::InternationalFeet:
            return "feet";
        case BtUnits::UsSurveyFeet:
            return "US survey feet";
    }
    return "?";
}

double metresPerUnit(BtUnits units)
{
    switch (units) {
        case BtUnits::InternationalFeet:
            return kInternationalFootMetres;
        case BtUnits::UsSurveyFeet:
            return kUsSurveyFootMetres;
        default:
            return 1.0;
    }
}

Expected<BtHeader> parseBtHeader(const std::filesystem::path& path, const std::uint8_t* h)
{
    const std::string name = path.string();
    if (std::memcmp(h, "binterr1.", 9) != 0 || h[9] < '0' || h[9] > '3') {
        return makeError(name, ": not a VTP Binary Terrain file: expected \"binterr1.0\" to \"binterr1.3\" ",
                         "at the start, found \"", detail::printableBytes(h, 10), "\"");
    }
    BtHeader header;
    header.minorVersion = h[9] - '0';
    header.columns = detail::loadLe<std::int32_t>(h + 10);
    header.rows = detail::loadLe<std::int32_t>(h + 14);
    int floatFlag = 0;
    int units = 0;
    if (header.minorVersion == 0) {
        header.dataSize = detail::loadLe<std::int32_t>(h + 18);
        units = detail::loadLe<std::int16_t>(h + 22);  // the UTM flag: 1 UTM (metres), 0 geographic (degrees)
        header.left = detail::loadLe<float>(h + 26);
        header.right = detail::loadLe<float>(h + 30);
        header.bottom = detail::loadLe<float>(h + 34);
        header.top = detail::loadLe<float>(h + 38);
        floatFlag = detail::loadLe<std::int16_t>(h + 42);
        if (units != 0 && units != 1) {
            return makeError(name, ": BT 1.0 UTM flag is ", units, " (expected 0 or 1)");
        }
    } else {
        header.dataSize = detail::loadLe<std::int16_t>(h + 18);
        floatFlag = detail::loadLe<std::int16_t>(h + 20);
        units = detail::loadLe<std::int16_t>(h + 22);
        header.left = detail::loadLe<double>(h + 28);
        header.right = detail::loadLe<double>(h + 36);
        header.bottom = detail::loadLe<double>(h + 44);
        header.top = detail::loadLe<double>(h + 52);
        if (units < 0 || units > 3) {
            return makeError(name, ": BT horizontal units code is ", units,
                             " (expected 0 degrees, 1 metres, 2 feet or 3 US survey feet)");
        }
    }
    header.units = static_cast<BtUnits>(units);
    if (header.minorVersion == 3) {
        const float scale = detail::loadLe<float>(h + 62);
        if (!std::isfinite(scale) || scale < 0.0f) {
            return makeError(name, ": BT vertical scale is ", scale,
                             " (expected a positive number of metres per unit, or 0 for 1)");
        }
        header.verticalScale = scale == 0.0f ? 1.0 : double(scale);
    }
    if (header.columns < 1 || header.rows < 1) {
        return makeError(name, ": BT size is ", header.columns, "x", header.rows,
                         " (columns and rows must be at least 1)");
    }
    if (header.dataSize != 2 && header.dataSize != 4) {
        return makeError(name, ": BT data size is ", header.dataSize, " bytes per sample (expected 2 or 4)");
    }
    if (floatFlag != 0 && floatFlag != 1) {
        return makeError(name, ": BT floating-point flag is ", floatFlag, " (expected 0 or 1)");
    }
    header.isFloat = floatFlag == 1;
    if (header.isFloat && header.dataSize != 4) {
        return makeError(name, ": BT says 2-byte floating-point samples, which the format does not have");
    }
    return header;
}

/// Sets spacing, origin and the description's notes from the extents.
void setGeometry(const BtHeader& header, HeightField& field, std::string& notes)
{
    std::optional<double> dx;
    std::optional<double> dy;
    if (header.columns > 1) {
        dx = (header.right - header.left) / (header.columns - 1);
    }
    if (header.rows > 1) {
        dy = (header.top - header.bottom) / (header.rows - 1);
    }
    if (header.units == BtUnits::Degrees) {
        const double centreLatitude = 0.5 * (header.top + header.bottom) * std::numbers::pi / 180.0;
        if (dx) {
            *dx *= kMetresPerDegreeLongitudeAtEquator * std::cos(centreLatitude);
        }
        if (dy) {
            *dy *= kMetresPerDegreeLatitude;
        }
    } else {
        const double unit = metresPerUnit(header.units);
        if (dx) {
            *dx *= unit;
        }
        if (dy) {
            *dy *= unit;
        }
        field.originX = header.left * unit;
        field.originY = header.bottom * unit;
    }
    const std::optional<double> spacing = dy ? dy : dx;
    if (!spacing) {
        return;  // a single sample: no spacing to speak of
    }
    if (!std::isfinite(*spacing) || *spacing <= 0.0) {
        notes += ", extents give no usable spacing";
        return;
    }
    field.spacing = spacing;
    notes += ", spacing " + detail::formatNumber(*spacing) + " m";
    if (dx && dy && std::abs(*dx - *dy) > kSpacingMismatchTolerance * std::abs(*dy)) {
        notes += " (y; x spacing is " + detail::formatNumber(*dx) + " m)";
    }
}

}  // namespace

Expected<HeightField> readBtHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options)
{
    auto file = detail::InputFile::open(path);
    TERRAIN_TRY(file);
    std::array<std::uint8_t, kBtHeaderSize> headerBytes{};
    if (!file->readAt(0, headerBytes.data(), headerBytes.size())) {
        return makeError(path.string(), ": truncated: a BT header is ", kBtHeaderSize, " bytes, the file has ",
                         file->size());
    }
    auto header = parseBtHeader(path, headerBytes.data());
    TERRAIN_TRY(header);

    const std::uint64_t count = std::uint64_t(header->columns) * std::uint64_t(header->rows);
    TERRAIN_TRY(detail::checkSampleMemory(path, std::uint64_t(header->columns), std::uint64_t(header->rows)));
    const std::uint64_t expectedBytes = count * std::uint64_t(header->dataSize);
    const std::uint64_t foundBytes = file->size() - kBtHeaderSize;
    if (foundBytes < expectedBytes) {
        return makeError(path.string(), ": truncated: expected ", expectedBytes, " bytes of samples, found ",
                         foundBytes, " (the header says ", header->columns, "x", header->rows, " ",
                         sampleTypeName(*header), " samples)");
    }

    HeightField field;
    field.width = header->columns;
    field.height = header->rows;
    field.integerSamples = !header->isFloat;
    field.verticalScale = header->verticalScale;
    detail::allocateSamples(field);
    const std::uint64_t rows = std::uint64_t(header->rows);
    const bool isFloat = header->isFloat;
    const int dataSize = header->dataSize;
    const bool ok = detail::forEachSample(*file, kBtHeaderSize, count, static_cast<std::size_t>(dataSize),
                                          [&](std::uint64_t k, const std::uint8_t* p) {
                                              float value = isFloat         ? detail::loadLe<float>(p)
                                                            : dataSize == 2 ? float(detail::loadLe<std::int16_t>(p))
                                                                            : float(detail::loadLe<std::int32_t>(p));
                                              if (value == kBtNoData) {
                                                  value = std::nanf("");
                                              }
                                              field.at(static_cast<int>(k / rows), static_cast<int>(k % rows)) = value;
                                          });
    if (!ok) {
        return makeError(path.string(), ": read error in the samples");
    }
    detail::applyNoData(field, options);

    std::string notes;
    setGeometry(*header, field, notes);
    field.description = "BT 1." + std::to_string(header->minorVersion) + " " + sampleTypeName(*header) + " " +
                        std::to_string(field.width) + "x" + std::to_string(field.height) + ", " +
                        unitsName(header->units) + notes;
    if (header->verticalScale != 1.0) {
        field.description += ", vertical scale " + detail::formatNumber(header->verticalScale) + " m";
    }
    return field;
}

Status writeBtHeightField(const std::filesystem::path& path, const HeightField& field, BtSampleType type,
                          int minorVersion)
{
    const std::string name = path.string();
    if (minorVersion < 0 || minorVersion > 3) {
        return makeError(name, ": cannot write BT version 1.", minorVersion, " (1.0 to 1.3 are supported)");
    }
    TERRAIN_TRY(detail::checkFieldShape(path, field));
    const double spacing = field.spacing.value_or(1.0);
    if (!std::isfinite(spacing) || spacing <= 0.0) {
        return makeError(name, ": cannot write a BT file with spacing ", spacing, " m");
    }
    const double scale = field.verticalScale.value_or(1.0);
    // BT stores no vertical offset, and before 1.3 no scale: then write metres instead of native values.
    const bool writeMetres = field.verticalOffset != 0.0 || (minorVersion < 3 && scale != 1.0);

    const int dataSize = type == BtSampleType::Int16 ? 2 : 4;
    const double left = field.originX;
    const double right = field.originX + (field.width - 1) * spacing;
    const double bottom = field.originY;
    const double top = field.originY + (field.height - 1) * spacing;
    const std::int16_t floatFlag = type == BtSampleType::Float32 ? 1 : 0;
    const std::int16_t metres = static_cast<std::int16_t>(BtUnits::Metres);
    std::vector<std::uint8_t> header;
    ByteWriter h(header);
    h.putFixedString("binterr1." + std::to_string(minorVersion), 10);
    h.put<std::int32_t>(field.width);
    h.put<std::int32_t>(field.height);
    if (minorVersion == 0) {
        h.put<std::int32_t>(dataSize);
        h.put<std::int16_t>(metres);  // UTM flag: metric coordinates
        h.put<std::int16_t>(0);       // UTM zone
        h.put(static_cast<float>(left));
        h.put(static_cast<float>(right));
        h.put(static_cast<float>(bottom));
        h.put(static_cast<float>(top));
        h.put<std::int16_t>(floatFlag);
    } else {
        h.put(static_cast<std::int16_t>(dataSize));
        h.put<std::int16_t>(floatFlag);
        h.put<std::int16_t>(metres);
        h.put<std::int16_t>(0);   // UTM zone
        h.put<std::int16_t>(-2);  // datum: none (as GDAL writes)
        h.put(left);
        h.put(right);
        h.put(bottom);
        h.put(top);
        if (minorVersion >= 2) {
            h.put<std::int16_t>(0);  // projection fully described by the header
        }
        if (minorVersion == 3) {
            h.put(writeMetres ? 1.0f : static_cast<float>(scale));
        }
    }
    h.padTo(kBtHeaderSize);

    auto file = AtomicFile::create(path);
    TERRAIN_TRY(file);
    file->write(header.data(), header.size());
    std::vector<std::uint8_t> column;
    column.reserve(static_cast<std::size_t>(field.height) * dataSize);
    for (int i = 0; i < field.width; ++i) {
        column.clear();
        ByteWriter out(column);
        for (int j = 0; j < field.height; ++j) {
            double value = field.at(i, j);
            if (writeMetres) {
                value = field.verticalOffset + scale * value;
            }
            const bool noData = std::isnan(value);
            if (noData) {
                value = kBtNoData;
            }
            switch (type) {
                case BtSampleType::Int16:
                    // Finite values stop at -32767 so that they never turn into the no-data marker.
                    out.put(
                        static_cast<std::int16_t>(detail::roundClamp(value, noData ? -32768.0 : -32767.0, 32767.0)));
                    break;
                case BtSampleType::Int32:
                    out.put(static_cast<std::int32_t>(detail::roundClamp(value, kInt32Min, kInt32Max)));
                    break;
                case BtSampleType::Float32:
                    out.put(static_cast<float>(value));
                    break;
            }
        }
        file->write(column.data(), column.size());
    }
    return file->commit();
}

}  // namespace terrain
