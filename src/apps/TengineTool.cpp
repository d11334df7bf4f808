// tengine-tool: inspect (info), check (verify) and query (height) terrain maps.
#include "apps/CommandLine.h"
#include "apps/DataDirectories.h"
#include "apps/DetailSetup.h"
#include "apps/ErrorCommand.h"
#include "core/AtomicFile.h"
#include "core/Memory.h"
#include "core/OutputGuard.h"
#include "core/Parse.h"
#include "heightfield/GdalRaster.h"
#include "heightfield/Image.h"
#include "lod/CameraPath.h"
#include "lod/HeightQuery.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "quadtree/MapFile.h"
#include "quadtree/MapVerifier.h"
#include "quadtree/QuadtreeBuilder.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

namespace {

using namespace terrain;

constexpr const char* kUsage = R"(usage: tengine-tool COMMAND FILE.map [arguments]

  info FILE.map           header, levels, nodes and errors per level, storage
  verify FILE.map         check structure, every checksum, bounds and errors; exit 1 on any problem
  height FILE.map X Y [--depth D [--material M.mat]... [--no-material]]
                          terrain height (metres) at world position X, Y (metres); exit 1 outside.
                          Without --depth: the finest static level. With it: the rendered surface at
                          quadtree level D, synthesized below the static leaves exactly as tengine draws
                          it with its default detail options (or these materials, blended in order)
  height FILE.map --lonlat LON LAT [same options]
                          the same at WGS 84 longitude, latitude (degrees), for maps that record a CRS
  height FILE.map --points FILE|- [same options]
                          the same for many points: one "X Y" a line in (blank lines and # comments
                          skipped; - reads standard input), one height a line out, in order; exit 1 at
                          the first bad line or point outside, naming its line
  export FILE.map OUT.tif --region X0,Y0,X1,Y1 --spacing S [--depth D] [--material M.mat]... [--no-material]
                          write the surface tengine draws (exactly what height --depth returns) on a grid
                          of S metres from X0,Y0 (world metres, the south-west sample) to X1,Y1 as a
                          float32 GeoTIFF in the map's CRS (no-data -9999 outside the terrain). The depth
                          defaults to the coarsest level at least as fine as S
  texture FILE.map LEVEL/X/Y OUT.png
                          write a static node's texture as a PNG (north up)
  select FILE.map --camera X,Y,Z,YAW,PITCH [--tau 2] [--size 1280x720] [--fov 60]
                          the nodes the viewer would draw from that camera (degrees; yaw 0 = north),
                          after loading everything they need
  stream FILE.map --path FILE.path [--cache 512] [--queue 8] [--workers 1] [--fps 30] [--tau 2]
                 [--size 1280x720] [--fov 60] [--fast]
                          replay a camera path through the selector, cache and loader in real time (or
                          as fast as possible) and print loading and selection figures

  error FILE.map [CONFIG.cfg...] (--camera X,Y,Z,YAW,PITCH | --path FILE.path) [--tau T] [--size WxH]
               [--fov DEG] [--fps F] [--set key=value]... [--levels] [--oracle[=B]]
                          measure the screen-space error the viewer draws: its options (configs and --set,
                          applied in order), materials and morph, every frame loaded to completion, against
                          the tree refined until a level changes the surface by < tau/8 px (static-only
                          maps: the input data); one line per frame, then the summary. --levels: bounds
                          against measured errors per level; --oracle: the fewest whole nodes within tau by
                          their measured errors, per frame (the floor for chunked LOD; =B: B x B blocks'
                          metres projected as the selection projects bounds)

Options:
)";

/// The flags every command takes: --reader.
CommandLine globalCommandLine(ReaderKind& reader)
{
    CommandLine line;
    line.flags.push_back({"--reader", "KIND", "stream or memory_mapped: how the map is read (default stream)",
                          [&reader](const std::string& value) -> Status {
                              auto kind = parseReaderKind(value);
                              TERRAIN_TRY(kind);
                              reader = *kind;
                              return {};
                          }});
    line.flags.push_back({"--help", "", "this text (also -h)", [](const std::string&) -> Status { return {}; }});
    return line;
}

/// The --help text: the commands, then the flags of globalCommandLine.
std::string usage()
{
    ReaderKind reader = ReaderKind::Stream;
    return kUsage + globalCommandLine(reader).help();
}

/// World coordinates export takes (metres): beyond what any map spans (2^24 samples of at most 1e6 m).
constexpr double kMaxWorldMetres = 1e15;

int fail(const std::string& message)
{
    std::fprintf(stderr, "tengine-tool: %s\n", message.c_str());
    return 1;
}

int info(const MapFile& map)
{
    const MapHeader& h = map.header();
    std::printf("map        %s\n", map.name().c_str());
    std::printf("source     %s\n", h.source.empty() ? "(unknown)" : h.source.c_str());
    std::printf("version    %u\n", h.version);
    std::printf("grid       %llu x %llu samples, spacing %g m, origin (%g, %g) m\n",
                static_cast<unsigned long long>(h.gridSize()), static_cast<unsigned long long>(h.gridSize()),
                h.sampleSpacing, h.originX, h.originY);
    if (h.crsWkt.empty()) {
        std::printf("crs        none recorded (world coordinates are the input's own metres)\n");
    } else {
        std::printf("crs        %s, %g m per unit\n", describeCrs(h.crsWkt).c_str(), h.crsUnitMetres);
        if (auto geo = GeoConverter::create(h.crsWkt, h.crsUnitMetres); geo.ok()) {
            const double cx = h.originX + (h.validX0 + (h.validWidth - 1) / 2.0) * h.sampleSpacing;
            const double cy = h.originY + (h.validY0 + (h.validHeight - 1) / 2.0) * h.sampleSpacing;
            if (auto ll = geo->toLonLat(cx, cy); ll.ok()) {
                std::printf("           centre at longitude %.6f, latitude %.6f\n", ll->first, ll->second);
            }
        }
    }
    std::printf("valid      %u x %u samples at (%u, %u); %llu no-data samples filled\n", h.validWidth, h.validHeight,
                h.validX0, h.validY0, static_cast<unsigned long long>(h.noDataFilled));
    std::printf("chunks     %u x %u samples (+%d border), textures %u x %u\n", h.chunkSize, h.chunkSize, kBorder,
                h.textureSize, h.textureSize);
    std::printf("heights    metres = %.9g + %.9g * code; %s\n", h.heightOffset, h.heightStep,
                describeHeightCoding(h).c_str());
    std::printf("levels     %u\n", h.levels);
    // What detail_delta_c was estimated for (version 3): the viewer warns when its settings differ.
    std::printf("detail     %s\n", h.detailRecipe ? ("errors estimated for " + h.detailRecipe->describe()).c_str()
                                   : h.hasDetailErrors() ? "errors below the leaves, settings not recorded"
                                                         : "no errors below the leaves (version 1)");
    // The leaves' roughness laws (version 5), which detail_roughness continues below them.
    if (h.roughness) {
        std::vector<double> amplitudes, exponents;
        for (const RoughnessLaw& law : h.roughness->laws) {
            amplitudes.push_back(law.amplitude);
            exponents.push_back(law.exponent);
        }
        std::sort(amplitudes.begin(), amplitudes.end());
        std::sort(exponents.begin(), exponents.end());
        const std::size_t mid = amplitudes.size() / 2;
        std::printf(
            "roughness  D(r) = A (r / %g m)^H over %zu leaves: A %.3g / %.3g / %.3g m, H %.2f / %.2f / %.2f "
            "(min / median / max)\n",
            h.sampleSpacing, amplitudes.size(), amplitudes.front(), amplitudes[mid], amplitudes.back(),
            exponents.front(), exponents[mid], exponents.back());
    } else {
        std::printf("roughness  not measured (%s)\n", h.version < 5 ? "made before format 5" : "prep left it out");
    }

    struct LevelStats {
        std::uint64_t nodes = 0, heightBytes = 0, textureBytes = 0;
        float minDeltaC = 1e30f, maxDeltaC = 0.0f;
        float maxDetailDeltaC = 0.0f;
    };
    std::vector<LevelStats> levels(h.levels);
    std::uint64_t heightBytes = 0, textureBytes = 0;
    for (const auto& e : map.directory()) {
        auto& l = levels[static_cast<std::size_t>(e.id.level)];
        ++l.nodes;
        l.heightBytes += e.heightBytes;
        l.textureBytes += e.textureBytes;
        l.minDeltaC = std::min(l.minDeltaC, e.deltaC);
        l.maxDeltaC = std::max(l.maxDeltaC, e.deltaC);
        l.maxDetailDeltaC = std::max(l.maxDetailDeltaC, e.detailDeltaC);
        heightBytes += e.heightBytes;
        textureBytes += e.textureBytes;
    }
    // detail_delta_c (version 2): the nested error with the detail synthesized below the leaves (3.4.1).
    std::printf("\nlevel  nodes  spacing(m)  delta_c min..max (m)   detail max (m)  height bytes  texture bytes\n");
    for (std::size_t i = 0; i < levels.size(); ++i) {
        const auto& l = levels[i];
        char detail[32] = "     -";
        if (h.hasDetailErrors()) {
            std::snprintf(detail, sizeof detail, "%14.3f", l.maxDetailDeltaC);
        }
        std::printf("%5zu %6llu %11.3f  %9.3f .. %-9.3f %14s %13llu %14llu\n", i,
                    static_cast<unsigned long long>(l.nodes), h.spacingAt(static_cast<int>(i)),
                    l.nodes ? l.minDeltaC : 0.0f, l.maxDeltaC, detail, static_cast<unsigned long long>(l.heightBytes),
                    static_cast<unsigned long long>(l.textureBytes));
    }
    const double inputSamples = static_cast<double>(h.validWidth) * h.validHeight;
    const double storedSamples = static_cast<double>(map.directory().size() * map.window().sampleCount());
    std::printf("\nnodes      %zu\n", map.directory().size());
    std::printf("heights    %s: %.3f bits per input sample, %.3f bits per stored sample (borders included)\n",
                formatBytes(heightBytes).c_str(), 8.0 * static_cast<double>(heightBytes) / inputSamples,
                8.0 * static_cast<double>(heightBytes) / storedSamples);
    std::printf("textures   %s: %.3f bits per input sample\n", formatBytes(textureBytes).c_str(),
                8.0 * static_cast<double>(textureBytes) / inputSamples);
    std::printf("file       %s\n", formatBytes(h.directoryOffset + h.directoryBytes).c_str());
    return 0;
}

int verify(const MapFile& map)
{
    auto problems = verifyMap(map);
    if (!problems.empty()) {
        for (const auto& p : problems) {
            std::fprintf(stderr, "%s\n", p.c_str());
        }
        std::fprintf(stderr, "tengine-tool: %s: %zu problem%s found\n", map.name().c_str(), problems.size(),
                     problems.size() == 1 ? "" : "s");
        return 1;
    }
    std::printf("%s: OK (%zu nodes, all checksums, bounds and errors verified)\n", map.name().c_str(),
                map.directory().size());
    return 0;
}

int texture(const MapFile& map, const std::string& node, const std::string& output)
{
    // LEVEL/X/Y, each a whole number, 0 <= X, Y < 2^LEVEL.
    std::array<long long, 3> parts{};
    std::size_t at = 0;
    bool parsed = true;
    for (std::size_t k = 0; k < 3 && parsed; ++k) {
        const std::size_t slash = k < 2 ? node.find('/', at) : node.size();
        parsed = slash != std::string::npos;
        if (parsed) {
            auto v = parseInteger(node.substr(at, slash - at));
            parsed = v.ok();
            parts[k] = parsed ? *v : 0;
            at = slash + 1;
        }
    }
    if (!parsed) {
        return fail("texture: '" + node + "' is not a node LEVEL/X/Y (whole numbers)");
    }
    if (parts[0] < 0 || parts[0] > NodeId::kMaxLevel) {
        return fail("texture: node '" + node + "': the level must be in [0, " + std::to_string(NodeId::kMaxLevel) +
                    "]");
    }
    const long long side = 1LL << parts[0];
    if (parts[1] < 0 || parts[1] >= side || parts[2] < 0 || parts[2] >= side) {
        return fail("texture: node '" + node + "': X and Y must be in [0, " + std::to_string(side - 1) + "] at level " +
                    std::to_string(parts[0]));
    }
    NodeId id;
    id.level = static_cast<int>(parts[0]);
    id.x = static_cast<std::uint32_t>(parts[1]);
    id.y = static_cast<std::uint32_t>(parts[2]);
    auto loaded = map.loadPath(id);
    if (!loaded.ok()) {
        return fail(loaded.error().message);
    }
    const int size = static_cast<int>(map.header().textureSize);
    Image image{size, size, 3, std::vector<std::uint8_t>(loaded->texture.size())};
    for (int y = 0; y < size; ++y) {  // node rows run south to north, image rows north to south
        std::copy_n(&loaded->texture[static_cast<std::size_t>(size - 1 - y) * size * 3],
                    static_cast<std::size_t>(size) * 3, image.pixel(0, y));
    }
    auto written = writePngImage(output, image);
    if (!written.ok()) {
        return fail(written.error().message);
    }
    std::printf("%s: node %s texture written to %s\n", map.name().c_str(), id.toString().c_str(), output.c_str());
    return 0;
}

/// Options of select and stream: "--name value" pairs after the map.
struct ViewOptions {
    Camera camera;
    double tau = 2.0;
    std::string path;
    StreamerOptions streamer;
    double fps = 30.0;
    bool fast = false;
};

Expected<ViewOptions> parseViewOptions(const std::vector<std::string>& args, std::size_t first, bool wantPath)
{
    ViewOptions view;
    bool haveCamera = false;
    auto degrees = [](double d) { return d * std::numbers::pi / 180.0; };
    auto number = [](double& target, double lo, double hi, std::string_view unit) {
        return [&target, lo, hi, unit](const std::string& value) -> Status {
            auto v = numberIn(value, lo, hi, unit);
            TERRAIN_TRY(v);
            target = *v;
            return {};
        };
    };
    auto count = [](auto& target, long long lo) {
        return [&target, lo](const std::string& value) -> Status {
            auto v = wholeNumberIn(value, lo, 1 << 24);
            TERRAIN_TRY(v);
            target = static_cast<std::remove_reference_t<decltype(target)>>(*v);
            return {};
        };
    };
    CommandLine line;
    line.flags = {
        {"--camera", "X,Y,Z,YAW,PITCH", "the camera (metres and degrees; yaw 0 = north)",
         [&](const std::string& value) -> Status {
             TERRAIN_TRY(parseCameraArgument(value, view.camera));
             haveCamera = true;
             return {};
         }},
        {"--tau", "T", "the screen-space error allowed (pixels)", number(view.tau, 0.01, 1000, "pixels")},
        {"--fov", "DEG", "vertical field of view (degrees)",
         [&](const std::string& value) -> Status {
             auto v = numberIn(value, 1, 179, "degrees");
             TERRAIN_TRY(v);
             view.camera.verticalFov = degrees(*v);
             return {};
         }},
        {"--fps", "F", "frames per second of the replay", number(view.fps, 1, 1000, "frames per second")},
        {"--cache", "N", "nodes the cache holds", count(view.streamer.cacheSize, 1)},
        {"--queue", "N", "node groups waiting to load", count(view.streamer.queueLimit, 1)},
        {"--workers", "N", "loader threads (0: on the selecting thread)", count(view.streamer.workers, 0)},
        {"--size", "WxH", "the viewport (pixels)",
         [&](const std::string& value) -> Status {
             auto size = sizeIn(value, 1, 16384);
             TERRAIN_TRY(size);
             view.camera.viewportWidth = size->first;
             view.camera.viewportHeight = size->second;
             return {};
         }},
        {"--fast", "", "replay as fast as possible",
         [&](const std::string&) -> Status {
             view.fast = true;
             return {};
         }},
    };
    if (wantPath) {
        line.flags.push_back({"--path", "FILE.path", "the camera path", [&](const std::string& value) -> Status {
                                  view.path = value;
                                  return {};
                              }});
    }
    TERRAIN_TRY(line.parse(std::span(args).subspan(first)));
    if (!wantPath && !haveCamera) {
        return makeError("select needs --camera X,Y,Z,YAW,PITCH");
    }
    if (wantPath && view.path.empty()) {
        return makeError("stream needs --path FILE.path");
    }
    return view;
}

std::uint64_t trianglesPerNode(const MapHeader& h)
{
    return static_cast<std::uint64_t>(trianglesPerChunk(static_cast<int>(h.chunkSize)));
}

int select(const MapFile& map, const ViewOptions& view)
{
    TerrainNodeSource source(map, {});
    StreamerOptions options = view.streamer;
    options.cacheSize = std::max<std::size_t>(options.cacheSize, map.directory().size());
    auto streamer = TerrainStreamer::create(source, extentOf(map.header()), options);
    if (!streamer.ok()) {
        return fail(streamer.error().message);
    }
    std::string loadError;
    (*streamer)->onLoadError([&](const std::string& message) { loadError = message; });
    // Select, load what is missing, repeat until the selection wants nothing more.
    (*streamer)->settle(Settle::Complete, view.camera, view.tau);
    if (!loadError.empty()) {
        std::fprintf(stderr, "tengine-tool: %s\n", loadError.c_str());
    }
    const auto& selection = (*streamer)->selection();
    std::printf("level      x      y  morph  distance(m)\n");
    for (const auto& node : selection.nodes) {
        std::printf("%5d %6u %6u  %5.3f  %11.1f\n", node.id.level, node.id.x, node.id.y, node.morph, node.distance);
    }
    std::printf("nodes %zu, triangles %llu (with skirts), culled %zu\n", selection.nodes.size(),
                static_cast<unsigned long long>(selection.nodes.size() * trianglesPerNode(map.header())),
                selection.culledNodes);
    return loadError.empty() ? 0 : 1;
}

int stream(const MapFile& map, const ViewOptions& view)
{
    auto path = CameraPath::load(view.path);
    if (!path.ok()) {
        return fail(path.error().message);
    }
    TerrainNodeSource source(map, {});
    auto streamer = TerrainStreamer::create(source, extentOf(map.header()), view.streamer);
    if (!streamer.ok()) {
        return fail(streamer.error().message);
    }
    std::uint64_t loadErrors = 0;
    (*streamer)->onLoadError([&](const std::string& message) {
        ++loadErrors;
        std::fprintf(stderr, "tengine-tool: %s\n", message.c_str());
    });
    Camera camera = view.camera;
    const auto frames = static_cast<std::size_t>(std::floor(path->duration() * view.fps)) + 1;
    std::vector<double> selectMicros;
    selectMicros.reserve(frames);
    std::size_t peakResident = 0, framesWaiting = 0, refused = 0;
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t frame = 0; frame < frames; ++frame) {
        const double t = path->startTime() + static_cast<double>(frame) / view.fps;
        if (!view.fast) {
            std::this_thread::sleep_until(start + std::chrono::duration<double>(t - path->startTime()));
        }
        path->evaluate(t).applyTo(camera);
        FrameStats stats = (*streamer)->update(camera, view.tau);
        selectMicros.push_back(stats.selectionSeconds * 1e6);
        peakResident = std::max(peakResident, (*streamer)->cache().size());
        framesWaiting += stats.requested > 0 ? 1 : 0;
        refused += stats.refused;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const auto server = (*streamer)->serverStats();
    std::sort(selectMicros.begin(), selectMicros.end());
    auto percentile = [&](double p) {
        return selectMicros[static_cast<std::size_t>(p * static_cast<double>(selectMicros.size() - 1))];
    };
    std::printf("frames                 %zu over %.1f s of path (%s, %.1f s wall)\n", frames, path->duration(),
                view.fast ? "as fast as possible" : "real time", seconds);
    std::printf("groups loaded          %llu (%.1f nodes/s), cancelled %llu, rejected (queue full) %llu, failed %llu\n",
                static_cast<unsigned long long>(server.completed),
                4.0 * static_cast<double>(server.completed) / seconds,
                static_cast<unsigned long long>(server.cancelled), static_cast<unsigned long long>(server.rejected),
                static_cast<unsigned long long>(server.failed));
    std::printf("resident nodes         peak %zu of %zu (cache), %llu evictions, %zu groups refused\n", peakResident,
                (*streamer)->cache().capacity(), static_cast<unsigned long long>((*streamer)->cache().evictions()),
                refused);
    std::printf("frames waiting         %zu of %zu wanted a node that was not resident yet\n", framesWaiting, frames);
    std::printf("selection per frame    median %.1f us, p95 %.1f us, max %.1f us\n", percentile(0.5), percentile(0.95),
                selectMicros.back());
    std::printf("peak memory            %s\n", formatBytes(peakResidentBytes()).c_str());
    return loadErrors == 0 ? 0 : 1;
}

/// `height` and `export`'s surface: the finest static level, or with `depth` the drawn surface at that level
/// with the viewer's detail (`detail`: tengine's defaults, --material, --no-material).
struct SurfaceRequest {
    std::optional<int> depth;
    TengineOptions detail;
};

/// `height`: one point (X Y, or --lonlat LON LAT) or --points FILE, then the surface's options.
struct HeightRequest {
    SurfaceRequest surface;
    std::optional<std::string> pointsFile;
    double x = 0.0, y = 0.0;
};

/// `export`: the region, spacing and output, and the surface (its depth the coarsest level as fine as the spacing
/// unless --depth).
struct ExportRequest {
    SurfaceRequest surface;
    std::string output;
    std::array<double, 4> region{};
    double spacing = 0.0;
};

/// The surface's flags: --depth D (a quadtree level), --material M.mat (repeatable), --no-material.
void addSurfaceFlags(CommandLine& line, SurfaceRequest& request)
{
    line.flags.push_back(
        {"--depth", "D", "the quadtree level of the drawn surface", [&request](const std::string& value) -> Status {
             auto depth = wholeNumberIn(value, 0, NodeId::kMaxLevel);
             TERRAIN_TRY(depth);
             request.depth = static_cast<int>(*depth);
             return {};
         }});
    line.flags.push_back({"--material", "M.mat", "a material of the synthesized detail, blended in order",
                          [&request](const std::string& value) -> Status {
                              request.detail.detailMaterials.emplace_back(value);
                              return {};
                          }});
    line.flags.push_back(
        {"--no-material", "", "no material: subdivision only", [&request](const std::string&) -> Status {
             request.detail.detailAddMaterial = false;
             return {};
         }});
}

/// The surface options from `args[first..]`: --depth D, --material M.mat, --no-material.
Expected<SurfaceRequest> parseSurface(const std::vector<std::string>& args, std::size_t first)
{
    SurfaceRequest request;
    CommandLine line;
    addSurfaceFlags(line, request);
    if (Status parsed = line.parse(std::span(args).subspan(first)); !parsed.ok()) {
        return makeError("height: ", parsed.error().message);
    }
    if (!request.depth && args.size() > first) {
        return makeError("height: --material and --no-material need --depth");
    }
    return request;
}

/// `height MAP` then X Y, --lonlat LON LAT or --points FILE from `args[first..]`, then the surface's options.
Expected<HeightRequest> parseHeight(const MapFile& map, const std::vector<std::string>& args, std::size_t first)
{
    HeightRequest request;
    std::size_t options = first + 2;
    if (args.size() >= first + 2 && args[first] == "--points") {
        request.pointsFile = args[first + 1];
    } else if (args.size() >= first + 1 && args[first] == "--lonlat") {
        if (args.size() < first + 3) {
            return makeError("height --lonlat needs LON and LAT (degrees)");
        }
        auto lon = parseDouble(args[first + 1]);
        auto lat = parseDouble(args[first + 2]);
        if (!lon.ok() || !lat.ok()) {
            return makeError("height --lonlat: ", (lon.ok() ? lat : lon).error().message);
        }
        const MapHeader& h = map.header();
        auto geo = GeoConverter::create(h.crsWkt, h.crsUnitMetres);
        if (!geo.ok()) {
            return makeError("height --lonlat: ", map.name(), ": ", geo.error().message);
        }
        auto world = geo->toWorld(*lon, *lat);
        if (!world.ok()) {
            return makeError("height --lonlat: ", world.error().message);
        }
        request.x = world->first;
        request.y = world->second;
        options = first + 3;
    } else {
        if (args.size() < first + 2) {
            return makeError("height needs X and Y (metres), or --points FILE");
        }
        auto px = parseDouble(args[first]);
        auto py = parseDouble(args[first + 1]);
        if (!px.ok() || !py.ok()) {
            return makeError("height: ", (px.ok() ? py : px).error().message);
        }
        request.x = *px;
        request.y = *py;
    }
    auto surface = parseSurface(args, options);
    TERRAIN_TRY(surface);
    request.surface = std::move(surface).value();
    return request;
}

/// `export MAP OUT.tif --region X0,Y0,X1,Y1 --spacing S` and the surface's options, in any order after OUT.tif.
Expected<ExportRequest> parseExport(const MapFile& map, const std::vector<std::string>& args)
{
    if (args.size() < 3) {
        return makeError("export needs an output .tif");
    }
    ExportRequest request;
    request.output = args[2];
    bool haveRegion = false, haveSpacing = false;
    CommandLine line;
    line.flags.push_back(
        {"--region", "X0,Y0,X1,Y1", "the region (world metres)", [&](const std::string& text) -> Status {
             std::size_t at = 0;
             for (int k = 0; k < 4; ++k) {
                 const std::size_t comma = k < 3 ? text.find(',', at) : text.size();
                 auto v = numberIn(comma == std::string::npos ? std::string() : text.substr(at, comma - at),
                                   -kMaxWorldMetres, kMaxWorldMetres);
                 if (!v.ok() || comma == std::string::npos) {
                     return makeError("'", text, "' is not X0,Y0,X1,Y1 (metres, within +-", kMaxWorldMetres, ")");
                 }
                 request.region[static_cast<std::size_t>(k)] = *v;
                 at = comma + 1;
             }
             const auto& r = request.region;
             if (!(r[2] > r[0] && r[3] > r[1])) {
                 return makeError("'", text, "' needs X1 > X0 and Y1 > Y0");
             }
             haveRegion = true;
             return {};
         }});
    line.flags.push_back({"--spacing", "S", "the grid's spacing (metres)", [&](const std::string& text) -> Status {
                              auto v = numberIn(text, kMinSpacingMetres, kMaxSpacingMetres, "metres");
                              TERRAIN_TRY(v);
                              request.spacing = *v;
                              haveSpacing = true;
                              return {};
                          }});
    addSurfaceFlags(line, request.surface);
    if (Status parsed = line.parse(std::span(args).subspan(3)); !parsed.ok()) {
        return makeError("export: ", parsed.error().message);
    }
    if (!haveRegion || !haveSpacing) {
        return makeError("export needs --region X0,Y0,X1,Y1 and --spacing S");
    }
    if (!request.surface.depth) {
        int level = 0;
        while (level < NodeId::kMaxLevel && map.header().spacingAt(level) > request.spacing * (1 + 1e-9)) {
            ++level;
        }
        request.surface.depth = level;
    }
    return request;
}

/// The surface a request samples: the static heights, or with a depth the synthesized surface at that level, as
/// tengine draws it. Remembers the coarsest level a point stopped at, for the note.
class RequestedSurface {
public:
    static Expected<std::unique_ptr<RequestedSurface>> open(const MapFile& map, const SurfaceRequest& request,
                                                            const std::filesystem::path& materialsDirectory)
    {
        std::unique_ptr<RequestedSurface> s(new RequestedSurface(map, request));
        if (!request.depth) {
            return s;
        }
        std::vector<std::string> warnings;
        auto made = makeDetailSynthesizer(request.detail, map.header(), materialsDirectory, warnings);
        for (const auto& warning : warnings) {
            std::fprintf(stderr, "tengine-tool: warning: %s\n", warning.c_str());
        }
        TERRAIN_TRY(made);
        s->mSynthesizer = std::move(made).value();
        // Heights only: no error bounds (they synthesize each node's children), normal maps or tessellation errors.
        s->mSource.emplace(map, DetailPolicy{s->mSynthesizer.get(), request.detail.lodMinimumSpacing, 0, 0, false});
        s->mSampler.emplace(map, *s->mSource, *request.depth);
        return s;
    }

    Expected<double> heightAt(double x, double y)
    {
        if (!mRequest.depth) {
            auto sample = staticHeightAt(mMap, x, y);
            TERRAIN_TRY(sample);
            return sample->height;
        }
        auto sample = mSampler->at(x, y);
        TERRAIN_TRY(sample);
        if (sample->node.level < mShallowest) {
            mShallowest = sample->node.level;
            mStoppedAt = sample->node;
        }
        return sample->height;
    }

    /// Says where the surface stopped above the depth asked for (lod_minimum_spacing).
    void noteShallower() const
    {
        if (mRequest.depth && mShallowest < *mRequest.depth) {
            std::fprintf(stderr,
                         "tengine-tool: note: the surface stops at level %d (%s); lod_minimum_spacing is %g m\n",
                         mShallowest, mStoppedAt.toString().c_str(), mRequest.detail.lodMinimumSpacing);
        }
    }

private:
    RequestedSurface(const MapFile& map, const SurfaceRequest& request) : mMap(map), mRequest(request) {}

    const MapFile& mMap;
    SurfaceRequest mRequest;
    std::unique_ptr<const DetailSynthesizer> mSynthesizer;
    std::optional<TerrainNodeSource> mSource;
    std::optional<SurfaceSampler> mSampler;
    int mShallowest = NodeId::kMaxLevel + 1;  // the coarsest level a point stopped at
    NodeId mStoppedAt;
};

/// export: the surface on the request's grid as a float32 GeoTIFF (no-data outside the terrain).
int exportSurface(const MapFile& map, const ExportRequest& request, const std::filesystem::path& materialsDirectory)
{
    const auto& r = request.region;
    const double s = request.spacing;
    const double nx = std::floor((r[2] - r[0]) / s + 1e-9) + 1, ny = std::floor((r[3] - r[1]) / s + 1e-9) + 1;
    if (!(nx * ny <= 1e9) || !(nx <= 1e6) || !(ny <= 1e6)) {
        char message[200];
        std::snprintf(message, sizeof message,
                      "export: %.6g x %.6g samples is too many (at most 1e9, 1e6 a side): a larger --spacing or a "
                      "smaller --region",
                      nx, ny);
        return fail(message);
    }
    auto surface = RequestedSurface::open(map, request.surface, materialsDirectory);
    if (!surface.ok()) {
        return fail(surface.error().message);
    }
    RasterGrid grid;
    grid.width = static_cast<int>(nx);
    grid.height = static_cast<int>(ny);
    grid.x0 = r[0];
    grid.y0 = r[1];
    grid.step = s;
    grid.crsWkt = map.header().crsWkt;
    grid.crsUnitMetres = map.header().crsUnitMetres;
    auto bytes = static_cast<std::uint64_t>(nx * ny * sizeof(float));
    if (auto room = checkAllocation(bytes, "the exported grid"); !room.ok()) {
        return fail("export: " + room.error().message);
    }
    std::vector<float> heights(static_cast<std::size_t>(nx * ny));
    std::uint64_t outside = 0;
    for (int j = 0; j < grid.height; ++j) {
        for (int i = 0; i < grid.width; ++i) {
            auto h = (*surface)->heightAt(grid.x0 + i * s, grid.y0 + j * s);
            heights[static_cast<std::size_t>(j) * grid.width + i] =
                h.ok() ? static_cast<float>(*h) : std::numeric_limits<float>::quiet_NaN();
            outside += h.ok() ? 0 : 1;
        }
    }
    if (auto written = writeFloat32GeoTiff(request.output, grid, heights); !written.ok()) {
        return fail("export: " + written.error().message);
    }
    std::printf("exported %s: %d x %d samples of %g m at depth %d (%s), %llu outside the terrain (no-data)\n",
                request.output.c_str(), grid.width, grid.height, s, *request.surface.depth,
                grid.crsWkt.empty() ? "no CRS" : describeCrs(grid.crsWkt).c_str(),
                static_cast<unsigned long long>(outside));
    return 0;
}

/// height --points: one "X Y" a line from `in` (`name` in messages), a height a line out; 1 at the first bad line
/// or point outside, naming its line.
int heightsOfPoints(std::FILE* in, const std::string& name, RequestedSurface& surface)
{
    std::string line;
    int number = 0;
    for (int c = 0; c != EOF;) {
        line.clear();
        while ((c = std::fgetc(in)) != EOF && c != '\n') {
            line.push_back(static_cast<char>(c));
        }
        if (c == EOF && line.empty()) {
            break;
        }
        ++number;
        const std::string text = line.substr(0, line.find('#'));
        std::vector<std::string> fields;
        for (std::size_t at = 0; at < text.size();) {
            const std::size_t begin = text.find_first_not_of(" \t\r,", at);
            if (begin == std::string::npos) {
                break;
            }
            const std::size_t stop = text.find_first_of(" \t\r,", begin);
            fields.push_back(text.substr(begin, stop == std::string::npos ? std::string::npos : stop - begin));
            at = stop == std::string::npos ? text.size() : stop;
        }
        if (fields.empty()) {
            continue;
        }
        auto px = fields.size() == 2 ? parseDouble(fields[0]) : Expected<double>(makeError("expected 'X Y'"));
        auto py = fields.size() == 2 ? parseDouble(fields[1]) : Expected<double>(makeError("expected 'X Y'"));
        if (!px.ok() || !py.ok()) {
            std::fprintf(stderr, "tengine-tool: %s:%d: %s, found '%s'\n", name.c_str(), number,
                         (px.ok() ? py : px).error().message.c_str(), line.c_str());
            return 1;
        }
        auto h = surface.heightAt(*px, *py);
        if (!h.ok()) {
            std::fprintf(stderr, "tengine-tool: %s:%d: %s\n", name.c_str(), number, h.error().message.c_str());
            return 1;
        }
        std::printf("%.6f\n", *h);
    }
    return 0;
}

/// height: the surface at one point or at the points of a file.
int height(const MapFile& map, const HeightRequest& request, const std::filesystem::path& materialsDirectory)
{
    auto surface = RequestedSurface::open(map, request.surface, materialsDirectory);
    if (!surface.ok()) {
        return fail(surface.error().message);
    }
    if (!request.pointsFile) {
        auto h = (*surface)->heightAt(request.x, request.y);
        if (!h.ok()) {
            return fail(h.error().message);
        }
        std::printf("%.6f\n", *h);
    } else {
        const std::string& file = *request.pointsFile;
        FILE* in = file == "-" ? stdin : std::fopen(file.c_str(), "r");
        if (!in) {
            return fail("height: cannot open " + file + ": " + std::strerror(errno));
        }
        const int status = heightsOfPoints(in, file == "-" ? std::string("standard input") : file, **surface);
        if (in != stdin) {
            std::fclose(in);
        }
        if (status != 0) {
            return status;
        }
    }
    (*surface)->noteShallower();
    return 0;
}

}  // namespace

int main(int argc, char** argv)
{
    const std::filesystem::path materialsDirectory = programDataDirectory("materials", TERRAIN_MATERIALS_DIR);
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
            std::fputs(usage().c_str(), stdout);
            return 0;
        }
    }
    std::vector<std::string> args;
    ReaderKind reader = ReaderKind::Stream;
    // The flags every command takes, anywhere; the rest goes to the command in order.
    CommandLine global = globalCommandLine(reader);
    global.passUnknown = true;
    global.positional = [&args](const std::string& argument) -> Status {
        args.push_back(argument);
        return {};
    };
    if (Status parsed = global.parse(std::vector<std::string>(argv + 1, argv + argc)); !parsed.ok()) {
        return fail(parsed.error().message);
    }
    if (args.size() < 2) {
        std::fputs(usage().c_str(), stderr);
        return 2;
    }
    const std::string& command = args[0];
    if (command != "info" && command != "verify" && command != "height" && command != "texture" &&
        command != "export" && command != "select" && command != "stream" && command != "error") {
        std::fprintf(stderr, "tengine-tool: unknown command '%s'\n%s", command.c_str(), usage().c_str());
        return 2;
    }
    // What texture and export write must not be one of the run's inputs: checked before anything is opened.
    if ((command == "texture" && args.size() == 4) || (command == "export" && args.size() >= 3)) {
        std::vector<InputFile> inputs = {{"map", args[1]}};
        for (std::size_t i = 3; i + 1 < args.size(); ++i) {
            if (args[i] == "--material" || args[i] == "--points") {
                inputs.push_back({args[i] == "--material" ? "material" : "points file", args[i + 1]});
            }
        }
        const std::string& output = command == "texture" ? args[3] : args[2];
        if (auto refused =
                refuseInputAsOutput(command == "texture" ? "texture PNG" : "exported GeoTIFF", output, inputs);
            !refused.ok()) {
            return fail(command + ": " + refused.error().message);
        }
        if (auto writable = checkOutputPath(output); !writable.ok()) {
            return fail(command + ": " + writable.error().message);
        }
    }
    auto map = MapFile::open(args[1], reader);
    if (!map.ok()) {
        return fail(map.error().message);
    }
    if (command == "info") {
        return info(**map);
    }
    if (command == "verify") {
        return verify(**map);
    }
    if (command == "error") {
        auto parsed = parseErrorCommand(args[1], std::vector<std::string>(args.begin() + 2, args.end()));
        if (!parsed.ok()) {
            return fail("error: " + parsed.error().message);
        }
        return runErrorCommand(**map, *parsed, materialsDirectory, stdout, stderr);
    }
    if (command == "select" || command == "stream") {
        auto view = parseViewOptions(args, 2, command == "stream");
        if (!view.ok()) {
            return fail(command + ": " + view.error().message);
        }
        return command == "select" ? select(**map, *view) : stream(**map, *view);
    }
    if (command == "texture") {
        if (args.size() != 4) {
            return fail("texture needs LEVEL/X/Y and an output PNG");
        }
        return texture(**map, args[2], args[3]);
    }
    if (command == "export") {
        auto request = parseExport(**map, args);
        if (!request.ok()) {
            return fail(request.error().message);
        }
        return exportSurface(**map, *request, materialsDirectory);
    }
    auto request = parseHeight(**map, args, 2);
    if (!request.ok()) {
        return fail(request.error().message);
    }
    return height(**map, *request, materialsDirectory);
}
