// Runtime core figures (paper 3.2.14-3.2.15): static node decode time, nodes per second through the node server with
// 1 and 2 workers, and memory over a long camera path on a large map with a bounded cache.
//
//   build/tests/StreamBench                      (TERRAIN_BENCH_STREAM_SIZE=2049 for a quick run)
//
// The map is generated once (8193 x 8193 by default) into the temp directory and reused.
#include "core/Memory.h"
#include "lod/CameraPath.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "quadtree/QuadtreeBuilder.h"

#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>

namespace {

using namespace terrain;

int mapSize()
{
    const char* env = std::getenv("TERRAIN_BENCH_STREAM_SIZE");
    return env ? std::atoi(env) : 8193;
}

/// Builds (once) a rolling, ridged terrain map of size x size samples at 10 m spacing.
const MapFile& benchMap()
{
    static std::unique_ptr<MapFile> map = [] {
        const int size = mapSize();
        auto path = std::filesystem::temp_directory_path() / ("stream-bench-" + std::to_string(size) + ".map");
        if (!std::filesystem::exists(path)) {
            HeightField field;
            field.width = field.height = size;
            field.samples.resize(static_cast<std::size_t>(size) * size);
            for (int j = 0; j < size; ++j) {
                for (int i = 0; i < size; ++i) {
                    double h = 2000 + 800 * std::sin(i * 0.0021) * std::cos(j * 0.0017) +
                               250 * (1 - 2 * std::abs(std::sin(i * 0.013 + j * 0.007))) +
                               40 * std::sin(i * 0.11) * std::sin(j * 0.09);
                    field.at(i, j) = static_cast<float>(std::round(h));
                }
            }
            BuildOptions options;
            options.spacing = 10.0;
            options.threads = 2;
            auto built = buildMap(std::move(field), options, path);
            if (!built.ok()) {
                std::fprintf(stderr, "%s\n", built.error().message.c_str());
                std::exit(1);
            }
        }
        // Stream reads: a mapping would count the touched pages of the file as resident memory.
        auto opened = MapFile::open(path, ReaderKind::Stream);
        if (!opened.ok()) {
            std::fprintf(stderr, "%s\n", opened.error().message.c_str());
            std::exit(1);
        }
        return std::move(opened.value());
    }();
    return *map;
}

/// A long low flight: four laps of a spiral from near the centre out to near the edge, 2900 m up (the
/// terrain spans about 950 .. 3050 m), looking along the track and a little down.
CameraPath longPath(const MapFile& map)
{
    const double size = map.header().nodeSizeAt(0);
    std::vector<CameraKeyframe> keys;
    const int steps = 192;
    for (int k = 0; k <= steps; ++k) {
        const double a = 2 * std::numbers::pi * k / 48;
        const double r = size * (0.05 + 0.4 * k / steps);
        CameraKeyframe key;
        key.time = k * 10.0;
        key.position = {size / 2 + r * std::cos(a), size / 2 + r * std::sin(a), 2900.0};
        key.yaw = -a;  // roughly along the track
        key.pitch = -0.15;
        keys.push_back(key);
    }
    return CameraPath::fromKeyframes(keys, "long flight").value();
}

void BM_DecodeStaticNode(benchmark::State& state)
{
    const MapFile& map = benchMap();
    // Decode every child group of one mid-level parent repeatedly.
    auto parent = map.loadPath({3, 3, 4});
    if (!parent.ok()) {
        state.SkipWithError(parent.error().message.c_str());
        return;
    }
    int q = 0;
    for (auto _ : state) {
        auto node = map.loadNode(NodeId{3, 3, 4}.child(q), parent->heights);
        benchmark::DoNotOptimize(node);
        q = (q + 1) & 3;
    }
    state.counters["nodes_per_s"] =
        benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_DecodeStaticNode)->Unit(benchmark::kMicrosecond);

void BM_ServerThroughput(benchmark::State& state)
{
    const MapFile& map = benchMap();
    TerrainNodeSource source(map, {});
    const int workers = static_cast<int>(state.range(0));
    // Every group of levels 0..4 requested at once; the server loads them nearest first.
    std::vector<NodePtr> parents;
    {
        auto root = source.loadRoot();
        parents.push_back(root.value());
        for (std::size_t i = 0; i < parents.size() && parents.size() < 341; ++i) {
            if (!parents[i]->hasChildren) {
                continue;
            }
            auto children = source.loadChildren(*parents[i]);
            for (auto& child : children.value()) {
                parents.push_back(child);
            }
        }
    }
    std::uint64_t groups = 0;
    for (auto _ : state) {
        NodeServer server(source, {workers, parents.size()});
        std::vector<LoadRequest> requests;
        for (std::size_t i = 0; i < parents.size(); ++i) {
            if (parents[i]->hasChildren) {
                requests.push_back({parents[i], static_cast<double>(i)});
            }
        }
        server.submit(requests);
        server.drain();
        groups += server.takeCompleted().size();
    }
    state.counters["nodes_per_s"] = benchmark::Counter(4.0 * static_cast<double>(groups), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ServerThroughput)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_StreamLongPath(benchmark::State& state)
{
    const MapFile& map = benchMap();
    const auto cacheSize = static_cast<std::size_t>(state.range(0));
    TerrainNodeSource source(map, {});
    const CameraPath path = longPath(map);
    for (auto _ : state) {
        StreamerOptions options;
        options.cacheSize = cacheSize;
        options.workers = 2;
        auto streamer = TerrainStreamer::create(source, extentOf(map.header()), options).value();
        Camera camera;
        std::size_t peakNodes = 0;
        std::vector<double> rssBySegment;
        const int frames = static_cast<int>(path.duration() * 30);
        for (int frame = 0; frame <= frames; ++frame) {
            path.evaluate(frame / 30.0).applyTo(camera);
            streamer->update(camera, 2.0);
            streamer->drain();  // loads keep up with the camera: the worst case for memory
            peakNodes = std::max(peakNodes, streamer->cache().size());
            if (frame % (frames / 8) == 0) {
                rssBySegment.push_back(static_cast<double>(currentResidentBytes()) / (1 << 20));
            }
        }
        state.counters["cache_size"] = static_cast<double>(cacheSize);
        state.counters["peak_nodes"] = static_cast<double>(peakNodes);
        state.counters["evictions"] = static_cast<double>(streamer->cache().evictions());
        state.counters["groups_loaded"] = static_cast<double>(streamer->serverStats().completed);
        for (std::size_t i = 0; i < rssBySegment.size(); ++i) {
            state.counters["rss_MiB_at_" + std::to_string(i) + "q"] = rssBySegment[i];
        }
    }
}
BENCHMARK(BM_StreamLongPath)->Arg(256)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
