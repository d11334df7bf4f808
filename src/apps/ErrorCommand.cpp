#include "apps/ErrorCommand.h"

#include "apps/CommandLine.h"
#include "apps/ViewerSession.h"
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
    auto number = [](std::optional<double>& target, double lo, double hi) {
        return [&target, lo, hi](const std::string& value) -> Status {
            auto v = numberIn(value, lo, hi);
            TERRAIN_TRY(v);
            target = *v;
            return {};
        };
    };
    auto set = [](bool& target) {
        return [&target](const std::string&) -> Status {
            target = true;
            return {};
        };
    };
    CommandLine line;
    line.flags = {
        {"--set", "key=value", "a viewer option, in order with the configs",
         [&](const std::string& value) -> Status {
             viewerArgs.push_back("--set");
             viewerArgs.push_back(value);
             return {};
         }},
        {"--camera", "X,Y,Z,YAW,PITCH", "one camera (metres and degrees)",
         [&](const std::string& value) -> Status {
             Camera camera;
             TERRAIN_TRY(parseCameraArgument(value, camera));
             command.camera = camera;
             return {};
         }},
        {"--path", "FILE.path", "a camera path",
         [&](const std::string& value) -> Status {
             command.path = value;
             return {};
         }},
        {"--tau", "T", "the screen-space error allowed (pixels)", number(tau, 0.01, 1000)},
        {"--fov", "DEG", "vertical field of view (degrees)", number(fov, 1, 179)},
        {"--fps", "F", "frames per second of the path", number(fps, 0.001, 1000)},
        {"--size", "WxH", "the window (pixels)",
         [&](const std::string& value) -> Status {
             auto parsed = sizeIn(value, 16, 16384);
             TERRAIN_TRY(parsed);
             size = *parsed;
             return {};
         }},
        {"--levels", "", "bounds against measured errors per level", set(command.levels)},
        {"--pops", "", "the pops between consecutive frames", set(command.pops)},
        {"--oracle", "", "the fewest whole nodes within tau; =B: B x B blocks",
         [&](const std::string& value) -> Status {
             command.oracle = true;
             if (!value.empty()) {
                 auto blocks = wholeNumberIn(value, 1, 64, "blocks");
                 TERRAIN_TRY(blocks);
                 command.oracleBlocks = static_cast<int>(*blocks);
             }
             return {};
         },
         true},
    };
    line.positional = [&](const std::string& argument) -> Status {
        if (!argument.ends_with(".cfg")) {
            return makeError("'", argument, "' is neither a CONFIG.cfg nor an option (the map comes first)");
        }
        viewerArgs.push_back(argument);
        return {};
    };
    TERRAIN_TRY(line.parse(args));
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

namespace {

/// Per level, the selected nodes' bounds against their measured errors (--levels).
struct LevelFigures {
    std::size_t nodes = 0, held = 0, dynamicNodes = 0;
    double sumBound = 0.0, sumMeasured = 0.0, worstRatio = 0.0;
    NodeId worst;
    std::vector<double> ratios;
};

/// The measured frames' figures, summed over the frames.
class ErrorTally {
public:
    explicit ErrorTally(double tau) : mTau(tau), mLevels(NodeId::kMaxLevel + 1) {}

    /// Adds a frame of `triangles` drawn.
    void add(const FrameError& e, std::uint64_t triangles)
    {
        for (float px : e.pixels) {
            mHistogram.add(px);
        }
        mWorst = std::max(mWorst, e.maxPixels);
        mSum += e.meanPixels * static_cast<double>(e.points);
        mPoints += e.points;
        mRefined += e.refined;
        mRefinedWithinTau += e.refinedWithinTau;
        mFramesOverTau += e.maxPixels > mTau ? 1 : 0;
        mTriangles.push_back(triangles);
        for (const auto& b : e.bounds) {
            LevelFigures& l = mLevels[static_cast<std::size_t>(b.id.level)];
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
    }
    /// Adds a frame's oracle selection of `triangles`.
    void addOracle(const OracleSelection& oracle, std::uint64_t triangles)
    {
        mOracleTriangles.push_back(triangles);
        mOracleWorst = std::max(mOracleWorst, oracle.maxPixels);
        mOracleRefined += oracle.refined.size();
        mOracleRefinedWithinTau += oracle.refinedWithinTau;
    }
    std::uint64_t lastTriangles() const { return mTriangles.back(); }

    void printLevels(std::FILE* out)
    {
        std::fprintf(out,
                     "# selected nodes per level: bound delta_c against the measured distance of the node's own "
                     "surface from the reference\n");
        std::fprintf(out,
                     "# level  nodes  dynamic  mean bound(m)  mean measured(m)  measured/bound: median, max  "
                     "bound held  worst node\n");
        for (std::size_t level = 0; level < mLevels.size(); ++level) {
            LevelFigures& l = mLevels[level];
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

    /// The summary lines; `oracleBlocks` as --oracle=B, negative without --oracle.
    void printSummary(std::FILE* out, std::uint64_t groupsMade, int oracleBlocks) const
    {
        const auto [median, most] = medianAndMax(mTriangles);
        const std::size_t frames = mTriangles.size();
        std::fprintf(out, "frames over tau: %zu of %zu\n", mFramesOverTau, frames);
        std::fprintf(out, "refinements that bought nothing: %llu of %llu refined nodes (%.1f%%)\n",
                     static_cast<unsigned long long>(mRefinedWithinTau), static_cast<unsigned long long>(mRefined),
                     percent(mRefinedWithinTau, mRefined));
        std::fprintf(out, "reference: %llu node groups made\n", static_cast<unsigned long long>(groupsMade));
        if (oracleBlocks >= 0) {
            const auto [oracleMedian, oracleMost] = medianAndMax(mOracleTriangles);
            const std::string kind = oracleBlocks == 0
                                         ? std::string("measured errors in pixels")
                                         : std::to_string(oracleBlocks) + "x" + std::to_string(oracleBlocks) +
                                               " blocks' measured metres at their bound distance";
            std::fprintf(
                out,
                "oracle (%s, morph 1): triangles median %llu, max %llu, max %.3f px; the selection "
                "draws %.2fx the oracle's median; its refinements that bought nothing: %llu of %llu (%.1f%%)\n",
                kind.c_str(), static_cast<unsigned long long>(oracleMedian),
                static_cast<unsigned long long>(oracleMost), mOracleWorst,
                oracleMedian ? static_cast<double>(median) / static_cast<double>(oracleMedian) : 0.0,
                static_cast<unsigned long long>(mOracleRefinedWithinTau),
                static_cast<unsigned long long>(mOracleRefined), percent(mOracleRefinedWithinTau, mOracleRefined));
        }
        std::fprintf(out,
                     "error: max %.3f px, p99 %.3f px, mean %.4f px over %zu frames; triangles median %llu, max %llu\n",
                     mWorst, mHistogram.percentile(0.99), mPoints ? mSum / static_cast<double>(mPoints) : 0.0, frames,
                     static_cast<unsigned long long>(median), static_cast<unsigned long long>(most));
    }

    static std::pair<std::uint64_t, std::uint64_t> medianAndMax(std::vector<std::uint64_t> values)
    {
        if (values.empty()) {
            return {0, 0};
        }
        std::sort(values.begin(), values.end());
        return {values[(values.size() - 1) / 2], values.back()};
    }

private:
    static double percent(std::uint64_t part, std::uint64_t whole)
    {
        return whole ? 100.0 * static_cast<double>(part) / static_cast<double>(whole) : 0.0;
    }

    double mTau;
    PixelHistogram mHistogram;
    std::vector<std::uint64_t> mTriangles, mOracleTriangles;
    double mWorst = 0.0, mSum = 0.0, mOracleWorst = 0.0;
    std::uint64_t mPoints = 0, mRefined = 0, mRefinedWithinTau = 0, mOracleRefined = 0, mOracleRefinedWithinTau = 0;
    std::size_t mFramesOverTau = 0;
    std::vector<LevelFigures> mLevels;
};

/// --pops: the tessellation blocks' level switches between consecutive frames, each at its size on screen.
class PopsTally {
public:
    /// The drawn nodes' blocks for `camera`, against the previous frame's; returns the frame's largest pop in pixels
    /// and counts its triangles.
    double frame(const ViewerSession& session, const Camera& camera)
    {
        const MapHeader& header = session.header();
        const int n = static_cast<int>(header.chunkSize);
        std::unordered_map<std::uint64_t, BlockLevels> now;
        std::uint64_t drawnTriangles = 0;
        const VerticalSegmentProjector projector(camera);
        double framePop = 0.0;
        for (const DrawnNode& drawn : session.drawList().nodes) {
            const SelectedNode& selected = drawn.selected;
            const NodeData& node = *drawn.node;
            drawnTriangles += drawn.levels.triangles();
            if (auto it = mPrevious.find(selected.id.key()); it != mPrevious.end()) {
                const std::vector<float> samples =
                    morphedSamples(node, n, selected.id.isRoot() ? 1.0f : selected.morph);
                mSwitches.clear();
                levelSwitches(samples, n, it->second, drawn.levels, mSwitches);
                const double spacing = selected.size / (n - 1);
                for (const LevelSwitch& w : mSwitches) {
                    const double x = camera.position.x + selected.cameraRelativeOrigin.x + w.lx * spacing;
                    const double y = camera.position.y + selected.cameraRelativeOrigin.y + w.ly * spacing;
                    const double z = header.heightOffset + nodeSurfaceAt(node, n, w.lx, w.ly);
                    const double px = projector.pixels(x, y, z, w.metres);
                    if (px >= 0.0) {
                        mPops.push_back(static_cast<float>(px));
                        framePop = std::max(framePop, px);
                    }
                }
            }
            now.emplace(selected.id.key(), drawn.levels);
        }
        mPrevious = std::move(now);
        mTriangles.push_back(drawnTriangles);
        return framePop;
    }
    std::uint64_t lastTriangles() const { return mTriangles.back(); }

    void printSummary(std::FILE* out, double blockPixels)
    {
        std::sort(mPops.begin(), mPops.end());
        auto at = [&](double share) {
            return mPops.empty() ? 0.0 : double{mPops[static_cast<std::size_t>(share * double(mPops.size() - 1))]};
        };
        const auto [median, most] = ErrorTally::medianAndMax(mTriangles);
        std::fprintf(out,
                     "pops: %zu points of switched blocks in %zu frames; largest %.3f px, p99 %.3f px, median %.3f px "
                     "(blocks' budget %g px); triangles median %llu, max %llu\n",
                     mPops.size(), mTriangles.size(), at(1.0), at(0.99), at(0.5), blockPixels,
                     static_cast<unsigned long long>(median), static_cast<unsigned long long>(most));
    }

private:
    std::unordered_map<std::uint64_t, BlockLevels> mPrevious;
    std::vector<LevelSwitch> mSwitches;
    std::vector<float> mPops;  // px
    std::vector<std::uint64_t> mTriangles;
};

/// Frame `frame`'s camera: the path's at its time `t`, or --camera's. Errors: a camera not over the terrain. A
/// camera below it is measured all the same (the viewer draws it so), but said: the figures are of the underside.
Expected<Camera> frameCamera(const MapFile& map, const ErrorCommand& command, const std::optional<CameraPath>& path,
                             std::size_t frame, double t, std::FILE* err, bool& below)
{
    Camera camera = command.lens;
    if (path) {
        path->evaluate(t).applyTo(camera);
    } else {
        camera.position = command.camera->position;
        camera.yaw = command.camera->yaw;
        camera.pitch = command.camera->pitch;
    }
    below = false;
    auto ground = staticHeightAt(map, camera.position.x, camera.position.y);
    if (!ground.ok()) {
        return makeError(
            path ? command.path.string() + ": frame " + std::to_string(frame) + " (t = " + std::to_string(t) + " s): "
                 : std::string("--camera: "),
            "the camera is not over the terrain: ", ground.error().message);
    }
    if (camera.position.z < ground->height) {
        below = true;
        std::fprintf(err, "tengine-tool: warning: frame %zu (t = %.2f s): the camera is %.1f m below the terrain\n",
                     frame, t, ground->height - camera.position.z);
    }
    return camera;
}

/// The session of the measurement and the camera path (if any); errors are printed.
struct Measurement {
    std::unique_ptr<ViewerSession> session;
    std::optional<CameraPath> path;
};

Expected<Measurement> openMeasurement(const MapFile& map, const ErrorCommand& command,
                                      const std::filesystem::path& builtInMaterials, std::FILE* err)
{
    for (const auto& warning : command.warnings) {
        std::fprintf(err, "tengine-tool: warning: %s\n", warning.c_str());
    }
    // Warnings are printed as they come; a load error ends the measurement after the frame that met it.
    auto printWarnings = [err](const std::string& message) {
        if (message.starts_with("warning: ")) {
            std::fprintf(err, "tengine-tool: %s\n", message.c_str());
        }
    };
    Measurement m;
    auto session = ViewerSession::open(command.options, builtInMaterials, SessionUse::Measure, printWarnings, &map);
    TERRAIN_TRY(session);
    m.session = std::move(session).value();
    auto started = m.session->startStreaming(GlCapabilities{});
    TERRAIN_TRY(started);
    if (!command.path.empty()) {
        auto loaded = CameraPath::load(command.path);
        TERRAIN_TRY(loaded);
        m.path = std::move(loaded).value();
    }
    if (command.pops && !command.options.tessellation) {
        return makeError(
            "--pops measures the tessellation blocks' level switches: --set render_mode=tessellation "
            "(chunks morph every switch, eq. 3.5)");
    }
    return m;
}

}  // namespace

int runErrorCommand(const MapFile& map, const ErrorCommand& command, const std::filesystem::path& builtInMaterials,
                    std::FILE* out, std::FILE* err)
{
    auto fail = [&](const std::string& message) {
        std::fprintf(err, "tengine-tool: error: %s\n", message.c_str());
        return 1;
    };
    const TengineOptions& o = command.options;
    auto opened = openMeasurement(map, command, builtInMaterials, err);
    if (!opened.ok()) {
        return fail(opened.error().message);
    }
    ViewerSession& session = *opened->session;
    const std::optional<CameraPath>& path = opened->path;
    const double tau = o.lodError;
    const std::size_t frames =
        path ? static_cast<std::size_t>(std::floor(path->duration() * command.fps + 1e-9)) + 1 : std::size_t{1};
    const auto trianglesPerNode =
        static_cast<std::uint64_t>(trianglesPerChunk(static_cast<int>(session.header().chunkSize)));
    std::fprintf(out,
                 "# tau %g px, %dx%d, fov %g deg, detail %s; reference: refined until a level changes it by "
                 "< %g px\n",
                 tau, command.lens.viewportWidth, command.lens.viewportHeight, o.cameraFov,
                 session.synthesizer() ? "on" : "off", tau / 8.0);
    std::fprintf(out, "# %s\n", session.cache().description.c_str());
    std::fprintf(out, command.pops ? "# frame  time(s)  largest pop(px)  triangles  nodes\n"
                                   : "# frame  time(s)  max(px)  p99(px)  mean(px)  triangles  nodes  refined  "
                                     "within-tau  worst: node, metres\n");
    ErrorTally tally(tau);
    PopsTally pops;
    std::size_t framesShort = 0, framesBelow = 0;
    for (std::size_t frame = 0; frame < frames; ++frame) {
        const double t = path ? path->startTime() + static_cast<double>(frame) / command.fps : 0.0;
        bool below = false;
        auto camera = frameCamera(map, command, path, frame, t, err, below);
        if (!camera.ok()) {
            return fail(camera.error().message);
        }
        framesBelow += below ? 1 : 0;
        const FrameStats stats = session.advance(*camera, t, 0.0, Settle::Complete);
        if (session.loadErrors() > 0) {
            return fail(session.firstLoadError());
        }
        framesShort += stats.deferred > 0 ? 1 : 0;
        if (command.pops) {
            const double framePop = pops.frame(session, *camera);
            std::fprintf(out, "%7zu %8.2f %8.3f %10llu %6zu\n", frame, t, framePop,
                         static_cast<unsigned long long>(pops.lastTriangles()), session.drawnSelection().nodes.size());
            continue;
        }
        auto measured = session.measureDrawn(*camera);
        if (!measured.ok()) {
            return fail(measured.error().message);
        }
        const FrameError& e = *measured;
        // The meter chose the blocks' levels as the renderer does: its count is what tessellation draws.
        tally.add(e, session.tessellation() ? e.tessellatedTriangles : e.nodes * trianglesPerNode);
        std::fprintf(out, "%7zu %8.2f %8.3f %8.3f %9.4f %10llu %6zu %8zu %11zu  %s %.3f\n", frame, t, e.maxPixels,
                     e.p99Pixels, e.meanPixels, static_cast<unsigned long long>(tally.lastTriangles()), e.nodes,
                     e.refined, e.refinedWithinTau, e.worstNode.toString().c_str(), e.maxMetres);
        if (command.oracle) {
            auto oracle = session.meter()->oracle(*camera, tau, command.oracleBlocks);
            if (!oracle.ok()) {
                return fail(oracle.error().message);
            }
            tally.addOracle(*oracle, oracle->nodes.size() * trianglesPerNode);
            std::fprintf(out,
                         "        oracle: %zu nodes, %llu triangles, max %.3f px, %zu refined, %zu within tau, %zu "
                         "over tau\n",
                         oracle->nodes.size(), static_cast<unsigned long long>(oracle->nodes.size() * trianglesPerNode),
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
                     framesShort, framesShort == 1 ? "" : "s", session.cache().nodes);
    }
    if (command.pops) {
        pops.printSummary(out, session.blockPixels());
        return 0;
    }
    if (command.levels) {
        tally.printLevels(out);
    }
    tally.printSummary(out, session.meter()->groupsMade(), command.oracle ? command.oracleBlocks : -1);
    return 0;
}

}  // namespace terrain
