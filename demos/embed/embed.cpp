// The engine as a library: opens a map, flies a camera path through the streamer as the viewer does
// (selection at tau pixels, static nodes from disk, dynamic nodes synthesized below the data), and walks a
// person along the flight's ground track on the surface the viewer draws, with height queries.
//
//   embed MAP PATH [--tau PIXELS] [--fps N] [--walk METRES]
//
// The streamer's loads are drained after every frame, so each frame sees what the one before it asked for
// (the viewer loads in the background instead). Prints per-frame figures and the walk; exits 1 on an error.
#include "apps/DetailSetup.h"
#include "apps/TengineOptions.h"
#include "core/Camera.h"
#include "core/Parse.h"
#include "lod/CameraPath.h"
#include "lod/HeightQuery.h"
#include "lod/LodSelector.h"
#include "lod/NodeMemory.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "quadtree/ChunkGeometry.h"
#include "quadtree/MapFile.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace {

int fail(const std::string& message)
{
    std::fprintf(stderr, "embed: %s\n", message.c_str());
    return 1;
}

}  // namespace

int main(int argc, char** argv)
{
    using namespace terrain;
    if (argc < 3) {
        std::fprintf(stderr, "usage: embed MAP PATH [--tau PIXELS] [--fps N] [--walk METRES]\n");
        return 2;
    }
    double tau = 2.0, fps = 30.0, walk = 600.0;
    for (int i = 3; i < argc; i += 2) {
        const std::string option = argv[i];
        if (i + 1 >= argc) {
            return fail(option + " needs a value");
        }
        double* target = option == "--tau" ? &tau : option == "--fps" ? &fps : option == "--walk" ? &walk : nullptr;
        if (target == nullptr) {
            return fail("unknown option '" + option + "'");
        }
        auto value = parseNumberIn(option, argv[i + 1], 0.01, 1e6);
        if (!value.ok()) {
            return fail(value.error().message);
        }
        *target = *value;
    }

    auto map = MapFile::open(argv[1], ReaderKind::Stream);
    if (!map.ok()) {
        return fail(map.error().message);
    }
    const MapHeader& header = (*map)->header();
    auto path = CameraPath::load(argv[2]);
    if (!path.ok()) {
        return fail(path.error().message);
    }

    // The viewer's defaults: detail synthesis on, the map's own materials or the built-in ones.
    TengineOptions options;
    std::vector<std::string> warnings;
    auto synthesizer = makeDetailSynthesizer(options, header, TENGINE_MATERIALS_DIR, warnings);
    for (const std::string& warning : warnings) {
        std::fprintf(stderr, "embed: warning: %s\n", warning.c_str());
    }
    if (!synthesizer.ok()) {
        return fail(synthesizer.error().message);
    }
    TerrainNodeSource source(**map, DetailPolicy{synthesizer->get(), options.lodMinimumSpacing});
    // The cache sized by memory as the viewer sizes it (memory_budget's default: lod/NodeMemory.h), for nodes
    // that take no GPU slot here: what the budget pays for at the root's CPU bytes (no node holds more).
    auto root = source.loadRoot();
    if (!root.ok()) {
        return fail(root.error().message);
    }
    StreamerOptions streamerOptions;
    streamerOptions.cacheSize =
        sizeCache(defaultMemoryBudget(physicalMemoryBytes()), residentBytes(**root), std::size_t{1} << 20).nodes;
    auto streamer = TerrainStreamer::create(source, extentOf(header), streamerOptions);
    if (!streamer.ok()) {
        return fail(streamer.error().message);
    }
    int loadErrors = 0;
    (*streamer)->onLoadError([&](const std::string& message) {
        ++loadErrors;
        std::fprintf(stderr, "embed: %s\n", message.c_str());
    });

    // The flight.
    Camera camera;
    const auto frames = static_cast<int>(std::floor(path->duration() * fps)) + 1;
    const std::int64_t perNode = trianglesPerChunk(static_cast<int>(header.chunkSize));
    std::int64_t triangles = 0, peakTriangles = 0;
    int deepest = 0, clearanceFrames = 0;
    double lowestClearance = 1e300;
    for (int frame = 0; frame < frames; ++frame) {
        path->evaluate(path->startTime() + frame / fps).applyTo(camera);
        (*streamer)->update(camera, tau);
        (*streamer)->drain();
        const auto& selected = (*streamer)->selection().nodes;
        const std::int64_t drawn = static_cast<std::int64_t>(selected.size()) * perNode;
        triangles += drawn;
        peakTriangles = std::max(peakTriangles, drawn);
        for (const auto& node : selected) {
            deepest = std::max(deepest, node.id.level);
        }
        // How high the camera flies above what is drawn below it (empty where nothing drawn covers it).
        if (auto ground = drawnHeightAt(**streamer, header, camera.position.x, camera.position.y)) {
            lowestClearance = std::min(lowestClearance, camera.position.z - *ground);
            ++clearanceFrames;
        }
    }
    std::printf(
        "flight   %d frames over %.1f s of %s at tau %.1f px: %.0f triangles a frame on average, %lld at "
        "most, nodes down to level %d (static levels 0-%u), %zu resident\n",
        frames, path->duration(), argv[2], tau, static_cast<double>(triangles) / frames,
        static_cast<long long>(peakTriangles), deepest, header.levels - 1, (*streamer)->cache().size());
    if (clearanceFrames > 0) {
        std::printf("         camera at least %.1f m above the drawn surface (%d frames over it)\n", lowestClearance,
                    clearanceFrames);
    }

    // The walk: 0.75 m strides along the flight's ground track, feet on the surface the viewer draws when it
    // refines to three levels below the data (static heights plus synthesized detail), eyes 1.7 m above.
    const int depth = static_cast<int>(header.levels) - 1 + 3;
    SurfaceSampler sampler(**map, source, depth);
    const auto& keys = path->keyframes();
    double walked = 0.0, climb = 0.0, descent = 0.0, lowest = 1e300, highest = -1e300, steepest = 0.0;
    std::optional<double> previous;
    for (std::size_t k = 0; k + 1 < keys.size() && walked < walk; ++k) {
        const double dx = keys[k + 1].position.x - keys[k].position.x, dy = keys[k + 1].position.y - keys[k].position.y;
        const double leg = std::hypot(dx, dy);
        for (double along = 0.0; along < leg && walked < walk; along += 0.75, walked += 0.75) {
            const double x = keys[k].position.x + dx * along / leg, y = keys[k].position.y + dy * along / leg;
            auto feet = sampler.at(x, y);
            if (!feet.ok()) {
                return fail("walk: " + feet.error().message);
            }
            lowest = std::min(lowest, feet->height);
            highest = std::max(highest, feet->height);
            if (previous) {
                const double rise = feet->height - *previous;
                (rise > 0 ? climb : descent) += std::abs(rise);
                steepest = std::max(steepest, std::abs(rise) / 0.75);
            }
            previous = feet->height;
        }
    }
    std::printf(
        "walk     %.0f m in 0.75 m strides on the surface at depth %d: feet from %.1f to %.1f m, %.1f m up "
        "and %.1f m down, steepest stride %.0f%%, eyes at %.1f m at the end\n",
        walked, depth, lowest, highest, climb, descent, 100.0 * steepest, previous.value_or(0.0) + 1.7);
    return loadErrors == 0 && previous ? 0 : 1;
}
