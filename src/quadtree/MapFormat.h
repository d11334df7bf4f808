// The .map file format (paper 3.2.14, figure 3.8): a fixed header, node payloads with siblings stored
// together, and a directory at the end. All integers little-endian. Full description: docs/map-format.md.
//
//   [header: kHeaderBytes]  [payload] [payload] ...  [directory: nodeCount * kDirectoryEntryBytes]
//
// A node's payload is its height stream followed by its texture stream; the directory entry gives both
// sizes and a CRC32 over the payload. The header has its own CRC32 (last 4 bytes) and the directory's CRC32.
#pragma once

#include "core/Expected.h"
#include "heightfield/Roughness.h"
#include "quadtree/ChunkGeometry.h"
#include "quadtree/NodeId.h"

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace terrain {

inline constexpr std::array<std::uint8_t, 8> kMapMagic = {0x89, 'T', 'M', 'A', 'P', '\r', '\n', 0x1a};
/// Version written. 2 added detail_delta_c to the directory entries (3.4.1); 3 the detail recipe block
/// after the header (what those errors were estimated for); 4 (same layout) measured errors: delta_c is the
/// largest distance to the leaves below, nested with max, and the leaves' detail errors come from the
/// synthesis model; 5 the roughness block (each static leaf's RoughnessLaw) and the
/// recipe's roughness flag. Versions 1 to 4 are still read: they have no roughness (the synthesis below
/// their leaves is subdivision and materials only, as they were made for). 6 the georeference block (the
/// CRS of the world coordinates; the source description shrinks to 88 bytes to make room).
inline constexpr std::uint32_t kMapVersion = 6;
/// Version 4 errors nest as delta_c(node) = max(measured, kErrorNesting x the children's largest): a parent's
/// error stays a quarter above its children's, so every split has a geomorph range (eq. 3.5 morphs a node
/// in between its own distance and its parent's); with plain max they could coincide and the split pop.
inline constexpr float kErrorNesting = 1.25f;
/// Oldest version read.
inline constexpr std::uint32_t kMinMapVersion = 1;
inline constexpr std::size_t kHeaderBytes = 256;
inline constexpr std::size_t kDirectoryEntryBytes = 48;

/// Height coding of node payloads: Kobbelt 4-point prediction from the parent's window (root: previous
/// sample), residuals divided by the quantizer bin, zigzag varints, zlib (quadtree/HeightCodec.h).
inline constexpr std::uint32_t kHeightCodingKobbeltResidual = 1;
/// Seed 003's fractal (PIFS) coding of node interiors, shared samples exact (quadtree/PifsCodec.h); lossy,
/// its measured error in maxErrorBound; quantizerBin is 1.
inline constexpr std::uint32_t kHeightCodingPifs = 2;
/// Texture coding: RGB8 planes, LOCO-I median predictor, residual bytes, zlib.
inline constexpr std::uint32_t kTextureCodingMedRgb8 = 1;

/// What the detail errors below the static leaves (detail_delta_c, 3.4.1) were estimated for: the
/// viewer's synthesis must be the same for them to bound what it draws. Stored from version 3.
struct DetailRecipe {
    /// A material by its name and a hash of its file's bytes (FNV-1a, 64 bits).
    struct Material {
        std::string name;
        std::uint64_t hash = 0;
        bool operator==(const Material&) const = default;
    };
    std::string scheme = "kobbelt";   ///< detail_subdivision_scheme (at most 32 bytes)
    double omega = 1.0;               ///< detail_subdivision_factor; means something for kobbelt only
    std::vector<Material> materials;  ///< in order, the first the ground; empty: subdivision only
    /// Version 5: the terrain's own roughness is continued below the leaves (the map's RoughnessGrid);
    /// false for older maps.
    bool roughness = false;

    bool operator==(const DetailRecipe&) const = default;
    /// Whether the synthesis is the same: scheme, materials and, for kobbelt, omega.
    bool sameSynthesis(const DetailRecipe& other) const;
    /// "kobbelt omega 1, materials grass (hash 0123456789abcdef), rock (hash ...)".
    std::string describe() const;
};

/// Limits of a stored recipe (the reader refuses more).
inline constexpr std::size_t kMaxRecipeMaterials = 64;
inline constexpr std::size_t kMaxRecipeNameBytes = 255;
inline constexpr std::size_t kMaxRecipeBytes = 1 << 16;

/// How rough the terrain is around each static leaf (heightfield/Roughness.h), measured by prep on the
/// input's samples (the finest static level) so the synthesis can continue it below the leaves. Version 5.
struct RoughnessGrid {
    int leavesPerSide = 0;           ///< 2^(levels - 1): the finest static level's nodes per side
    std::vector<RoughnessLaw> laws;  ///< leavesPerSide^2, leaf (x, y) at y * leavesPerSide + x (rows south
                                     ///< to north); laws at the spacing of the finest static level

    const RoughnessLaw& at(int x, int y) const { return laws[static_cast<std::size_t>(y) * leavesPerSide + x]; }
    bool operator==(const RoughnessGrid&) const = default;
};

/// Most leaves per side a roughness block may hold (2^14: 2 GiB of laws at 8 bytes each would be absurd).
inline constexpr int kMaxRoughnessLeavesPerSide = 1 << 14;

/// Everything needed to interpret a map: geometry of the grid and of the chunks, height quantization.
struct MapHeader {
    std::uint32_t version = kMapVersion;
    std::uint32_t chunkSize = 65;    ///< N: samples per node side, isValidChunkSize (quadtree/ChunkGeometry.h)
    std::uint32_t levels = 1;        ///< static levels; leaves of level levels-1 have the input's spacing
    std::uint32_t textureSize = 65;  ///< T: texels per node side, 2^k + 1; corner texels centred on the corners
    std::uint32_t heightCoding = kHeightCodingKobbeltResidual;
    std::uint32_t textureCoding = kTextureCodingMedRgb8;
    std::uint32_t quantizerBin = 1;  ///< 2 * E + 1 codes: residuals are multiples of this (1 = lossless)
    double sampleSpacing = 1.0;      ///< metres between samples at the finest static level
    double heightOffset = 0.0;       ///< metres = heightOffset + heightStep * code
    double heightStep = 1.0;         ///< metres per 16-bit code
    double maxErrorBound = 0.0;      ///< guaranteed L-infinity error of stored heights vs input (metres)
    double originX = 0.0;            ///< world position (metres) of grid sample (0, 0) = south-west corner
    double originY = 0.0;
    std::uint32_t validX0 = 0;  ///< the input's samples inside the padded grid (the rest is padding)
    std::uint32_t validY0 = 0;
    std::uint32_t validWidth = 0;
    std::uint32_t validHeight = 0;
    std::uint64_t noDataFilled = 0;  ///< input samples that had no data and were filled from neighbours
    std::uint32_t nodeCount = 0;
    std::uint64_t directoryOffset = 0;
    std::uint64_t directoryBytes = 0;
    std::uint32_t directoryCrc = 0;
    std::string source;  ///< what prep read, e.g. "PNG 16-bit gray 1025x1025" (at most 95 bytes)
    /// Version 3: what the detail errors assume; empty when the writer did not say (or versions 1, 2).
    /// Set it with setDetailRecipe(), which also sets the two fields below.
    std::optional<DetailRecipe> detailRecipe;
    std::uint32_t detailRecipeBytes = 0;  ///< size of the recipe block at offset kHeaderBytes; 0 = none
    std::uint32_t detailRecipeCrc = 0;    ///< its CRC32
    /// Version 5: the leaves' roughness; empty when the writer did not measure it (or older versions). Set
    /// it with setRoughness(), which also sets the two fields below.
    std::optional<RoughnessGrid> roughness;
    std::uint32_t roughnessBytes = 0;  ///< size of the roughness block after the recipe block; 0 = none
    std::uint32_t roughnessCrc = 0;    ///< its CRC32
    /// Version 6: the CRS of originX/Y (WKT2; empty: none recorded) and metres per CRS unit (world metres =
    /// CRS coordinate x crsUnitMetres). Set them with setGeoreference(), which also sets the two fields below.
    std::string crsWkt;
    double crsUnitMetres = 1.0;
    std::uint32_t georeferenceBytes = 0;  ///< size of the georeference block after the roughness block; 0 = none
    std::uint32_t georeferenceCrc = 0;    ///< its CRC32

    /// Samples per side of the whole padded grid at the finest level: (N - 1) * 2^(levels-1) + 1.
    std::uint64_t gridSize() const { return std::uint64_t{chunkSize - 1} * (std::uint64_t{1} << (levels - 1)) + 1; }
    /// Samples per side of the grid at `level`.
    std::uint64_t levelGridSize(int level) const
    {
        return std::uint64_t{chunkSize - 1} * (std::uint64_t{1} << level) + 1;
    }
    /// Samples per node side including the border on both sides (quadtree/ChunkGeometry.h).
    int windowSize() const { return terrain::windowSize(static_cast<int>(chunkSize)); }
    /// Metres between samples of a node at `level` (may be deeper than the static levels).
    double spacingAt(int level) const;
    /// Metres covered by one node side at `level`.
    double nodeSizeAt(int level) const { return spacingAt(level) * (chunkSize - 1); }
    double heightOf(std::uint16_t code) const { return heightOffset + heightStep * code; }
    /// Whether directory entries carry detailDeltaC (version 2 and later).
    bool hasDetailErrors() const { return version >= 2; }
    /// Where the roughness block starts: after the header and the recipe block.
    std::uint64_t roughnessOffset() const { return kHeaderBytes + detailRecipeBytes; }
    /// Where the georeference block starts: after the roughness block.
    std::uint64_t georeferenceOffset() const { return roughnessOffset() + roughnessBytes; }
    /// Where node payloads may start: after the header, the recipe, roughness and georeference blocks.
    std::uint64_t nodeAreaOffset() const { return georeferenceOffset() + georeferenceBytes; }
};

/// "Kobbelt residual, lossless", "Kobbelt residual, max error 2 m" or "fractal (PIFS), measured max error
/// 3.5 m": how the heights are coded and how far they may lie from the input.
std::string describeHeightCoding(const MapHeader& header);

/// One directory entry: where a node's payload is and what the LOD selection needs without loading it.
struct DirectoryEntry {
    NodeId id;
    bool hasChildren = false;
    bool hasFilledNoData = false;  ///< some of its samples were no-data in the input
    std::uint64_t offset = 0;      ///< file offset of the payload
    std::uint32_t heightBytes = 0;
    std::uint32_t textureBytes = 0;
    std::uint32_t crc = 0;      ///< CRC32 of the payload (heightBytes + textureBytes bytes)
    float deltaM = 0.0f;        ///< metres: own simplification error (3.2.5)
    float deltaC = 0.0f;        ///< metres: nested error, eq. 3.1 (max over children + deltaM)
    std::uint16_t minCode = 0;  ///< nested bounding box in height codes (3.2.12)
    std::uint16_t maxCode = 0;
    /// metres: nested error including the detail synthesized below the static leaves (3.4.1): a leaf's is
    /// its estimated detail error, an inner node's max over children + deltaM, so >= deltaC. Version 1: 0.
    float detailDeltaC = 0.0f;

    std::uint64_t payloadBytes() const { return std::uint64_t{heightBytes} + textureBytes; }
};

/// The recipe block's bytes: scheme (u8 length + bytes), omega (f64), material count (u32), per material
/// its name (u8 length + bytes) and hash (u64).
/// Version 5 appends the roughness flag (u8, 0 or 1).
std::vector<std::uint8_t> encodeDetailRecipe(const DetailRecipe& recipe, std::uint32_t version = kMapVersion);
/// Sets header.detailRecipe and the block's size and CRC (empty: no block).
void setDetailRecipe(MapHeader& header, std::optional<DetailRecipe> recipe);
/// Parses the recipe block (header.detailRecipeBytes bytes read at kHeaderBytes) into header.detailRecipe,
/// checking its CRC and limits; `name` is used in messages.
Status decodeDetailRecipe(std::span<const std::uint8_t> bytes, MapHeader& header, const std::string& name);

/// The roughness block's bytes: leaves per side (u32), then per leaf its amplitude and exponent (f32 each).
std::vector<std::uint8_t> encodeRoughness(const RoughnessGrid& grid);
/// Sets header.roughness and the block's size and CRC (empty: no block). Precondition: the grid has
/// 2^(levels - 1) leaves per side.
void setRoughness(MapHeader& header, std::optional<RoughnessGrid> grid);
/// Parses the roughness block (header.roughnessBytes bytes read at header.roughnessOffset()) into
/// header.roughness, checking its CRC, size and values; `name` is used in messages.
Status decodeRoughness(std::span<const std::uint8_t> bytes, MapHeader& header, const std::string& name);

/// Longest CRS a map stores (WKT2 of projected CRSs is a few kilobytes).
inline constexpr std::size_t kMaxGeoreferenceBytes = 1 << 16;
/// The georeference block's bytes: metres per CRS unit (f64), then the WKT (UTF-8, no terminator).
std::vector<std::uint8_t> encodeGeoreference(const std::string& crsWkt, double crsUnitMetres);
/// Sets header.crsWkt / crsUnitMetres and the block's size and CRC (an empty WKT: no block, unit 1).
/// Precondition: crsUnitMetres > 0 and finite, the block within kMaxGeoreferenceBytes.
void setGeoreference(MapHeader& header, std::string crsWkt, double crsUnitMetres);
/// Parses the georeference block (header.georeferenceBytes read at header.georeferenceOffset()).
Status decodeGeoreference(std::span<const std::uint8_t> bytes, MapHeader& header, const std::string& name);

/// Serializes the header into kHeaderBytes bytes, including its CRC.
std::array<std::uint8_t, kHeaderBytes> encodeHeader(const MapHeader& header);
/// Parses and validates a header; `name` is used in messages (the file's path).
Expected<MapHeader> decodeHeader(std::span<const std::uint8_t> bytes, const std::string& name);

/// Serializes directory entries for a file of format `version` (version 1 stores zero for detailDeltaC).
std::vector<std::uint8_t> encodeDirectory(std::span<const DirectoryEntry> entries, std::uint32_t version = kMapVersion);
/// Parses and validates the directory against the header: sorted unique ids, ids inside their level,
/// payloads inside the node area of the file, errors and bounds consistent (0 <= delta_m <= delta_c;
/// version 2: delta_c <= detail_delta_c, finite), a complete quadtree (root present; every node flagged
/// with children has all four; every other node's parent is present and flagged). Version 1 entries get
/// detailDeltaC = 0.
Expected<std::vector<DirectoryEntry>> decodeDirectory(std::span<const std::uint8_t> bytes, const MapHeader& header,
                                                      const std::string& name);

std::uint32_t crc32Of(std::span<const std::uint8_t> bytes);

}  // namespace terrain
