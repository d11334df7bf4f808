// Readers and writers of height field files (paper 4.1): PNG gray 8/16-bit, VTP Binary Terrain (.bt),
// Terragen (.ter) and headerless raw 16-bit.
#pragma once

#include "core/Expected.h"
#include "heightfield/HeightField.h"

#include <cstdint>
#include <filesystem>
#include <optional>

namespace terrain {

/// How to read a file whose format does not describe itself (raw) or needs overrides.
struct HeightFieldReadOptions {
    /// Raw 16-bit input: size in samples (both required for raw, ignored otherwise).
    int rawWidth = 0;
    int rawHeight = 0;
    /// Raw 16-bit input: samples are signed (int16) rather than unsigned (uint16).
    bool rawSigned = false;
    /// Raw 16-bit input: samples are big-endian rather than little-endian.
    bool rawBigEndian = false;
    /// A native value to treat as no-data in addition to the format's own marker (e.g. -32768 for SRTM).
    std::optional<double> noData;
};

/// Reads a height field, choosing the format by extension: .png, .bt, .ter, .raw/.r16/.bin (raw 16-bit).
/// Fails with a message naming the file and what is wrong: missing, unknown extension, truncated,
/// malformed header, unsupported variant, or too large for the memory available (checked before any
/// large allocation).
Expected<HeightField> readHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options = {});

Expected<HeightField> readPngHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options = {});
Expected<HeightField> readBtHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options = {});
Expected<HeightField> readTerHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options = {});
Expected<HeightField> readRawHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options);

/// Sample formats the .bt writer can produce.
enum class BtSampleType { Int16, Int32, Float32 };

/// Writers, used by tests to make hand-made files and by tools to export. Each writes to a temporary name
/// and renames, so a failed write leaves no partial file. NaN samples are written as the format's no-data
/// marker where it has one (.bt: -32768 for int16, INT32_MIN for int32, NaN... see implementation).
Status writePngHeightField(const std::filesystem::path& path, const HeightField& field, int bitDepth = 16);
Status writeBtHeightField(const std::filesystem::path& path, const HeightField& field, BtSampleType type,
                          int minorVersion = 3);
Status writeTerHeightField(const std::filesystem::path& path, const HeightField& field);
Status writeRawHeightField(const std::filesystem::path& path, const HeightField& field, bool isSigned = false,
                           bool bigEndian = false);

}  // namespace terrain
