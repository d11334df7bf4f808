#include "heightfield/HeightRows.h"

#include "core/Check.h"

#include <algorithm>
#include <utility>

namespace terrain {

namespace {
HeightField describe(const HeightField& field)
{
    HeightField info;
    info.width = field.width;
    info.height = field.height;
    info.integerSamples = field.integerSamples;
    info.spacing = field.spacing;
    info.verticalScale = field.verticalScale;
    info.verticalOffset = field.verticalOffset;
    info.originX = field.originX;
    info.originY = field.originY;
    info.crsWkt = field.crsWkt;
    info.crsUnitMetres = field.crsUnitMetres;
    info.notes = field.notes;
    info.description = field.description;
    return info;
}
}  // namespace

FieldRows::FieldRows(HeightField field) : mField(std::move(field)), mInfo(describe(mField)) {}

Status FieldRows::readRows(int j0, int rows, std::span<float> out)
{
    TERRAIN_EXPECTS(j0 >= 0 && rows >= 0 && j0 + rows <= mField.height, "rows inside the field");
    const std::size_t count = static_cast<std::size_t>(rows) * mField.width;
    TERRAIN_EXPECTS(out.size() >= count, "room for the rows");
    TERRAIN_EXPECTS(mField.samples.size() == static_cast<std::size_t>(mField.width) * mField.height,
                    "the field's samples were taken");
    const auto first =
        mField.samples.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(j0) * mField.width);
    std::copy(first, first + static_cast<std::ptrdiff_t>(count), out.begin());
    return {};
}

RasterRows::RasterRows(ElevationRaster raster) : mRaster(std::move(raster))
{
    mInfo.width = mRaster.width();
    mInfo.height = mRaster.height();
    mInfo.integerSamples = mRaster.integerSamples();
    mInfo.spacing = mRaster.spacing();
    mInfo.verticalScale = mRaster.verticalScale();
    mInfo.verticalOffset = mRaster.verticalOffset();
    mInfo.originX = mRaster.originX();
    mInfo.originY = mRaster.originY();
    mInfo.crsWkt = mRaster.crsWkt();
    mInfo.crsUnitMetres = mRaster.crsUnitMetres();
    mInfo.notes = mRaster.notes();
    mInfo.description = mRaster.description();
}

}  // namespace terrain
