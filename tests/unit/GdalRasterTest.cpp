// Elevation through GDAL (issue 15): files made at test time with GDAL's own tools, read by
// readHeightField, compared with GDAL's own reading of the same file (the independent reference).
#include "MapTestSupport.h"
#include "TestSupport.h"
#include "heightfield/GdalRaster.h"
#include "heightfield/HeightFieldIo.h"
#include "lod/HeightQuery.h"
#include "quadtree/MapFile.h"

#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>

namespace terrain {
namespace {

/// Runs a GDAL command-line tool; fails the test with its output when it fails.
void gdalTool(const std::string& tool, const std::vector<std::string>& args)
{
    const test::RunResult run = test::runProgram(tool, args);
    ASSERT_EQ(run.exitCode, 0) << tool << " failed:\n" << run.output;
}

/// A smooth 16-bit test surface (values 100 .. ~3000) written as PNG, the source of the GDAL files.
std::filesystem::path writeSourcePng(const std::filesystem::path& dir, int width, int height)
{
    const HeightField field = test::makeHeightField(width, height, [](int i, int j) {
        return static_cast<float>(std::round(1500.0 + 700.0 * std::sin(0.05 * i) * std::cos(0.07 * j) + 3.0 * i - j));
    });
    const auto path = dir / "source.png";
    EXPECT_TRUE(writePngHeightField(path, field).ok());
    return path;
}

/// GDAL's own reading of band 1 (rows north to south as stored) and the file's geotransform.
struct GdalReading {
    int width = 0, height = 0;
    std::vector<double> values;
    std::array<double, 6> gt{};
    double scale = 1.0, offset = 0.0;
};

GdalReading readWithGdal(const std::filesystem::path& path)
{
    GDALAllRegister();
    GdalReading r;
    std::unique_ptr<GDALDataset> ds(GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
    EXPECT_TRUE(ds) << path;
    if (!ds) {
        return r;
    }
    r.width = ds->GetRasterXSize();
    r.height = ds->GetRasterYSize();
    ds->GetGeoTransform(r.gt.data());
    GDALRasterBand* band = ds->GetRasterBand(1);
    r.scale = band->GetScale();
    r.offset = band->GetOffset();
    r.values.resize(static_cast<std::size_t>(r.width) * r.height);
    EXPECT_EQ(band->RasterIO(GF_Read, 0, 0, r.width, r.height, r.values.data(), r.width, r.height, GDT_Float64, 0, 0,
                             nullptr),
              CE_None);
    return r;
}

/// Every sample of `field` against GDAL's reading: row j (south = 0) is GDAL line height - 1 - j, the value
/// (native) the same, NaN exactly where GDAL reads `noData`; the origin at the south-west pixel centre.
void expectSameAsGdal(const HeightField& field, const GdalReading& gdal, std::optional<double> noData)
{
    ASSERT_EQ(field.width, gdal.width);
    ASSERT_EQ(field.height, gdal.height);
    ASSERT_TRUE(field.spacing);
    EXPECT_DOUBLE_EQ(*field.spacing, gdal.gt[1]);
    EXPECT_DOUBLE_EQ(field.originX, gdal.gt[0] + 0.5 * gdal.gt[1]);
    EXPECT_DOUBLE_EQ(field.originY, gdal.gt[3] + (gdal.height - 0.5) * gdal.gt[5]);
    int mismatches = 0, holes = 0;
    for (int j = 0; j < field.height; ++j) {
        for (int i = 0; i < field.width; ++i) {
            const double expected = gdal.values[static_cast<std::size_t>(field.height - 1 - j) * gdal.width + i];
            const float got = field.at(i, j);
            if (noData && expected == *noData) {
                ++holes;
                mismatches += std::isnan(got) ? 0 : 1;
            } else {
                mismatches += static_cast<double>(got) == static_cast<double>(static_cast<float>(expected)) ? 0 : 1;
            }
        }
    }
    EXPECT_EQ(mismatches, 0);
    if (noData) {
        EXPECT_GT(holes, 0) << "the test file should hold no-data samples";
    }
}

TEST(GdalRasterTest, TiledDeflateInt16GeoTiffWithNoDataReadsAsGdalReadsIt)
{
    test::ScratchDir dir;
    const auto png = writeSourcePng(dir.path(), 300, 200);
    const auto tif = dir / "dem_i16.tif";
    gdalTool("gdal_translate", {"-q",         "-ot",           "Int16",     "-a_srs",
                                "EPSG:32613", "-a_ullr",       "500000",    "4100000",
                                "509000",     "4094000",       "-a_nodata", "1300",
                                "-co",        "TILED=YES",     "-co",       "BLOCKXSIZE=64",
                                "-co",        "BLOCKYSIZE=64", "-co",       "COMPRESS=DEFLATE",
                                png.string(), tif.string()});
    auto field = readHeightField(tif);
    ASSERT_TRUE(field.ok()) << field.error().message;
    expectSameAsGdal(*field, readWithGdal(tif), 1300.0);
    EXPECT_TRUE(field->integerSamples);
    EXPECT_EQ(describeCrs(field->crsWkt), "WGS 84 / UTM zone 13N (EPSG:32613)");
    EXPECT_DOUBLE_EQ(*field->spacing, 30.0);
    EXPECT_DOUBLE_EQ(field->originX, 500015.0);
    EXPECT_DOUBLE_EQ(field->originY, 4094015.0);
}

TEST(GdalRasterTest, Float32InFeetWithScaleAndOffsetBecomesMetres)
{
    test::ScratchDir dir;
    const auto png = writeSourcePng(dir.path(), 120, 90);
    const auto tif = dir / "dem_ft.tif";
    gdalTool("gdal_translate", {"-q", "-ot", "Float32", "-a_srs", "EPSG:32613", "-a_ullr", "500000", "4100000",
                                "501200", "4099100", "-a_scale", "0.5", "-a_offset", "10", png.string(), tif.string()});
    gdalTool("gdal_edit.py", {"-units", "ft", tif.string()});
    auto field = readHeightField(tif);
    ASSERT_TRUE(field.ok()) << field.error().message;
    const GdalReading gdal = readWithGdal(tif);
    expectSameAsGdal(*field, gdal, std::nullopt);
    ASSERT_TRUE(field->verticalScale);
    EXPECT_DOUBLE_EQ(*field->verticalScale, 0.5 * 0.3048);
    EXPECT_DOUBLE_EQ(field->verticalOffset, 10 * 0.3048);
    // Through prep's build: the map's heights are GDAL's values x scale + offset, in metres.
    const auto map = dir / "ft.map";
    const test::RunResult prep = test::runProgram(TERRAIN_PREP_EXE, {tif.string(), "-o", map.string()});
    ASSERT_EQ(prep.exitCode, 0) << prep.output;
    auto opened = MapFile::open(map, ReaderKind::Stream);
    ASSERT_TRUE(opened.ok()) << opened.error().message;
    EXPECT_EQ(describeCrs((*opened)->header().crsWkt), "WGS 84 / UTM zone 13N (EPSG:32613)");
    // Float32 samples holding whole numbers lie on a lattice: stored losslessly, one code per native unit.
    EXPECT_EQ((*opened)->header().maxErrorBound, 0.0);
    EXPECT_DOUBLE_EQ((*opened)->header().heightStep, 0.5 * 0.3048);
    for (const auto& [col, line] : std::vector<std::pair<int, int>>{{0, 0}, {17, 33}, {119, 89}, {60, 45}}) {
        const double x = gdal.gt[0] + (col + 0.5) * gdal.gt[1], y = gdal.gt[3] + (line + 0.5) * gdal.gt[5];
        auto h = staticHeightAt(**opened, x, y);
        ASSERT_TRUE(h.ok()) << h.error().message;
        const double expected = (gdal.values[static_cast<std::size_t>(line) * gdal.width + col] * 0.5 + 10) * 0.3048;
        EXPECT_NEAR(h->height, expected, (*opened)->header().maxErrorBound + 1e-9) << col << ", " << line;
    }
    // The map records the CRS: info names it, and height --lonlat answers at geographic coordinates.
    const test::RunResult info = test::runProgram(TERRAIN_TENGINE_TOOL_EXE, {"info", map.string()});
    ASSERT_EQ(info.exitCode, 0) << info.output;
    EXPECT_NE(info.output.find("crs        WGS 84 / UTM zone 13N (EPSG:32613)"), std::string::npos) << info.output;
    auto geo = GeoConverter::create((*opened)->header().crsWkt, (*opened)->header().crsUnitMetres);
    ASSERT_TRUE(geo.ok()) << geo.error().message;
    const double x = gdal.gt[0] + 40.5 * gdal.gt[1], y = gdal.gt[3] + 20.5 * gdal.gt[5];
    auto lonLat = geo->toLonLat(x, y);
    ASSERT_TRUE(lonLat.ok());
    EXPECT_NEAR(lonLat->first, -105.0 + 0.0046, 0.001) << "405 m east of UTM 13N's central meridian";
    char lon[32], lat[32];
    std::snprintf(lon, sizeof lon, "%.10f", lonLat->first);
    std::snprintf(lat, sizeof lat, "%.10f", lonLat->second);
    const test::RunResult query =
        test::runProgram(TERRAIN_TENGINE_TOOL_EXE, {"height", map.string(), "--lonlat", lon, lat});
    ASSERT_EQ(query.exitCode, 0) << query.output;
    auto h = staticHeightAt(**opened, x, y);
    ASSERT_TRUE(h.ok());
    EXPECT_NEAR(std::stod(query.output), h->height, 1e-3) << query.output;
}

TEST(GdalRasterTest, EsriAsciiGridAndSrtmHgtRead)
{
    test::ScratchDir dir;
    const auto png = writeSourcePng(dir.path(), 64, 48);
    const auto tif = dir / "base.tif";
    gdalTool("gdal_translate", {"-q", "-ot", "Int16", "-a_srs", "EPSG:32613", "-a_ullr", "600000", "4000000", "601280",
                                "3999040", png.string(), tif.string()});
    const auto asc = dir / "dem.asc";
    gdalTool("gdal_translate", {"-q", "-of", "AAIGrid", tif.string(), asc.string()});
    auto field = readHeightField(asc);
    ASSERT_TRUE(field.ok()) << field.error().message;
    expectSameAsGdal(*field, readWithGdal(asc), std::nullopt);

    // SRTM-3: 1201 x 1201 geographic samples; reprojected to UTM 13N (the zone of -104.5).
    const auto geo = dir / "geo.tif";
    gdalTool("gdal_translate", {"-q", "-ot", "Int16", "-outsize", "1201", "1201", "-a_srs", "EPSG:4326", "-a_ullr",
                                "-105.000416666666667", "38.000416666666667", "-103.999583333333333",
                                "36.999583333333333", png.string(), geo.string()});
    const auto hgt = dir / "N37W105.hgt";
    gdalTool("gdal_translate", {"-q", "-of", "SRTMHGT", geo.string(), hgt.string()});
    auto srtm = readHeightField(hgt);
    ASSERT_TRUE(srtm.ok()) << srtm.error().message;
    EXPECT_EQ(describeCrs(srtm->crsWkt), "WGS 84 / UTM zone 13N (EPSG:32613)");
    ASSERT_FALSE(srtm->notes.empty());
    // 3 arc-seconds: about 92.6 m north-south and 73.9 m east-west at 37.5 N; the square grid lies between.
    EXPECT_GT(*srtm->spacing, 70.0);
    EXPECT_LT(*srtm->spacing, 95.0);
}

TEST(GdalRasterTest, GeographicInputIsReprojectedWithinTheResamplingError)
{
    test::ScratchDir dir;
    // A plane in longitude and latitude: bilinear resampling reproduces it up to the projection's curvature.
    const HeightField plane =
        test::makeHeightField(201, 201, [](int i, int j) { return static_cast<float>(1000 + 5 * i + 3 * j); });
    ASSERT_TRUE(writePngHeightField(dir / "plane.png", plane).ok());
    const auto geo = dir / "plane_geo.tif";
    gdalTool("gdal_translate", {"-q", "-ot", "UInt16", "-a_srs", "EPSG:4326", "-a_ullr", "-105.1005", "37.6005",
                                "-104.8995", "37.3995", (dir / "plane.png").string(), geo.string()});
    auto field = readHeightField(geo);
    ASSERT_TRUE(field.ok()) << field.error().message;
    auto converter = GeoConverter::create(field->crsWkt, field->crsUnitMetres);
    ASSERT_TRUE(converter.ok()) << converter.error().message;
    // Interior samples against the plane at their longitude and latitude (pixel centres of the source:
    // lon = -105.1 + col 0.001, lat = 37.6 - line 0.001; value 1000 + 5 col + 3 (200 - line), PNG row 0 north).
    double worst = 0.0;
    int checked = 0;
    for (int j = 20; j < field->height - 20; j += 7) {
        for (int i = 20; i < field->width - 20; i += 7) {
            if (std::isnan(field->at(i, j))) {
                continue;
            }
            auto lonLat =
                converter->toLonLat(field->originX + i * *field->spacing, field->originY + j * *field->spacing);
            ASSERT_TRUE(lonLat.ok());
            const double col = (lonLat->first + 105.1) / 0.001, line = (37.6 - lonLat->second) / 0.001;
            if (col < 1 || line < 1 || col > 199 || line > 199) {
                continue;
            }
            worst = std::max(worst, std::abs(field->at(i, j) - (1000 + 5 * col + 3 * (200 - line))));
            ++checked;
        }
    }
    EXPECT_GT(checked, 100);
    // The resampling's own error: GDAL's bilinear kernel is scale-aware (wider along an axis where the
    // output is coarser than the source, 111 m north-south here) and its discrete weights are not exactly
    // symmetric, so a plane is reproduced within a fraction of one source pixel's change (5 and 3 units a
    // pixel): measured 0.38 units, 0.05 of a pixel's change. A shift of half a pixel would give 2.5 to 4.
    EXPECT_LT(worst, 0.6);
}

TEST(GdalRasterTest, AMosaicOfFourTilesEqualsTheWhole)
{
    test::ScratchDir dir;
    const auto png = writeSourcePng(dir.path(), 129, 97);
    const auto whole = dir / "whole.tif";
    gdalTool("gdal_translate", {"-q", "-ot", "Int16", "-a_srs", "EPSG:32613", "-a_ullr", "500000", "4100000", "503870",
                                "4097090", png.string(), whole.string()});
    std::filesystem::create_directory(dir / "tiles");
    std::vector<std::filesystem::path> tiles;
    for (int j = 0; j < 2; ++j) {
        for (int i = 0; i < 2; ++i) {
            tiles.push_back(dir / "tiles" / ("t" + std::to_string(j) + std::to_string(i) + ".tif"));
            gdalTool("gdal_translate",
                     {"-q", "-srcwin", std::to_string(64 * i), std::to_string(48 * j), std::to_string(i ? 65 : 64),
                      std::to_string(j ? 49 : 48), whole.string(), tiles.back().string()});
        }
    }
    auto reference = readHeightField(whole);
    ASSERT_TRUE(reference.ok());
    auto listed = readHeightFields(tiles);
    ASSERT_TRUE(listed.ok()) << listed.error().message;
    auto directory = readHeightField(dir / "tiles");
    ASSERT_TRUE(directory.ok()) << directory.error().message;
    const auto vrt = dir / "mosaic.vrt";
    std::vector<std::string> vrtArgs = {"-q", vrt.string()};
    for (const auto& t : tiles) {
        vrtArgs.push_back(t.string());
    }
    gdalTool("gdalbuildvrt", vrtArgs);
    auto fromVrt = readHeightField(vrt);
    ASSERT_TRUE(fromVrt.ok()) << fromVrt.error().message;
    for (const HeightField* f : {&*listed, &*directory, &*fromVrt}) {
        EXPECT_EQ(f->width, reference->width);
        EXPECT_EQ(f->height, reference->height);
        EXPECT_DOUBLE_EQ(f->originX, reference->originX);
        EXPECT_DOUBLE_EQ(f->originY, reference->originY);
        EXPECT_EQ(f->samples, reference->samples);
    }
}

TEST(GdalRasterTest, ImageryIsAlignedByCoordinatesOverTheGeneratedColours)
{
    test::ScratchDir dir;
    const auto png = writeSourcePng(dir.path(), 129, 129);
    const auto dem = dir / "dem.tif";
    // 129 samples of 10 m: pixel centres 500005 .. 501285 east, 4098715 .. 4099995 north.
    gdalTool("gdal_translate", {"-q", "-ot", "Int16", "-a_srs", "EPSG:32613", "-a_ullr", "500000", "4100000", "501290",
                                "4098710", png.string(), dem.string()});
    // Red imagery over the north-east quarter only, in another CRS (WGS 84 geographic), 4x coarser.
    const auto red = dir / "red.tif";
    gdalTool("gdal_create",
             {"-q",     "-of",        "GTiff",   "-ot",    "Byte",    "-outsize", "40",      "40",
              "-bands", "3",          "-burn",   "220",    "-burn",   "20",       "-burn",   "30",
              "-a_srs", "EPSG:32613", "-a_ullr", "500645", "4100000", "501290",   "4099355", red.string()});
    const auto geoRed = dir / "red_geo.tif";
    gdalTool("gdalwarp", {"-q", "-t_srs", "EPSG:4326", "-r", "near", red.string(), geoRed.string()});
    const auto map = dir / "img.map";
    const test::RunResult prep =
        test::runProgram(TERRAIN_PREP_EXE, {dem.string(), "-t", geoRed.string(), "-o", map.string(), "--chunk", "33"});
    ASSERT_EQ(prep.exitCode, 0) << prep.output;
    EXPECT_NE(prep.output.find("imagery"), std::string::npos) << prep.output;
    // Leaves of level 2 (4 x 4 of 33 samples): (3, 3) lies inside the imagery, (0, 0) outside it.
    for (const auto& [node, inside] : std::vector<std::pair<std::string, bool>>{{"2/3/3", true}, {"2/0/0", false}}) {
        const auto out = dir / ("tex" + node.substr(2, 1) + ".png");
        const test::RunResult tex =
            test::runProgram(TERRAIN_TENGINE_TOOL_EXE, {"texture", map.string(), node, out.string()});
        ASSERT_EQ(tex.exitCode, 0) << tex.output;
        auto image = readPngImage(out, 3);
        ASSERT_TRUE(image.ok());
        const std::uint8_t* centre = image->pixel(image->width / 2, image->height / 2);
        if (inside) {
            EXPECT_NEAR(centre[0], 220, 3) << node;
            EXPECT_NEAR(centre[1], 20, 3) << node;
            EXPECT_NEAR(centre[2], 30, 3) << node;
        } else {
            EXPECT_FALSE(std::abs(centre[0] - 220) <= 3 && std::abs(centre[1] - 20) <= 3) << node << ": generated";
        }
    }
}

TEST(GdalRasterTest, AnExportPreparedAgainGivesTheSurfaceItWasExportedFrom)
{
    test::ScratchDir dir;
    const auto png = writeSourcePng(dir.path(), 200, 150);
    const auto dem = dir / "dem.tif";
    gdalTool("gdal_translate", {"-q", "-ot", "Int16", "-a_srs", "EPSG:32613", "-a_ullr", "500000", "4100000", "506000",
                                "4095500", png.string(), dem.string()});
    const auto map = dir / "dem.map";
    ASSERT_EQ(test::runProgram(TERRAIN_PREP_EXE, {dem.string(), "-o", map.string()}).exitCode, 0);
    auto original = MapFile::open(map, ReaderKind::Stream);
    ASSERT_TRUE(original.ok());
    const int finest = static_cast<int>((*original)->header().levels) - 1;
    // A region on the static lattice (sample centres 500015 + 30 k), at the static spacing.
    const auto tif = dir / "export.tif";
    const test::RunResult exported = test::runProgram(
        TERRAIN_TENGINE_TOOL_EXE,
        {"export", map.string(), tif.string(), "--region", "501215,4096415,504815,4099115", "--spacing", "30"});
    ASSERT_EQ(exported.exitCode, 0) << exported.output;
    const GdalReading gdal = readWithGdal(tif);
    EXPECT_EQ(gdal.width, 121);
    EXPECT_EQ(gdal.height, 91);
    EXPECT_DOUBLE_EQ(gdal.gt[0], 501200.0);
    EXPECT_DOUBLE_EQ(gdal.gt[3], 4099130.0);
    const auto again = dir / "again.map";
    const test::RunResult prep = test::runProgram(TERRAIN_PREP_EXE, {tif.string(), "-o", again.string()});
    ASSERT_EQ(prep.exitCode, 0) << prep.output;
    auto copy = MapFile::open(again, ReaderKind::Stream);
    ASSERT_TRUE(copy.ok());
    // 100 random points of the region: the copy's static surface against height --depth of the original.
    std::mt19937 random(15);
    std::uniform_real_distribution<double> ux(501215.0, 504815.0), uy(4096415.0, 4099115.0);
    std::string points;
    std::vector<double> expected;
    for (int k = 0; k < 100; ++k) {
        const double x = ux(random), y = uy(random);
        auto h = staticHeightAt(**copy, x, y);
        ASSERT_TRUE(h.ok()) << h.error().message;
        expected.push_back(h->height);
        points += std::to_string(x) + " " + std::to_string(y) + "\n";
    }
    const auto pointsFile = dir / "points.txt";
    test::runProgram("sh", {"-c", "printf '" + points + "' > " + pointsFile.string()});
    const test::RunResult query =
        test::runProgram(TERRAIN_TENGINE_TOOL_EXE,
                         {"height", map.string(), "--points", pointsFile.string(), "--depth", std::to_string(finest)});
    ASSERT_EQ(query.exitCode, 0) << query.output;
    std::istringstream lines(query.output);
    double worst = 0.0;
    for (double e : expected) {
        double h = 0.0;
        ASSERT_TRUE(lines >> h);
        worst = std::max(worst, std::abs(h - e));
    }
    std::printf("export round trip: worst %.6f m over 100 points, the copy's stored max error %.6f m\n", worst,
                (*copy)->header().maxErrorBound);
    // Within the copy's own stored error (its float heights quantized to 16-bit codes: half a step).
    EXPECT_LE(worst, (*copy)->header().maxErrorBound + 1e-4) << "worst " << worst;
}

TEST(GdalRasterTest, BadInputIsAClearErrorNamingTheFile)
{
    test::ScratchDir dir;
    const auto png = writeSourcePng(dir.path(), 40, 30);
    const auto a = dir / "a.tif", b = dir / "b.tif", c = dir / "c.tif", rgb = dir / "rgb.tif", bare = dir / "bare.tif";
    gdalTool("gdal_translate", {"-q", "-ot", "Int16", "-a_srs", "EPSG:32613", "-a_ullr", "500000", "4100000", "501200",
                                "4099100", png.string(), a.string()});
    gdalTool("gdal_translate", {"-q", "-a_srs", "EPSG:32614", a.string(), b.string()});
    gdalTool("gdal_translate", {"-q", "-a_ullr", "501200", "4100000", "501600", "4099700", a.string(), c.string()});
    gdalTool("gdal_translate", {"-q", "-b", "1", "-b", "1", "-b", "1", a.string(), rgb.string()});
    gdalTool("gdal_translate", {"-q", "-of", "GTiff", png.string(), bare.string()});

    auto crs = readHeightFields(std::vector{a, b});
    ASSERT_FALSE(crs.ok());
    EXPECT_NE(crs.error().message.find(b.string()), std::string::npos) << crs.error().message;
    EXPECT_NE(crs.error().message.find("CRS"), std::string::npos) << crs.error().message;
    auto resolution = readHeightFields(std::vector{a, c});
    ASSERT_FALSE(resolution.ok());
    EXPECT_NE(resolution.error().message.find(c.string()), std::string::npos) << resolution.error().message;
    EXPECT_NE(resolution.error().message.find("resolution"), std::string::npos) << resolution.error().message;
    auto bands = readHeightField(rgb);
    ASSERT_FALSE(bands.ok());
    EXPECT_NE(bands.error().message.find(rgb.string() + ": has 3 bands"), std::string::npos) << bands.error().message;
    auto garbage = dir / "garbage.tif";
    test::runProgram("sh", {"-c", "printf 'not a tiff at all' > " + garbage.string()});
    auto unreadable = readHeightField(garbage);
    ASSERT_FALSE(unreadable.ok());
    EXPECT_NE(unreadable.error().message.find(garbage.string() + ": GDAL cannot read it"), std::string::npos)
        << unreadable.error().message;
    // Mars is not on Earth: no transformation to a UTM zone.
    const auto mars = dir / "mars.tif";
    gdalTool("gdal_translate",
             {"-q", "-a_srs", "IAU_2015:49900", "-a_ullr", "10", "20", "10.4", "19.7", a.string(), mars.string()});
    auto planet = readHeightField(mars);
    ASSERT_FALSE(planet.ok());
    EXPECT_NE(planet.error().message.find(mars.string()), std::string::npos) << planet.error().message;
    // No georeferencing: the raster reads with no spacing, so prep's -h applies as for PNG.
    auto plain = readHeightField(bare);
    ASSERT_TRUE(plain.ok()) << plain.error().message;
    EXPECT_FALSE(plain->spacing);
    EXPECT_TRUE(plain->crsWkt.empty());
}

}  // namespace
}  // namespace terrain
