// Out-of-core prep (issue 15, part 4): builds a map from a generated 32769 x 32769 int16 GeoTIFF (1.07 G
// samples, tiled, deflate) within a memory budget and prints peak resident memory and million input samples
// per second. With TERRAIN_BENCH_COMPARE=1 it then builds the same input in memory and compares the files.
//
//   build/tests/OutOfCoreBench            (TERRAIN_BENCH_SIZE=8193 for a quicker run; TERRAIN_BENCH_MEMORY=1G)
//
// Targets: peak <= 2 GiB and >= 10 million samples per second on the 2-core CI machine. The input is made
// in a child process (its memory does not count) and kept in the temporary directory for the next run.
#include "core/Memory.h"
#include "core/Parse.h"
#include "heightfield/GdalRaster.h"
#include "heightfield/HeightRows.h"
#include "quadtree/QuadtreeBuilder.h"

#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace terrain;

int benchSize()
{
    const char* env = std::getenv("TERRAIN_BENCH_SIZE");
    return env ? std::atoi(env) : 32769;
}

/// A ridged terrain, separable per octave so a sample costs a few multiply-adds: sum over octaves of
/// a (1 - 2 |sin(kx x + p) sin(ky y + q)|), 11 octaves from 0.6 of the side down to ~4 samples.
bool writeTerrain(const std::filesystem::path& path, int size)
{
    GDALAllRegister();
    GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
    char** options = nullptr;
    options = CSLSetNameValue(options, "TILED", "YES");
    options = CSLSetNameValue(options, "BLOCKXSIZE", "256");
    options = CSLSetNameValue(options, "BLOCKYSIZE", "256");
    options = CSLSetNameValue(options, "COMPRESS", "DEFLATE");
    options = CSLSetNameValue(options, "ZLEVEL", "1");
    options = CSLSetNameValue(options, "NUM_THREADS", "ALL_CPUS");
    options = CSLSetNameValue(options, "BIGTIFF", "YES");
    GDALDataset* dataset = driver->Create(path.c_str(), size, size, 1, GDT_Int16, options);
    CSLDestroy(options);
    if (!dataset) {
        return false;
    }
    double transform[6] = {400000.0, 10.0, 0.0, 4200000.0 + 10.0 * size, 0.0, -10.0};
    dataset->SetGeoTransform(transform);
    OGRSpatialReference srs;
    srs.importFromEPSG(32613);
    dataset->SetSpatialRef(&srs);
    std::mt19937 random(12345);
    std::uniform_real_distribution<double> phase(0, 2 * M_PI), tilt(0.7, 1.4);
    constexpr int kOctaves = 11;
    std::vector<std::vector<float>> columns(kOctaves), rows(kOctaves);
    std::vector<float> amplitude(kOctaves);
    double wavelength = size * 0.6, a = 3000;
    for (int o = 0; o < kOctaves; ++o) {
        const double kx = 2 * M_PI / wavelength * tilt(random), ky = 2 * M_PI / wavelength * tilt(random);
        const double px = phase(random), py = phase(random);
        columns[o].resize(size);
        rows[o].resize(size);
        for (int i = 0; i < size; ++i) {
            columns[o][i] = static_cast<float>(std::sin(kx * i + px));
            rows[o][i] = static_cast<float>(std::sin(ky * i + py));
        }
        amplitude[o] = static_cast<float>(a);
        wavelength *= 0.52;
        a *= 0.5;
    }
    GDALRasterBand* band = dataset->GetRasterBand(1);
    const int strip = 256;
    std::vector<std::int16_t> samples(static_cast<std::size_t>(size) * strip);
    bool ok = true;
    for (int y0 = 0; y0 < size && ok; y0 += strip) {
        const int count = std::min(strip, size - y0);
        for (int r = 0; r < count; ++r) {
            for (int x = 0; x < size; ++x) {
                float h = 1500.0f;
                for (int o = 0; o < kOctaves; ++o) {
                    h += amplitude[o] * (1.0f - 2.0f * std::abs(columns[o][x] * rows[o][y0 + r]));
                }
                samples[static_cast<std::size_t>(r) * size + x] =
                    static_cast<std::int16_t>(std::clamp(h, -32000.0f, 32000.0f));
            }
        }
        ok = band->RasterIO(GF_Write, 0, y0, size, count, samples.data(), size, count, GDT_Int16, 0, 0, nullptr) ==
             CE_None;
    }
    GDALClose(dataset);
    return ok;
}

/// The input, made once in a child process so its memory is not the build's.
std::filesystem::path input(int size)
{
    const auto path = std::filesystem::temp_directory_path() / ("ooc-bench-" + std::to_string(size) + ".tif");
    if (std::filesystem::exists(path)) {
        return path;
    }
    const auto partial = path.string() + ".partial.tif";
    std::printf("generating %s (%d x %d int16, tiled deflate) ...\n", path.c_str(), size, size);
    std::fflush(stdout);
    const pid_t child = fork();
    if (child == 0) {
        _exit(writeTerrain(partial, size) ? 0 : 1);
    }
    int status = 0;
    waitpid(child, &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::fprintf(stderr, "cannot write %s\n", partial.c_str());
        std::exit(1);
    }
    std::filesystem::rename(partial, path);
    return path;
}

/// Samples /proc/self/status while a build runs: the peak of anonymous memory and of resident file pages
/// (the scratch grid is a shared file mapping; its dirty pages count as resident until released).
class ResidentSampler {
public:
    ResidentSampler()
        : mThread([this] {
              while (!mStop.load()) {
                  sample();
                  std::this_thread::sleep_for(std::chrono::milliseconds(5));
              }
          })
    {
    }
    ~ResidentSampler()
    {
        mStop = true;
        mThread.join();
    }
    std::uint64_t peakAnonymous() const { return mAnonymous.load(); }
    std::uint64_t peakFile() const { return mFile.load(); }

private:
    void sample()
    {
        std::ifstream status("/proc/self/status");
        std::string key;
        std::uint64_t kb = 0, anonymous = 0, file = 0;
        while (status >> key) {
            if (key == "RssAnon:" && status >> kb) {
                anonymous = kb << 10;
            } else if ((key == "RssFile:" || key == "RssShmem:") && status >> kb) {
                file += kb << 10;
            }
        }
        mAnonymous = std::max(mAnonymous.load(), anonymous);
        mFile = std::max(mFile.load(), file);
    }
    std::atomic<bool> mStop{false};
    std::atomic<std::uint64_t> mAnonymous{0}, mFile{0};
    std::thread mThread;
};

struct Run {
    BuildReport report;
    double seconds = 0;
};

Run build(const std::filesystem::path& path, const std::filesystem::path& output, std::uint64_t budget, bool outOfCore)
{
    const std::filesystem::path inputs[] = {path};
    auto raster = ElevationRaster::open(inputs);
    if (!raster.ok()) {
        std::fprintf(stderr, "%s\n", raster.error().message.c_str());
        std::exit(1);
    }
    RasterRows rows(std::move(raster.value()));
    BuildOptions options;
    options.threads = 2;
    options.memoryBudget = budget;
    options.forceOutOfCore = outOfCore;
    const auto start = std::chrono::steady_clock::now();
    auto built = buildMap(rows, options, output);
    if (!built.ok()) {
        std::fprintf(stderr, "%s\n", built.error().message.c_str());
        std::exit(1);
    }
    return {built.value(), std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()};
}

}  // namespace

int main()
{
    const int size = benchSize();
    std::uint64_t budget = std::uint64_t{1} << 30;
    if (const char* env = std::getenv("TERRAIN_BENCH_MEMORY")) {
        auto parsed = parseByteSize(env);
        if (!parsed.ok()) {
            std::fprintf(stderr, "TERRAIN_BENCH_MEMORY: %s\n", parsed.error().message.c_str());
            return 1;
        }
        budget = *parsed;
    }
    const auto path = input(size);
    const double samples = double(size) * size;
    configureGdalReading(budget, 2);
    const auto outOfCoreMap = std::filesystem::temp_directory_path() / "ooc-bench.map";
    std::printf("before build: peak RSS %s\n", formatBytes(peakResidentBytes()).c_str());
    std::uint64_t peakAnonymous = 0, peakFile = 0;
    const Run ooc = [&] {
        ResidentSampler sampler;
        Run run = build(path, outOfCoreMap, budget, true);
        peakAnonymous = sampler.peakAnonymous();
        peakFile = sampler.peakFile();
        return run;
    }();
    const std::uint64_t oocPeak = peakResidentBytes();
    std::printf(
        "out of core: %d x %d (%.3f G samples), budget %s, 2 threads: %.1f s, %.1f million samples/s, "
        "peak RSS %s, map %s, %llu nodes\n",
        size, size, samples / 1e9, formatBytes(budget).c_str(), ooc.seconds, samples / ooc.seconds / 1e6,
        formatBytes(oocPeak).c_str(), formatBytes(ooc.report.fileBytes).c_str(),
        static_cast<unsigned long long>(ooc.report.nodes));
    std::printf("             sampled peaks: anonymous %s, resident file pages (scratch grid, libraries) %s\n",
                formatBytes(peakAnonymous).c_str(), formatBytes(peakFile).c_str());
    std::fflush(stdout);
    const char* compare = std::getenv("TERRAIN_BENCH_COMPARE");
    if (compare && std::string(compare) == "1") {
        const auto inMemoryMap = std::filesystem::temp_directory_path() / "ooc-bench-in-memory.map";
        const Run whole = build(path, inMemoryMap, 0, false);
        std::printf("in memory:   %.1f s, %.1f million samples/s, peak RSS %s (%.2fx the out-of-core peak)\n",
                    whole.seconds, samples / whole.seconds / 1e6, formatBytes(peakResidentBytes()).c_str(),
                    double(peakResidentBytes()) / double(oocPeak));
        std::ifstream a(outOfCoreMap, std::ios::binary), b(inMemoryMap, std::ios::binary);
        const bool same = std::equal(std::istreambuf_iterator<char>(a), std::istreambuf_iterator<char>(),
                                     std::istreambuf_iterator<char>(b), std::istreambuf_iterator<char>());
        std::printf("maps %s\n", same ? "byte-identical" : "DIFFER");
        std::filesystem::remove(inMemoryMap);
    }
    std::filesystem::remove(outOfCoreMap);
    return 0;
}
