#include "quadtree/MapFormat.h"

#include "core/ByteIo.h"
#include "core/Check.h"

#include <zlib.h>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>

namespace terrain {

namespace {
constexpr std::size_t kSourceBytes = 96;
/// Version 6 keeps 88 of them for the source; the last 8 give the georeference block.
constexpr std::size_t kSourceBytesV6 = 88;
}  // namespace

std::uint32_t crc32Of(std::span<const std::uint8_t> bytes)
{
    uLong crc = ::crc32(0L, Z_NULL, 0);
    // zlib takes uInt lengths: feed in pieces so payloads over 4 GiB are still summed correctly.
    std::size_t done = 0;
    while (done < bytes.size()) {
        auto piece = static_cast<uInt>(std::min<std::size_t>(bytes.size() - done, 1u << 30));
        crc = ::crc32(crc, bytes.data() + done, piece);
        done += piece;
    }
    return static_cast<std::uint32_t>(crc);
}

double MapHeader::spacingAt(int level) const
{
    return sampleSpacing * std::ldexp(1.0, static_cast<int>(levels) - 1 - level);
}

bool DetailRecipe::sameSynthesis(const DetailRecipe& other) const
{
    return scheme == other.scheme && materials == other.materials && roughness == other.roughness &&
           (scheme != "kobbelt" || omega == other.omega);
}

std::string describeHeightCoding(const MapHeader& header)
{
    std::ostringstream out;
    out << (header.heightCoding == kHeightCodingPifs ? "fractal (PIFS), measured " : "Kobbelt residual, ");
    if (header.maxErrorBound == 0) {
        out << "lossless";
    } else {
        out << "max error " << header.maxErrorBound << " m";
    }
    return out.str();
}

std::string DetailRecipe::describe() const
{
    std::ostringstream s;
    s << scheme;
    if (scheme == "kobbelt") {
        s << " omega " << omega;
    }
    if (materials.empty()) {
        s << ", no materials (subdivision only)";
    }
    for (std::size_t i = 0; i < materials.size(); ++i) {
        char hash[24];
        std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(materials[i].hash));
        s << (i == 0 ? ", materials " : ", ") << materials[i].name << " (hash " << hash << ")";
    }
    if (roughness) {
        s << ", the terrain's roughness continued";
    }
    return s.str();
}

std::vector<std::uint8_t> encodeDetailRecipe(const DetailRecipe& recipe, std::uint32_t version)
{
    TERRAIN_EXPECTS(recipe.scheme.size() <= 32 && recipe.materials.size() <= kMaxRecipeMaterials,
                    "encodeDetailRecipe: scheme of at most 32 bytes, at most kMaxRecipeMaterials materials");
    std::vector<std::uint8_t> bytes;
    ByteWriter w(bytes);
    auto putText = [&](const std::string& text, std::size_t length) {
        w.put(static_cast<std::uint8_t>(length));
        for (std::size_t k = 0; k < length; ++k) {
            w.put(static_cast<std::uint8_t>(text[k]));
        }
    };
    putText(recipe.scheme, recipe.scheme.size());
    w.put(recipe.omega);
    w.put(static_cast<std::uint32_t>(recipe.materials.size()));
    for (const auto& m : recipe.materials) {
        putText(m.name, std::min(m.name.size(), kMaxRecipeNameBytes));
        w.put(m.hash);
    }
    if (version >= 5) {
        w.put(static_cast<std::uint8_t>(recipe.roughness ? 1 : 0));
    }
    return bytes;
}

void setDetailRecipe(MapHeader& header, std::optional<DetailRecipe> recipe)
{
    header.detailRecipe = std::move(recipe);
    header.detailRecipeBytes = 0;
    header.detailRecipeCrc = 0;
    if (header.detailRecipe) {
        const auto bytes = encodeDetailRecipe(*header.detailRecipe, header.version);
        header.detailRecipeBytes = static_cast<std::uint32_t>(bytes.size());
        header.detailRecipeCrc = crc32Of(bytes);
    }
}

namespace {

/// A block after the header (`what`: "detail recipe", "roughness block") has the size and CRC the header
/// gives it.
Status checkBlock(std::span<const std::uint8_t> bytes, std::uint32_t size, std::uint32_t crc, const std::string& name,
                  const char* what)
{
    if (bytes.size() != size) {
        return makeError(name, ": invalid ", what, ": ", bytes.size(), " bytes, the header says ", size);
    }
    if (crc32Of(bytes) != crc) {
        return makeError(name, ": ", what, " checksum mismatch (file is corrupt)");
    }
    return {};
}

}  // namespace

Status decodeDetailRecipe(std::span<const std::uint8_t> bytes, MapHeader& header, const std::string& name)
{
    auto bad = [&](auto&&... what) { return makeError(name, ": invalid detail recipe: ", what...); };
    TERRAIN_TRY(checkBlock(bytes, header.detailRecipeBytes, header.detailRecipeCrc, name, "detail recipe"));
    ByteReader r(bytes);
    auto text = [&](std::size_t length) {
        std::string t;
        for (std::size_t i = 0; i < length && !r.failed(); ++i) {
            t.push_back(static_cast<char>(r.get<std::uint8_t>()));
        }
        return t;
    };
    DetailRecipe recipe;
    recipe.scheme = text(r.get<std::uint8_t>());
    recipe.omega = r.get<double>();
    const auto count = r.get<std::uint32_t>();
    if (count > kMaxRecipeMaterials) {
        return bad(count, " materials, at most ", kMaxRecipeMaterials);
    }
    for (std::uint32_t i = 0; i < count && !r.failed(); ++i) {
        DetailRecipe::Material m;
        m.name = text(r.get<std::uint8_t>());
        m.hash = r.get<std::uint64_t>();
        recipe.materials.push_back(std::move(m));
    }
    if (header.version >= 5) {
        const auto flag = r.get<std::uint8_t>();
        if (flag > 1) {
            return bad("roughness flag ", int{flag}, ", expected 0 or 1");
        }
        recipe.roughness = flag == 1;
    }
    if (r.failed() || r.position() != bytes.size()) {
        return bad("its fields do not fill its ", bytes.size(), " bytes");
    }
    if (recipe.scheme.empty() || !std::isfinite(recipe.omega)) {
        return bad("empty scheme or omega not finite");
    }
    header.detailRecipe = std::move(recipe);
    return {};
}

std::vector<std::uint8_t> encodeRoughness(const RoughnessGrid& grid)
{
    TERRAIN_EXPECTS(grid.leavesPerSide >= 1 && grid.leavesPerSide <= kMaxRoughnessLeavesPerSide &&
                        grid.laws.size() == static_cast<std::size_t>(grid.leavesPerSide) * grid.leavesPerSide,
                    "encodeRoughness: leavesPerSide^2 laws");
    std::vector<std::uint8_t> bytes;
    bytes.reserve(4 + grid.laws.size() * 8);
    ByteWriter w(bytes);
    w.put(static_cast<std::uint32_t>(grid.leavesPerSide));
    for (const RoughnessLaw& law : grid.laws) {
        w.put(static_cast<float>(law.amplitude));
        w.put(static_cast<float>(law.exponent));
    }
    return bytes;
}

void setRoughness(MapHeader& header, std::optional<RoughnessGrid> grid)
{
    header.roughness = std::move(grid);
    header.roughnessBytes = 0;
    header.roughnessCrc = 0;
    if (header.roughness) {
        TERRAIN_EXPECTS(header.roughness->leavesPerSide == (1 << (header.levels - 1)),
                        "the roughness grid has one law per leaf of the finest static level");
        // Stored as float: the laws the reader gets, so writer and reader synthesize the same surface.
        for (RoughnessLaw& law : header.roughness->laws) {
            law.amplitude = static_cast<float>(law.amplitude);
            law.exponent = static_cast<float>(law.exponent);
        }
        const auto bytes = encodeRoughness(*header.roughness);
        header.roughnessBytes = static_cast<std::uint32_t>(bytes.size());
        header.roughnessCrc = crc32Of(bytes);
    }
}

Status decodeRoughness(std::span<const std::uint8_t> bytes, MapHeader& header, const std::string& name)
{
    auto bad = [&](auto&&... what) { return makeError(name, ": invalid roughness block: ", what...); };
    TERRAIN_TRY(checkBlock(bytes, header.roughnessBytes, header.roughnessCrc, name, "roughness block"));
    ByteReader r(bytes);
    RoughnessGrid grid;
    const auto side = r.get<std::uint32_t>();
    const std::uint64_t expected = std::uint64_t{1} << (header.levels - 1);
    if (side != expected) {
        return bad(side, " leaves per side, the map has ", expected);
    }
    if (bytes.size() != 4 + std::uint64_t{side} * side * 8) {
        return bad(bytes.size(), " bytes for ", side, " x ", side, " leaves (", 4 + std::uint64_t{side} * side * 8,
                   " expected)");
    }
    grid.leavesPerSide = static_cast<int>(side);
    grid.laws.resize(static_cast<std::size_t>(side) * side);
    for (std::size_t k = 0; k < grid.laws.size(); ++k) {
        RoughnessLaw& law = grid.laws[k];
        law.amplitude = r.get<float>();
        law.exponent = r.get<float>();
        if (!(law.amplitude >= 0.0 && std::isfinite(law.amplitude)) ||
            !(law.exponent >= static_cast<float>(kMinRoughnessExponent) &&
              law.exponent <= static_cast<float>(kMaxRoughnessExponent))) {
            return bad("leaf ", k % side, ",", k / side, ": amplitude ", law.amplitude, " m, exponent ", law.exponent,
                       " (expected an amplitude >= 0 and an exponent in [", kMinRoughnessExponent, ", ",
                       kMaxRoughnessExponent, "])");
        }
    }
    header.roughness = std::move(grid);
    return {};
}

std::vector<std::uint8_t> encodeGeoreference(const std::string& crsWkt, double crsUnitMetres)
{
    std::vector<std::uint8_t> bytes;
    ByteWriter w(bytes);
    w.put(crsUnitMetres);
    w.putBytes(reinterpret_cast<const std::uint8_t*>(crsWkt.data()), crsWkt.size());
    return bytes;
}

void setGeoreference(MapHeader& header, std::string crsWkt, double crsUnitMetres)
{
    TERRAIN_EXPECTS(crsUnitMetres > 0 && std::isfinite(crsUnitMetres), "metres per CRS unit must be positive");
    header.crsWkt = std::move(crsWkt);
    header.crsUnitMetres = header.crsWkt.empty() ? 1.0 : crsUnitMetres;
    header.georeferenceBytes = 0;
    header.georeferenceCrc = 0;
    if (!header.crsWkt.empty()) {
        const auto bytes = encodeGeoreference(header.crsWkt, header.crsUnitMetres);
        TERRAIN_EXPECTS(bytes.size() <= kMaxGeoreferenceBytes, "the CRS fits the georeference block");
        header.georeferenceBytes = static_cast<std::uint32_t>(bytes.size());
        header.georeferenceCrc = crc32Of(bytes);
    }
}

Status decodeGeoreference(std::span<const std::uint8_t> bytes, MapHeader& header, const std::string& name)
{
    TERRAIN_TRY(checkBlock(bytes, header.georeferenceBytes, header.georeferenceCrc, name, "georeference block"));
    ByteReader r(bytes);
    const double unit = r.get<double>();
    if (r.failed() || !(unit > 0) || !std::isfinite(unit)) {
        return makeError(name, ": invalid georeference block: metres per CRS unit ", unit, " is not positive");
    }
    std::string wkt(bytes.begin() + 8, bytes.end());
    if (wkt.find('\0') != std::string::npos) {
        return makeError(name, ": invalid georeference block: the CRS text holds a zero byte");
    }
    header.crsWkt = std::move(wkt);
    header.crsUnitMetres = unit;
    return {};
}

std::array<std::uint8_t, kHeaderBytes> encodeHeader(const MapHeader& h)
{
    std::vector<std::uint8_t> bytes;
    bytes.reserve(kHeaderBytes);
    ByteWriter w(bytes);
    w.putBytes(kMapMagic.data(), kMapMagic.size());
    w.put(h.version);
    w.put(static_cast<std::uint32_t>(kHeaderBytes));
    w.put(h.chunkSize);
    w.put(static_cast<std::uint32_t>(kBorder));
    w.put(h.levels);
    w.put(h.textureSize);
    w.put(h.heightCoding);
    w.put(h.textureCoding);
    w.put(h.quantizerBin);
    w.put(h.sampleSpacing);
    w.put(h.heightOffset);
    w.put(h.heightStep);
    w.put(h.maxErrorBound);
    w.put(h.originX);
    w.put(h.originY);
    w.put(h.validX0);
    w.put(h.validY0);
    w.put(h.validWidth);
    w.put(h.validHeight);
    w.put(h.noDataFilled);
    w.put(h.nodeCount);
    w.put(h.directoryOffset);
    w.put(h.directoryBytes);
    w.put(h.directoryCrc);
    const std::size_t sourceBytes = h.version >= 6 ? kSourceBytesV6 : kSourceBytes;
    w.putFixedString(h.source, sourceBytes - 1);
    w.put(std::uint8_t{0});
    if (h.version >= 6) {
        w.put(h.georeferenceBytes);
        w.put(h.georeferenceCrc);
    }
    if (h.version >= 3) {
        w.put(h.detailRecipeBytes);
        w.put(h.detailRecipeCrc);
    }
    if (h.version >= 5) {
        w.put(h.roughnessBytes);
        w.put(h.roughnessCrc);
    }
    w.padTo(kHeaderBytes - 4);
    w.put(crc32Of(bytes));
    std::array<std::uint8_t, kHeaderBytes> out{};
    std::copy(bytes.begin(), bytes.end(), out.begin());
    return out;
}

Expected<MapHeader> decodeHeader(std::span<const std::uint8_t> bytes, const std::string& name)
{
    if (bytes.size() < kHeaderBytes) {
        return makeError(name, ": not a terrain map: file is ", bytes.size(), " bytes, shorter than the ", kHeaderBytes,
                         "-byte header");
    }
    if (!std::equal(kMapMagic.begin(), kMapMagic.end(), bytes.begin())) {
        return makeError(name, ": not a terrain map (wrong magic bytes; expected a file written by prep)");
    }
    ByteReader r(bytes.first(kHeaderBytes));
    r.skip(kMapMagic.size());
    MapHeader h;
    h.version = r.get<std::uint32_t>();
    if (h.version < kMinMapVersion || h.version > kMapVersion) {
        return makeError(name, ": map format version ", h.version, ", this build reads versions ", kMinMapVersion,
                         " to ", kMapVersion, " (re-run prep on the source height field)");
    }
    std::uint32_t storedCrc = ByteReader(bytes.subspan(kHeaderBytes - 4, 4)).get<std::uint32_t>();
    std::uint32_t actualCrc = crc32Of(bytes.first(kHeaderBytes - 4));
    if (storedCrc != actualCrc) {
        return makeError(name, ": header checksum mismatch (file is corrupt)");
    }
    auto headerBytes = r.get<std::uint32_t>();
    h.chunkSize = r.get<std::uint32_t>();
    auto border = r.get<std::uint32_t>();
    h.levels = r.get<std::uint32_t>();
    h.textureSize = r.get<std::uint32_t>();
    h.heightCoding = r.get<std::uint32_t>();
    h.textureCoding = r.get<std::uint32_t>();
    h.quantizerBin = r.get<std::uint32_t>();
    h.sampleSpacing = r.get<double>();
    h.heightOffset = r.get<double>();
    h.heightStep = r.get<double>();
    h.maxErrorBound = r.get<double>();
    h.originX = r.get<double>();
    h.originY = r.get<double>();
    h.validX0 = r.get<std::uint32_t>();
    h.validY0 = r.get<std::uint32_t>();
    h.validWidth = r.get<std::uint32_t>();
    h.validHeight = r.get<std::uint32_t>();
    h.noDataFilled = r.get<std::uint64_t>();
    h.nodeCount = r.get<std::uint32_t>();
    h.directoryOffset = r.get<std::uint64_t>();
    h.directoryBytes = r.get<std::uint64_t>();
    h.directoryCrc = r.get<std::uint32_t>();
    h.source = r.getFixedString(h.version >= 6 ? kSourceBytesV6 : kSourceBytes);
    if (h.version >= 6) {
        h.georeferenceBytes = r.get<std::uint32_t>();
        h.georeferenceCrc = r.get<std::uint32_t>();
    }
    if (h.version >= 3) {
        h.detailRecipeBytes = r.get<std::uint32_t>();
        h.detailRecipeCrc = r.get<std::uint32_t>();
    }
    if (h.version >= 5) {
        h.roughnessBytes = r.get<std::uint32_t>();
        h.roughnessCrc = r.get<std::uint32_t>();
    }

    auto bad = [&](auto&&... what) { return makeError(name, ": invalid header: ", what...); };
    if (headerBytes != kHeaderBytes) {
        return bad("header size ", headerBytes, ", expected ", kHeaderBytes);
    }
    if (border != kBorder) {
        return bad("node border ", border, ", expected ", kBorder);
    }
    if (!isValidChunkSize(h.chunkSize)) {
        return bad("chunk size ", h.chunkSize, " is not 2^k+1 in [3, ", kMaxChunkSize, "]");
    }
    if (h.levels < 1 || h.levels > 24) {
        return bad("level count ", h.levels, " outside [1, 24]");
    }
    if (!isPowerOfTwoPlusOne(h.textureSize) || h.textureSize > std::uint32_t{kMaxTextureSize}) {
        return bad("texture size ", h.textureSize, " is not 2^k+1 in [3, ", kMaxTextureSize, "]");
    }
    if ((h.heightCoding != kHeightCodingKobbeltResidual && h.heightCoding != kHeightCodingPifs) ||
        h.textureCoding != kTextureCodingMedRgb8) {
        return bad("unknown height coding ", h.heightCoding, " or texture coding ", h.textureCoding);
    }
    if (h.quantizerBin < 1 || h.quantizerBin % 2 == 0) {
        return bad("quantizer bin ", h.quantizerBin, " is not a positive odd number");
    }
    if (h.heightCoding == kHeightCodingPifs && (h.quantizerBin != 1 || h.chunkSize < 9)) {
        return bad("fractal height coding with quantizer bin ", h.quantizerBin, " and chunk size ", h.chunkSize,
                   " (it needs bin 1 and chunks of at least 9 samples)");
    }
    if (!(h.sampleSpacing > 0) || !std::isfinite(h.sampleSpacing) || !(h.heightStep > 0) ||
        !std::isfinite(h.heightStep) || !std::isfinite(h.heightOffset) || !std::isfinite(h.originX) ||
        !std::isfinite(h.originY)) {
        return bad("spacing, height step, offset or origin not a positive finite number");
    }
    std::uint64_t grid = h.gridSize();
    if (h.validWidth < 1 || h.validHeight < 1 || std::uint64_t{h.validX0} + h.validWidth > grid ||
        std::uint64_t{h.validY0} + h.validHeight > grid) {
        return bad("valid region ", h.validX0, ",", h.validY0, " ", h.validWidth, "x", h.validHeight,
                   " does not fit the ", grid, "x", grid, " grid");
    }
    // The offset is checked against wrapping too: offset + bytes must be the file's size, and a sum that
    // wraps past 2^64 could match a small file while claiming a directory of hundreds of gigabytes.
    if (h.detailRecipeBytes > kMaxRecipeBytes) {
        return bad("detail recipe of ", h.detailRecipeBytes, " bytes, at most ", kMaxRecipeBytes);
    }
    if (h.roughnessBytes != 0 && h.roughnessBytes != 4 + (std::uint64_t{1} << (2 * (h.levels - 1))) * 8) {
        return bad("roughness block of ", h.roughnessBytes, " bytes, expected 0 or ",
                   4 + (std::uint64_t{1} << (2 * (h.levels - 1))) * 8, " for ", h.levels, " levels");
    }
    if (h.georeferenceBytes > kMaxGeoreferenceBytes || (h.georeferenceBytes != 0 && h.georeferenceBytes < 9)) {
        return bad("georeference block of ", h.georeferenceBytes, " bytes, expected 0 or 9 to ", kMaxGeoreferenceBytes);
    }
    if (h.nodeCount < 1 || h.directoryBytes != std::uint64_t{h.nodeCount} * kDirectoryEntryBytes ||
        h.directoryOffset < h.nodeAreaOffset() || h.directoryOffset > UINT64_MAX - h.directoryBytes) {
        return bad("directory of ", h.nodeCount, " nodes at offset ", h.directoryOffset, " with ", h.directoryBytes,
                   " bytes is inconsistent");
    }
    // A quadtree of L levels has at most (4^L - 1) / 3 nodes, and each node's data takes a byte at least.
    const std::uint64_t mostNodes = ((std::uint64_t{1} << (2 * h.levels)) - 1) / 3;  // levels <= 24
    if (h.nodeCount > mostNodes || h.nodeCount > h.directoryOffset - h.nodeAreaOffset()) {
        return bad("header claims ", h.nodeCount, " nodes, more than ", h.levels, " levels hold (",
                   std::min(mostNodes, h.directoryOffset - h.nodeAreaOffset()),
                   " at most, a byte of node data each before the directory)");
    }
    return h;
}

std::vector<std::uint8_t> encodeDirectory(std::span<const DirectoryEntry> entries, std::uint32_t version)
{
    std::vector<std::uint8_t> bytes;
    bytes.reserve(entries.size() * kDirectoryEntryBytes);
    ByteWriter w(bytes);
    for (const auto& e : entries) {
        w.put(static_cast<std::uint8_t>(e.id.level));
        w.put(static_cast<std::uint8_t>((e.hasChildren ? 1 : 0) | (e.hasFilledNoData ? 2 : 0)));
        w.put(std::uint16_t{0});
        w.put(e.id.x);
        w.put(e.id.y);
        w.put(e.offset);
        w.put(e.heightBytes);
        w.put(e.textureBytes);
        w.put(e.crc);
        w.put(e.deltaM);
        w.put(e.deltaC);
        w.put(e.minCode);
        w.put(e.maxCode);
        if (version >= 2) {
            w.put(e.detailDeltaC);
        } else {
            w.put(std::uint32_t{0});
        }
    }
    return bytes;
}

Expected<std::vector<DirectoryEntry>> decodeDirectory(std::span<const std::uint8_t> bytes, const MapHeader& header,
                                                      const std::string& name)
{
    if (bytes.size() != std::uint64_t{header.nodeCount} * kDirectoryEntryBytes) {
        return makeError(name, ": directory is ", bytes.size(), " bytes, expected ",
                         std::uint64_t{header.nodeCount} * kDirectoryEntryBytes);
    }
    if (crc32Of(bytes) != header.directoryCrc) {
        return makeError(name, ": directory checksum mismatch (file is corrupt)");
    }
    std::vector<DirectoryEntry> entries(header.nodeCount);
    ByteReader r(bytes);
    for (auto& e : entries) {
        e.id.level = r.get<std::uint8_t>();
        auto flags = r.get<std::uint8_t>();
        e.hasChildren = (flags & 1) != 0;
        e.hasFilledNoData = (flags & 2) != 0;
        r.get<std::uint16_t>();
        e.id.x = r.get<std::uint32_t>();
        e.id.y = r.get<std::uint32_t>();
        e.offset = r.get<std::uint64_t>();
        e.heightBytes = r.get<std::uint32_t>();
        e.textureBytes = r.get<std::uint32_t>();
        e.crc = r.get<std::uint32_t>();
        e.deltaM = r.get<float>();
        e.deltaC = r.get<float>();
        e.minCode = r.get<std::uint16_t>();
        e.maxCode = r.get<std::uint16_t>();
        if (header.hasDetailErrors()) {
            e.detailDeltaC = r.get<float>();
        } else {
            r.get<std::uint32_t>();  // zero in version 1
        }

        auto bad = [&](auto&&... what) {
            return makeError(name, ": directory entry for node ", e.id.toString(), ": ", what...);
        };
        if (e.id.level >= static_cast<int>(header.levels)) {
            return bad("level beyond the map's ", header.levels, " levels");
        }
        std::uint32_t side = 1u << e.id.level;
        if (e.id.x >= side || e.id.y >= side) {
            return bad("position outside its level");
        }
        if (e.offset < header.nodeAreaOffset() || e.offset > header.directoryOffset ||
            e.payloadBytes() > header.directoryOffset - e.offset || e.heightBytes == 0 || e.textureBytes == 0) {
            return bad("payload at ", e.offset, " with ", e.payloadBytes(), " bytes lies outside the node area");
        }
        if (e.minCode > e.maxCode || !(e.deltaC >= e.deltaM) || !(e.deltaM >= 0)) {
            return bad("inconsistent bounds or errors");
        }
        if (header.hasDetailErrors() &&
            !(std::isfinite(e.detailDeltaC) && e.detailDeltaC >= 0.0f && e.detailDeltaC >= e.deltaC)) {
            return bad("detail_delta_c ", e.detailDeltaC, " m is not a finite number >= 0 and >= delta_c (", e.deltaC,
                       " m)");
        }
        if (e.hasChildren && e.id.level + 1 >= static_cast<int>(header.levels)) {
            return bad("flagged with children but is on the deepest level");
        }
    }
    std::sort(entries.begin(), entries.end(),
              [](const DirectoryEntry& a, const DirectoryEntry& b) { return a.id.key() < b.id.key(); });
    auto find = [&](const NodeId& id) -> const DirectoryEntry* {
        auto it = std::lower_bound(entries.begin(), entries.end(), id.key(),
                                   [](const DirectoryEntry& e, std::uint64_t key) { return e.id.key() < key; });
        return it != entries.end() && it->id == id ? &*it : nullptr;
    };
    for (std::size_t i = 1; i < entries.size(); ++i) {
        if (entries[i].id == entries[i - 1].id) {
            return makeError(name, ": directory lists node ", entries[i].id.toString(), " twice");
        }
    }
    if (entries.front().id != NodeId::root()) {
        return makeError(name, ": directory has no root node");
    }
    for (const auto& e : entries) {
        if (!e.id.isRoot()) {
            const auto* parent = find(e.id.parent());
            if (!parent || !parent->hasChildren) {
                return makeError(name, ": node ", e.id.toString(), " has no parent node in the directory");
            }
        }
        if (e.hasChildren) {
            for (int q = 0; q < 4; ++q) {
                if (!find(e.id.child(q))) {
                    return makeError(name, ": node ", e.id.toString(), " is missing its child ",
                                     e.id.child(q).toString());
                }
            }
        }
    }
    return entries;
}

}  // namespace terrain
