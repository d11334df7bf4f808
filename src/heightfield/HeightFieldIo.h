// Readers and writers of height field files (paper 4.1): PNG gray 8/16-bit, VTP Binary Terrain (.bt),
// Terragen (.ter) and headerless raw 16-bit.
#pragma once

#include "core/Expected.h"
#include "heightfield/HeightField.h"
#include "heightfield/HeightRows.h"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>

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
    /// GDAL inputs: the projected CRS to reproject to (prep --srs; ElevationReadOptions::targetSrs).
    std::string targetSrs;
};

/// Reads a height field, choosing the reader by extension: .png, .bt, .ter, .raw/.r16/.bin (raw 16-bit) by
/// our own readers, anything else (GeoTIFF, SRTM .hgt, ESRI .asc, USGS DEM, VRT, ...) and a directory of
/// tiles through GDAL (heightfield/GdalRaster.h). Fails with a message naming the file and what is wrong: missing,
/// unknown extension, truncated, malformed header, unsupported variant, or too large for the memory available (checked
/// before any large allocation).
Expected<HeightField> readHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options = {});

/// Several files: one mosaic through GDAL (their tiles must agree, GdalRaster.h); one file: readHeightField.
Expected<HeightField> readHeightFields(std::span<const std::filesystem::path> paths,
                                       const HeightFieldReadOptions& options = {});

/// The same as a source of rows (prep's input): GDAL inputs stay on disk and are read in bands as the build
/// asks for them; the formats read by our own readers are read whole.
Expected<std::unique_ptr<HeightRows>> openHeightRows(std::span<const std::filesystem::path> paths,
                                                     const HeightFieldReadOptions& options = {});

/// Format readers (readHeightField picks one). Orientation and units as HeightField.h describes; each
/// format's own no-data marker reads as NaN (.bt: -32768 in any sample type, VTP's INVALID_ELEVATION).
Expected<HeightField> readPngHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options = {});
Expected<HeightField> readBtHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options = {});
Expected<HeightField> readTerHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options = {});
Expected<HeightField> readRawHeightField(const std::filesystem::path& path, const HeightFieldReadOptions& options);

/// Sample formats the .bt writer can produce.
enum class BtSampleType { Int16, Int32, Float32 };

/// Writers, used by tests to make hand-made files and by tools to export. Each writes to a temporary name
/// and renames, so a failed write leaves no partial file. Native values are written, rounded and clamped to
/// the sample type's range. NaN samples become the format's no-data marker where it has one: .bt -32768
/// for every sample type (VTP's INVALID_ELEVATION; finite int16 values stop at -32767), signed raw -32768
/// (the SRTM void, read back with options.noData). PNG, .ter and unsigned raw have no marker and refuse NaN.
/// Format notes:
/// - PNG: 8 or 16 bits; spacing and vertical mapping are not stored.
/// - .bt: horizontal units metres, extents from originX/Y and spacing (1 m when absent). Version 1.3 stores
///   verticalScale; when the mapping does not fit (an offset, or a scale before 1.3) heights are written in
///   metres instead, with scale 1.
/// - .ter: SCAL = spacing (30 m when absent). A field whose mapping is already a Terragen one with int16
///   natives (as read from a .ter) is written unchanged; otherwise heights in metres are re-encoded with
///   BaseHeight at mid-range and the smallest HeightScale that fits, within half a step
///   (SCAL * HeightScale / 65536 m).
Status writePngHeightField(const std::filesystem::path& path, const HeightField& field, int bitDepth = 16);
Status writeBtHeightField(const std::filesystem::path& path, const HeightField& field, BtSampleType type,
                          int minorVersion = 3);
Status writeTerHeightField(const std::filesystem::path& path, const HeightField& field);
Status writeRawHeightField(const std::filesystem::path& path, const HeightField& field, bool isSigned = false,
                           bool bigEndian = false);

}  // namespace terrain
