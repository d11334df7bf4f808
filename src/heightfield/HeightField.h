// In-memory height fields as read from their files (paper 4.1), before any quantization.
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace terrain {

/// A regular grid of height samples exactly as the file stores them ("native units").
///
/// Orientation: sample (i, j) lies at world (originX + i * spacing, originY + j * spacing): i grows
/// east, j grows north, so row j = 0 is the SOUTH edge. Readers of north-up images (PNG, raw) flip rows.
/// Heights in metres are `verticalOffset + verticalScale * native`.
struct HeightField {
    int width = 0;   ///< samples along x (east), >= 1
    int height = 0;  ///< samples along y (north), >= 1
    /// width * height native values, index j * width + i. NaN marks a no-data sample (the reader turns the
    /// format's own marker into NaN).
    std::vector<float> samples;
    /// True when every native value is an integer (PNG, raw 16-bit, .ter, integer .bt): such input can be
    /// stored losslessly with a quantization step of one native unit.
    bool integerSamples = true;
    /// Metres between neighbouring samples when the file says so; empty for formats without spacing (PNG, raw).
    std::optional<double> spacing;
    /// Metres per native unit when the file says so (.bt vertical scale, .ter SCAL/HeightScale).
    std::optional<double> verticalScale;
    /// Metres added after scaling when the file says so (.ter BaseHeight); 0 otherwise.
    double verticalOffset = 0.0;
    /// World position (metres) of sample (0, 0) when the file is georeferenced in a metric projection.
    double originX = 0.0;
    double originY = 0.0;
    /// The coordinate reference system of originX/Y and spacing (WKT2), for georeferenced inputs read
    /// through GDAL; empty when unknown.
    std::string crsWkt;
    /// Metres per unit of the CRS's horizontal axes: world metres = CRS coordinate x crsUnitMetres.
    double crsUnitMetres = 1.0;
    /// What the reader assumed or changed (reprojected, a unit assumed); prep prints them.
    std::vector<std::string> notes;
    /// One line saying what was read, e.g. "PNG 16-bit gray 1025x1025"; for summaries and `tengine-tool info`.
    std::string description;

    float at(int i, int j) const { return samples[static_cast<std::size_t>(j) * width + i]; }
    float& at(int i, int j) { return samples[static_cast<std::size_t>(j) * width + i]; }
};

/// Whether a sample read as float equals a no-data value given as a double (the file's tag, or --nodata as
/// gdalinfo prints it): compared in the samples' own type, the value rounded to the nearest float (a float
/// max printed to 17 digits is float max again); beyond the float range, the infinity or float max of its
/// sign (what a wider raster's value reads as). NaN equals nothing (NaN samples are no-data anyway).
inline bool isNoDataValue(float sample, double noData)
{
    constexpr double kMax = std::numeric_limits<float>::max();
    if (std::isnan(noData)) {
        return false;
    }
    if (std::abs(noData) > kMax) {
        // Double values rounding to float max round to it; those further out are infinite as floats.
        const float signedMax = noData > 0 ? std::numeric_limits<float>::max() : -std::numeric_limits<float>::max();
        return (std::isinf(sample) && (sample > 0) == (noData > 0)) ||
               (sample == signedMax && std::abs(noData) < static_cast<double>(kMax) * (1.0 + 0x1p-24));
    }
    return sample == static_cast<float>(noData);
}

}  // namespace terrain
