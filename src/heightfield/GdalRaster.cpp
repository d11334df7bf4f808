// Rasters through GDAL's C++ API (research and the API facts used here: docs/gdal-notes.md).
#include "heightfield/GdalRaster.h"

#include "core/AtomicFile.h"
#include "core/Memory.h"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <gdal_priv.h>
#include <gdal_utils.h>
#include <gdalwarper.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>
#include <mutex>
#include <set>
#include <sstream>

namespace terrain {

namespace {

/// GDAL's drivers, registered once per process (GDAL's own driver manager; GDALAllRegister is not safe to
/// call concurrently).
void registerGdal()
{
    static std::once_flag once;
    std::call_once(once, [] { GDALAllRegister(); });
}

/// Collects the messages GDAL reports on this thread while it lives (GDAL's handler stack is per thread),
/// so they go into our errors instead of to stderr.
class GdalMessages {
public:
    GdalMessages() : mPusher(&GdalMessages::collect, this) { CPLErrorReset(); }
    /// The last error (or warning) GDAL reported, or "no reason given".
    std::string last() const { return mMessages.empty() ? std::string("no reason given") : mMessages.back(); }
    const std::vector<std::string>& all() const { return mMessages; }

private:
    static void CPL_STDCALL collect(CPLErr type, CPLErrorNum, const char* message)
    {
        if (type >= CE_Warning && message != nullptr) {
            static_cast<GdalMessages*>(CPLGetErrorHandlerUserData())->mMessages.emplace_back(message);
        }
    }
    std::vector<std::string> mMessages;
    CPLErrorHandlerPusher mPusher;
};

/// Sets a GDAL configuration option on this thread for its lifetime (GDAL 3.6 has no CPLConfigOptionSetter).
class ThreadConfigOption {
public:
    ThreadConfigOption(const char* key, const char* value) : mKey(key)
    {
        const char* old = CPLGetThreadLocalConfigOption(key, nullptr);
        if (old != nullptr) {
            mOld = old;
        }
        CPLSetThreadLocalConfigOption(key, value);
    }
    ~ThreadConfigOption() { CPLSetThreadLocalConfigOption(mKey, mOld ? mOld->c_str() : nullptr); }
    ThreadConfigOption(const ThreadConfigOption&) = delete;
    ThreadConfigOption& operator=(const ThreadConfigOption&) = delete;

private:
    const char* mKey;
    std::optional<std::string> mOld;
};

struct DatasetCloser {
    void operator()(GDALDataset* dataset) const
    {
        if (dataset != nullptr) {
            GDALClose(GDALDataset::ToHandle(dataset));
        }
    }
};
using Dataset = std::unique_ptr<GDALDataset, DatasetCloser>;

Expected<Dataset> openRaster(const std::filesystem::path& path, GdalMessages& messages)
{
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) {
        return makeError(path.string(), ": cannot open: no such file");
    }
    Dataset dataset(GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY | GDAL_OF_VERBOSE_ERROR));
    if (!dataset) {
        return makeError(path.string(), ": GDAL cannot read it as a raster: ", messages.last());
    }
    return dataset;
}

std::string lower(std::string text)
{
    for (char& c : text) {
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    return text;
}

/// Metres per unit of a vertical unit name as drivers spell it; 0 for a name we do not know, -1 for none.
double verticalUnitMetres(const std::string& unit)
{
    const std::string u = lower(unit);
    if (u.empty()) {
        return -1.0;
    }
    if (u == "m" || u == "metre" || u == "metres" || u == "meter" || u == "meters") {
        return 1.0;
    }
    if (u == "ft" || u == "foot" || u == "feet" || u == "international foot" || u == "ft_intl") {
        return 0.3048;
    }
    if (u == "us-ft" || u == "ftus" || u == "sft" || u == "us survey foot" || u == "foot_us" || u == "us_survey_foot") {
        return 1200.0 / 3937.0;
    }
    if (u == "cm" || u == "centimetre" || u == "centimeter") {
        return 0.01;
    }
    if (u == "mm" || u == "millimetre" || u == "millimeter") {
        return 0.001;
    }
    return 0.0;
}

std::string wktOf(const OGRSpatialReference& srs)
{
    char* text = nullptr;
    const char* const options[] = {"FORMAT=WKT2_2018", "MULTILINE=NO", nullptr};
    if (srs.exportToWkt(&text, options) != OGRERR_NONE || text == nullptr) {
        CPLFree(text);
        return {};
    }
    std::string wkt(text);
    CPLFree(text);
    return wkt;
}

std::string nameOf(const OGRSpatialReference& srs)
{
    std::string name = srs.GetName() != nullptr ? srs.GetName() : "unnamed CRS";
    const char* authority = srs.GetAuthorityName(nullptr);
    const char* code = srs.GetAuthorityCode(nullptr);
    if (authority != nullptr && code != nullptr) {
        name += std::string(" (") + authority + ":" + code + ")";
    }
    return name;
}

/// The UTM zone (WGS 84) of a longitude and latitude; ignores the Norway and Svalbard exceptions.
OGRSpatialReference utmOf(double lon, double lat)
{
    const int zone = std::clamp(static_cast<int>(std::floor((lon + 180.0) / 6.0)) + 1, 1, 60);
    OGRSpatialReference utm;
    utm.importFromEPSG((lat >= 0 ? 32600 : 32700) + zone);
    utm.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    return utm;
}

std::string formatNumber(double value)
{
    std::ostringstream s;
    s.precision(10);
    s << value;
    return s.str();
}

/// What a mosaic's tiles must share, read from one tile.
struct TileFacts {
    std::filesystem::path path;
    int bands = 0;
    GDALDataType type = GDT_Unknown;
    bool hasGeoTransform = false;
    std::array<double, 6> gt{};
    const OGRSpatialReference* srs = nullptr;
    bool hasNoData = false;
    double noData = 0.0;
    double scale = 1.0;
    double offset = 0.0;
    bool hasScaleOrOffset = false;  ///< the band sets either (else -v applies when no unit is known either)
    std::string unit;
};

TileFacts factsOf(GDALDataset& dataset, const std::filesystem::path& path)
{
    TileFacts facts;
    facts.path = path;
    facts.bands = dataset.GetRasterCount();
    facts.hasGeoTransform = dataset.GetGeoTransform(facts.gt.data()) == CE_None;
    facts.srs = dataset.GetSpatialRef();
    if (facts.bands >= 1) {
        GDALRasterBand* band = dataset.GetRasterBand(1);
        facts.type = band->GetRasterDataType();
        int has = 0;
        facts.noData = band->GetNoDataValue(&has);
        facts.hasNoData = has != 0;
        int hasScale = 0, hasOffset = 0;
        facts.scale = band->GetScale(&hasScale);
        facts.offset = band->GetOffset(&hasOffset);
        facts.hasScaleOrOffset = hasScale != 0 || hasOffset != 0;
        facts.unit = band->GetUnitType() != nullptr ? band->GetUnitType() : "";
    }
    return facts;
}

Status checkOneBand(const TileFacts& facts)
{
    if (facts.bands == 0) {
        return makeError(facts.path.string(),
                         ": has no raster band (a container of subdatasets? open one of them, see gdalinfo)");
    }
    if (facts.bands != 1) {
        return makeError(facts.path.string(), ": has ", facts.bands,
                         " bands; an elevation raster has one (imagery goes to -t; to use one band of it, "
                         "gdal_translate -b N first)");
    }
    return {};
}

/// Whether two tiles can be one mosaic; the error names `b` and what differs from `a`.
Status checkSameGrid(const TileFacts& a, const TileFacts& b)
{
    auto differ = [&](auto&&... what) {
        return makeError(b.path.string(), ": cannot be mosaicked with ", a.path.string(), ": ", what...);
    };
    if (!b.hasGeoTransform || !a.hasGeoTransform) {
        return differ("tiles of a mosaic need georeferencing (", (b.hasGeoTransform ? a : b).path.string(),
                      " has none)");
    }
    if ((a.srs == nullptr) != (b.srs == nullptr) || (a.srs != nullptr && !a.srs->IsSame(b.srs))) {
        return differ("its CRS ", b.srs ? nameOf(*b.srs) : std::string("(none)"), " differs from ",
                      a.srs ? nameOf(*a.srs) : std::string("(none)"));
    }
    if (b.gt[2] != 0.0 || b.gt[4] != 0.0) {
        return differ("it is rotated (geotransform terms ", b.gt[2], ", ", b.gt[4], ")");
    }
    auto close = [](double x, double y) { return std::abs(x - y) <= 1e-9 * std::max(std::abs(x), std::abs(y)); };
    if (!close(a.gt[1], b.gt[1]) || !close(a.gt[5], b.gt[5])) {
        return differ("its resolution ", formatNumber(b.gt[1]), " x ", formatNumber(std::abs(b.gt[5])),
                      " differs from ", formatNumber(a.gt[1]), " x ", formatNumber(std::abs(a.gt[5])));
    }
    const double fx = (b.gt[0] - a.gt[0]) / a.gt[1], fy = (b.gt[3] - a.gt[3]) / a.gt[5];
    if (std::abs(fx - std::round(fx)) > 1e-6 || std::abs(fy - std::round(fy)) > 1e-6) {
        return differ("its samples are not on the same grid (offset by ", formatNumber(fx - std::round(fx)), ", ",
                      formatNumber(fy - std::round(fy)), " samples)");
    }
    if (a.type != b.type) {
        return differ("its sample type ", GDALGetDataTypeName(b.type), " differs from ", GDALGetDataTypeName(a.type));
    }
    const bool sameNoData = a.hasNoData == b.hasNoData &&
                            (!a.hasNoData || a.noData == b.noData || (std::isnan(a.noData) && std::isnan(b.noData)));
    if (!sameNoData) {
        return differ("its no-data value differs");
    }
    if (a.scale != b.scale || a.offset != b.offset || lower(a.unit) != lower(b.unit)) {
        return differ("its scale, offset or unit (", formatNumber(b.scale), ", ", formatNumber(b.offset), ", '", b.unit,
                      "') differ from (", formatNumber(a.scale), ", ", formatNumber(a.offset), ", '", a.unit, "')");
    }
    return {};
}

/// The files of a directory GDAL takes as rasters, sorted by name; other files are skipped.
Expected<std::vector<std::filesystem::path>> rastersIn(const std::filesystem::path& directory,
                                                       std::vector<std::string>& notes)
{
    std::vector<std::filesystem::path> files;
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator(directory, ec)) {
        if (entry.is_regular_file(ec) && isGdalRasterExtension(entry.path())) {
            files.push_back(entry.path());
        }
    }
    if (ec) {
        return makeError(directory.string(), ": cannot list: ", ec.message());
    }
    std::sort(files.begin(), files.end());
    if (files.empty()) {
        return makeError(directory.string(), ": holds no raster file (.tif, .hgt, .asc, .vrt, ...)");
    }
    notes.push_back("mosaic of the " + std::to_string(files.size()) + " rasters in " + directory.string());
    return files;
}

/// A warped VRT of `source` onto a north-up grid in `target` (warp options as described in gdal-notes.md).
struct WarpSpec {
    std::array<double, 6> gt{};
    int width = 0;
    int height = 0;
};

Expected<WarpSpec> suggestGrid(GDALDataset& source, const std::string& targetWkt, const std::string& name,
                               GdalMessages& messages, double pixelSize)
{
    char** options = CSLSetNameValue(nullptr, "DST_SRS", targetWkt.c_str());
    void* transformer = GDALCreateGenImgProjTransformer2(GDALDataset::ToHandle(&source), nullptr, options);
    CSLDestroy(options);
    if (transformer == nullptr) {
        return makeError(name, ": cannot reproject it: ", messages.last());
    }
    WarpSpec spec;
    double extent[4] = {0, 0, 0, 0};
    const CPLErr err = GDALSuggestedWarpOutput2(GDALDataset::ToHandle(&source), GDALGenImgProjTransform, transformer,
                                                spec.gt.data(), &spec.width, &spec.height, extent, 0);
    GDALDestroyGenImgProjTransformer(transformer);
    if (err != CE_None) {
        return makeError(name, ": cannot reproject it: ", messages.last());
    }
    const double r = pixelSize > 0 ? pixelSize : std::min(std::abs(spec.gt[1]), std::abs(spec.gt[5]));
    const double x0 = std::floor(extent[0] / r) * r, y1 = std::ceil(extent[3] / r) * r;
    const double nx = std::ceil((extent[2] - x0) / r - 1e-9), ny = std::ceil((y1 - extent[1]) / r - 1e-9);
    if (!(nx >= 1 && ny >= 1 && nx < 1 << 30 && ny < 1 << 30)) {
        return makeError(name, ": reprojected, it would be ", nx, "x", ny, " samples");
    }
    spec.gt = {x0, r, 0.0, y1, 0.0, -r};
    spec.width = static_cast<int>(nx);
    spec.height = static_cast<int>(ny);
    return spec;
}

/// Creates the warped VRT. `bands` source bands to bands 1..n; `srcAlpha`/`dstAlpha` 0 for none.
Expected<Dataset> createWarped(GDALDataset& source, const OGRSpatialReference& target, const WarpSpec& spec,
                               const std::vector<int>& bands, int srcAlpha, int dstAlpha, GDALDataType working,
                               GDALResampleAlg resampling, std::optional<double> srcNoData, bool dstNoDataNaN,
                               const std::string& name, GdalMessages& messages)
{
    const std::string wkt = wktOf(target);
    GDALWarpOptions* wo = GDALCreateWarpOptions();
    wo->hSrcDS = GDALDataset::ToHandle(&source);
    wo->nBandCount = static_cast<int>(bands.size());
    wo->panSrcBands = static_cast<int*>(CPLMalloc(sizeof(int) * bands.size()));
    wo->panDstBands = static_cast<int*>(CPLMalloc(sizeof(int) * bands.size()));
    for (std::size_t k = 0; k < bands.size(); ++k) {
        wo->panSrcBands[k] = bands[k];
        wo->panDstBands[k] = static_cast<int>(k) + 1;
    }
    wo->nSrcAlphaBand = srcAlpha;
    wo->nDstAlphaBand = dstAlpha;
    wo->eResampleAlg = resampling;
    wo->eWorkingDataType = working;
    if (srcNoData) {
        GDALWarpInitSrcNoDataReal(wo, *srcNoData);
    }
    if (dstNoDataNaN) {
        GDALWarpInitDstNoDataReal(wo, std::numeric_limits<double>::quiet_NaN());
    }
    wo->papszWarpOptions = CSLSetNameValue(wo->papszWarpOptions, "INIT_DEST", dstNoDataNaN ? "NO_DATA" : "0");
    char** to = CSLSetNameValue(nullptr, "DST_SRS", wkt.c_str());
    void* transformer = GDALCreateGenImgProjTransformer2(wo->hSrcDS, nullptr, to);
    CSLDestroy(to);
    if (transformer == nullptr) {
        GDALDestroyWarpOptions(wo);
        return makeError(name, ": cannot reproject it to ", nameOf(target), ": ", messages.last());
    }
    std::array<double, 6> gt = spec.gt;
    GDALSetGenImgProjTransformerDstGeoTransform(transformer, gt.data());
    wo->pfnTransformer = GDALGenImgProjTransform;
    wo->pTransformerArg = transformer;
    GDALDatasetH warped = GDALCreateWarpedVRT(wo->hSrcDS, spec.width, spec.height, gt.data(), wo);
    GDALDestroyWarpOptions(wo);  // the VRT keeps its own copy and owns the transformer
    if (warped == nullptr) {
        GDALDestroyGenImgProjTransformer(transformer);
        return makeError(name, ": cannot set up its reprojection to ", nameOf(target), ": ", messages.last());
    }
    Dataset dataset(GDALDataset::FromHandle(warped));
    dataset->SetProjection(wkt.c_str());
    return dataset;
}

/// The index of a dataset's alpha band, 0 for none.
int alphaBandOf(GDALDataset& dataset)
{
    for (int b = 1; b <= dataset.GetRasterCount(); ++b) {
        if (dataset.GetRasterBand(b)->GetColorInterpretation() == GCI_AlphaBand) {
            return b;
        }
    }
    return 0;
}

}  // namespace

bool isGdalRasterExtension(const std::filesystem::path& path)
{
    static const std::set<std::string> kExtensions = {".tif", ".tiff", ".hgt", ".asc", ".dem", ".vrt", ".img",
                                                      ".bil", ".flt",  ".adf", ".nc",  ".grd", ".dt0", ".dt1",
                                                      ".dt2", ".bt",   ".ter", ".xyz", ".jp2", ".sdat"};
    return kExtensions.count(lower(path.extension().string())) != 0;
}

namespace {

/// The files `inputs` name: the rasters of a directory given alone (rastersIn, noting what it skipped in
/// `notes`), or the files given. Error: a directory given with other inputs.
Expected<std::vector<std::filesystem::path>> inputFiles(std::span<const std::filesystem::path> inputs,
                                                        std::vector<std::string>& notes)
{
    std::error_code ec;
    if (inputs.size() == 1 && std::filesystem::is_directory(inputs.front(), ec)) {
        return rastersIn(inputs.front(), notes);
    }
    std::vector<std::filesystem::path> files;
    for (const auto& input : inputs) {
        if (std::filesystem::is_directory(input, ec)) {
            return makeError(input.string(), ": a directory can only be given alone (as a mosaic of its tiles)");
        }
        files.push_back(input);
    }
    return files;
}

/// How errors and notes name the input: its one file, or the first input and how many more.
std::string inputsName(const std::vector<std::filesystem::path>& files, std::span<const std::filesystem::path> inputs)
{
    std::string name = files.size() == 1 ? files.front().string() : inputs.front().string();
    if (inputs.size() > 1) {
        name += " (and " + std::to_string(inputs.size() - 1) + " more)";
    }
    return name;
}

/// The input files opened, with what each says of itself (facts[i] of datasets[i], whose CRS it points to).
struct OpenedTiles {
    std::vector<Dataset> datasets;
    std::vector<TileFacts> facts;
};

/// Opens `files` in order, checking that each has one band and lies on the first one's grid.
Expected<OpenedTiles> openTiles(const std::vector<std::filesystem::path>& files, GdalMessages& messages)
{
    OpenedTiles tiles;
    for (const auto& file : files) {
        auto dataset = openRaster(file, messages);
        TERRAIN_TRY(dataset);
        tiles.facts.push_back(factsOf(**dataset, file));
        TERRAIN_TRY(checkOneBand(tiles.facts.back()));
        if (tiles.facts.size() > 1) {
            TERRAIN_TRY(checkSameGrid(tiles.facts.front(), tiles.facts.back()));
        }
        tiles.datasets.push_back(std::move(dataset).value());
    }
    return tiles;
}

/// A VRT mosaic of `files` at the highest resolution: later tiles win where tiles overlap, and an added alpha
/// band marks what no tile covers (read through the mask). `name` names the input in errors.
Expected<Dataset> mosaicOf(const std::vector<std::filesystem::path>& files, const std::string& name,
                           GdalMessages& messages)
{
    CPLStringList args;
    for (const char* arg : {"-resolution", "highest", "-strict", "-addalpha"}) {
        args.AddString(arg);
    }
    GDALBuildVRTOptions* vrtOptions = GDALBuildVRTOptionsNew(args.List(), nullptr);
    std::vector<std::string> names;
    std::vector<const char*> pointers;
    for (const auto& file : files) {
        names.push_back(file.string());
    }
    for (const auto& n : names) {
        pointers.push_back(n.c_str());
    }
    int usageError = 0;
    GDALDatasetH vrt =
        GDALBuildVRT("", static_cast<int>(pointers.size()), nullptr, pointers.data(), vrtOptions, &usageError);
    GDALBuildVRTOptionsFree(vrtOptions);
    if (vrt == nullptr) {
        return makeError(name, ": cannot mosaic its tiles: ", messages.last());
    }
    return Dataset(GDALDataset::FromHandle(vrt));
}

/// Metres = scale x native + offset, from the band's scale and offset times its vertical unit; no scale when
/// the band gives neither a scale, an offset nor a unit (-v then applies).
struct VerticalMapping {
    std::optional<double> scale;
    double offset = 0.0;
};

/// The first tile's vertical mapping, noting in `notes` when it gives no unit. Error: a unit prep does not know.
Expected<VerticalMapping> verticalMappingOf(const TileFacts& first, std::vector<std::string>& notes)
{
    const double unit = verticalUnitMetres(first.unit);
    if (unit == 0.0) {
        return makeError(first.path.string(), ": vertical unit '", first.unit,
                         "' is not one prep knows (m, ft, US survey ft, cm, mm); set it with gdal_edit.py -units");
    }
    VerticalMapping mapping;
    if (first.hasScaleOrOffset || unit > 0) {
        mapping.scale = first.scale * (unit > 0 ? unit : 1.0);
        mapping.offset = first.offset * (unit > 0 ? unit : 1.0);
    }
    if (unit < 0) {
        notes.push_back("the raster gives no vertical unit: heights taken as metres (-v to scale them)");
    }
    return mapping;
}

/// Where a raster lies and whether it is resampled (warped) onto `target`.
struct Placement {
    bool georeferenced = false;                ///< it has a geotransform
    std::array<double, 6> gt{};                ///< its geotransform
    const OGRSpatialReference* srs = nullptr;  ///< its CRS, owned by the dataset; null for none
    OGRSpatialReference target;                ///< the CRS it is warped to, when `warp`
    bool warp = false;
};

/// Decides the reprojection of `base`: to --srs (options.targetSrs, a projected CRS) when it differs from the
/// raster's; geographic rasters to the UTM zone of their centre; rotated or non-square pixels resampled in
/// their own CRS (noted in `notes`). Errors: an unknown or unprojected --srs, --srs for a raster without a
/// CRS, a CRS neither projected nor geographic, and rotated or non-square pixels without a CRS.
Expected<Placement> placementOf(GDALDataset& base, const ElevationReadOptions& options, const std::string& name,
                                std::vector<std::string>& notes, GdalMessages& messages)
{
    Placement placement;
    std::array<double, 6>& gt = placement.gt;
    placement.georeferenced = base.GetGeoTransform(gt.data()) == CE_None;
    placement.srs = base.GetSpatialRef();
    const OGRSpatialReference* srs = placement.srs;
    const bool georeferenced = placement.georeferenced;
    OGRSpatialReference& target = placement.target;
    if (!options.targetSrs.empty()) {
        if (target.SetFromUserInput(options.targetSrs.c_str()) != OGRERR_NONE) {
            return makeError("--srs '", options.targetSrs, "': GDAL does not know this CRS: ", messages.last());
        }
        target.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
        if (!target.IsProjected()) {
            return makeError("--srs '", options.targetSrs, "' (", nameOf(target),
                             ") is not a projected CRS: the terrain needs metric coordinates");
        }
        if (!georeferenced || srs == nullptr) {
            return makeError(name, ": has no CRS, so --srs cannot reproject it");
        }
        placement.warp = !srs->IsSame(&target);
    } else if (georeferenced && srs != nullptr && srs->IsGeographic()) {
        const double lon = gt[0] + gt[1] * base.GetRasterXSize() / 2.0 + gt[2] * base.GetRasterYSize() / 2.0;
        const double lat = gt[3] + gt[4] * base.GetRasterXSize() / 2.0 + gt[5] * base.GetRasterYSize() / 2.0;
        target = utmOf(lon, lat);
        placement.warp = true;
    } else if (georeferenced && srs != nullptr && !srs->IsProjected()) {
        return makeError(name, ": its CRS ", nameOf(*srs),
                         " is neither projected nor geographic: give --srs to say where it lies, or reproject it");
    }
    const bool square = std::abs(std::abs(gt[1]) - std::abs(gt[5])) <= 1e-9 * std::abs(gt[1]);
    if (georeferenced && !placement.warp && (gt[2] != 0.0 || gt[4] != 0.0 || !square)) {
        if (srs == nullptr) {
            return makeError(name, ": its pixels are ", (square ? "rotated" : "not square"),
                             " and it has no CRS to resample it in");
        }
        target = *srs;
        placement.warp = true;
        notes.push_back(std::string("its pixels are ") + (square ? "rotated" : "not square") +
                        ": resampled onto a square north-up grid");
    }
    return placement;
}

}  // namespace

struct ElevationRaster::State {
    std::vector<Dataset> sources;  ///< the input files (closed last)
    Dataset mosaic;                ///< VRT over several sources
    Dataset warped;                ///< warped VRT (closed first)
    GDALDataset* read = nullptr;   ///< what rows are read from
    std::string name;              ///< the input(s), for errors
    bool southUp = false;          ///< row 0 of `read` is the south row
    bool useMask = false;          ///< read band 1's mask band (alpha, per-dataset or internal masks)
    bool hasNoData = false;
    double noData = 0.0;
    std::optional<double> userNoData;
    int width = 0;
    int height = 0;
    std::optional<double> spacing;
    double originX = 0.0;
    double originY = 0.0;
    std::string crsWkt;
    std::string crsName;
    double crsUnitMetres = 1.0;
    std::optional<double> verticalScale;
    double verticalOffset = 0.0;
    bool integerSamples = false;
    std::string description;
    std::vector<std::string> notes;

    /// Reads `base` warped onto placement.target (bilinear, NaN where nothing maps, the mosaic's alpha
    /// honoured), noting it; placement.gt becomes the warped grid's, and `description` gets its size.
    Status readReprojected(GDALDataset& base, Placement& placement, const TileFacts& first,
                           std::ostringstream& descriptionText, GdalMessages& messages)
    {
        auto spec = suggestGrid(base, wktOf(placement.target), name, messages, 0.0);
        TERRAIN_TRY(spec);
        std::optional<double> srcNoData;
        if (first.hasNoData) {
            srcNoData = first.noData;
        }
        auto reprojected = createWarped(base, placement.target, *spec, {1}, mosaic ? alphaBandOf(base) : 0, 0,
                                        GDT_Float32, GRA_Bilinear, srcNoData, true, name, messages);
        TERRAIN_TRY(reprojected);
        warped = std::move(reprojected).value();
        notes.push_back("reprojected from " + (placement.srs ? nameOf(*placement.srs) : std::string("its CRS")) +
                        " to " + nameOf(placement.target) + " (bilinear), " + std::to_string(spec->width) + "x" +
                        std::to_string(spec->height) + " samples of " + formatNumber(spec->gt[1]) + " units");
        read = warped.get();
        placement.gt = spec->gt;
        hasNoData = true;
        noData = std::numeric_limits<double>::quiet_NaN();
        useMask = false;
        descriptionText << " -> " << spec->width << "x" << spec->height;
        return {};
    }

    /// Reads `base` as it is, through band 1's mask where it has one beyond no-data.
    void readDirectly(GDALDataset& base)
    {
        read = &base;
        const int flags = base.GetRasterBand(1)->GetMaskFlags();
        useMask = (flags & GMF_ALL_VALID) == 0 && (flags & GMF_NODATA) == 0;
    }

    /// Spacing, origin (the south-west sample's centre) and CRS, in metres, from geotransform `gt` and CRS
    /// `srs` (null: coordinates taken as metres, noted); `descriptionText` gets the CRS's name. Error: a CRS whose
    /// linear unit is not a positive finite number of metres.
    Status setGeoreference(const std::array<double, 6>& gt, const OGRSpatialReference* srs,
                           std::ostringstream& descriptionText)
    {
        crsUnitMetres = srs != nullptr ? srs->GetLinearUnits() : 1.0;
        if (!(crsUnitMetres > 0) || !std::isfinite(crsUnitMetres)) {
            return makeError(name, ": its CRS has a linear unit of ", crsUnitMetres, " m");
        }
        const double u = crsUnitMetres;
        spacing = std::abs(gt[1]) * u;
        southUp = gt[5] > 0;
        // Sample centres: x = gt0 + (col + 0.5) gt1; the south row is the last one when north-up.
        originX = (gt[0] + 0.5 * gt[1]) * u;
        originY = (southUp ? gt[3] + 0.5 * gt[5] : gt[3] + (height - 0.5) * gt[5]) * u;
        if (srs != nullptr) {
            crsWkt = wktOf(*srs);
            crsName = nameOf(*srs);
            descriptionText << ", " << (srs->GetName() ? srs->GetName() : "unnamed CRS");
        } else {
            notes.push_back("the raster has a geotransform but no CRS: its coordinates are taken as metres");
        }
        return {};
    }
};

ElevationRaster::ElevationRaster(std::unique_ptr<State> state) : mState(std::move(state)) {}
ElevationRaster::ElevationRaster(ElevationRaster&&) noexcept = default;
ElevationRaster& ElevationRaster::operator=(ElevationRaster&&) noexcept = default;
ElevationRaster::~ElevationRaster() = default;

int ElevationRaster::width() const
{
    return mState->width;
}
int ElevationRaster::height() const
{
    return mState->height;
}
std::optional<double> ElevationRaster::spacing() const
{
    return mState->spacing;
}
double ElevationRaster::originX() const
{
    return mState->originX;
}
double ElevationRaster::originY() const
{
    return mState->originY;
}
const std::string& ElevationRaster::crsWkt() const
{
    return mState->crsWkt;
}
const std::string& ElevationRaster::crsName() const
{
    return mState->crsName;
}
double ElevationRaster::crsUnitMetres() const
{
    return mState->crsUnitMetres;
}
std::optional<double> ElevationRaster::verticalScale() const
{
    return mState->verticalScale;
}
double ElevationRaster::verticalOffset() const
{
    return mState->verticalOffset;
}
bool ElevationRaster::integerSamples() const
{
    return mState->integerSamples;
}
const std::string& ElevationRaster::description() const
{
    return mState->description;
}
const std::vector<std::string>& ElevationRaster::notes() const
{
    return mState->notes;
}

Expected<ElevationRaster> ElevationRaster::open(std::span<const std::filesystem::path> inputs,
                                                const ElevationReadOptions& options)
{
    registerGdal();
    GdalMessages messages;
    auto state = std::make_unique<State>();
    state->userNoData = options.noData;
    if (inputs.empty()) {
        return makeError("no elevation raster given");
    }
    auto files = inputFiles(inputs, state->notes);
    TERRAIN_TRY(files);
    state->name = inputsName(*files, inputs);
    auto tiles = openTiles(*files, messages);
    TERRAIN_TRY(tiles);
    state->sources = std::move(tiles->datasets);
    const TileFacts& first = tiles->facts.front();
    GDALDataset* base = state->sources.front().get();
    if (files->size() > 1) {
        auto mosaic = mosaicOf(*files, state->name, messages);
        TERRAIN_TRY(mosaic);
        state->mosaic = std::move(mosaic).value();
        base = state->mosaic.get();
        state->notes.push_back("mosaic of " + std::to_string(files->size()) + " tiles, " +
                               std::to_string(base->GetRasterXSize()) + "x" + std::to_string(base->GetRasterYSize()) +
                               " samples");
    }
    state->hasNoData = first.hasNoData;
    state->noData = first.noData;
    auto vertical = verticalMappingOf(first, state->notes);
    TERRAIN_TRY(vertical);
    state->verticalScale = vertical->scale;
    state->verticalOffset = vertical->offset;

    auto placement = placementOf(*base, options, state->name, state->notes, messages);
    TERRAIN_TRY(placement);
    const char* driver =
        state->sources.front()->GetDriver() != nullptr ? state->sources.front()->GetDriver()->GetDescription() : "GDAL";
    std::ostringstream description;
    description << driver << " " << GDALGetDataTypeName(first.type) << " " << base->GetRasterXSize() << "x"
                << base->GetRasterYSize();
    if (placement->warp) {
        TERRAIN_TRY(state->readReprojected(*base, *placement, first, description, messages));
    } else {
        state->readDirectly(*base);
    }
    state->integerSamples = !placement->warp && GDALDataTypeIsInteger(first.type) != 0;
    state->width = state->read->GetRasterXSize();
    state->height = state->read->GetRasterYSize();
    if (placement->georeferenced) {
        const OGRSpatialReference* srs = placement->warp ? &placement->target : placement->srs;
        TERRAIN_TRY(state->setGeoreference(placement->gt, srs, description));
    } else {
        state->notes.push_back("the raster has no georeferencing: -h gives its spacing");
    }
    state->description = description.str();
    if (state->description.size() > 95) {
        state->description.resize(95);
    }
    return ElevationRaster(std::move(state));
}

Status ElevationRaster::readRows(int j0, int rows, std::span<float> out)
{
    State& s = *mState;
    if (j0 < 0 || rows < 0 || j0 + rows > s.height ||
        out.size() != static_cast<std::size_t>(s.width) * static_cast<std::size_t>(rows)) {
        return makeError(s.name, ": rows ", j0, "..", j0 + rows, " outside its ", s.height, " rows");
    }
    if (rows == 0) {
        return {};
    }
    GdalMessages messages;
    GDALRasterBand* band = s.read->GetRasterBand(1);
    const int line0 = s.southUp ? j0 : s.height - j0 - rows;
    std::vector<float> buffer(out.size());
    if (band->RasterIO(GF_Read, 0, line0, s.width, rows, buffer.data(), s.width, rows, GDT_Float32, 0, 0, nullptr) !=
        CE_None) {
        return makeError(s.name, ": cannot read rows ", line0, "..", line0 + rows - 1, ": ", messages.last());
    }
    std::vector<std::uint8_t> mask;
    if (s.useMask) {
        mask.resize(out.size());
        if (band->GetMaskBand()->RasterIO(GF_Read, 0, line0, s.width, rows, mask.data(), s.width, rows, GDT_Byte, 0, 0,
                                          nullptr) != CE_None) {
            return makeError(s.name, ": cannot read the mask of rows ", line0, "..", line0 + rows - 1, ": ",
                             messages.last());
        }
    }
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (int r = 0; r < rows; ++r) {
        const int from = s.southUp ? r : rows - 1 - r;
        for (int i = 0; i < s.width; ++i) {
            const std::size_t k = static_cast<std::size_t>(from) * s.width + i;
            float v = buffer[k];
            if (std::isnan(v) || (s.hasNoData && isNoDataValue(v, s.noData)) ||
                (s.userNoData && isNoDataValue(v, *s.userNoData)) || (!mask.empty() && mask[k] == 0)) {
                v = nan;
            }
            out[static_cast<std::size_t>(r) * s.width + i] = v;
        }
    }
    return {};
}

Expected<HeightField> ElevationRaster::readAll()
{
    const State& s = *mState;
    const std::uint64_t bytes = std::uint64_t{static_cast<std::uint32_t>(s.width)} * s.height * sizeof(float);
    TERRAIN_TRY(checkAllocation(
        bytes, s.name + ": a " + std::to_string(s.width) + "x" + std::to_string(s.height) + " height field"));
    HeightField field;
    field.width = s.width;
    field.height = s.height;
    field.samples.resize(static_cast<std::size_t>(s.width) * s.height);
    const int band = std::max(1, static_cast<int>((std::size_t{1} << 23) / static_cast<std::size_t>(s.width)));
    for (int j = 0; j < s.height; j += band) {
        const int rows = std::min(band, s.height - j);
        TERRAIN_TRY(
            readRows(j, rows,
                     std::span(field.samples)
                         .subspan(static_cast<std::size_t>(j) * s.width, static_cast<std::size_t>(rows) * s.width)));
    }
    field.integerSamples = s.integerSamples;
    field.spacing = s.spacing;
    field.verticalScale = s.verticalScale;
    field.verticalOffset = s.verticalOffset;
    field.originX = s.originX;
    field.originY = s.originY;
    field.crsWkt = s.crsWkt;
    field.crsUnitMetres = s.crsUnitMetres;
    field.description = s.description;
    field.notes = s.notes;
    return field;
}

void configureGdalReading(std::uint64_t memoryBudget, int threads)
{
    GDALSetCacheMax64(static_cast<GIntBig>(gdalCacheBytesFor(memoryBudget)));
    if (CPLGetConfigOption("GDAL_NUM_THREADS", nullptr) == nullptr) {
        CPLSetConfigOption("GDAL_NUM_THREADS", std::to_string(std::max(threads, 1)).c_str());
    }
}

std::uint64_t gdalCacheBytesFor(std::uint64_t memoryBudget)
{
    return std::clamp<std::uint64_t>(memoryBudget / 8, std::uint64_t{16} << 20, std::uint64_t{256} << 20);
}

Expected<HeightField> readGdalHeightField(std::span<const std::filesystem::path> inputs,
                                          const ElevationReadOptions& options)
{
    auto raster = ElevationRaster::open(inputs, options);
    TERRAIN_TRY(raster);
    return raster->readAll();
}

bool isGeoreferencedRaster(const std::filesystem::path& path)
{
    registerGdal();
    GdalMessages messages;
    Dataset dataset(GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
    if (!dataset) {
        return false;
    }
    std::array<double, 6> gt{};
    return dataset->GetGeoTransform(gt.data()) == CE_None && dataset->GetSpatialRef() != nullptr;
}

Expected<Image> readGeoImagery(const std::filesystem::path& path, const RasterGrid& grid)
{
    registerGdal();
    GdalMessages messages;
    auto source = openRaster(path, messages);
    TERRAIN_TRY(source);
    GDALDataset& ds = **source;
    std::array<double, 6> gt{};
    if (ds.GetGeoTransform(gt.data()) != CE_None || ds.GetSpatialRef() == nullptr) {
        return makeError(path.string(), ": imagery has no georeferencing (geotransform and CRS) to align it by");
    }
    if (grid.crsWkt.empty()) {
        return makeError(path.string(), ": the terrain has no CRS, so georeferenced imagery cannot be aligned to it");
    }
    const int alpha = alphaBandOf(ds);
    const int colours = ds.GetRasterCount() - (alpha != 0 ? 1 : 0);
    if (colours != 3) {
        return makeError(path.string(), ": imagery has ", ds.GetRasterCount(), " bands", alpha ? " (one alpha)" : "",
                         "; expected RGB or RGBA");
    }
    for (int b = 1; b <= 3; ++b) {
        if (ds.GetRasterBand(b)->GetRasterDataType() != GDT_Byte) {
            return makeError(path.string(), ": imagery band ", b, " is ",
                             GDALGetDataTypeName(ds.GetRasterBand(b)->GetRasterDataType()), "; expected 8-bit (Byte)");
        }
    }
    OGRSpatialReference target;
    if (target.importFromWkt(grid.crsWkt.c_str()) != OGRERR_NONE) {
        return makeError(path.string(), ": the terrain's CRS is not valid WKT");
    }
    target.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    const double u = grid.crsUnitMetres, step = grid.step / u;
    WarpSpec spec;
    spec.width = grid.width;
    spec.height = grid.height;
    spec.gt = {grid.x0 / u - 0.5 * step, step, 0.0, grid.y0 / u + (grid.height - 0.5) * step, 0.0, -step};
    // Averaging where the imagery is finer than the grid (no aliasing), bilinear where it is coarser.
    const double sourceStep = std::abs(gt[1]) * ds.GetSpatialRef()->GetLinearUnits();
    const bool projected = ds.GetSpatialRef()->IsProjected();
    const GDALResampleAlg resampling = projected && sourceStep < grid.step / 1.5 ? GRA_Average : GRA_Bilinear;
    int hasNoData = 0;
    const double noData = ds.GetRasterBand(1)->GetNoDataValue(&hasNoData);
    std::optional<double> srcNoData;
    if (hasNoData) {
        srcNoData = noData;
    }
    auto warped = createWarped(ds, target, spec, {1, 2, 3}, alpha, 4, GDT_Byte, resampling, srcNoData, false,
                               path.string(), messages);
    TERRAIN_TRY(warped);
    const std::uint64_t bytes = std::uint64_t{static_cast<std::uint32_t>(grid.width)} * grid.height * 4;
    TERRAIN_TRY(checkAllocation(bytes, path.string() + ": imagery of " + std::to_string(grid.width) + "x" +
                                           std::to_string(grid.height) + " texels"));
    Image image;
    image.width = grid.width;
    image.height = grid.height;
    image.channels = 4;
    image.pixels.resize(static_cast<std::size_t>(bytes));
    int bandMap[4] = {1, 2, 3, 4};
    if ((*warped)->RasterIO(GF_Read, 0, 0, grid.width, grid.height, image.pixels.data(), grid.width, grid.height,
                            GDT_Byte, 4, bandMap, 4, 4L * grid.width, 1, nullptr) != CE_None) {
        return makeError(path.string(), ": cannot read the imagery: ", messages.last());
    }
    return image;
}

struct GeoConverter::State {
    OGRSpatialReference map;
    OGRSpatialReference wgs84;
    std::unique_ptr<OGRCoordinateTransformation> toMap;
    std::unique_ptr<OGRCoordinateTransformation> toGeo;
    double unit = 1.0;
};

GeoConverter::GeoConverter(std::unique_ptr<State> state) : mState(std::move(state)) {}
GeoConverter::GeoConverter(GeoConverter&&) noexcept = default;
GeoConverter& GeoConverter::operator=(GeoConverter&&) noexcept = default;
GeoConverter::~GeoConverter() = default;

Expected<GeoConverter> GeoConverter::create(const std::string& crsWkt, double crsUnitMetres)
{
    registerGdal();
    GdalMessages messages;
    if (crsWkt.empty()) {
        return makeError("the map records no CRS (it was made from a raster without one)");
    }
    auto state = std::make_unique<State>();
    if (state->map.importFromWkt(crsWkt.c_str()) != OGRERR_NONE) {
        return makeError("the map's CRS is not valid WKT: ", messages.last());
    }
    state->map.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    state->wgs84.importFromEPSG(4326);
    state->wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    state->toMap.reset(OGRCreateCoordinateTransformation(&state->wgs84, &state->map));
    state->toGeo.reset(OGRCreateCoordinateTransformation(&state->map, &state->wgs84));
    if (!state->toMap || !state->toGeo) {
        return makeError("cannot transform between WGS 84 and the map's CRS ", nameOf(state->map), ": ",
                         messages.last());
    }
    state->unit = crsUnitMetres;
    return GeoConverter(std::move(state));
}

Expected<std::pair<double, double>> GeoConverter::toWorld(double lon, double lat) const
{
    GdalMessages messages;
    double x = lon, y = lat;
    int ok = 0;
    if (!mState->toMap->Transform(1, &x, &y, nullptr, &ok) || !ok || !std::isfinite(x) || !std::isfinite(y)) {
        return makeError("longitude ", lon, ", latitude ", lat,
                         " cannot be placed in the map's CRS: ", messages.last());
    }
    return std::pair{x * mState->unit, y * mState->unit};
}

Expected<std::pair<double, double>> GeoConverter::toLonLat(double x, double y) const
{
    GdalMessages messages;
    double lon = x / mState->unit, lat = y / mState->unit;
    int ok = 0;
    if (!mState->toGeo->Transform(1, &lon, &lat, nullptr, &ok) || !ok) {
        return makeError("world position ", x, ", ", y, " has no longitude and latitude: ", messages.last());
    }
    return std::pair{lon, lat};
}

std::string describeCrs(const std::string& crsWkt)
{
    if (crsWkt.empty()) {
        return {};
    }
    registerGdal();
    GdalMessages messages;
    OGRSpatialReference srs;
    if (srs.importFromWkt(crsWkt.c_str()) != OGRERR_NONE) {
        return "(invalid CRS)";
    }
    return nameOf(srs);
}

Status writeFloat32GeoTiff(const std::filesystem::path& path, const RasterGrid& grid, std::span<const float> heights)
{
    registerGdal();
    GdalMessages messages;
    if (grid.width < 1 || grid.height < 1 ||
        heights.size() != static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height)) {
        return makeError(path.string(), ": ", heights.size(), " heights for a ", grid.width, "x", grid.height,
                         " raster");
    }
    GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
    if (driver == nullptr) {
        return makeError(path.string(), ": this GDAL has no GTiff driver");
    }
    TERRAIN_TRY(checkOutputPath(path));
    // A temporary name in the same directory, ending in .tif (GTiff checks nothing, but sidecars follow it).
    const std::filesystem::path temporary = temporaryOutputName(path, ".tif");
    CPLStringList create;
    create.SetNameValue("TILED", "YES");
    create.SetNameValue("COMPRESS", "DEFLATE");
    create.SetNameValue("PREDICTOR", "3");
    create.SetNameValue("BIGTIFF", "IF_SAFER");
    // Everything goes into the TIFF itself: no .aux.xml sidecar under the temporary name.
    ThreadConfigOption noPam("GDAL_PAM_ENABLED", "NO");
    Dataset out(driver->Create(temporary.c_str(), grid.width, grid.height, 1, GDT_Float32, create.List()));
    if (!out) {
        return makeError(path.string(), ": cannot create: ", messages.last());
    }
    auto fail = [&](const std::string& what) -> Status {
        out.reset();
        std::error_code ec;
        std::filesystem::remove(temporary, ec);
        return makeError(path.string(), ": ", what, ": ", messages.last());
    };
    const double u = grid.crsUnitMetres, step = grid.step / u;
    double gt[6] = {grid.x0 / u - 0.5 * step, step, 0.0, grid.y0 / u + (grid.height - 0.5) * step, 0.0, -step};
    out->SetGeoTransform(gt);
    if (!grid.crsWkt.empty()) {
        OGRSpatialReference srs;
        if (srs.importFromWkt(grid.crsWkt.c_str()) != OGRERR_NONE) {
            return fail("the CRS is not valid WKT");
        }
        out->SetSpatialRef(&srs);
    }
    GDALRasterBand* band = out->GetRasterBand(1);
    constexpr double kNoData = -9999.0;
    band->SetNoDataValue(kNoData);
    band->SetUnitType("m");
    // Rows south to north in memory; GeoTIFF row 0 is north. Written in bands of whole tile rows.
    constexpr int kRows = 256;
    std::vector<float> rows;
    for (int line0 = 0; line0 < grid.height; line0 += kRows) {
        const int count = std::min(kRows, grid.height - line0);
        rows.resize(static_cast<std::size_t>(count) * grid.width);
        for (int r = 0; r < count; ++r) {
            const int j = grid.height - 1 - (line0 + r);
            for (int i = 0; i < grid.width; ++i) {
                const float h = heights[static_cast<std::size_t>(j) * grid.width + i];
                rows[static_cast<std::size_t>(r) * grid.width + i] = std::isnan(h) ? static_cast<float>(kNoData) : h;
            }
        }
        if (band->RasterIO(GF_Write, 0, line0, grid.width, count, rows.data(), grid.width, count, GDT_Float32, 0, 0,
                           nullptr) != CE_None) {
            return fail("cannot write rows");
        }
    }
    CPLErrorReset();
    out.reset();
    if (CPLGetLastErrorType() == CE_Failure) {
        std::error_code ec;
        std::filesystem::remove(temporary, ec);
        return makeError(path.string(), ": cannot finish writing: ", messages.last());
    }
    std::error_code ec;
    std::filesystem::rename(temporary, path, ec);
    if (ec) {
        std::error_code removed;  // its own: the rename's reason is the one to report
        std::filesystem::remove(temporary, removed);
        return makeError(path.string(), ": cannot rename the finished file into place: ", ec.message());
    }
    return {};
}

}  // namespace terrain
