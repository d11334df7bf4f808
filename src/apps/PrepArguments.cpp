// prep's flag table and --help (PrepArguments.h).
#include "apps/PrepArguments.h"

#include "apps/CommandLine.h"
#include "core/Parse.h"
#include "quadtree/MapFormat.h"
#include "quadtree/QuantizedGrid.h"
#include "synthesis/Subdivider.h"

#include <cmath>
#include <limits>

namespace terrain {

namespace {

constexpr const char* kUsageHead = R"(usage: prep <heightfield>... [options]

Builds a terrain map (.map) from elevation: any raster GDAL reads (GeoTIFF of any sample type, SRTM .hgt,
ESRI .asc, USGS DEM, VRT, ...), PNG (8/16-bit gray), VTP .bt, Terragen .ter or raw 16-bit. Several files,
or one directory, are tiles of one mosaic: they must share CRS, resolution and grid. Geographic
(longitude/latitude) rasters are reprojected to the UTM zone of their centre, or to --srs.

)";

constexpr const char* kUsageTail = R"(
The map stores the estimated error of the detail synthesized below its static leaves (paper 3.4.1), so
the viewer refines past them, and what it was estimated for (materials, scheme, factor, roughness): the viewer warns
when its own detail_* options differ. The defaults are the viewer's defaults.
)";

/// A flag that stores its text.
template <class T>
Flag pathFlag(std::string name, std::string value, std::string help, T& target)
{
    return {std::move(name), std::move(value), std::move(help), [&target](const std::string& v) -> Status {
                target = v;
                return {};
            }};
}

/// A switch that sets `target`.
Flag switchFlag(std::string name, std::string help, bool& target)
{
    return {std::move(name), "", std::move(help), [&target](const std::string&) -> Status {
                target = true;
                return {};
            }};
}

/// A number in [lo, hi], stored in `target`; out of range: "WHAT must be in [LO, HI] UNIT, got VALUE".
template <class T>
Flag numberFlag(std::string name, std::string value, std::string help, double lo, double hi, std::string range,
                T& target)
{
    return {std::move(name), std::move(value), std::move(help),
            [&target, lo, hi, range](const std::string& text) -> Status {
                auto v = parseDouble(text);
                TERRAIN_TRY(v);
                if (!(*v >= lo && *v <= hi)) {
                    return makeError(range, ", got ", *v);
                }
                target = *v;
                return {};
            }};
}

/// A whole number that `valid` accepts, stored in `target`; otherwise `invalid(n)` says why.
Flag integerFlag(std::string name, std::string value, std::string help, const std::function<bool(long long)>& valid,
                 const std::function<Error(long long)>& invalid, int& target)
{
    return {std::move(name), std::move(value), std::move(help),
            [&target, valid, invalid](const std::string& text) -> Status {
                auto v = parseInteger(text);
                if (!v.ok()) {
                    return makeError("'", text, "' is not an integer");
                }
                if (!valid(*v)) {
                    return invalid(*v);
                }
                target = static_cast<int>(*v);
                return {};
            }};
}

Status parseClamp(const std::string& text, BuildOptions& build)
{
    const std::size_t comma = text.find(',');
    const bool pair = comma != std::string::npos;
    auto lo = parseDouble(pair ? text.substr(0, comma) : text);
    auto hi = parseDouble(pair ? text.substr(comma + 1) : std::string());
    if (!pair || !lo.ok() || !hi.ok() || !(*lo <= *hi) || !(std::abs(*lo) <= kMaxHeightMetres) ||
        !(std::abs(*hi) <= kMaxHeightMetres)) {
        return makeError("'", text, "' is not LO,HI: two heights in metres, LO <= HI, within +-", kMaxHeightMetres);
    }
    build.clampMetres = std::array<double, 2>{*lo, *hi};
    return {};
}

Status parseRawSize(const std::string& text, HeightFieldReadOptions& read)
{
    const std::size_t x = text.find('x');
    auto w = parseInteger(text.substr(0, x == std::string::npos ? 0 : x));
    auto h = parseInteger(x == std::string::npos ? "" : text.substr(x + 1));
    if (!w.ok() || !h.ok() || *w < 1 || *h < 1 || *w > (1 << 30) || *h > (1 << 30)) {
        return makeError("'", text, "' is not WIDTHxHEIGHT");
    }
    read.rawWidth = static_cast<int>(*w);
    read.rawHeight = static_cast<int>(*h);
    return {};
}

/// --nodata: a number in the file's sample type, or inf / -inf for infinite samples.
Status parseNoData(const std::string& text, HeightFieldReadOptions& read)
{
    if (text == "inf" || text == "+inf" || text == "-inf") {
        read.noData =
            text.front() == '-' ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
        return {};
    }
    auto v = parseDouble(text);
    TERRAIN_TRY(v);
    read.noData = *v;
    return {};
}

/// prep's flags, in --help order, applying to `args`; `detailFactorGiven` records --detail-factor.
CommandLine prepCommandLine(PrepArguments& args, bool& detailFactorGiven)
{
    BuildOptions& build = args.build;
    CommandLine line;
    line.unknownHint = " (see prep --help)";
    line.positional = [&args](const std::string& argument) -> Status {
        args.inputs.emplace_back(argument);
        return {};
    };
    auto& f = line.flags;
    f.push_back(pathFlag("-t", "FILE",
                         "imagery over the terrain: any RGB(A) raster GDAL reads with a CRS is aligned by its\n"
                         "coordinates (the generated colours show where it does not cover); a PNG without\n"
                         "one is stretched over the input (default: colours generated from height and slope)",
                         build.texture));
    f.push_back(pathFlag("--srs", "CRS", "projected CRS to reproject the elevation to (EPSG:32613, WKT, PROJ string)",
                         args.read.targetSrs));
    f.push_back(pathFlag("-w", "FILE.png",
                         "weight map for pruning: white keeps the full resolution, black only the root (3.2.13)",
                         build.weights));
    f.push_back(numberFlag(
        "-h", "METRES", "sample spacing, when the file gives none (default 1)", kMinSpacingMetres, kMaxSpacingMetres,
        makeError("the spacing must be in [", kMinSpacingMetres, ", ", kMaxSpacingMetres, "] metres").message,
        build.spacing));
    f.push_back(numberFlag("-v", "SCALE", "vertical scale (metres per file unit), when the file gives none (default 1)",
                           1e-9, 1e9, "the vertical scale must be in [1e-09, 1e+09] metres a unit",
                           build.verticalScale));
    f.push_back(pathFlag("-o", "FILE.map", "output (default: the input's name with the extension .map)", args.output));
    f.push_back(numberFlag("--offset", "METRES", "added to every height after -v (default 0)", -kMaxHeightMetres,
                           kMaxHeightMetres, makeError("must be within +-", kMaxHeightMetres, " metres").message,
                           build.offset));
    f.push_back(integerFlag(
        "--chunk", "N", "samples per node side, 2^k+1 (default 65)",
        [](long long n) { return n >= 3 && n <= kMaxChunkSize && isValidChunkSize(static_cast<int>(n)); },
        [](long long n) {
            return makeError("chunk size ", n, " must be 2^k+1 between 3 and ", kMaxChunkSize, " (e.g. 33, 65, 129)");
        },
        build.chunkSize));
    f.push_back(numberFlag("--max-error", "METRES", "L-infinity bound on stored heights; 0 = lossless (default 0)", 0,
                           kMaxHeightMetres, makeError("must be in [0, ", kMaxHeightMetres, "] metres").message,
                           build.maxError));
    f.push_back({"--height-codec", "C",
                 "residual: Kobbelt prediction from the parent plus residuals, lossless or within\n"
                 "--max-error (default); pifs: seed 003's fractal code of node interiors (lossy, its\n"
                 "measured error stored; in memory only, no --max-error)",
                 [&build](const std::string& text) -> Status {
                     if (text == "residual") {
                         build.heightCoding = kHeightCodingKobbeltResidual;
                     } else if (text == "pifs") {
                         build.heightCoding = kHeightCodingPifs;
                     } else {
                         return makeError("unknown codec '", text, "' (expected residual or pifs)");
                     }
                     return {};
                 }});
    f.push_back(integerFlag(
        "--texture-size", "T", "texels per node side, 2^k+1 (default: the chunk size)",
        [](long long n) {
            return n == 0 || (n >= 3 && n <= kMaxTextureSize && isPowerOfTwoPlusOne(static_cast<int>(n)));
        },
        [](long long n) {
            return makeError("texture size ", n, " must be 2^k+1 between 3 and ", kMaxTextureSize,
                             " (e.g. 65, 129, 257)");
        },
        build.textureSize));
    f.push_back(integerFlag(
        "--threads", "N", "worker threads (default: all cores)",
        [](long long n) { return n >= 1 && n <= kMaxPrepThreads; },
        [](long long n) { return makeError("thread count ", n, " must be in [1, ", kMaxPrepThreads, "]"); },
        build.threads));
    f.push_back({"--memory", "SIZE",
                 "memory prep may use, e.g. 256M, 2G (suffixes K, M, G); inputs larger than that are\n"
                 "built out of core, streamed in bands with the height grid in a scratch file next to\n"
                 "the output, giving the same map (default: half the memory available)",
                 [&build](const std::string& text) -> Status {
                     auto bytes = parseByteSize(text);
                     TERRAIN_TRY(bytes);
                     build.memoryBudget = *bytes;
                     return {};
                 }});
    f.push_back(
        switchFlag("--out-of-core", "build out of core even when the input fits --memory", build.forceOutOfCore));
    f.push_back({"--raw-size", "WxH", "size of a raw 16-bit input (required for .raw/.r16/.bin)",
                 [&args](const std::string& text) { return parseRawSize(text, args.read); }});
    f.push_back(switchFlag("--raw-signed", "raw samples are signed 16-bit (default unsigned)", args.read.rawSigned));
    f.push_back(
        switchFlag("--raw-big-endian", "raw samples are big-endian (default little-endian)", args.read.rawBigEndian));
    f.push_back({"--nodata", "V",
                 "treat the file value V as no-data (filled from neighbours), compared in the file's\n"
                 "sample type (the value gdalinfo prints works); inf or -inf for infinite samples",
                 [&args](const std::string& text) { return parseNoData(text, args.read); }});
    f.push_back({"--clamp", "LO,HI", "heights (metres, after -v and --offset) below LO become LO, above HI become HI",
                 [&build](const std::string& text) { return parseClamp(text, build); }});
    f.push_back({"--material", "FILE.mat",
                 "material the viewer's detail synthesis adds below the static leaves; repeat for a\n"
                 "set, the first is the ground (default: the viewer's default, the built-in\n"
                 "grass.mat alone)",
                 [&args](const std::string& text) -> Status {
                     args.materials.emplace_back(text);
                     return {};
                 }});
    f.push_back(switchFlag("--no-material",
                           "no material: the detail below the leaves is subdivision only (the viewer's\n"
                           "detail_add_material = false)",
                           args.noMaterial));
    f.push_back(switchFlag("--no-roughness",
                           "the detail errors assume the viewer does not continue the terrain's roughness\n"
                           "below the leaves (detail_roughness = false); the roughness is measured and\n"
                           "stored either way",
                           args.noRoughness));
    f.push_back({"--detail-scheme", "S",
                 "subdivision of the synthesized detail: kobbelt, bilinear or catmull-clark\n(default kobbelt)",
                 [&args](const std::string& text) -> Status {
                     if (!makeSubdivider(text, 3, args.detail.omega).ok()) {
                         return makeError("unknown scheme '", text, "' (expected kobbelt, bilinear or catmull-clark)");
                     }
                     args.detail.scheme = text;
                     return {};
                 }});
    f.push_back({"--detail-factor", "W", "Kobbelt's omega in [0, 2]: 0 linear, 1 Kobbelt (default 1)",
                 [&args, &detailFactorGiven](const std::string& text) -> Status {
                     auto v = parseDouble(text);
                     TERRAIN_TRY(v);
                     if (!(*v >= 0.0 && *v <= 2.0)) {
                         return makeError("omega must be in [0, 2], got ", *v);
                     }
                     args.detail.omega = *v;
                     detailFactorGiven = true;
                     return {};
                 }});
    f.push_back({"--help", "", "this text", [](const std::string&) -> Status { return {}; }});
    return line;
}

}  // namespace

Expected<PrepArguments> parsePrepArguments(const std::vector<std::string>& arguments, int defaultThreads,
                                           const std::filesystem::path& defaultMaterial)
{
    PrepArguments args;
    args.build.threads = defaultThreads;
    bool detailFactorGiven = false;
    TERRAIN_TRY(prepCommandLine(args, detailFactorGiven).parse(arguments));
    if (args.inputs.empty()) {
        return makeError("no height field given (see prep --help)");
    }
    if (args.noMaterial && !args.materials.empty()) {
        return makeError("--no-material and --material exclude each other");
    }
    if (args.materials.empty() && !args.noMaterial) {
        // The viewer's defaults (detail_material_type = 0, material_path empty): grass.mat alone.
        args.materials.push_back(defaultMaterial);
    }
    if (detailFactorGiven && args.detail.scheme != "kobbelt") {
        args.warnings.push_back("--detail-factor has no effect with --detail-scheme " + args.detail.scheme +
                                " (Kobbelt's scheme only)");
    }
    return args;
}

std::string prepUsage()
{
    PrepArguments args;
    bool detailFactorGiven = false;
    return kUsageHead + prepCommandLine(args, detailFactorGiven).help() + kUsageTail;
}

}  // namespace terrain
