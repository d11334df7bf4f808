// Rasters through GDAL: elevation from any raster GDAL reads (one file, a mosaic of tiles, a
// VRT), reprojected block by block when it is geographic; georeferenced imagery resampled onto a map's
// texel lattice; geographic <-> map coordinates; float32 GeoTIFF output. GDAL's headers stay in the .cpp.
//
// Threads: each object opens its own GDAL datasets and must be used from one thread at a time (GDAL
// datasets are not thread-safe); different objects may be used on different threads.
#pragma once

#include "core/Expected.h"
#include "heightfield/HeightField.h"
#include "heightfield/Image.h"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace terrain {

/// How prep reads elevation rasters through GDAL.
struct ElevationReadOptions {
    /// A raw value to treat as no-data in addition to the band's own no-data value and mask.
    std::optional<double> noData;
    /// `--srs`: the projected CRS to reproject to (anything OGRSpatialReference::SetFromUserInput takes:
    /// EPSG:32613, WKT, a PROJ string). Empty: projected inputs stay as they are, geographic ones go to the
    /// UTM zone (WGS 84) of their centre.
    std::string targetSrs;
};

/// The extensions `readHeightField` sends to GDAL when a directory is given as a mosaic (lower case).
bool isGdalRasterExtension(const std::filesystem::path& path);

/// One elevation surface read through GDAL: a single raster, or several tiles checked to agree (same CRS,
/// spacing, alignment, sample type, no-data, scale, offset and units) and mosaicked with a VRT, or a
/// directory of such tiles. Geographic inputs, a --srs, rotated or non-square pixels are warped
/// (bilinear) onto a square grid in the target CRS, block by block as rows are read.
///
/// Sample (i, j) (j = 0 the south row) lies at world metres (originX + i spacing, originY + j spacing), the
/// centre of its GDAL pixel (GDAL places PixelIsPoint samples there too). Natives are the band's values;
/// metres = verticalOffset + verticalScale x native (band scale and offset times the vertical unit).
class ElevationRaster {
public:
    /// Opens and checks `inputs` (files or one directory). Errors name the file and what is wrong: GDAL
    /// cannot read it, not one band, tiles that disagree, a CRS it cannot transform, an unknown unit.
    static Expected<ElevationRaster> open(std::span<const std::filesystem::path> inputs,
                                          const ElevationReadOptions& options = {});
    ElevationRaster(ElevationRaster&&) noexcept;
    ElevationRaster& operator=(ElevationRaster&&) noexcept;
    ~ElevationRaster();

    int width() const;
    int height() const;
    /// Metres between samples; empty for a raster without georeferencing (then -h applies).
    std::optional<double> spacing() const;
    double originX() const;  ///< world metres of sample (0, 0)
    double originY() const;
    /// The CRS (WKT2) of the world coordinates, empty when the raster has none, and its name.
    const std::string& crsWkt() const;
    const std::string& crsName() const;
    /// Metres per unit of the CRS's horizontal axes (world metres = CRS coordinate x this).
    double crsUnitMetres() const;
    /// Metres per native value; empty when neither a band scale nor a vertical unit is known (-v applies).
    std::optional<double> verticalScale() const;
    double verticalOffset() const;  ///< metres
    bool integerSamples() const;    ///< the natives are integers (integer sample type, not resampled)
    /// "GTiff Int16 1201x1201, WGS 84 / UTM zone 13N" and the like.
    const std::string& description() const;
    /// What opening assumed or changed (metres assumed, reprojected from ..., a directory's skipped files).
    const std::vector<std::string>& notes() const;

    /// Reads `rows` rows starting at row `j0` (0 = south) into `out` (width x rows natives, rows south to
    /// north; NaN where there is no data). Errors name the file.
    Status readRows(int j0, int rows, std::span<float> out);
    /// The whole raster as a HeightField (memory checked first).
    Expected<HeightField> readAll();

private:
    struct State;
    explicit ElevationRaster(std::unique_ptr<State> state);
    std::unique_ptr<State> mState;
};

/// Sets GDAL's process-wide reading settings for a build within `memoryBudget` on `threads` threads: the
/// block cache (by default 5% of the machine's memory) to an eighth of the budget, 16 to 256 MiB, since a
/// build reads each block once and a band's margin rows twice; and, unless GDAL_NUM_THREADS is set in the
/// environment, decoding on `threads` threads (GTiff decodes the tiles of one request in parallel: the
/// input passes of OutOfCoreBench went from 3.9 to 3.2 s and 6.2 to 5.3 s on 2 cores).
void configureGdalReading(std::uint64_t memoryBudget, int threads);
/// The block cache configureGdalReading gives a build within `memoryBudget`, bytes.
std::uint64_t gdalCacheBytesFor(std::uint64_t memoryBudget);

/// Reads elevation through GDAL: ElevationRaster::open + readAll.
Expected<HeightField> readGdalHeightField(std::span<const std::filesystem::path> inputs,
                                          const ElevationReadOptions& options = {});

/// The grid imagery is resampled onto: width x height pixels whose centres are at world metres
/// (x0 + i step, y0 + j step), row j = 0 the south row, in the CRS `crsWkt` (metres per unit crsUnitMetres).
struct RasterGrid {
    int width = 0;
    int height = 0;
    double x0 = 0.0;
    double y0 = 0.0;
    double step = 1.0;
    std::string crsWkt;
    double crsUnitMetres = 1.0;
};

/// Whether `path` is a raster with georeferencing (a geotransform and a CRS). False for files GDAL cannot
/// open (the reader then reports them).
bool isGeoreferencedRaster(const std::filesystem::path& path);

/// Reads RGB(A) imagery resampled (bilinear, or averaged where the imagery is finer) onto `grid`, aligned by
/// coordinates: an RGBA image, row 0 the NORTH row (as Image stores), alpha 0 where the imagery does not
/// cover (outside it, its no-data or its own alpha). Errors name the file: not georeferenced, not 3 or 4
/// bands, a CRS that cannot be transformed to the grid's.
Expected<Image> readGeoImagery(const std::filesystem::path& path, const RasterGrid& grid);

/// Converts between geographic coordinates (WGS 84 longitude, latitude in degrees) and a map's world metres.
class GeoConverter {
public:
    /// Fails when the CRS is empty or cannot be transformed to WGS 84.
    static Expected<GeoConverter> create(const std::string& crsWkt, double crsUnitMetres);
    GeoConverter(GeoConverter&&) noexcept;
    GeoConverter& operator=(GeoConverter&&) noexcept;
    ~GeoConverter();
    /// World metres of (lon, lat); fails outside the CRS's domain.
    Expected<std::pair<double, double>> toWorld(double lon, double lat) const;
    Expected<std::pair<double, double>> toLonLat(double x, double y) const;

private:
    struct State;
    explicit GeoConverter(std::unique_ptr<State> state);
    std::unique_ptr<State> mState;
};

/// A CRS's name (e.g. "WGS 84 / UTM zone 13N") and EPSG code ("EPSG:32613"), for summaries; empty for "".
std::string describeCrs(const std::string& crsWkt);

/// Writes heights (metres, rows SOUTH to north, NaN = no data written as -9999) as a tiled, deflate-compressed
/// float32 GeoTIFF whose pixel centres are the grid's sample positions. Written to a temporary name and
/// renamed; errors name the file.
Status writeFloat32GeoTiff(const std::filesystem::path& path, const RasterGrid& grid, std::span<const float> heights);

}  // namespace terrain
