// tengine-tool: inspect (info), check (verify) and query (height) terrain maps.
#include "core/Memory.h"
#include "core/Parse.h"
#include "lod/HeightQuery.h"
#include "quadtree/MapFile.h"
#include "heightfield/Image.h"
#include "quadtree/MapVerifier.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

namespace {

using namespace terrain;

constexpr const char* kUsage = R"(usage: tengine-tool COMMAND FILE.map [arguments]

  info FILE.map           header, levels, nodes and errors per level, storage
  verify FILE.map         check structure, every checksum, bounds and errors; exit 1 on any problem
  height FILE.map X Y     static terrain height (metres) at world position X, Y (metres); exit 1 outside
  texture FILE.map LEVEL/X/Y OUT.png
                          write a static node's texture as a PNG (north up)

Options: --reader stream|memory_mapped (default stream)
)";

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
    std::printf("valid      %u x %u samples at (%u, %u); %llu no-data samples filled\n", h.validWidth, h.validHeight,
                h.validX0, h.validY0, static_cast<unsigned long long>(h.noDataFilled));
    std::printf("chunks     %u x %u samples (+%d border), textures %u x %u\n", h.chunkSize, h.chunkSize, kBorder,
                h.textureSize, h.textureSize);
    std::printf("heights    metres = %.9g + %.9g * code; %s\n", h.heightOffset, h.heightStep,
                h.maxErrorBound == 0 ? "lossless" : ("max error " + std::to_string(h.maxErrorBound) + " m").c_str());
    std::printf("levels     %u\n", h.levels);

    struct LevelStats {
        std::uint64_t nodes = 0, heightBytes = 0, textureBytes = 0;
        float minDeltaC = 1e30f, maxDeltaC = 0.0f;
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
        heightBytes += e.heightBytes;
        textureBytes += e.textureBytes;
    }
    std::printf("\nlevel  nodes  spacing(m)  delta_c min..max (m)   height bytes  texture bytes\n");
    for (std::size_t i = 0; i < levels.size(); ++i) {
        const auto& l = levels[i];
        std::printf("%5zu %6llu %11.3f  %9.3f .. %-9.3f %13llu %14llu\n", i, static_cast<unsigned long long>(l.nodes),
                    h.spacingAt(static_cast<int>(i)), l.nodes ? l.minDeltaC : 0.0f, l.maxDeltaC,
                    static_cast<unsigned long long>(l.heightBytes), static_cast<unsigned long long>(l.textureBytes));
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
    NodeId id;
    unsigned level = 0;
    char tail = 0;
    if (std::sscanf(node.c_str(), "%u/%u/%u%c", &level, &id.x, &id.y, &tail) != 3 || level > NodeId::kMaxLevel) {
        return fail("texture: '" + node + "' is not a node LEVEL/X/Y");
    }
    id.level = static_cast<int>(level);
    auto loaded = map.loadPath(id);
    if (!loaded.ok()) {
        return fail(loaded.error().message);
    }
    const int size = static_cast<int>(map.header().textureSize);
    Image image{size, size, 3, std::vector<std::uint8_t>(loaded->texture.size())};
    for (int y = 0; y < size; ++y) {  // node rows run south to north, image rows north to south
        std::copy_n(&loaded->texture[static_cast<std::size_t>(size - 1 - y) * size * 3], static_cast<std::size_t>(size) * 3,
                    image.pixel(0, y));
    }
    auto written = writePngImage(output, image);
    if (!written.ok()) {
        return fail(written.error().message);
    }
    std::printf("%s: node %s texture written to %s\n", map.name().c_str(), id.toString().c_str(), output.c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv)
{
    std::vector<std::string> args;
    ReaderKind reader = ReaderKind::Stream;
    for (int i = 1; i < argc; ++i) {
        std::string arg = argv[i];
        if (arg == "--help" || arg == "-h") {
            std::fputs(kUsage, stdout);
            return 0;
        }
        if (arg == "--reader") {
            if (i + 1 >= argc) {
                return fail("--reader needs a value");
            }
            auto kind = parseReaderKind(argv[++i]);
            if (!kind.ok()) {
                return fail(kind.error().message);
            }
            reader = *kind;
        } else {
            args.push_back(arg);
        }
    }
    if (args.size() < 2) {
        std::fputs(kUsage, stderr);
        return 2;
    }
    const std::string& command = args[0];
    if (command != "info" && command != "verify" && command != "height" && command != "texture") {
        std::fprintf(stderr, "tengine-tool: unknown command '%s'\n%s", command.c_str(), kUsage);
        return 2;
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
    if (command == "texture") {
        if (args.size() != 4) {
            return fail("texture needs LEVEL/X/Y and an output PNG");
        }
        return texture(**map, args[2], args[3]);
    }
    if (args.size() != 4) {
        return fail("height needs X and Y (metres)");
    }
    auto x = parseDouble(args[2]);
    auto y = parseDouble(args[3]);
    if (!x.ok() || !y.ok()) {
        return fail("height: " + (x.ok() ? y : x).error().message);
    }
    auto sample = staticHeightAt(**map, *x, *y);
    if (!sample.ok()) {
        return fail(sample.error().message);
    }
    std::printf("%.6f\n", sample->height);
    return 0;
}
