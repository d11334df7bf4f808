// prep throughput and peak memory (paper 4.1.1): builds a map from a generated 4097 x 4097 raw 16-bit height
// field and prints million input samples per second and peak resident memory against the input's size.
//
//   build/tests/PrepBench [--benchmark_filter=...]       (TERRAIN_BENCH_SIZE=1025 for a quick run)
//
// Targets: >= 10 million samples per second on the 2-core CI machine, peak memory <= 2x the input in memory.
#include "core/Memory.h"
#include "core/ParallelFor.h"
#include "heightfield/HeightFieldIo.h"
#include "quadtree/QuadtreeBuilder.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <vector>

namespace {

using namespace terrain;

int benchSize()
{
    const char* env = std::getenv("TERRAIN_BENCH_SIZE");
    return env ? std::atoi(env) : 4097;
}

/// Writes a size x size raw little-endian uint16 terrain: a sum of randomly oriented ridged sine octaves,
/// rough enough to be a fair compression and error workload. Streams rows so it never holds a float grid.
std::filesystem::path generateRaw(int size)
{
    auto path = std::filesystem::temp_directory_path() / ("prep-bench-" + std::to_string(size) + ".raw");
    if (std::filesystem::exists(path) && std::filesystem::file_size(path) == std::uint64_t(size) * size * 2) {
        return path;
    }
    std::mt19937 random(12345);
    std::uniform_real_distribution<double> angle(0, 2 * M_PI), phase(0, 2 * M_PI);
    struct Octave {
        double kx, ky, phase, amplitude;
    };
    std::vector<Octave> octaves;
    double wavelength = size * 0.7, amplitude = 9000;
    for (int i = 0; i < 12; ++i) {
        double a = angle(random);
        octaves.push_back(
            {std::cos(a) * 2 * M_PI / wavelength, std::sin(a) * 2 * M_PI / wavelength, phase(random), amplitude});
        wavelength *= 0.55;
        amplitude *= 0.5;
    }
    std::ofstream out(path, std::ios::binary);
    std::vector<std::uint8_t> row(static_cast<std::size_t>(size) * 2);
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
            double h = 30000;
            for (const auto& o : octaves) {
                h += o.amplitude * (1.0 - 2.0 * std::abs(std::sin(o.kx * x + o.ky * y + o.phase)));
            }
            auto v = static_cast<std::uint16_t>(std::clamp(h, 0.0, 65535.0));
            row[2 * x] = static_cast<std::uint8_t>(v);
            row[2 * x + 1] = static_cast<std::uint8_t>(v >> 8);
        }
        out.write(reinterpret_cast<const char*>(row.data()), static_cast<std::streamsize>(row.size()));
    }
    return path;
}

void BM_PrepBuild(benchmark::State& state)
{
    const int size = benchSize();
    const auto input = generateRaw(size);
    const auto output = std::filesystem::temp_directory_path() / "prep-bench.map";
    const double samples = double(size) * size;
    const double inputBytes = samples * sizeof(float);  // the height field as the reader holds it
    BuildReport report;
    double seconds = 0;
    for (auto _ : state) {
        auto start = std::chrono::steady_clock::now();
        HeightFieldReadOptions read;
        read.rawWidth = size;
        read.rawHeight = size;
        auto field = readHeightField(input, read);
        if (!field.ok()) {
            state.SkipWithError(field.error().message.c_str());
            return;
        }
        BuildOptions options;
        options.spacing = 10.0;
        options.threads = static_cast<int>(state.range(0));
        auto built = buildMap(std::move(field.value()), options, output);
        if (!built.ok()) {
            state.SkipWithError(built.error().message.c_str());
            return;
        }
        seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        report = built.value();
    }
    state.counters["Msamples_per_s"] = samples / seconds / 1e6;
    state.counters["input_MiB"] = inputBytes / (1 << 20);
    state.counters["peak_rss_MiB"] = double(peakResidentBytes()) / (1 << 20);
    state.counters["peak_over_input"] = double(peakResidentBytes()) / inputBytes;
    state.counters["height_bits_per_sample"] = 8.0 * double(report.heightBytes) / samples;
    state.counters["nodes"] = double(report.nodes);
    std::filesystem::remove(output);
}
BENCHMARK(BM_PrepBuild)->Arg(2)->Arg(1)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
