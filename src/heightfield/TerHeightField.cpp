// Terragen terrain files (.ter), after Planetside's "Terragen Terrain file specification"
// (planetside.co.uk/terragen/dev/tgterrain.html). Little-endian.
//
// "TERRAGEN" "TERRAIN " then 4-byte-aligned chunks that carry no length, so a reader must know each one:
//   SIZE  int16 points on the shortest side minus 1, 2 bytes padding
//   XPTS  int16 points along x, 2 bytes padding (with YPTS, required when the terrain is not square)
//   YPTS  int16 points along y, 2 bytes padding
//   SCAL  3 x float32 metres per terrain unit along x, y, z (default 30)
//   CRAD  float32 planet radius in km
//   CRVM  uint32 curve mode
//   ALTW  int16 HeightScale, int16 BaseHeight, xpts * ypts int16 Elevations, rows of increasing x starting
//         at the y = 0 edge (south, as GDAL's reader also takes it)
//   "EOF "
// Height in metres = SCAL.z * (BaseHeight + Elevation * HeightScale / 65536).
// Point counts are read as unsigned 16-bit (as GDAL does), so sizes up to 65535 work.
#include "heightfield/HeightFieldIo.h"

#include "core/AtomicFile.h"
#include "heightfield/HeightFieldIoSupport.h"

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace terrain {

namespace {

constexpr std::size_t kTerHeaderSize = 16;
constexpr std::size_t kMarkerSize = 4;
/// Metres per terrain unit when there is no SCAL chunk (the specification's default).
constexpr float kTerDefaultScale = 30.0f;
/// HeightScale is in units of 1/65536 terrain unit per elevation step.
constexpr double kHeightScaleUnit = 65536.0;
/// Largest point count a 16-bit XPTS/YPTS/SIZE field holds (read as unsigned).
constexpr int kTerMaxPoints = 65535;

bool markerIs(const std::uint8_t* marker, const char* name)
{
    return std::memcmp(marker, name, kMarkerSize) == 0;
}

}  // namespace

Expected<HeightField> readTerHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options)
{
    const std::string name = path.string();
    auto file = detail::InputFile::open(path);
    TERRAIN_TRY(file);
    std::array<std::uint8_t, kTerHeaderSize> magic{};
    if (!file->readAt(0, magic.data(), magic.size()) || std::memcmp(magic.data(), "TERRAGENTERRAIN ", 16) != 0) {
        const std::size_t shown = static_cast<std::size_t>(std::min<std::uint64_t>(file->size(), kTerHeaderSize));
        return makeError(name, ": not a Terragen terrain file: expected \"TERRAGENTERRAIN \" at the start, found \"",
                         detail::printableBytes(magic.data(), shown), "\"");
    }

    HeightField field;
    std::optional<int> size;
    std::optional<int> xPoints;
    std::optional<int> yPoints;
    std::array<float, 3> scal = {kTerDefaultScale, kTerDefaultScale, kTerDefaultScale};
    std::int16_t heightScale = 0;
    std::int16_t baseHeight = 0;
    bool haveAltw = false;

    std::uint64_t position = kTerHeaderSize;
    while (true) {
        std::array<std::uint8_t, kMarkerSize> marker{};
        if (!file->readAt(position, marker.data(), marker.size())) {
            if (haveAltw) {
                break;  // no "EOF " marker: tolerated, the elevations are complete
            }
            return makeError(name, ": ends at byte ", position, " before an ALTW (elevation) chunk");
        }
        const std::uint64_t chunkStart = position;
        position += kMarkerSize;
        // Reads `count` bytes of chunk data; false when the file ends first.
        auto readData = [&](void* data, std::size_t count) {
            const bool ok = file->readAt(position, data, count);
            position += count;
            return ok;
        };
        const std::string markerText = detail::printableBytes(marker.data(), marker.size());
        auto truncatedChunk = [&]() {
            return makeError(name, ": truncated ", markerText, " chunk at byte ", chunkStart);
        };

        if (markerIs(marker.data(), "SIZE") || markerIs(marker.data(), "XPTS") || markerIs(marker.data(), "YPTS")) {
            std::array<std::uint8_t, 4> data{};
            if (!readData(data.data(), data.size())) {
                return truncatedChunk();
            }
            const int value = detail::loadLe<std::uint16_t>(data.data());
            if (markerIs(marker.data(), "SIZE")) {
                size = value + 1;
                continue;
            }
            if (haveAltw) {
                return makeError(name, ": ", markerText, " chunk at byte ", chunkStart,
                                 " comes after the elevations (ALTW); it must come before");
            }
            if (value < 1) {
                return makeError(name, ": ", markerText, " is 0 (the terrain needs at least 1 point per side)");
            }
            (markerIs(marker.data(), "XPTS") ? xPoints : yPoints) = value;
        } else if (markerIs(marker.data(), "SCAL")) {
            std::array<std::uint8_t, 12> data{};
            if (!readData(data.data(), data.size())) {
                return truncatedChunk();
            }
            for (std::size_t k = 0; k < 3; ++k) {
                scal[k] = detail::loadLe<float>(data.data() + 4 * k);
                if (!std::isfinite(scal[k]) || scal[k] <= 0.0f) {
                    return makeError(name, ": SCAL chunk holds ", scal[k],
                                     " (expected positive metres per terrain unit)");
                }
            }
        } else if (markerIs(marker.data(), "CRAD") || markerIs(marker.data(), "CRVM")) {
            // Planet radius (float32) and curve mode (uint32): they do not change the grid.
            if (position + 4 > file->size()) {
                return truncatedChunk();
            }
            position += 4;
        } else if (markerIs(marker.data(), "ALTW")) {
            if (!size) {
                return makeError(name, ": ALTW chunk at byte ", chunkStart, " comes before the SIZE chunk");
            }
            if (haveAltw) {
                return makeError(name, ": second ALTW chunk at byte ", chunkStart);
            }
            std::array<std::uint8_t, 4> data{};
            if (!readData(data.data(), data.size())) {
                return truncatedChunk();
            }
            heightScale = detail::loadLe<std::int16_t>(data.data());
            baseHeight = detail::loadLe<std::int16_t>(data.data() + 2);
            field.width = xPoints.value_or(*size);
            field.height = yPoints.value_or(*size);
            const std::uint64_t count = std::uint64_t(field.width) * std::uint64_t(field.height);
            TERRAIN_TRY(detail::checkSampleMemory(path, std::uint64_t(field.width), std::uint64_t(field.height)));
            const std::uint64_t expectedBytes = count * 2;
            const std::uint64_t foundBytes = file->size() - std::min(file->size(), position);
            if (foundBytes < expectedBytes) {
                return makeError(name, ": truncated: expected ", expectedBytes, " bytes of samples, found ", foundBytes,
                                 " (the header says ", field.width, "x", field.height, " samples)");
            }
            detail::allocateSamples(field);
            const std::uint64_t width = std::uint64_t(field.width);
            auto decode = [&](std::uint64_t k, const std::uint8_t* p) {
                field.at(static_cast<int>(k % width), static_cast<int>(k / width)) =
                    float(detail::loadLe<std::int16_t>(p));
            };
            if (!detail::forEachSample(*file, position, count, 2, decode)) {
                return makeError(name, ": read error in the ALTW samples");
            }
            position += expectedBytes;
            haveAltw = true;
        } else if (markerIs(marker.data(), "EOF ")) {
            if (haveAltw) {
                break;
            }
            // Some writers put "EOF " before ALTW; keep looking for the elevations.
        } else if (chunkStart % 4 != 0) {
            // Chunks are 4-byte aligned: an ALTW with an odd number of points is followed by 2 padding bytes.
            position = (chunkStart + 3) / 4 * 4;
        } else {
            return makeError(name, ": unknown chunk \"", markerText, "\" at byte ", chunkStart,
                             "; Terragen chunks carry no length, so it cannot be skipped");
        }
    }

    field.integerSamples = true;
    field.spacing = double(scal[0]);
    field.verticalScale = double(scal[2]) * heightScale / kHeightScaleUnit;
    field.verticalOffset = double(scal[2]) * baseHeight;
    detail::applyNoData(field, options);
    field.description = "Terragen " + std::to_string(field.width) + "x" + std::to_string(field.height) + ", spacing " +
                        detail::formatNumber(scal[0]) + " m, HeightScale " + std::to_string(heightScale) +
                        ", BaseHeight " + std::to_string(baseHeight);
    if (scal[1] != scal[0]) {
        field.description += " (x; SCAL y is " + detail::formatNumber(scal[1]) + " m)";
    }
    if (scal[2] != scal[0]) {
        field.description += ", vertical SCAL " + detail::formatNumber(scal[2]) + " m";
    }
    return field;
}

namespace {

/// The ALTW encoding chosen for a field: metres = scal * (baseHeight + elevation * heightScale / 65536).
struct TerEncoding {
    std::int16_t heightScale = 1;
    std::int16_t baseHeight = 0;
    std::vector<std::int16_t> elevations;  ///< index j * width + i
};

/// When the field's own mapping is already a Terragen one (e.g. it was read from a .ter file) and every
/// native value is an int16, keep the natives: the file then round-trips exactly.
bool tryNativeEncoding(const HeightField& field, float scal, TerEncoding& encoding)
{
    if (!field.verticalScale) {
        return false;
    }
    const double heightScale = *field.verticalScale * kHeightScaleUnit / scal;
    const double baseHeight = field.verticalOffset / scal;
    auto isInt16 = [](double v) {
        return v == std::nearbyint(v) && v >= std::numeric_limits<std::int16_t>::min() &&
               v <= std::numeric_limits<std::int16_t>::max();
    };
    // Exact within float-to-double rounding of SCAL: a relative 1e-9 absorbs it.
    auto nearInt = [](double v) { return std::abs(v - std::nearbyint(v)) <= 1e-9 * std::max(1.0, std::abs(v)); };
    if (!nearInt(heightScale) || !nearInt(baseHeight) || !isInt16(std::nearbyint(heightScale)) ||
        !isInt16(std::nearbyint(baseHeight)) || std::nearbyint(heightScale) < 1) {
        return false;
    }
    for (float sample : field.samples) {
        if (!isInt16(sample)) {
            return false;
        }
    }
    encoding.heightScale = static_cast<std::int16_t>(std::nearbyint(heightScale));
    encoding.baseHeight = static_cast<std::int16_t>(std::nearbyint(baseHeight));
    encoding.elevations.assign(field.samples.begin(), field.samples.end());
    return true;
}

/// Picks BaseHeight at the middle of the range and the smallest HeightScale that fits the range into
/// int16 elevations: the finest step (scal * HeightScale / 65536 metres) the format allows for this field.
Status quantizeEncoding(const std::filesystem::path& path, const HeightField& field, float scal, TerEncoding& encoding)
{
    const double scale = field.verticalScale.value_or(1.0);
    std::vector<double> units(field.samples.size());
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    for (std::size_t k = 0; k < units.size(); ++k) {
        units[k] = (field.verticalOffset + scale * field.samples[k]) / scal;  // terrain units
        lo = std::min(lo, units[k]);
        hi = std::max(hi, units[k]);
    }
    const double base = std::nearbyint(0.5 * (lo + hi));
    if (!std::isfinite(lo) || !std::isfinite(hi) || base < std::numeric_limits<std::int16_t>::min() ||
        base > std::numeric_limits<std::int16_t>::max()) {
        return makeError(path.string(), ": heights ", lo * scal, " .. ", hi * scal,
                         " m do not fit a Terragen file with SCAL ", scal, " m");
    }
    const double needed = std::max((hi - base) * kHeightScaleUnit / 32767.0, (base - lo) * kHeightScaleUnit / 32768.0);
    const double heightScale = std::max(1.0, std::ceil(needed));
    if (heightScale > std::numeric_limits<std::int16_t>::max()) {
        return makeError(path.string(), ": height range ", lo * scal, " .. ", hi * scal,
                         " m is too large for a Terragen file with SCAL ", scal, " m");
    }
    encoding.heightScale = static_cast<std::int16_t>(heightScale);
    encoding.baseHeight = static_cast<std::int16_t>(base);
    encoding.elevations.resize(units.size());
    for (std::size_t k = 0; k < units.size(); ++k) {
        encoding.elevations[k] = static_cast<std::int16_t>(
            detail::roundClamp((units[k] - base) * kHeightScaleUnit / heightScale, -32768.0, 32767.0));
    }
    return {};
}

}  // namespace

Status writeTerHeightField(const std::filesystem::path& path, const HeightField& field)
{
    const std::string name = path.string();
    TERRAIN_TRY(detail::checkFieldShape(path, field));
    if (field.width > kTerMaxPoints || field.height > kTerMaxPoints) {
        return makeError(name, ": a ", field.width, "x", field.height,
                         " height field is too large for Terragen (at most ", kTerMaxPoints, " points per side)");
    }
    TERRAIN_TRY(detail::checkNoNaN(path, field, "Terragen"));
    const float scal = field.spacing ? static_cast<float>(*field.spacing) : kTerDefaultScale;
    if (!std::isfinite(scal) || scal <= 0.0f) {
        return makeError(name, ": cannot write a Terragen file with spacing ", scal, " m");
    }
    TerEncoding encoding;
    if (!tryNativeEncoding(field, scal, encoding)) {
        TERRAIN_TRY(quantizeEncoding(path, field, scal, encoding));
    }

    std::vector<std::uint8_t> header;
    ByteWriter h(header);
    auto putPaddedPoints = [&](int value) {
        h.put(static_cast<std::uint16_t>(value));
        h.put<std::uint16_t>(0);
    };
    h.putFixedString("TERRAGENTERRAIN ", kTerHeaderSize);
    h.putFixedString("SIZE", kMarkerSize);
    putPaddedPoints(std::min(field.width, field.height) - 1);
    if (field.width != field.height) {
        h.putFixedString("XPTS", kMarkerSize);
        putPaddedPoints(field.width);
        h.putFixedString("YPTS", kMarkerSize);
        putPaddedPoints(field.height);
    }
    h.putFixedString("SCAL", kMarkerSize);
    h.put(scal);
    h.put(scal);
    h.put(scal);
    h.putFixedString("ALTW", kMarkerSize);
    h.put(encoding.heightScale);
    h.put(encoding.baseHeight);

    auto file = AtomicFile::create(path);
    TERRAIN_TRY(file);
    file->write(header.data(), header.size());
    std::vector<std::uint8_t> row;
    row.reserve(static_cast<std::size_t>(field.width) * 2);
    for (int j = 0; j < field.height; ++j) {
        row.clear();
        ByteWriter out(row);
        for (int i = 0; i < field.width; ++i) {
            out.put(encoding.elevations[static_cast<std::size_t>(j) * field.width + i]);
        }
        file->write(row.data(), row.size());
    }
    if (field.samples.size() % 2 != 0) {
        const std::uint8_t padding[2] = {0, 0};  // keep the next chunk 4-byte aligned
        file->write(padding, sizeof padding);
    }
    file->write("EOF ", kMarkerSize);
    return file->commit();
}

}  // namespace terrain
