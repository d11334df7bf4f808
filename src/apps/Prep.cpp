// prep: height field -> .map (paper 4.4.1). Argument parsing and reporting only; the work is buildMap().
#include "apps/DataDirectories.h"
#include "core/Memory.h"
#include "core/OutputGuard.h"
#include "core/ParallelFor.h"
#include "core/Parse.h"
#include "heightfield/GdalRaster.h"
#include "heightfield/HeightFieldIo.h"
#include "quadtree/QuadtreeBuilder.h"
#include "quadtree/QuantizedGrid.h"
#include "synthesis/DetailErrorModel.h"
#include "synthesis/DetailRecipeSetup.h"
#include "synthesis/DetailSynthesizer.h"

#include <unistd.h>
#include <array>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace {

using namespace terrain;

constexpr const char* kUsage = R"(usage: prep <heightfield>... [options]

Builds a terrain map (.map) from elevation: any raster GDAL reads (GeoTIFF of any sample type, SRTM .hgt,
ESRI .asc, USGS DEM, VRT, ...), PNG (8/16-bit gray), VTP .bt, Terragen .ter or raw 16-bit. Several files,
or one directory, are tiles of one mosaic: they must share CRS, resolution and grid. Geographic
(longitude/latitude) rasters are reprojected to the UTM zone of their centre, or to --srs.

  -t FILE              imagery over the terrain: any RGB(A) raster GDAL reads with a CRS is aligned by its
                       coordinates (the generated colours show where it does not cover); a PNG without
                       one is stretched over the input (default: colours generated from height and slope)
  --srs CRS            projected CRS to reproject the elevation to (EPSG:32613, WKT, PROJ string)
  -w FILE.png          weight map for pruning: white keeps the full resolution, black only the root (3.2.13)
  -h METRES            sample spacing, when the file gives none (default 1)
  -v SCALE             vertical scale (metres per file unit), when the file gives none (default 1)
  -o FILE.map          output (default: the input's name with the extension .map)
  --offset METRES      added to every height after -v (default 0)
  --chunk N            samples per node side, 2^k+1 (default 65)
  --max-error METRES   L-infinity bound on stored heights; 0 = lossless (default 0)
  --height-codec C     residual: Kobbelt prediction from the parent plus residuals, lossless or within
                       --max-error (default); pifs: seed 003's fractal code of node interiors (lossy, its
                       measured error stored; in memory only, no --max-error)
  --texture-size T     texels per node side, 2^k+1 (default: the chunk size)
  --threads N          worker threads (default: all cores)
  --memory SIZE        memory prep may use, e.g. 256M, 2G (suffixes K, M, G); inputs larger than that are
                       built out of core, streamed in bands with the height grid in a scratch file next to
                       the output, giving the same map (default: half the memory available)
  --out-of-core        build out of core even when the input fits --memory
  --raw-size WxH       size of a raw 16-bit input (required for .raw/.r16/.bin)
  --raw-signed         raw samples are signed 16-bit (default unsigned)
  --raw-big-endian     raw samples are big-endian (default little-endian)
  --nodata V           treat the file value V as no-data (filled from neighbours), compared in the file's
                       sample type (the value gdalinfo prints works); inf or -inf for infinite samples
  --clamp LO,HI        heights (metres, after -v and --offset) below LO become LO, above HI become HI
  --material FILE.mat  material the viewer's detail synthesis adds below the static leaves; repeat for a
                       set, the first is the ground (default: the viewer's default, the built-in
                       grass.mat alone)
  --no-material        no material: the detail below the leaves is subdivision only (the viewer's
                       detail_add_material = false)
  --no-roughness       the detail errors assume the viewer does not continue the terrain's roughness
                       below the leaves (detail_roughness = false); the roughness is measured and
                       stored either way
  --detail-scheme S    subdivision of the synthesized detail: kobbelt, bilinear or catmull-clark
                       (default kobbelt)
  --detail-factor W    Kobbelt's omega in [0, 2]: 0 linear, 1 Kobbelt (default 1)
  --help               this text

The map stores the estimated error of the detail synthesized below its static leaves (paper 3.4.1), so
the viewer refines past them, and what it was estimated for (materials, scheme, factor, roughness): the viewer warns
when its own detail_* options differ. The defaults are the viewer's defaults.
)";

struct Arguments {
    std::vector<std::filesystem::path> inputs;
    std::optional<std::filesystem::path> output;
    BuildOptions build;
    HeightFieldReadOptions read;
    DetailSettings detail;
    bool detailFactorGiven = false;
    std::vector<std::string> warnings;             ///< about options that have no effect
    std::vector<std::filesystem::path> materials;  ///< empty: the viewer's default (built-in grass.mat)
    bool noMaterial = false;                       ///< --no-material
    bool noRoughness = false;                      ///< --no-roughness
};

Expected<Arguments> parseArguments(int argc, char** argv)
{
    Arguments args;
    args.build.threads = defaultThreadCount();
    std::vector<std::string> positional;
    for (int i = 1; i < argc; ++i) {
        std::string arg = argv[i];
        auto value = [&]() -> Expected<std::string> {
            if (i + 1 >= argc) {
                return makeError(arg, " needs a value");
            }
            return std::string(argv[++i]);
        };
        auto number = [&]() -> Expected<double> {
            auto text = value();
            TERRAIN_TRY(text);
            if (arg == "--nodata" && (*text == "inf" || *text == "+inf" || *text == "-inf")) {
                // Infinite samples marking missing data.
                return text->front() == '-' ? -std::numeric_limits<double>::infinity()
                                            : std::numeric_limits<double>::infinity();
            }
            auto parsed = parseDouble(*text);
            if (!parsed.ok()) {
                return makeError(arg, ": ", parsed.error().message);
            }
            return parsed;
        };
        auto integer = [&]() -> Expected<int> {
            auto text = value();
            TERRAIN_TRY(text);
            auto parsed = parseInteger(*text);
            if (!parsed.ok() || *parsed < -(1 << 30) || *parsed > (1 << 30)) {
                return makeError(arg, ": '", *text, "' is not an integer");
            }
            return static_cast<int>(*parsed);
        };
        if (arg == "-t" || arg == "-w" || arg == "-o") {
            auto path = value();
            TERRAIN_TRY(path);
            (arg == "-t" ? args.build.texture : arg == "-w" ? args.build.weights : args.output) = *path;
        } else if (arg == "--srs") {
            auto text = value();
            TERRAIN_TRY(text);
            args.read.targetSrs = *text;
        } else if (arg == "--height-codec") {
            auto text = value();
            TERRAIN_TRY(text);
            if (*text == "residual") {
                args.build.heightCoding = kHeightCodingKobbeltResidual;
            } else if (*text == "pifs") {
                args.build.heightCoding = kHeightCodingPifs;
            } else {
                return makeError("--height-codec: unknown codec '", *text, "' (expected residual or pifs)");
            }
        } else if (arg == "--material" || arg == "--detail-scheme") {
            auto text = value();
            TERRAIN_TRY(text);
            if (arg == "--material") {
                args.materials.push_back(*text);
            } else if (!makeSubdivider(*text, 3, args.detail.omega).ok()) {
                return makeError("--detail-scheme: unknown scheme '", *text,
                                 "' (expected kobbelt, bilinear or catmull-clark)");
            } else {
                args.detail.scheme = *text;
            }
        } else if (arg == "--detail-factor") {
            auto v = number();
            TERRAIN_TRY(v);
            if (!(*v >= 0.0 && *v <= 2.0)) {
                return makeError("--detail-factor: omega must be in [0, 2], got ", *v);
            }
            args.detail.omega = *v;
            args.detailFactorGiven = true;
        } else if (arg == "-h" || arg == "-v" || arg == "--offset" || arg == "--max-error" || arg == "--nodata") {
            auto v = number();
            TERRAIN_TRY(v);
            if (arg == "-h") {
                if (!(*v >= kMinSpacingMetres && *v <= kMaxSpacingMetres)) {
                    return makeError("-h: the spacing must be in [", kMinSpacingMetres, ", ", kMaxSpacingMetres,
                                     "] metres, got ", *v);
                }
                args.build.spacing = *v;
            } else if (arg == "-v") {
                if (!(*v >= 1e-9 && *v <= 1e9)) {
                    return makeError("-v: the vertical scale must be in [1e-09, 1e+09] metres a unit, got ", *v);
                }
                args.build.verticalScale = *v;
            } else if (arg == "--offset") {
                if (!(std::abs(*v) <= kMaxHeightMetres)) {
                    return makeError("--offset: must be within +-", kMaxHeightMetres, " metres, got ", *v);
                }
                args.build.offset = *v;
            } else if (arg == "--max-error") {
                if (!(*v >= 0 && *v <= kMaxHeightMetres)) {
                    return makeError("--max-error: must be in [0, ", kMaxHeightMetres, "] metres, got ", *v);
                }
                args.build.maxError = *v;
            } else {
                args.read.noData = *v;
            }
        } else if (arg == "--chunk" || arg == "--texture-size" || arg == "--threads") {
            auto v = integer();
            TERRAIN_TRY(v);
            (arg == "--chunk"          ? args.build.chunkSize
             : arg == "--texture-size" ? args.build.textureSize
                                       : args.build.threads) = *v;
        } else if (arg == "--clamp") {
            auto text = value();
            TERRAIN_TRY(text);
            const std::size_t comma = text->find(',');
            const bool pair = comma != std::string::npos;
            auto lo = parseDouble(pair ? text->substr(0, comma) : *text);
            auto hi = parseDouble(pair ? text->substr(comma + 1) : std::string());
            if (!pair || !lo.ok() || !hi.ok() || !(*lo <= *hi) || !(std::abs(*lo) <= kMaxHeightMetres) ||
                !(std::abs(*hi) <= kMaxHeightMetres)) {
                return makeError("--clamp: '", *text, "' is not LO,HI: two heights in metres, LO <= HI, within +-",
                                 kMaxHeightMetres);
            }
            args.build.clampMetres = std::array<double, 2>{*lo, *hi};
        } else if (arg == "--memory") {
            auto text = value();
            TERRAIN_TRY(text);
            auto bytes = parseByteSize(*text);
            if (!bytes.ok()) {
                return makeError("--memory: ", bytes.error().message);
            }
            args.build.memoryBudget = *bytes;
        } else if (arg == "--raw-size") {
            auto text = value();
            TERRAIN_TRY(text);
            auto x = text->find('x');
            auto w = parseInteger(text->substr(0, x == std::string::npos ? 0 : x));
            auto h = parseInteger(x == std::string::npos ? "" : text->substr(x + 1));
            if (!w.ok() || !h.ok() || *w < 1 || *h < 1 || *w > (1 << 30) || *h > (1 << 30)) {
                return makeError("--raw-size: '", *text, "' is not WIDTHxHEIGHT");
            }
            args.read.rawWidth = static_cast<int>(*w);
            args.read.rawHeight = static_cast<int>(*h);
        } else if (arg == "--out-of-core") {
            args.build.forceOutOfCore = true;
        } else if (arg == "--no-material") {
            args.noMaterial = true;
        } else if (arg == "--no-roughness") {
            args.noRoughness = true;
        } else if (arg == "--raw-signed") {
            args.read.rawSigned = true;
        } else if (arg == "--raw-big-endian") {
            args.read.rawBigEndian = true;
        } else if (!arg.empty() && arg[0] == '-' && arg != "-") {
            return makeError("unknown option '", arg, "' (see prep --help)");
        } else {
            positional.push_back(arg);
        }
    }
    if (positional.empty()) {
        return makeError("no height field given (see prep --help)");
    }
    args.inputs.assign(positional.begin(), positional.end());
    if (args.noMaterial && !args.materials.empty()) {
        return makeError("--no-material and --material exclude each other");
    }
    if (args.materials.empty() && !args.noMaterial) {
        // The viewer's defaults (detail_material_type = 0, material_path empty): grass.mat alone.
        args.materials.push_back(programDataDirectory("materials", TERRAIN_MATERIALS_DIR) / "grass.mat");
    }
    if (args.detailFactorGiven && args.detail.scheme != "kobbelt") {
        args.warnings.push_back("--detail-factor has no effect with --detail-scheme " + args.detail.scheme +
                                " (Kobbelt's scheme only)");
    }
    return args;
}

/// The synthesizer the viewer will use below the static leaves, with the materials loaded as the viewer
/// loads them (errors name the file and line; warnings go to `warnings`), and its recipe for the map. Null
/// when the chunk size is not 2^k + 1 (buildMap reports it).
Expected<std::unique_ptr<const DetailSynthesizer>> makeSynthesizer(Arguments& args, std::vector<std::string>& warnings)
{
    DetailSettings settings = args.detail;
    if (!args.materials.empty()) {
        auto set = loadDetailMaterials(args.materials, warnings);
        TERRAIN_TRY(set);
        settings.materials = std::move(set).value();
    }
    auto recipe = makeDetailRecipe(settings, args.materials);
    TERRAIN_TRY(recipe);
    recipe->roughness = !args.noRoughness;
    args.build.detailRecipe = std::move(recipe).value();
    if (!isValidChunkSize(args.build.chunkSize)) {
        return std::unique_ptr<const DetailSynthesizer>();
    }
    return DetailSynthesizer::create(args.build.chunkSize, std::move(settings));
}

class ProgressBar {
public:
    explicit ProgressBar(bool enabled) : mEnabled(enabled) {}
    void update(double fraction, std::string_view stage)
    {
        if (!mEnabled) {
            return;
        }
        std::lock_guard lock(mMutex);
        constexpr int kWidth = 40;
        int filled = static_cast<int>(fraction * kWidth + 0.5);
        std::fprintf(stderr, "\r[%.*s%*s] %3d%% %-24.*s", filled, "########################################",
                     kWidth - filled, "", static_cast<int>(fraction * 100 + 0.5), static_cast<int>(stage.size()),
                     stage.data());
        std::fflush(stderr);
        mShown = true;
    }
    void finish()
    {
        if (mShown) {
            std::fprintf(stderr, "\r%*s\r", 72, "");
        }
    }

private:
    bool mEnabled;
    bool mShown = false;
    std::mutex mMutex;
};

}  // namespace

int main(int argc, char** argv)
{
    // Over a file size limit (ulimit -f) write() fails with EFBIG once SIGXFSZ is ignored; by default the
    // signal would kill prep with a core dump instead of the error naming the output.
    std::signal(SIGXFSZ, SIG_IGN);
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--help") == 0) {
            std::fputs(kUsage, stdout);
            return 0;
        }
    }
    auto args = parseArguments(argc, argv);
    if (!args.ok()) {
        std::fprintf(stderr, "prep: %s\n", args.error().message.c_str());
        return 2;
    }
    if (args->inputs.size() > 1 && !args->output) {
        std::fprintf(stderr, "prep: a mosaic of several inputs needs -o FILE.map\n");
        return 2;
    }
    std::filesystem::path output = args->output ? *args->output : args->inputs.front();
    if (!args->output) {
        // A directory of tiles becomes DIR.map beside it.
        output = std::filesystem::path(output.string().substr(0, output.string().find_last_not_of('/') + 1));
        output.replace_extension(".map");
    }
    std::vector<InputFile> inputs = {{"texture (-t)", args->build.texture.value_or(std::filesystem::path())},
                                     {"weight map (-w)", args->build.weights.value_or(std::filesystem::path())}};
    for (const auto& material : args->materials) {
        inputs.push_back({"material", material});
    }
    for (const auto& input : args->inputs) {
        inputs.push_back({"height field", input});
    }
    if (auto refused = refuseInputAsOutput("map", output, inputs); !refused.ok()) {
        std::fprintf(stderr, "prep: %s\n", refused.error().message.c_str());
        return 2;
    }
    std::vector<std::string> warnings = args->warnings;
    auto synthesizer = makeSynthesizer(*args, warnings);
    for (const auto& warning : warnings) {
        std::fprintf(stderr, "prep: warning: %s\n", warning.c_str());
    }
    if (!synthesizer.ok()) {
        std::fprintf(stderr, "prep: %s\n", synthesizer.error().message.c_str());
        return 1;
    }
    if (*synthesizer) {
        args->build.leafDetailError = leafDetailErrorFunction(**synthesizer, !args->noRoughness);
        args->build.detailDisplacementRangeFor = detailDisplacementRangeFunction(**synthesizer);
    }
    configureGdalReading(effectiveMemoryBudget(args->build), args->build.threads);
    auto source = openHeightRows(args->inputs, args->read);
    if (!source.ok()) {
        std::fprintf(stderr, "prep: %s\n", source.error().message.c_str());
        return 1;
    }
    const HeightField& field = (*source)->info();
    for (const auto& note : field.notes) {
        std::fprintf(stderr, "prep: note: %s\n", note.c_str());
    }

    ProgressBar bar(::isatty(STDERR_FILENO) != 0);
    args->build.progress = [&](double fraction, std::string_view stage) { bar.update(fraction, stage); };
    args->build.warn = [&](std::string_view message) {
        bar.finish();
        std::fprintf(stderr, "prep: warning: %.*s\n", static_cast<int>(message.size()), message.data());
    };
    const std::string description = field.description;
    auto report = buildMap(**source, args->build, output);
    bar.finish();
    if (!report.ok()) {
        std::fprintf(stderr, "prep: %s: %s\n", args->inputs.front().c_str(), report.error().message.c_str());
        return 1;
    }
    const MapHeader& h = report->header;
    const double inputSamples = static_cast<double>(report->inputWidth) * report->inputHeight;
    std::printf("prep: wrote %s\n", output.c_str());
    std::printf("  input     %s: %d x %d samples, spacing %g m\n", description.c_str(), report->inputWidth,
                report->inputHeight, h.sampleSpacing);
    if (!h.crsWkt.empty()) {
        std::printf("            CRS %s, origin %.3f, %.3f m\n", describeCrs(h.crsWkt).c_str(), h.originX, h.originY);
    }
    if (report->imageryCoverage) {
        std::printf("            imagery %s covers %.1f%% of the terrain\n", args->build.texture->c_str(),
                    100.0 * *report->imageryCoverage);
    }
    if (h.noDataFilled > 0) {
        std::printf("            %llu no-data samples filled from their neighbours\n",
                    static_cast<unsigned long long>(h.noDataFilled));
    }
    std::printf("  quadtree  %u levels, %llu nodes of %u x %u samples (grid %llu x %llu), textures %u x %u\n", h.levels,
                static_cast<unsigned long long>(report->nodes), h.chunkSize, h.chunkSize,
                static_cast<unsigned long long>(h.gridSize()), static_cast<unsigned long long>(h.gridSize()),
                h.textureSize, h.textureSize);
    std::printf("  heights   step %g m, %s\n", h.heightStep, describeHeightCoding(h).c_str());
    std::printf("  file      %s: heights %s (%.2f bits per input sample, %.2f per stored sample),\n",
                formatBytes(report->fileBytes).c_str(), formatBytes(report->heightBytes).c_str(),
                8.0 * static_cast<double>(report->heightBytes) / inputSamples,
                8.0 * static_cast<double>(report->heightBytes) / static_cast<double>(report->storedSamples));
    std::printf("            textures %s (%.2f bits per input sample)\n", formatBytes(report->textureBytes).c_str(),
                8.0 * static_cast<double>(report->textureBytes) / inputSamples);
    std::printf(
        "  detail    leaf error max %.3f m, mean %.3f m over %llu leaves (3.4.1, the synthesis model: "
        "synthesis/DetailErrorModel.h)\n",
        static_cast<double>(report->maxLeafDetailError), report->meanLeafDetailError,
        static_cast<unsigned long long>(report->leaves));
    std::printf("            for %s; %.2f s estimating (summed over threads)\n",
                h.detailRecipe ? h.detailRecipe->describe().c_str() : "no recipe", report->leafDetailSeconds);
    std::printf("  time      %.2f s, %.1f million input samples per second (%d threads)\n", report->seconds,
                inputSamples / report->seconds / 1e6, report->threads);
    std::printf("  memory    peak %s, %s (budget %s)\n", formatBytes(peakResidentBytes()).c_str(),
                report->outOfCore ? "out of core" : "in memory", formatBytes(report->memoryBudget).c_str());
    return 0;
}
