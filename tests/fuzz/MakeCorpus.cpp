// Seed inputs for the binary fuzz targets (tests/fuzz/run): small real files made from the real elevation
// data in ../shared/data, one folder per target, in the layouts the targets expect (FuzzTargets.h): maps
// as prep writes them (several chunk sizes, lossless and lossy, with and without detail errors) behind
// each reader/checksum prefix byte; PNG, .bt (every version and sample type), .ter and raw crops. Text
// targets are seeded by the script from the shipped configs, materials and camera paths.
//
// Usage: fuzz_corpus DEM.png OUTPUT_DIR
#include "heightfield/HeightFieldIo.h"
#include "heightfield/Image.h"
#include "quadtree/QuadtreeBuilder.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace {

using namespace terrain;

int fail(const std::string& message)
{
    std::fprintf(stderr, "fuzz_corpus: %s\n", message.c_str());
    return 1;
}

HeightField crop(const HeightField& field, int x0, int y0, int width, int height)
{
    HeightField out = field;
    out.width = width;
    out.height = height;
    out.samples.assign(static_cast<std::size_t>(width) * height, 0.0f);
    for (int j = 0; j < height; ++j) {
        for (int i = 0; i < width; ++i) {
            out.at(i, j) = field.at(x0 + i, y0 + j);
        }
    }
    return out;
}

std::vector<std::uint8_t> readAll(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

bool writeAll(const std::filesystem::path& path, const std::vector<std::uint8_t>& prefix,
              const std::vector<std::uint8_t>& bytes)
{
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(prefix.data()), static_cast<std::streamsize>(prefix.size()));
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    return static_cast<bool>(out);
}

}  // namespace

int main(int argc, char** argv)
{
    if (argc != 3) {
        return fail("usage: fuzz_corpus DEM.png OUTPUT_DIR");
    }
    auto field = readHeightField(argv[1]);
    if (!field.ok()) {
        return fail(field.error().message);
    }
    const std::filesystem::path out = argv[2];
    const std::filesystem::path scratch = out / "scratch";
    for (const char* target : {"map", "png", "bt", "ter", "raw"}) {
        std::filesystem::create_directories(out / target);
    }
    std::filesystem::create_directories(scratch);
    const HeightField small = crop(*field, 100, 80, 33, 25);  // a ridge of the fault scarp
    HeightField voids = crop(*field, 40, 40, 17, 13);
    voids.at(3, 4) = NAN;
    voids.at(9, 2) = NAN;

    // Maps: each behind the four prefix bytes (reader x checksum repair).
    struct MapSeed {
        const char* name;
        int chunk;
        double maxError;
        bool detail;
        std::uint32_t heightCoding = kHeightCodingKobbeltResidual;
    };
    for (const MapSeed& seed :
         {MapSeed{"chunk5", 5, 0.0, false}, MapSeed{"chunk9-lossy", 9, 2.0, false},
          MapSeed{"chunk17-detail", 17, 0.0, true}, MapSeed{"chunk9-pifs", 9, 0.0, false, kHeightCodingPifs}}) {
        BuildOptions options;
        options.chunkSize = seed.chunk;
        options.heightCoding = seed.heightCoding;
        options.spacing = 30.0;
        options.maxError = seed.maxError;
        if (seed.detail) {
            options.leafDetailError = [](const MapHeader&, const NodeId& id, std::span<const std::uint16_t>) {
                return 1.5f + 0.25f * static_cast<float>(id.x + id.y);
            };
        }
        const auto mapPath = scratch / (std::string(seed.name) + ".map");
        auto built = buildMap(seed.detail ? small : voids, options, mapPath);
        if (!built.ok()) {
            return fail(built.error().message);
        }
        const auto bytes = readAll(mapPath);
        for (std::uint8_t prefix = 0; prefix < 4; ++prefix) {
            if (!writeAll(out / "map" / (std::string(seed.name) + "-" + std::to_string(prefix)), {prefix}, bytes)) {
                return fail("cannot write the map seeds");
            }
        }
    }

    // PNG: 8- and 16-bit gray height fields and an RGB texture.
    Status status = writePngHeightField(out / "png" / "gray16.png", small, 16);
    status = status.ok() ? writePngHeightField(out / "png" / "gray8.png", crop(*field, 0, 0, 9, 7), 8) : status;
    if (status.ok()) {
        Image rgb;
        rgb.width = 8;
        rgb.height = 6;
        rgb.channels = 3;
        rgb.pixels.resize(8 * 6 * 3);
        for (std::size_t k = 0; k < rgb.pixels.size(); ++k) {
            rgb.pixels[k] = static_cast<std::uint8_t>(k * 37);
        }
        status = writePngImage(out / "png" / "rgb8.png", rgb);
    }
    // .bt: every version and sample type, with no-data samples.
    for (int minor = 0; minor <= 3 && status.ok(); ++minor) {
        for (auto [type, name] : {std::pair{BtSampleType::Int16, "int16"}, std::pair{BtSampleType::Int32, "int32"},
                                  std::pair{BtSampleType::Float32, "float32"}}) {
            status = writeBtHeightField(out / "bt" / ("v1" + std::to_string(minor) + "-" + name + ".bt"), voids, type,
                                        minor);
            if (!status.ok()) {
                break;
            }
        }
    }
    status = status.ok() ? writeTerHeightField(out / "ter" / "small.ter", small) : status;
    // Raw: the 6-byte prefix of FuzzTargets.h (size, sign and byte order, no-data) and the samples.
    for (std::uint8_t flags = 0; flags < 4 && status.ok(); ++flags) {
        const auto rawPath = scratch / "raw.r16";
        status = writeRawHeightField(rawPath, flags & 1 ? voids : crop(*field, 5, 5, 17, 13), flags & 1, flags & 2);
        if (status.ok()) {
            const std::vector<std::uint8_t> prefix = {17, 0, 13, 0, flags, static_cast<std::uint8_t>(flags & 1)};
            if (!writeAll(out / "raw" / ("flags" + std::to_string(flags)), prefix, readAll(rawPath))) {
                return fail("cannot write the raw seeds");
            }
        }
    }
    if (!status.ok()) {
        return fail(status.error().message);
    }
    std::filesystem::remove_all(scratch);
    return 0;
}
