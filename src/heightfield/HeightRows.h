// Where prep reads heights from: a field's description and its rows on demand, so a build can
// stream an input larger than memory through in bands instead of holding it whole.
#pragma once

#include "core/Expected.h"
#include "heightfield/GdalRaster.h"
#include "heightfield/HeightField.h"

#include <memory>
#include <span>

namespace terrain {

class HeightRows {
public:
    virtual ~HeightRows() = default;
    /// Everything a HeightField says but its samples (`samples` is empty).
    virtual const HeightField& info() const = 0;
    /// Rows [j0, j0 + rows) (0 = south), width natives each, NaN where there is no data. Errors name the file.
    virtual Status readRows(int j0, int rows, std::span<float> out) = 0;
    /// The whole field, when the source holds it in memory already (then it can be taken without a copy).
    virtual HeightField* held() { return nullptr; }
    /// Whether rows are read through GDAL's block cache (configureGdalReading sizes it by the budget).
    virtual bool readsThroughGdalCache() const { return false; }
};

/// A field already in memory (PNG, raw, .bt, .ter, or a test's).
class FieldRows final : public HeightRows {
public:
    explicit FieldRows(HeightField field);
    const HeightField& info() const override { return mInfo; }
    Status readRows(int j0, int rows, std::span<float> out) override;
    HeightField* held() override { return &mField; }

private:
    HeightField mField;
    HeightField mInfo;
};

/// A raster read through GDAL, rows by block reads as they are asked for.
class RasterRows final : public HeightRows {
public:
    explicit RasterRows(ElevationRaster raster);
    const HeightField& info() const override { return mInfo; }
    Status readRows(int j0, int rows, std::span<float> out) override { return mRaster.readRows(j0, rows, out); }
    bool readsThroughGdalCache() const override { return true; }

private:
    ElevationRaster mRaster;
    HeightField mInfo;
};

}  // namespace terrain
