#include "FuzzTargets.h"

#include "apps/TengineOptions.h"
#include "core/ConfigFile.h"
#include "heightfield/GdalRaster.h"
#include "heightfield/HeightFieldIo.h"
#include "heightfield/HeightRows.h"
#include "heightfield/Image.h"
#include "heightfield/NoDataFill.h"
#include "lod/CameraPath.h"
#include "quadtree/MapFile.h"
#include "quadtree/MapVerifier.h"
#include "quadtree/QuadtreeBuilder.h"
#include "synthesis/Material.h"

#include <sys/mman.h>
#include <unistd.h>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace terrain::fuzz {

namespace {

/// The input as a file the readers can open by path: an anonymous in-memory file (memfd), named
/// /proc/self/fd/N, so the readers run exactly as on disk with no files left behind.
class MemoryFile {
public:
    explicit MemoryFile(std::span<const std::uint8_t> bytes)
    {
        mFd = ::memfd_create("fuzz-input", MFD_CLOEXEC);
        if (mFd < 0) {
            std::perror("fuzz: memfd_create");
            std::abort();
        }
        std::size_t done = 0;
        while (done < bytes.size()) {
            const ssize_t n = ::write(mFd, bytes.data() + done, bytes.size() - done);
            if (n <= 0) {
                std::perror("fuzz: write to memfd");
                std::abort();
            }
            done += static_cast<std::size_t>(n);
        }
        mPath = "/proc/self/fd/" + std::to_string(mFd);
    }
    MemoryFile(const MemoryFile&) = delete;
    MemoryFile& operator=(const MemoryFile&) = delete;
    ~MemoryFile() { ::close(mFd); }

    const std::filesystem::path& path() const { return mPath; }

private:
    int mFd = -1;
    std::filesystem::path mPath;
};

std::string_view asText(std::span<const std::uint8_t> data)
{
    return {reinterpret_cast<const char*>(data.data()), data.size()};
}

void putLe32(std::uint8_t* p, std::uint32_t v)
{
    for (int k = 0; k < 4; ++k) {
        p[k] = static_cast<std::uint8_t>(v >> (8 * k));
    }
}

/// Recomputes the header, directory and node checksums of a would-be map in place, so that mutated
/// structure reaches the checks behind them. Leaves the bytes as they are where the header or directory
/// cannot be parsed far enough to find what to checksum.
void repairChecksums(std::vector<std::uint8_t>& bytes)
{
    if (bytes.size() < kHeaderBytes) {
        return;
    }
    putLe32(bytes.data() + kHeaderBytes - 4, crc32Of(std::span(bytes).first(kHeaderBytes - 4)));
    auto header = decodeHeader(bytes, "fuzz.map");
    if (!header.ok() || header->directoryOffset > bytes.size() ||
        header->directoryBytes > bytes.size() - header->directoryOffset) {
        return;
    }
    MapHeader fixed = header.value();
    const auto directoryBytes = std::span(bytes).subspan(fixed.directoryOffset, fixed.directoryBytes);
    fixed.directoryCrc = crc32Of(directoryBytes);
    auto directory = decodeDirectory(directoryBytes, fixed, "fuzz.map");
    if (directory.ok()) {
        for (DirectoryEntry& entry : directory.value()) {
            if (entry.offset <= bytes.size() && entry.payloadBytes() <= bytes.size() - entry.offset) {
                entry.crc = crc32Of(std::span(bytes).subspan(entry.offset, entry.payloadBytes()));
            }
        }
        const auto encoded = encodeDirectory(directory.value(), fixed.version);
        if (encoded.size() == directoryBytes.size()) {
            std::copy(encoded.begin(), encoded.end(), directoryBytes.begin());
            fixed.directoryCrc = crc32Of(encoded);
        }
    }
    const auto encodedHeader = encodeHeader(fixed);
    std::copy(encodedHeader.begin(), encodedHeader.end(), bytes.begin());
}

/// What prep does with a height field it has read: fill no-data, look at the values.
void useHeightField(HeightField& field)
{
    fillNoData(field);
    double sum = 0.0;
    for (float v : field.samples) {
        sum += v;
    }
    volatile double sink = sum;
    (void)sink;
}

}  // namespace

void fuzzMap(std::span<const std::uint8_t> data)
{
    if (data.empty()) {
        return;
    }
    const ReaderKind kind = (data[0] & 1) ? ReaderKind::Stream : ReaderKind::MemoryMapped;
    std::vector<std::uint8_t> bytes(data.begin() + 1, data.end());
    if (data[0] & 2) {
        repairChecksums(bytes);
    }
    MemoryFile file(bytes);
    auto map = MapFile::open(file.path(), kind);
    if (!map.ok()) {
        return;
    }
    (void)verifyMap(**map);
    const auto directory = (*map)->directory();
    if (!directory.empty()) {
        (void)(*map)->loadPath(directory.back().id);
    }
}

void fuzzPng(std::span<const std::uint8_t> data)
{
    MemoryFile file(data);
    auto field = readPngHeightField(file.path());
    if (field.ok()) {
        useHeightField(field.value());
    }
    for (int channels : {1, 3}) {
        (void)readPngImage(file.path(), channels);
    }
}

void fuzzBt(std::span<const std::uint8_t> data)
{
    MemoryFile file(data);
    auto field = readBtHeightField(file.path());
    if (field.ok()) {
        useHeightField(field.value());
    }
}

void fuzzTer(std::span<const std::uint8_t> data)
{
    MemoryFile file(data);
    auto field = readTerHeightField(file.path());
    if (field.ok()) {
        useHeightField(field.value());
    }
}

void fuzzRaw(std::span<const std::uint8_t> data)
{
    constexpr std::size_t kPrefix = 6;
    if (data.size() < kPrefix) {
        return;
    }
    HeightFieldReadOptions options;
    options.rawWidth = data[0] | (data[1] << 8);
    options.rawHeight = data[2] | (data[3] << 8);
    options.rawSigned = (data[4] & 1) != 0;
    options.rawBigEndian = (data[4] & 2) != 0;
    if (data[5] & 1) {
        options.noData = -32768.0;
    }
    MemoryFile file(data.subspan(kPrefix));
    auto field = readRawHeightField(file.path(), options);
    if (field.ok()) {
        useHeightField(field.value());
    }
}

void fuzzConfig(std::span<const std::uint8_t> data)
{
    auto config = ConfigFile::parse(asText(data), "fuzz.cfg");
    if (!config.ok()) {
        return;
    }
    TengineOptions options;
    std::vector<std::string> warnings;
    if (applyConfig(config.value(), options, warnings).ok()) {
        (void)validateTengineOptions(options);
        (void)tengineConfigText(options);
    }
}

void fuzzMaterial(std::span<const std::uint8_t> data)
{
    auto config = ConfigFile::parse(asText(data), "fuzz.mat");
    if (!config.ok()) {
        return;
    }
    std::vector<std::string> warnings;
    auto material = parseMaterial(config.value(), warnings);
    if (!material.ok()) {
        return;
    }
    // Far from the origin too: the displacement must stay finite and bounded wherever it is asked.
    constexpr std::array<double, 4> kPositions = {0.0, 12.5, -3.75e5, 9.1e5};
    MaterialSet set({material.value()});
    std::array<double, 1> weight{};
    for (double x : kPositions) {
        for (double y : kPositions) {
            const double d = material->displacementAt(x, y);
            const float blended = set.displacement(x, y, 30.0, 2000.0);
            set.weights(45.0, 1000.0, weight);
            if (!std::isfinite(d) || !std::isfinite(blended)) {
                std::fprintf(stderr, "fuzz: displacement at (%g, %g) is not finite\n", x, y);
                std::abort();
            }
        }
    }
}

void fuzzCameraPath(std::span<const std::uint8_t> data)
{
    auto path = CameraPath::parse(asText(data), "fuzz.path");
    if (!path.ok()) {
        return;
    }
    const double start = path->startTime(), duration = path->duration();
    for (double f : {-1.0, 0.0, 0.25, 0.5, 0.999, 1.0, 2.5}) {
        const CameraPose a = path->evaluate(start + f * duration);
        const CameraPose b = path->evaluateLooping(start + f * duration);
        if (!std::isfinite(a.position.x + a.position.y + a.position.z + a.yaw + a.pitch) ||
            !std::isfinite(b.position.x + b.position.y + b.position.z + b.yaw + b.pitch)) {
            std::fprintf(stderr, "fuzz: camera pose at %g of the path is not finite\n", f);
            std::abort();
        }
    }
}

void fuzzElevation(std::span<const std::uint8_t> data)
{
    if (data.size() < 4) {
        return;
    }
    const int width = 2 + data[0] % 32, height = 2 + data[1] % 32;
    std::vector<float> samples(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 100.0f);
    const auto bytes = data.subspan(4);
    for (std::size_t k = 0; k < samples.size() && 4 * k + 4 <= bytes.size(); ++k) {
        std::memcpy(&samples[k], bytes.data() + 4 * k, 4);
    }
    // A scratch directory per process (GDAL writes and reads files by name), removed at exit.
    struct ScratchDirectory {
        std::filesystem::path path;
        ScratchDirectory()
        {
            std::string pattern = (std::filesystem::temp_directory_path() / "fuzz-elevation-XXXXXX").string();
            if (::mkdtemp(pattern.data()) == nullptr) {
                std::perror("fuzz: mkdtemp");
                std::abort();
            }
            path = pattern;
        }
        ~ScratchDirectory()
        {
            std::error_code ec;
            std::filesystem::remove_all(path, ec);
        }
    };
    static const ScratchDirectory scratch;
    const auto tif = scratch.path / "in.tif", map = scratch.path / "out.map";
    RasterGrid grid;
    grid.width = width;
    grid.height = height;
    grid.step = 30.0;
    if (!writeFloat32GeoTiff(tif, grid, samples).ok()) {
        return;
    }
    ElevationReadOptions read;
    if (data[2] % 3 == 1) {
        read.noData = samples[0];
    } else if (data[2] % 3 == 2) {
        read.noData = std::numeric_limits<double>::infinity();
    }
    const std::filesystem::path inputs[] = {tif};
    auto raster = ElevationRaster::open(inputs, read);
    if (!raster.ok()) {
        return;
    }
    RasterRows rows(std::move(raster).value());
    BuildOptions options;
    options.chunkSize = 5;
    options.threads = 1;
    options.zlibLevel = 1;
    const std::uint8_t extremes = data[3];
    // The extremes each option's range ends at, as prep lets them through.
    if (extremes & 1) {
        options.verticalScale = (extremes & 2) ? 1e9 : 1e-9;
    }
    if (extremes & 4) {
        options.offset = (extremes & 8) ? 1e7 : -1e7;
    }
    if (extremes & 16) {
        options.maxError = (extremes & 32) ? 1e7 : 1e-3;
    }
    if (extremes & 64) {
        options.clampMetres = std::array<double, 2>{-50.0, (extremes & 128) ? 1e7 : 500.0};
    }
    auto built = buildMap(rows, options, map);
    if (built.ok()) {
        auto opened = MapFile::open(map, ReaderKind::Stream);
        if (!opened.ok()) {
            std::fprintf(stderr, "fuzz: a map the builder wrote does not open: %s\n", opened.error().message.c_str());
            std::abort();
        }
        const std::vector<std::string> problems = verifyMap(**opened);
        if (!problems.empty()) {
            std::fprintf(stderr, "fuzz: a map the builder wrote does not verify: %s\n", problems.front().c_str());
            std::abort();
        }
    }
    std::error_code ec;
    std::filesystem::remove(map, ec);
}

void fuzzTengineArguments(std::span<const std::uint8_t> data)
{
    std::vector<std::string> arguments;
    std::string_view text = asText(data);
    while (!text.empty() && arguments.size() < 64) {
        const std::size_t end = std::min(text.find('\0'), text.size());
        arguments.emplace_back(text.substr(0, end));
        text.remove_prefix(std::min(end + 1, text.size()));
    }
    auto parsed = parseTengineCommandLine(arguments);
    if (parsed.ok()) {
        (void)checkOutputsAreNotInputs(*parsed, {});
        (void)tengineConfigText(parsed->options);
    }
}

std::span<const Target> targets()
{
    static constexpr Target kTargets[] = {
        {"map", fuzzMap},
        {"png", fuzzPng},
        {"bt", fuzzBt},
        {"ter", fuzzTer},
        {"raw", fuzzRaw},
        {"config", fuzzConfig},
        {"material", fuzzMaterial},
        {"camera_path", fuzzCameraPath},
        {"elevation", fuzzElevation},
        {"tengine_arguments", fuzzTengineArguments},
    };
    return kTargets;
}

}  // namespace terrain::fuzz
