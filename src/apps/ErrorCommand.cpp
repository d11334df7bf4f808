#include "apps/ErrorCommand.h"

#include "apps/DetailSetup.h"
#include "apps/NodeBudget.h"
#include "core/Parse.h"
#include "lod/CameraPath.h"
#include "lod/ErrorMeter.h"
#include "lod/HeightQuery.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "lod/TessellationLevels.h"
#include "quadtree/ChunkGeometry.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_map>

namespace terrain {

namespace {

}  // namespace

Status parseCameraArgument(const std::string& value, Camera& camera)
{
    std::vector<double> parts;
    std::size_t start = 0;
    while (true) {
        const auto comma = value.find(',', start);
        auto piece = parseDouble(value.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
        if (!piece.ok() || !std::isfinite(*piece)) {
            return makeError("--camera: '", value, "' is not X,Y,Z,YAW,PITCH");
        }
        parts.push_back(*piece);
        if (comma == std::string::npos) {
            break;
        }
        start = comma + 1;
    }
    if (parts.size() != 5 || std::abs(parts[4]) > 90) {
        return makeError("--camera: '", value, "' is not X,Y,Z,YAW,PITCH (metres and degrees, pitch in [-90, 90])");
    }
    camera.position = {parts[0], parts[1], parts[2]};
    camera.yaw = parts[3] * kRadiansPerDegree;
    camera.pitch = parts[4] * kRadiansPerDegree;
    return {};
}

namespace {

/// Errors in pixels over many frames, binned finely enough for a percentile: 1/1000 px up to 100 px.
class PixelHistogram {
public:
    void add(float px)
    {
        const auto bin = static_cast<std::size_t>(std::min<double>(px * kBinsPerPixel, kBins - 1));
        ++mCounts[bin];
        ++mTotal;
    }
    /// The value below which a share `p` of the points lies (bin upper edge); 0 when empty.
    double percentile(double p) const
    {
        const auto wanted = static_cast<std::uint64_t>(std::ceil(p * static_cast<double>(mTotal)));
        std::uint64_t seen = 0;
        for (std::size_t b = 0; b < kBins; ++b) {
            seen += mCounts[b];
            if (seen >= wanted && seen > 0) {
                return static_cast<double>(b + 1) / kBinsPerPixel;
            }
        }
        return 0.0;
    }

private:
    static constexpr double kBinsPerPixel = 1000.0;
    static constexpr std::size_t kBins = 100000;
    std::vector<std::uint64_t> mCounts = std::vector<std::uint64_t>(kBins, 0);
    std::uint64_t mTotal = 0;
};

}  // namespace

Expected<ErrorCommand> parseErrorCommand(const std::filesystem::path& mapFile, const std::vector<std::string>& args)
{
    ErrorCommand command;
    std::vector<std::string> viewerArgs;
    std::optional<double> tau, fov, fps;
    std::optional<std::pair<int, int>> size;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& arg = args[i];
        if (arg.starts_with("--set=")) {  // tengine's other spelling of --set key=value
            viewerArgs.push_back(arg);
            continue;
        }
        if (!arg.starts_with("--")) {
            if (!arg.ends_with(".cfg")) {
                return makeError("'", arg, "' is neither a CONFIG.cfg nor an option (the map comes first)");
            }
            viewerArgs.push_back(arg);
            continue;
        }
        if (arg == "--levels") {
            command.levels = true;
            continue;
        }
        if (arg == "--pops") {
            command.pops = true;
            continue;
        }
        if (arg == "--oracle") {
            command.oracle = true;
            continue;
        }
        if (arg.starts_with("--oracle=")) {
            auto blocks = parseNumberIn("--oracle", arg.substr(9), 1.0, 64.0);
            TERRAIN_TRY(blocks);
            if (*blocks != std::floor(*blocks)) {
                return makeError("--oracle=B: '", arg.substr(9), "' is not a whole number of blocks");
            }
            command.oracle = true;
            command.oracleBlocks = static_cast<int>(*blocks);
            continue;
        }
        if (i + 1 >= args.size()) {
            return makeError(arg, " needs a value");
        }
        const std::string& value = args[++i];
        auto number = [&](double lo, double hi) { return parseNumberIn(arg, value, lo, hi); };
        if (arg == "--set") {
            viewerArgs.push_back(arg);
            viewerArgs.push_back(value);
        } else if (arg == "--camera") {
            Camera camera;
            auto parsed = parseCameraArgument(value, camera);
            TERRAIN_TRY(parsed);
            command.camera = camera;
        } else if (arg == "--path") {
            command.path = value;
        } else if (arg == "--tau") {
            auto v = number(0.01, 1000);
            TERRAIN_TRY(v);
            tau = *v;
        } else if (arg == "--fov") {
            auto v = number(1, 179);
            TERRAIN_TRY(v);
            fov = *v;
        } else if (arg == "--fps") {
            auto v = number(0.001, 1000);
            TERRAIN_TRY(v);
            fps = *v;
        } else if (arg == "--size") {
            unsigned w = 0, h = 0;
            char tail = 0;
            if (std::sscanf(value.c_str(), "%ux%u%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 16384 ||
                h > 16384) {
                return makeError("--size: '", value, "' is not WIDTHxHEIGHT (16 to 16384 pixels each)");
            }
            size = {static_cast<int>(w), static_cast<int>(h)};
        } else {
            return makeError("unknown option '", arg, "'");
        }
    }
    if (command.pops && command.path.empty()) {
        return makeError("--pops compares consecutive frames: it needs --path");
    }
    if (command.camera.has_value() == !command.path.empty()) {
        return makeError("give exactly one of --camera X,Y,Z,YAW,PITCH and --path FILE.path");
    }
    viewerArgs.push_back(mapFile.string());
    auto parsed = parseTengineCommandLine(viewerArgs);
    TERRAIN_TRY(parsed);
    command.options = std::move(parsed->options);
    command.warnings = std::move(parsed->warnings);
    TengineOptions& o = command.options;
    if (tau) {
        o.lodError = *tau;
    }
    if (fov) {
        o.cameraFov = *fov;
    }
    if (size) {
        o.windowWidth = size->first;
        o.windowHeight = size->second;
    }
    command.fps = fps ? *fps : static_cast<double>(o.framesPerSecond);
    command.lens.viewportWidth = o.windowWidth;
    command.lens.viewportHeight = o.windowHeight;
    command.lens.verticalFov = o.cameraFov * kRadiansPerDegree;
    command.lens.nearPlane = o.cameraZNear;
    command.lens.farPlane = o.cameraZFar;
    return command;
}

int runErrorCommand(const MapFile& map, const ErrorCommand& command, const std::filesystem::path& builtInMaterials,
                    std::FILE* out, std::FILE* err)
{
    auto fail = [&](const std::string& message) {
        std::fprintf(err, "tengine-tool: error: %s\n", message.c_str());
        return 1;
    };
    const TengineOptions& o = command.options;
    const MapHeader& header = map.header();
    for (const auto& warning : command.warnings) {
        std::fprintf(err, "tengine-tool: warning: %s\n", warning.c_str());
    }
    std::vector<std::string> warnings;
    auto synthesizer = makeDetailSynthesizer(o, header, builtInMaterials, warnings);
    for (const auto& warning : warnings) {
        std::fprintf(err, "tengine-tool: warning: %s\n", warning.c_str());
    }
    if (!synthesizer.ok()) {
        return fail(synthesizer.error().message);
    }
    if (*synthesizer && header.hasDetailErrors()) {
        auto recipe = viewerDetailRecipe(o, **synthesizer, builtInMaterials);
        if (!recipe.ok()) {
            return fail(recipe.error().message);
        }
        const auto files = synthesizedMaterialFiles(o, **synthesizer, builtInMaterials);
        if (auto mismatch = detailRecipeMismatch(header, map.name(), *recipe, files)) {
            std::fprintf(err, "tengine-tool: warning: %s\n", mismatch->c_str());
        }
    }
    std::optional<CameraPath> path;
    if (!command.path.empty()) {
        auto loaded = CameraPath::load(command.path);
        if (!loaded.ok()) {
            return fail(loaded.error().message);
        }
        path = std::move(loaded).value();
    }

    // render_mode = tessellation: the selection spends part of tau and the blocks the rest (as tengine does).
    const double blockPixels = o.tessellation ? o.lodError * o.tessellationShare : 0.0;
    const double nodePixels = o.lodError - blockPixels;
    TerrainNodeSource source(map,
                             {synthesizer->get(), o.lodMinimumSpacing, o.tessellation ? kTessellationBlockQuads : 0});
    StreamerOptions streamerOptions;
    // The viewer's cache: its nodes' CPU bytes are those of its own source (normal maps included; auto
    // compression taken as on a software rasterizer, where no GL can be asked: RG8, the larger).
    TerrainNodeSource viewerSource(
        map, {synthesizer->get(), o.lodMinimumSpacing, o.tessellation ? kTessellationBlockQuads : 0,
              o.dynamicTextureSize, true, compressNormalMaps(o, true)});
    auto root = viewerSource.loadRoot();
    if (!root.ok()) {
        return fail(root.error().message);
    }
    const CacheChoice cache =
        chooseCacheSize(o, header, *synthesizer ? (*synthesizer)->settings().materials.get() : nullptr, true,
                        compressNormalMaps(o, true), residentBytes(**root), kSlotsWithoutContext);
    streamerOptions.cacheSize = cache.nodes;
    streamerOptions.queueLimit = static_cast<std::size_t>(o.requestQueueSize);
    streamerOptions.workers = o.workerThreads;
    streamerOptions.velocityLimit = 0.0;  // the loader runs to completion every frame
    auto streamer = TerrainStreamer::create(source, extentOf(header), streamerOptions);
    if (!streamer.ok()) {
        return fail(streamer.error().message);
    }
    std::string loadError;
    (*streamer)->onLoadError([&](const std::string& message) {
        if (loadError.empty()) {
            loadError = message;
        }
    });
    const double tau = o.lodError;
    // The reference nodes are the same nodes without the tessellation errors they do not need.
    // Reference surfaces: heights only (no bounds, normal maps or tessellation errors).
    TerrainNodeSource referenceSource(map, {synthesizer->get(), o.lodMinimumSpacing, 0, 0, false});
    ErrorMeter meter(header, referenceSource, {tau / 8.0, 1024, 16});

    const std::size_t frames =
        path ? static_cast<std::size_t>(std::floor(path->duration() * command.fps + 1e-9)) + 1 : std::size_t{1};
    const auto trianglesPerNode = static_cast<std::uint64_t>(trianglesPerChunk(static_cast<int>(header.chunkSize)));
    PixelHistogram histogram;
    std::vector<std::uint64_t> triangles, oracleTriangles;
    double oracleWorst = 0.0;
    std::uint64_t oracleRefined = 0, oracleRefinedWithinTau = 0;
    double worst = 0.0, sum = 0.0;
    std::uint64_t points = 0, refined = 0, refinedWithinTau = 0;
    std::size_t framesOverTau = 0, framesShort = 0, framesBelow = 0;
    struct LevelFigures {
        std::size_t nodes = 0, held = 0, dynamicNodes = 0;
        double sumBound = 0.0, sumMeasured = 0.0, worstRatio = 0.0;
        NodeId worst;
        std::vector<double> ratios;
    };
    std::vector<LevelFigures> levels(NodeId::kMaxLevel + 1);
    LodSelection atOwnDetail;                                       // geomorph = false: what the renderer draws
    std::unordered_map<std::uint64_t, BlockLevels> previousLevels;  // --pops
    std::vector<LevelSwitch> switches;
    std::vector<float> pops;  // px
    std::fprintf(out,
                 "# tau %g px, %dx%d, fov %g deg, detail %s; reference: refined until a level changes it by "
                 "< %g px\n",
                 tau, command.lens.viewportWidth, command.lens.viewportHeight, o.cameraFov, *synthesizer ? "on" : "off",
                 tau / 8.0);
    std::fprintf(out, "# %s\n", cache.description.c_str());
    if (command.pops) {
        if (!o.tessellation) {
            return fail(
                "--pops measures the tessellation blocks' level switches: --set render_mode=tessellation "
                "(chunks morph every switch, eq. 3.5)");
        }
        std::fprintf(out, "# frame  time(s)  largest pop(px)  triangles  nodes\n");
    } else {
        std::fprintf(out,
                     "# frame  time(s)  max(px)  p99(px)  mean(px)  triangles  nodes  refined  within-tau  "
                     "worst: node, metres\n");
    }
    for (std::size_t frame = 0; frame < frames; ++frame) {
        Camera camera = command.lens;
        double t = 0.0;
        if (path) {
            t = path->startTime() + static_cast<double>(frame) / command.fps;
            path->evaluate(t).applyTo(camera);
        } else {
            camera.position = command.camera->position;
            camera.yaw = command.camera->yaw;
            camera.pitch = command.camera->pitch;
        }
        if (auto ground = staticHeightAt(map, camera.position.x, camera.position.y); !ground.ok()) {
            return fail((path ? command.path.string() + ": frame " + std::to_string(frame) +
                                    " (t = " + std::to_string(t) + " s): "
                              : std::string("--camera: ")) +
                        "the camera is not over the terrain: " + ground.error().message);
        } else if (camera.position.z < ground->height) {
            // Measured all the same (the viewer draws it so), but said: the figures are of the underside.
            ++framesBelow;
            std::fprintf(err, "tengine-tool: warning: frame %zu (t = %.2f s): the camera is %.1f m below the terrain\n",
                         frame, t, ground->height - camera.position.z);
        }
        FrameStats stats;
        for (int round = 0; round < 256; ++round) {
            stats = (*streamer)->update(camera, nodePixels, 0.0);
            if (stats.requested == stats.deferred || !loadError.empty()) {
                break;
            }
            (*streamer)->drain();
        }
        if (!loadError.empty()) {
            return fail(loadError);
        }
        framesShort += stats.deferred > 0 ? 1 : 0;
        const TerrainStreamer& s = **streamer;
        const LodSelection* drawn = &s.selection();
        if (!o.geomorph) {  // the renderer then draws every node at its own detail
            atOwnDetail = unmorphed(s.selection());
            drawn = &atOwnDetail;
        }
        if (command.pops) {
            // The blocks' level switches since the previous frame, each at its size on screen now.
            std::unordered_map<std::uint64_t, BlockLevels> now;
            std::uint64_t drawnTriangles = 0;
            const VerticalSegmentProjector projector(camera);
            double framePop = 0.0;
            for (const SelectedNode& selected : drawn->nodes) {
                const NodePtr node = s.node(selected.id);
                BlockLevels blockLevels =
                    chooseBlockLevels(*node->tessellation, extentOf(header).box(selected.id, node->zMin, node->zMax),
                                      camera, blockPixels);
                drawnTriangles += blockLevels.triangles();
                if (auto it = previousLevels.find(selected.id.key()); it != previousLevels.end()) {
                    const int n = static_cast<int>(header.chunkSize);
                    const std::vector<float> samples =
                        morphedSamples(*node, n, selected.id.isRoot() ? 1.0f : selected.morph);
                    switches.clear();
                    levelSwitches(samples, n, it->second, blockLevels, switches);
                    const double spacing = selected.size / (n - 1);
                    for (const LevelSwitch& w : switches) {
                        const double x = camera.position.x + selected.cameraRelativeOrigin.x + w.lx * spacing;
                        const double y = camera.position.y + selected.cameraRelativeOrigin.y + w.ly * spacing;
                        const double z = header.heightOffset + nodeSurfaceAt(*node, n, w.lx, w.ly);
                        const double px = projector.pixels(x, y, z, w.metres);
                        if (px >= 0.0) {
                            pops.push_back(static_cast<float>(px));
                            framePop = std::max(framePop, px);
                        }
                    }
                }
                now.emplace(selected.id.key(), std::move(blockLevels));
            }
            previousLevels = std::move(now);
            triangles.push_back(drawnTriangles);
            std::fprintf(out, "%7zu %8.2f %8.3f %10llu %6zu\n", frame, t, framePop,
                         static_cast<unsigned long long>(drawnTriangles), drawn->nodes.size());
            continue;
        }
        auto measured = meter.measure(
            *drawn, [&s](const NodeId& id) { return s.node(id); }, camera, tau, blockPixels);
        if (!measured.ok()) {
            return fail(measured.error().message);
        }
        const FrameError& e = *measured;
        for (float px : e.pixels) {
            histogram.add(px);
        }
        worst = std::max(worst, e.maxPixels);
        sum += e.meanPixels * static_cast<double>(e.points);
        points += e.points;
        refined += e.refined;
        refinedWithinTau += e.refinedWithinTau;
        framesOverTau += e.maxPixels > tau ? 1 : 0;
        for (const auto& b : e.bounds) {
            LevelFigures& l = levels[static_cast<std::size_t>(b.id.level)];
            ++l.nodes;
            l.dynamicNodes += b.isStatic ? 0 : 1;
            l.held += b.measured <= b.deltaC ? 1 : 0;
            l.sumBound += b.deltaC;
            l.sumMeasured += b.measured;
            const double ratio = b.deltaC > 0.0f ? b.measured / b.deltaC : (b.measured > 0.0 ? 1e9 : 0.0);
            if (ratio > l.worstRatio) {
                l.worstRatio = ratio;
                l.worst = b.id;
            }
            l.ratios.push_back(ratio);
        }
        // The meter chose the blocks' levels as the renderer does: its count is what tessellation draws.
        triangles.push_back(o.tessellation ? e.tessellatedTriangles : e.nodes * trianglesPerNode);
        std::fprintf(out, "%7zu %8.2f %8.3f %8.3f %9.4f %10llu %6zu %8zu %11zu  %s %.3f\n", frame, t, e.maxPixels,
                     e.p99Pixels, e.meanPixels, static_cast<unsigned long long>(triangles.back()), e.nodes, e.refined,
                     e.refinedWithinTau, e.worstNode.toString().c_str(), e.maxMetres);
        if (command.oracle) {
            auto oracle = meter.oracle(camera, tau, command.oracleBlocks);
            if (!oracle.ok()) {
                return fail(oracle.error().message);
            }
            oracleTriangles.push_back(oracle->nodes.size() * trianglesPerNode);
            oracleWorst = std::max(oracleWorst, oracle->maxPixels);
            oracleRefined += oracle->refined.size();
            oracleRefinedWithinTau += oracle->refinedWithinTau;
            std::fprintf(out,
                         "        oracle: %zu nodes, %llu triangles, max %.3f px, %zu refined, %zu within tau, %zu "
                         "over tau\n",
                         oracle->nodes.size(), static_cast<unsigned long long>(oracleTriangles.back()),
                         oracle->maxPixels, oracle->refined.size(), oracle->refinedWithinTau, oracle->overTau);
        }
        std::fflush(out);
    }
    if (framesBelow > 0) {
        std::fprintf(out,
                     "# camera below the terrain in %zu of %zu frames: those figures are of the terrain seen "
                     "from below\n",
                     framesBelow, frames);
    }
    if (framesShort > 0) {
        std::fprintf(err,
                     "tengine-tool: warning: in %zu frame%s the node cache (%zu nodes; memory_budget, "
                     "quad_cache_size) had no room for every node the selection wanted; measured what the viewer "
                     "draws then\n",
                     framesShort, framesShort == 1 ? "" : "s", cache.nodes);
    }
    if (command.levels) {
        std::fprintf(out,
                     "# selected nodes per level: bound delta_c against the measured distance of the node's own "
                     "surface from the reference\n");
        std::fprintf(out,
                     "# level  nodes  dynamic  mean bound(m)  mean measured(m)  measured/bound: median, max  "
                     "bound held  worst node\n");
        for (std::size_t level = 0; level < levels.size(); ++level) {
            LevelFigures& l = levels[level];
            if (l.nodes == 0) {
                continue;
            }
            std::sort(l.ratios.begin(), l.ratios.end());
            std::fprintf(out, "%7zu %6zu %8zu %14.4f %17.4f %15.3f %6.3f %8.1f%%  %s\n", level, l.nodes, l.dynamicNodes,
                         l.sumBound / static_cast<double>(l.nodes), l.sumMeasured / static_cast<double>(l.nodes),
                         l.ratios[(l.ratios.size() - 1) / 2], l.worstRatio,
                         100.0 * static_cast<double>(l.held) / static_cast<double>(l.nodes),
                         l.worst.toString().c_str());
        }
    }
    std::vector<std::uint64_t> sorted = triangles;
    std::sort(sorted.begin(), sorted.end());
    const std::uint64_t median = sorted[(sorted.size() - 1) / 2];
    if (command.pops) {
        std::sort(pops.begin(), pops.end());
        std::fprintf(out,
                     "pops: %zu points of switched blocks in %zu frames; largest %.3f px, p99 %.3f px, median %.3f px "
                     "(blocks' budget %g px); triangles median %llu, max %llu\n",
                     pops.size(), frames, pops.empty() ? 0.0 : double{pops.back()},
                     pops.empty() ? 0.0 : double{pops[static_cast<std::size_t>(0.99 * double(pops.size() - 1))]},
                     pops.empty() ? 0.0 : double{pops[(pops.size() - 1) / 2]}, blockPixels,
                     static_cast<unsigned long long>(median), static_cast<unsigned long long>(sorted.back()));
        return 0;
    }
    std::fprintf(out, "frames over tau: %zu of %zu\n", framesOverTau, frames);
    std::fprintf(out, "refinements that bought nothing: %llu of %llu refined nodes (%.1f%%)\n",
                 static_cast<unsigned long long>(refinedWithinTau), static_cast<unsigned long long>(refined),
                 refined ? 100.0 * static_cast<double>(refinedWithinTau) / static_cast<double>(refined) : 0.0);
    std::fprintf(out, "reference: %llu node groups made\n", static_cast<unsigned long long>(meter.groupsMade()));
    if (command.oracle) {
        std::vector<std::uint64_t> sortedOracle = oracleTriangles;
        std::sort(sortedOracle.begin(), sortedOracle.end());
        const std::uint64_t oracleMedian = sortedOracle[(sortedOracle.size() - 1) / 2];
        std::fprintf(
            out,
            "oracle (%s, morph 1): triangles median %llu, max %llu, max %.3f px; the selection "
            "draws %.2fx the oracle's median; its refinements that bought nothing: %llu of %llu (%.1f%%)\n",
            command.oracleBlocks == 0
                ? "measured errors in pixels"
                : (std::to_string(command.oracleBlocks) + "x" + std::to_string(command.oracleBlocks) +
                   " blocks' measured metres at their bound distance")
                      .c_str(),
            static_cast<unsigned long long>(oracleMedian), static_cast<unsigned long long>(sortedOracle.back()),
            oracleWorst, oracleMedian ? static_cast<double>(median) / static_cast<double>(oracleMedian) : 0.0,
            static_cast<unsigned long long>(oracleRefinedWithinTau), static_cast<unsigned long long>(oracleRefined),
            oracleRefined ? 100.0 * static_cast<double>(oracleRefinedWithinTau) / static_cast<double>(oracleRefined)
                          : 0.0);
    }
    std::fprintf(out,
                 "error: max %.3f px, p99 %.3f px, mean %.4f px over %zu frames; triangles median %llu, max %llu\n",
                 worst, histogram.percentile(0.99), points ? sum / static_cast<double>(points) : 0.0, frames,
                 static_cast<unsigned long long>(median), static_cast<unsigned long long>(sorted.back()));
    return 0;
}

}  // namespace terrain
