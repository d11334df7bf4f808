// Issue 15, part 6: our own .bt and .ter readers against GDAL's BT and Terragen drivers, on files
// gdal_translate writes. Both read the same samples in metres; they place them differently, and that is why
// the own readers stay (docs/design.md, "Own readers and GDAL's"):
// - BT: VTP, the format's author, puts the corner samples on the header's extents (vtHeightFieldGrid3d::
//   GetSpacing divides by columns - 1); GDAL's BT driver reads the extents as pixel edges, so its samples
//   sit half a spacing inside them and its spacing is extent / columns. A VTP file read through GDAL would
//   be stretched by columns / (columns - 1) and shifted by half a sample, and the other way round.
// - Terragen: GDAL gives the file a local "Terragen world space" CRS that our GDAL path refuses (it must
//   know where a raster lies), and places samples at pixel centres, half a spacing off the points
//   Terragen's SCAL lattice has at multiples of the spacing.
#include "heightfield/GdalRaster.h"
#include "heightfield/HeightFieldIo.h"

#include "MapTestSupport.h"
#include "TestSupport.h"

#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace terrain {
namespace {

void gdalTool(const std::string& tool, const std::vector<std::string>& args)
{
    const test::RunResult run = test::runProgram(tool, args);
    ASSERT_EQ(run.exitCode, 0) << tool << " failed:\n" << run.output;
}

/// A 50 x 40 int16 GeoTIFF in UTM 13N, 30 m pixels, heights 800 .. 2300 m with one no-data sample.
std::filesystem::path writeSource(const test::ScratchDir& dir, bool withHole)
{
    const HeightField field = test::makeHeightField(50, 40, [&](int i, int j) {
        if (withHole && i == 5 && j == 7) {
            return 0.0f;
        }
        return static_cast<float>(std::round(1500.0 + 700.0 * std::sin(0.1 * i) * std::cos(0.13 * j) + 3.0 * i - j));
    });
    EXPECT_TRUE(writePngHeightField(dir / "source.png", field).ok());
    const auto tif = dir / "source.tif";
    gdalTool("gdal_translate",
             {"-q", "-ot", "Int16", "-a_srs", "EPSG:32613", "-a_ullr", "500000", "4101200", "501500", "4100000",
              "-a_nodata", withHole ? "0" : "none", (dir / "source.png").string(), tif.string()});
    return tif;
}

struct Difference {
    int samples = 0;     ///< samples whose metres differ by more than float rounding
    double worst = 0.0;  ///< the largest difference, metres
    int validity = 0;    ///< samples no-data in one reading only
};

Difference compareSamples(const HeightField& ours, const HeightField& gdal)
{
    Difference d;
    const double oursScale = ours.verticalScale.value_or(1.0), gdalScale = gdal.verticalScale.value_or(1.0);
    for (int j = 0; j < ours.height; ++j) {
        for (int i = 0; i < ours.width; ++i) {
            const double a = ours.verticalOffset + oursScale * ours.at(i, j);
            const double b = gdal.verticalOffset + gdalScale * gdal.at(i, j);
            if (std::isnan(a) != std::isnan(b)) {
                ++d.validity;
            } else if (!std::isnan(a) && std::abs(a - b) > 1e-3) {
                ++d.samples;
                d.worst = std::max(d.worst, std::abs(a - b));
            }
        }
    }
    return d;
}

TEST(OwnReadersVsGdalTest, BtWrittenByGdalReadsTheSameBothWays)
{
    test::ScratchDir dir;
    const auto tif = writeSource(dir, true);
    for (const char* type : {"Int16", "Int32", "Float32"}) {
        SCOPED_TRACE(type);
        const auto bt = dir / (std::string(type) + ".bt");
        gdalTool("gdal_translate", {"-q", "-of", "BT", "-ot", type, "-a_nodata", "-32768", tif.string(), bt.string()});
        auto ours = readBtHeightField(bt);
        ASSERT_TRUE(ours.ok()) << ours.error().message;
        const std::filesystem::path inputs[] = {bt};
        auto gdal = readGdalHeightField(inputs);
        ASSERT_TRUE(gdal.ok()) << gdal.error().message;
        ASSERT_EQ(ours->width, gdal->width);
        ASSERT_EQ(ours->height, gdal->height);
        const Difference d = compareSamples(*ours, *gdal);
        EXPECT_EQ(d.samples, 0) << "worst " << d.worst << " m";
        EXPECT_EQ(d.validity, 0);
        // gdal_translate wrote the GeoTIFF's pixel edges as the extents: 50 x 40 pixels of 30 m from
        // (500000, 4100000). GDAL reads them back as it wrote them; VTP's convention (ours) puts the corner
        // samples there.
        ASSERT_TRUE(ours->spacing && gdal->spacing);
        EXPECT_DOUBLE_EQ(*gdal->spacing, 30.0);
        EXPECT_DOUBLE_EQ(gdal->originX, 500015.0);
        EXPECT_DOUBLE_EQ(gdal->originY, 4100015.0);
        EXPECT_DOUBLE_EQ(*ours->spacing, 1200.0 / 39.0);  // the y extent over rows - 1 (x: 1500 / 49, noted)
        EXPECT_DOUBLE_EQ(ours->originX, 500000.0);
        EXPECT_DOUBLE_EQ(ours->originY, 4100000.0);
        EXPECT_EQ(describeCrs(gdal->crsWkt), "WGS 84 / UTM zone 13N (EPSG:32613)");
    }
}

TEST(OwnReadersVsGdalTest, TerragenWrittenByGdalReadsTheSameBothWays)
{
    test::ScratchDir dir;
    const auto tif = writeSource(dir, false);
    const auto ter = dir / "out.ter";
    gdalTool("gdal_translate", {"-q", "-of", "Terragen", "-ot", "Float32", "-co", "MINUSERPIXELVALUE=0", "-co",
                                "MAXUSERPIXELVALUE=3000", tif.string(), ter.string()});
    auto ours = readTerHeightField(ter);
    ASSERT_TRUE(ours.ok()) << ours.error().message;

    // GDAL's own reading, through its API: metres = offset + scale x value, its first row the north one as
    // in the GeoTIFF the file was made from (the driver reports a positive y pixel size all the same).
    GDALAllRegister();
    std::unique_ptr<GDALDataset> dataset(GDALDataset::Open(ter.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
    ASSERT_TRUE(dataset);
    ASSERT_EQ(dataset->GetRasterXSize(), ours->width);
    ASSERT_EQ(dataset->GetRasterYSize(), ours->height);
    GDALRasterBand* band = dataset->GetRasterBand(1);
    std::vector<double> values(static_cast<std::size_t>(ours->width) * ours->height);
    ASSERT_EQ(band->RasterIO(GF_Read, 0, 0, ours->width, ours->height, values.data(), ours->width, ours->height,
                             GDT_Float64, 0, 0),
              CE_None);
    const double scale = band->GetScale(), offset = band->GetOffset();
    const double oursScale = ours->verticalScale.value_or(1.0);
    double worst = 0.0;
    for (int j = 0; j < ours->height; ++j) {
        for (int i = 0; i < ours->width; ++i) {
            const double gdalMetres =
                offset + scale * values[static_cast<std::size_t>(ours->height - 1 - j) * ours->width + i];
            worst = std::max(worst, std::abs(ours->verticalOffset + oursScale * ours->at(i, j) - gdalMetres));
        }
    }
    EXPECT_LT(worst, 1e-3) << "the same samples in metres";
    double transform[6];
    ASSERT_EQ(dataset->GetGeoTransform(transform), CE_None);
    ASSERT_TRUE(ours->spacing);
    EXPECT_DOUBLE_EQ(*ours->spacing, 30.0);
    EXPECT_DOUBLE_EQ(transform[1], 30.0);
    EXPECT_DOUBLE_EQ(transform[5], 30.0);
    // Terragen's samples at multiples of SCAL from 0; GDAL's pixel centres half a spacing further.
    EXPECT_DOUBLE_EQ(ours->originX, 0.0);
    EXPECT_DOUBLE_EQ(transform[0] + 0.5 * transform[1], 15.0);
    // And our GDAL path refuses the file: its local CRS says nothing of where it lies.
    const std::filesystem::path inputs[] = {ter};
    auto gdal = readGdalHeightField(inputs);
    ASSERT_FALSE(gdal.ok());
    EXPECT_NE(gdal.error().message.find("Terragen world space is neither projected nor geographic"), std::string::npos)
        << gdal.error().message;
}

}  // namespace
}  // namespace terrain
