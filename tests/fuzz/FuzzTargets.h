// The fuzz targets (docs/hardening.md, "Fuzzing"): one entry point per parser of untrusted input. Each takes arbitrary
// bytes, runs the parser as the programs do and exercises what a successful parse hands on, and must never crash, hang,
// leak or allocate without bound, whatever the bytes. libFuzzer drives them (tests/fuzz/FuzzMain.cpp, clang builds with
// TERRAIN_FUZZ=ON); the unit tests replay every stored input under tests/data/fuzz/ (FuzzRegressionTest), so a finding
// stays fixed in every build.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace terrain::fuzz {

/// One target: what libFuzzer calls it (also the folder of its stored inputs) and its entry point.
struct Target {
    std::string_view name;
    void (*run)(std::span<const std::uint8_t> data);
};

/// `.map` files. data[0] picks the reader (bit 0: stream or memory-mapped) and whether the header,
/// directory and node checksums are recomputed first (bit 1), so mutations reach the structure checks and
/// the node decoders behind the CRCs; the rest is the file. Opens, verifies (every node decoded) and loads
/// the path to the last node.
void fuzzMap(std::span<const std::uint8_t> data);
/// PNG height fields (8/16-bit gray) and PNG images (RGB textures, detail textures), as prep reads them.
void fuzzPng(std::span<const std::uint8_t> data);
/// VTP .bt height fields; no-data filled as prep does.
void fuzzBt(std::span<const std::uint8_t> data);
/// Terragen .ter height fields.
void fuzzTer(std::span<const std::uint8_t> data);
/// Raw 16-bit height fields: data[0..3] give the size (two little-endian uint16, as --raw-size), data[4]
/// the sign and byte order, data[5] whether -32768 is no-data; the rest is the file.
void fuzzRaw(std::span<const std::uint8_t> data);
/// Viewer config files: parsed, applied to the options and validated, as tengine does.
void fuzzConfig(std::span<const std::uint8_t> data);
/// Material files: parsed into a material whose displacement is then evaluated.
void fuzzMaterial(std::span<const std::uint8_t> data);
/// Camera path files: parsed and evaluated (clamped and looping) over and beyond their time range.
void fuzzCameraPath(std::span<const std::uint8_t> data);
/// Elevation through GDAL with extreme samples: data[0] and data[1] give the raster's width and height (2 to
/// 33), data[2] a --nodata choice (none, the first sample's value, +inf) and data[3] the options' extremes
/// (-v, --offset, --max-error, --clamp); the rest are float32 samples of any bit pattern (NaN, +-inf, float
/// max, denormals), written as a GeoTIFF and built into a map by prep's builder, which then verifies.
void fuzzElevation(std::span<const std::uint8_t> data);
/// tengine's command line: the arguments separated by NUL bytes, parsed as tengine does (maps, configs,
/// --set), and what a successful parse hands on: the output check and the config text.
void fuzzTengineArguments(std::span<const std::uint8_t> data);

/// Every target, in a fixed order.
std::span<const Target> targets();

}  // namespace terrain::fuzz
