// Shared fixtures for the quadtree, map-file and prep tests: generated height fields, whole decoded trees,
// and reference implementations written from docs/map-format.md and docs/design.md rather than from
// the code under test (the 4-point predictor in floating point, the edge reflection as a recursion, the
// template triangulation as explicit triangles with barycentric interpolation, a PNG reader on libpng).
#pragma once

#include "TestSupport.h"

#include "heightfield/HeightField.h"
#include "quadtree/MapFile.h"
#include "quadtree/QuadtreeBuilder.h"
#include "synthesis/DetailErrorModel.h"
#include "synthesis/DetailSynthesizer.h"

#include <gtest/gtest.h>
#include <png.h>
#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace terrain::test {

using Bytes = std::vector<std::uint8_t>;

// ---- Deterministic fixtures ----

/// 32 well-mixed bits from (seed, i, j): fixtures must not depend on <random>'s distributions.
inline std::uint32_t hashNoise(std::uint32_t seed, std::int64_t i, std::int64_t j)
{
    std::uint64_t h = (std::uint64_t{seed} + 1) * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<std::uint64_t>(i) * 0xC2B2AE3D27D4EB4Full;
    h ^= static_cast<std::uint64_t>(j) * 0x165667B19E3779F9ull;
    h ^= h >> 33;
    h *= 0xFF51AFD7ED558CCDull;
    h ^= h >> 33;
    h *= 0xC4CEB9FE1A85EC53ull;
    h ^= h >> 33;
    return static_cast<std::uint32_t>(h);
}

/// A uniform double in [0, 1) from (seed, i, j).
inline double unitNoise(std::uint32_t seed, std::int64_t i, std::int64_t j)
{
    return hashNoise(seed, i, j) / 4294967296.0;
}

inline HeightField makeHeightField(int width, int height, const std::function<float(int, int)>& value)
{
    HeightField field;
    field.width = width;
    field.height = height;
    field.samples.resize(static_cast<std::size_t>(width) * height);
    for (int j = 0; j < height; ++j) {
        for (int i = 0; i < width; ++i) {
            field.at(i, j) = value(i, j);
        }
    }
    field.description = "generated " + std::to_string(width) + "x" + std::to_string(height);
    return field;
}

/// Hills and valleys in whole metres (about 600 .. 1400) with a little integer noise: smooth at coarse
/// levels, never exactly planar.
inline HeightField hillyField(int width, int height, std::uint32_t seed = 1)
{
    return makeHeightField(width, height, [seed](int i, int j) {
        double h = 1000.0 + 250.0 * std::sin(0.071 * i + seed) * std::cos(0.053 * j) +
                   60.0 * std::sin(0.31 * i + 0.17 * j) + 8.0 * unitNoise(seed, i, j);
        return static_cast<float>(std::round(h));
    });
}

/// Independent uniform integers in [lo, hi]: the worst case for prediction and simplification.
inline HeightField roughField(int width, int height, std::uint32_t seed, int lo, int hi)
{
    return makeHeightField(width, height, [=](int i, int j) {
        return static_cast<float>(lo +
                                  static_cast<int>(hashNoise(seed, i, j) % static_cast<std::uint32_t>(hi - lo + 1)));
    });
}

/// Non-integer samples (as a float .bt would give): cannot be stored losslessly.
inline HeightField fractionalField(int width, int height, std::uint32_t seed = 3)
{
    HeightField field = makeHeightField(width, height, [seed](int i, int j) {
        return static_cast<float>(150.0 + 40.0 * std::sin(0.11 * i) * std::cos(0.07 * j) + 5.0 * unitNoise(seed, i, j));
    });
    field.integerSamples = false;
    return field;
}

/// Native value of the padded finest grid at (gx, gy): the input with its last column and row replicated.
inline double paddedNative(const HeightField& field, std::int64_t gx, std::int64_t gy)
{
    return field.at(static_cast<int>(std::min<std::int64_t>(gx, field.width - 1)),
                    static_cast<int>(std::min<std::int64_t>(gy, field.height - 1)));
}

/// Options for small test maps: one thread, spacing 2 m (a power of two, so world positions of samples
/// are exact doubles and lossless heights can be compared for equality).
inline BuildOptions testOptions(int chunkSize, int threads = 1)
{
    BuildOptions options;
    options.chunkSize = chunkSize;
    options.spacing = 2.0;
    options.threads = threads;
    return options;
}

/// A stand-in for prep's leaf detail error estimate (BuildOptions::leafDetailError): a multiple of 1/4 m
/// from 0.25 to 1.25 m that depends on the leaf's position only, so nested sums are exact in float.
inline float fakeLeafDetailError(const MapHeader&, const NodeId& id, std::span<const std::uint16_t>)
{
    return 0.25f * static_cast<float>(1 + (id.x * 7 + id.y * 3) % 5);
}

// ---- Files ----

inline Bytes readFileBytes(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void writeFileBytes(const std::filesystem::path& path, std::span<const std::uint8_t> bytes)
{
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

inline std::uint64_t readLe(std::span<const std::uint8_t> bytes, std::size_t offset, int size)
{
    std::uint64_t v = 0;
    for (int k = 0; k < size; ++k) {
        v |= std::uint64_t{bytes[offset + static_cast<std::size_t>(k)]} << (8 * k);
    }
    return v;
}

inline void writeLe(std::span<std::uint8_t> bytes, std::size_t offset, std::uint64_t value, int size)
{
    for (int k = 0; k < size; ++k) {
        bytes[offset + static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(value >> (8 * k));
    }
}

namespace detail {
/// libpng's part of readGray16PngRows, kept apart so no local of the caller lives across setjmp.
inline bool readGray16Png(std::FILE* file, std::vector<std::vector<std::uint16_t>>& rowsOut)
{
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png_create_info_struct(png);
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, nullptr);
        return false;
    }
    png_init_io(png, file);
    png_read_png(png, info, PNG_TRANSFORM_IDENTITY, nullptr);
    const png_uint_32 width = png_get_image_width(png, info);
    const png_uint_32 height = png_get_image_height(png, info);
    const bool gray16 = png_get_bit_depth(png, info) == 16 && png_get_color_type(png, info) == PNG_COLOR_TYPE_GRAY;
    if (gray16) {
        png_bytepp rows = png_get_rows(png, info);
        rowsOut.assign(height, std::vector<std::uint16_t>(width));
        for (png_uint_32 y = 0; y < height; ++y) {
            for (png_uint_32 x = 0; x < width; ++x) {
                rowsOut[y][x] = static_cast<std::uint16_t>((rows[y][2 * x] << 8) | rows[y][2 * x + 1]);
            }
        }
    }
    png_destroy_read_struct(&png, &info, nullptr);
    return gray16;
}
}  // namespace detail

/// A 16-bit gray PNG read straight through libpng, rows top (north) to bottom as stored; empty on failure.
inline std::vector<std::vector<std::uint16_t>> readGray16PngRows(const std::filesystem::path& path)
{
    std::vector<std::vector<std::uint16_t>> rows;
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) {
        return rows;
    }
    const bool ok = detail::readGray16Png(file, rows);
    std::fclose(file);
    if (!ok) {
        rows.clear();
    }
    return rows;
}

// ---- Reference implementations from the format description ----

inline std::uint16_t clampToCode(std::int64_t v)
{
    return static_cast<std::uint16_t>(std::clamp<std::int64_t>(v, 0, 65535));
}

/// Code of a level grid extended beyond [0, last] by point reflection, first along x, then along y
/// (docs/map-format.md "Grid and nodes"): `inside(gx, gy)` gives the codes of the grid itself.
inline std::uint16_t reflectedCode(const std::function<std::uint16_t(std::int64_t, std::int64_t)>& inside,
                                   std::int64_t last, std::int64_t gx, std::int64_t gy)
{
    if (gy < 0) {
        return clampToCode(2 * std::int64_t{reflectedCode(inside, last, gx, 0)} - reflectedCode(inside, last, gx, -gy));
    }
    if (gy > last) {
        return clampToCode(2 * std::int64_t{reflectedCode(inside, last, gx, last)} -
                           reflectedCode(inside, last, gx, 2 * last - gy));
    }
    if (gx < 0) {
        return clampToCode(2 * std::int64_t{inside(0, gy)} - inside(-gx, gy));
    }
    if (gx > last) {
        return clampToCode(2 * std::int64_t{inside(last, gy)} - inside(2 * last - gx, gy));
    }
    return inside(gx, gy);
}

/// The Kobbelt 4-point prediction (weights -1/16, 9/16, 9/16, -1/16, tensor product) of child window
/// sample (cx, cy) of child `quadrant`, evaluated in floating point from the positions the samples stand
/// at, then rounded half up. Positions are in parent window indices.
inline std::int64_t referencePrediction(std::span<const std::uint16_t> parent, int size, int chunkSize, int quadrant,
                                        int cx, int cy)
{
    auto weights = [&](double position) {
        std::vector<std::pair<int, double>> taps;
        double m = std::floor(position);
        if (m == position) {
            taps.emplace_back(static_cast<int>(m), 1.0);
        } else {
            const int base = static_cast<int>(m);
            taps = {{base - 1, -1.0 / 16}, {base, 9.0 / 16}, {base + 1, 9.0 / 16}, {base + 2, -1.0 / 16}};
        }
        return taps;
    };
    const double half = (chunkSize - 1) / 2.0;
    const double px = kBorder + (quadrant & 1) * half + (cx - kBorder) * 0.5;
    const double py = kBorder + (quadrant >> 1) * half + (cy - kBorder) * 0.5;
    double sum = 0.0;
    for (auto [iy, wy] : weights(py)) {
        for (auto [ix, wx] : weights(px)) {
            if (ix < 0 || iy < 0 || ix >= size || iy >= size) {
                return std::numeric_limits<std::int64_t>::min();  // the stencil must stay in the window
            }
            sum += wx * wy * parent[static_cast<std::size_t>(iy) * size + ix];
        }
    }
    return static_cast<std::int64_t>(std::floor(sum + 0.5));
}

/// One triangle of a triangulated surface, in any plane coordinates.
struct Triangle {
    double x[3];
    double y[3];
    double z[3];
};

/// The template triangulation (docs/design.md "Template mesh"; 3.2.9) of a grid of `cells` x `cells` quads
/// whose corner (i, j) stands at (i, j) with height z(i, j): each quad split along its south-west to
/// north-east diagonal.
inline std::vector<Triangle> templateTriangles(int cells, const std::function<double(int, int)>& z)
{
    std::vector<Triangle> triangles;
    for (int j = 0; j < cells; ++j) {
        for (int i = 0; i < cells; ++i) {
            const double x0 = i, x1 = i + 1, y0 = j, y1 = j + 1;
            triangles.push_back({{x0, x1, x1}, {y0, y0, y1}, {z(i, j), z(i + 1, j), z(i + 1, j + 1)}});
            triangles.push_back({{x0, x1, x0}, {y0, y1, y1}, {z(i, j), z(i + 1, j + 1), z(i, j + 1)}});
        }
    }
    return triangles;
}

/// Height at (px, py) by generic barycentric interpolation in the first triangle containing the point
/// (points on shared edges get the same height from either side); nothing if no triangle contains it.
inline std::optional<double> heightInTriangles(std::span<const Triangle> triangles, double px, double py)
{
    constexpr double kTolerance = 1e-9;
    for (const Triangle& t : triangles) {
        if (px < std::min({t.x[0], t.x[1], t.x[2]}) - kTolerance ||
            px > std::max({t.x[0], t.x[1], t.x[2]}) + kTolerance ||
            py < std::min({t.y[0], t.y[1], t.y[2]}) - kTolerance ||
            py > std::max({t.y[0], t.y[1], t.y[2]}) + kTolerance) {
            continue;
        }
        const double det = (t.y[1] - t.y[2]) * (t.x[0] - t.x[2]) + (t.x[2] - t.x[1]) * (t.y[0] - t.y[2]);
        const double l0 = ((t.y[1] - t.y[2]) * (px - t.x[2]) + (t.x[2] - t.x[1]) * (py - t.y[2])) / det;
        const double l1 = ((t.y[2] - t.y[0]) * (px - t.x[2]) + (t.x[0] - t.x[2]) * (py - t.y[2])) / det;
        const double l2 = 1.0 - l0 - l1;
        if (l0 >= -kTolerance && l1 >= -kTolerance && l2 >= -kTolerance) {
            return l0 * t.z[0] + l1 * t.z[1] + l2 * t.z[2];
        }
    }
    return std::nullopt;
}

// ---- Decoded maps ----

/// Every node of a map decoded (parents before children), by NodeId::key().
struct DecodedTree {
    std::map<std::uint64_t, StaticNode> nodes;

    const StaticNode* find(const NodeId& id) const
    {
        auto it = nodes.find(id.key());
        return it == nodes.end() ? nullptr : &it->second;
    }
};

inline Expected<DecodedTree> decodeTree(const MapFile& map)
{
    DecodedTree tree;
    for (const DirectoryEntry& entry : map.directory()) {  // sorted by key: levels in order
        std::span<const std::uint16_t> parent;
        if (!entry.id.isRoot()) {
            const StaticNode* p = tree.find(entry.id.parent());
            if (!p) {
                return makeError("node ", entry.id.toString(), " decoded before its parent");
            }
            parent = p->heights;
        }
        auto node = map.loadNode(entry.id, parent);
        TERRAIN_TRY(node);
        tree.nodes.emplace(entry.id.key(), std::move(node.value()));
    }
    return tree;
}

/// Code of window sample (u, v) of a node, u and v in [-kBorder, N - 1 + kBorder] (0 = the node's
/// south-west sample).
inline std::uint16_t windowCode(const MapHeader& header, const StaticNode& node, int u, int v)
{
    const int w = header.windowSize();
    return node.heights[static_cast<std::size_t>(v + kBorder) * w + u + kBorder];
}

/// Finest-grid samples between neighbouring samples of a node at `level`.
inline std::uint64_t strideAt(const MapHeader& header, int level)
{
    return std::uint64_t{1} << (header.levels - 1 - static_cast<std::uint32_t>(level));
}

/// Opens a map or records a test failure and returns null.
inline std::unique_ptr<MapFile> openMap(const std::filesystem::path& path, ReaderKind kind = ReaderKind::Stream)
{
    auto map = MapFile::open(path, kind);
    if (!map.ok()) {
        ADD_FAILURE() << map.error().message;
        return nullptr;
    }
    return std::move(map.value());
}

/// `field` built into a map at `path` (chunks of the synthesizer's size, `spacing` metres, 2 threads) whose leaves
/// carry the detail errors of `synthesizer` (3.4.1), opened memory-mapped; null (a test failure recorded) when
/// either fails.
inline std::unique_ptr<MapFile> detailErrorMap(HeightField field, double spacing, const DetailSynthesizer& synthesizer,
                                               const std::filesystem::path& path)
{
    BuildOptions options;
    options.chunkSize = synthesizer.chunkSize();
    options.spacing = spacing;
    options.threads = 2;
    options.leafDetailError = leafDetailErrorFunction(synthesizer);
    auto report = buildMap(std::move(field), options, path);
    if (!report.ok()) {
        ADD_FAILURE() << report.error().message;
        return nullptr;
    }
    return openMap(path, ReaderKind::MemoryMapped);
}

/// The shipped grass and rock materials under Kobbelt subdivision (the viewer's detail), for chunk size N.
inline std::unique_ptr<const DetailSynthesizer> grassAndRockSynthesizer(int chunkSize)
{
    const std::filesystem::path materials = TERRAIN_MATERIALS_DIR;
    std::vector<std::string> warnings;
    auto set = MaterialSet::load({materials / "grass.mat", materials / "rock.mat"}, warnings);
    EXPECT_TRUE(set.ok()) << set.error().message;
    auto s = DetailSynthesizer::create(chunkSize,
                                       {"kobbelt", 1.0, std::make_shared<const MaterialSet>(std::move(set).value())});
    EXPECT_TRUE(s.ok()) << s.error().message;
    return std::move(s).value();
}

}  // namespace terrain::test
