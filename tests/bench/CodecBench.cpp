// Height codecs side by side on the bundled terrain (issue 17): the residual coding (Kobbelt prediction from
// the parent, lossless and --max-error 1, 2, 5 m) and seed 003's fractal coding (prep --height-codec pifs).
// Per codec: height bits per input sample, the largest error of any stored sample of any node against the
// input (measured here from the PNG) and the mean at the leaves, prep's time, and the decode time per node
// (the height stream alone, parents already decoded, as the node server's loaders do it).
//
//   build/tests/CodecBench [--benchmark_filter=...]
//
// Prints Google Benchmark's table (decode time) and then one table of all figures.
#include "heightfield/HeightFieldIo.h"
#include "quadtree/HeightCodec.h"
#include "quadtree/MapFile.h"
#include "quadtree/PifsCodec.h"
#include "quadtree/QuadtreeBuilder.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>

namespace {

using namespace terrain;

struct Codec {
    const char* name;
    std::uint32_t coding;
    double maxError;
};
constexpr Codec kCodecs[] = {
    {"residual lossless", kHeightCodingKobbeltResidual, 0.0},
    {"residual --max-error 1", kHeightCodingKobbeltResidual, 1.0},
    {"residual --max-error 2", kHeightCodingKobbeltResidual, 2.0},
    {"residual --max-error 5", kHeightCodingKobbeltResidual, 5.0},
    {"pifs", kHeightCodingPifs, 0.0},
};

/// One codec's map of the bundled terrain, its figures and every node's height stream and parent window.
struct Built {
    std::unique_ptr<MapFile> map;
    double buildSeconds = 0.0;
    double bitsPerInputSample = 0.0;
    double maxError = 0.0;       ///< metres, any stored sample of any node
    double meanLeafError = 0.0;  ///< metres, over the leaves' squares
    std::map<std::uint64_t, std::vector<std::uint8_t>> streams;
    std::map<std::uint64_t, std::vector<std::uint16_t>> heights;
};

const HeightField& input()
{
    static const HeightField field = [] {
        auto read = readHeightField(std::filesystem::path(TERRAIN_DEMO_DATA_DIR) / "trinidad_co_srtm3_crop_1025.png");
        if (!read.ok()) {
            std::fprintf(stderr, "%s\n", read.error().message.c_str());
            std::exit(1);
        }
        return read.value();
    }();
    return field;
}

Built& built(const Codec& codec)
{
    static std::map<std::string, Built> cache;
    auto it = cache.find(codec.name);
    if (it != cache.end()) {
        return it->second;
    }
    Built& b = cache[codec.name];
    BuildOptions options;
    options.spacing = 90.0;
    options.threads = 2;
    options.maxError = codec.maxError;
    options.heightCoding = codec.coding;
    const auto path = std::filesystem::temp_directory_path() /
                      ("codec-bench-" + std::to_string(codec.coding) + "-" + std::to_string(codec.maxError) + ".map");
    auto report = buildMap(input(), options, path);
    if (!report.ok()) {
        std::fprintf(stderr, "%s\n", report.error().message.c_str());
        std::exit(1);
    }
    b.buildSeconds = report->seconds;
    b.bitsPerInputSample =
        8.0 * static_cast<double>(report->heightBytes) / (static_cast<double>(input().width) * input().height);
    auto map = MapFile::open(path, ReaderKind::Stream);
    if (!map.ok()) {
        std::fprintf(stderr, "%s\n", map.error().message.c_str());
        std::exit(1);
    }
    b.map = std::move(map.value());
    const MapHeader& h = b.map->header();
    const int n = static_cast<int>(h.chunkSize), w = h.windowSize();
    double leafSum = 0.0;
    std::size_t leafSamples = 0;
    for (const DirectoryEntry& entry : b.map->directory()) {  // parents first
        auto payload = b.map->readPayload(entry);
        auto node = b.map->loadNode(
            entry.id, entry.id.isRoot() ? std::span<const std::uint16_t>() : b.heights.at(entry.id.parent().key()));
        if (!payload.ok() || !node.ok()) {
            std::fprintf(stderr, "%s: node %s does not decode\n", path.c_str(), entry.id.toString().c_str());
            std::exit(1);
        }
        payload->resize(entry.heightBytes);
        b.streams[entry.id.key()] = std::move(payload.value());
        const auto stride = std::int64_t{1} << (h.levels - 1 - static_cast<std::uint32_t>(entry.id.level));
        const auto last = static_cast<std::int64_t>(h.levelGridSize(entry.id.level)) - 1;
        for (int v = -kBorder; v < n + kBorder; ++v) {
            for (int u = -kBorder; u < n + kBorder; ++u) {
                const std::int64_t gx = std::int64_t{entry.id.x} * (n - 1) + u;
                const std::int64_t gy = std::int64_t{entry.id.y} * (n - 1) + v;
                if (gx < 0 || gy < 0 || gx > last || gy > last) {
                    continue;
                }
                const int ix = static_cast<int>(std::min<std::int64_t>(gx * stride, input().width - 1));
                const int iy = static_cast<int>(std::min<std::int64_t>(gy * stride, input().height - 1));
                const double stored =
                    h.heightOf(node->heights[static_cast<std::size_t>(v + kBorder) * w + u + kBorder]);
                const double error = std::abs(stored - input().at(ix, iy));
                b.maxError = std::max(b.maxError, error);
                if (!entry.hasChildren && u >= 0 && v >= 0 && u < n && v < n) {
                    leafSum += error;
                    ++leafSamples;
                }
            }
        }
        b.heights[entry.id.key()] = std::move(node->heights);
    }
    b.meanLeafError = leafSum / static_cast<double>(leafSamples);
    return b;
}

void BM_DecodeHeights(benchmark::State& state)
{
    const Codec& codec = kCodecs[state.range(0)];
    Built& b = built(codec);
    const MapHeader& h = b.map->header();
    const NodeWindow& geometry = b.map->window();
    std::vector<std::uint16_t> window(geometry.sampleCount());
    std::size_t nodes = 0;
    for (auto _ : state) {
        for (const DirectoryEntry& entry : b.map->directory()) {
            const std::span<const std::uint16_t> parent =
                entry.id.isRoot() ? std::span<const std::uint16_t>() : b.heights.at(entry.id.parent().key());
            const auto& stream = b.streams.at(entry.id.key());
            auto status = h.heightCoding == kHeightCodingPifs
                              ? decodePifsHeights(geometry, entry.id, stream, parent, window)
                              : decodeNodeHeights(geometry, entry.id, stream, parent, h.quantizerBin, window);
            if (!status.ok()) {
                state.SkipWithError(status.error().message.c_str());
                return;
            }
            benchmark::DoNotOptimize(window.data());
            ++nodes;
        }
    }
    const auto perNode = static_cast<double>(nodes);
    state.counters["us_per_node"] =
        benchmark::Counter(perNode, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
    state.counters["bits_per_sample"] = b.bitsPerInputSample;
    state.counters["max_error_m"] = b.maxError;
    state.SetLabel(codec.name);
}
BENCHMARK(BM_DecodeHeights)->DenseRange(0, std::size(kCodecs) - 1)->Unit(benchmark::kMillisecond);

/// The figures as one table, decode time measured again plainly (median of 9 passes over all nodes).
void printTable()
{
    std::printf("\nbundled terrain (trinidad_co_srtm3_crop_1025.png, 1025 x 1025 at 90 m, chunks of 65, 341 nodes)\n");
    std::printf("%-24s %10s %12s %15s %10s %12s\n", "codec", "bits/sample", "max error m", "leaf mean err m", "prep s",
                "decode us/node");
    for (const Codec& codec : kCodecs) {
        Built& b = built(codec);
        const MapHeader& h = b.map->header();
        const NodeWindow& geometry = b.map->window();
        std::vector<std::uint16_t> window(geometry.sampleCount());
        std::vector<double> passes;
        for (int pass = 0; pass < 9; ++pass) {
            const auto start = std::chrono::steady_clock::now();
            for (const DirectoryEntry& entry : b.map->directory()) {
                const std::span<const std::uint16_t> parent =
                    entry.id.isRoot() ? std::span<const std::uint16_t>() : b.heights.at(entry.id.parent().key());
                const auto& stream = b.streams.at(entry.id.key());
                (void)(h.heightCoding == kHeightCodingPifs
                           ? decodePifsHeights(geometry, entry.id, stream, parent, window)
                           : decodeNodeHeights(geometry, entry.id, stream, parent, h.quantizerBin, window));
            }
            passes.push_back(
                std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count() /
                static_cast<double>(b.map->directory().size()));
        }
        std::sort(passes.begin(), passes.end());
        std::printf("%-24s %10.3f %12.2f %15.3f %10.2f %12.1f\n", codec.name, b.bitsPerInputSample, b.maxError,
                    b.meanLeafError, b.buildSeconds, passes[passes.size() / 2]);
    }
}

}  // namespace

int main(int argc, char** argv)
{
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    printTable();
    return 0;
}
