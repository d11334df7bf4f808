// tengine's options (paper Appendix A) as one table: each option's key, documentation, valid values, how
// to parse it and how to write it back. Errors, configs/tengine.cfg and --print-config all come from it.
#include "apps/TengineOptions.h"

#include "lod/ClipmapLayout.h"

#include "apps/VideoRecorder.h"
#include "core/OutputGuard.h"

#include "core/Check.h"
#include "core/Parse.h"
#include "quadtree/ChunkGeometry.h"
#include "quadtree/MapFormat.h"

#include <algorithm>
#include <charconv>
#include <climits>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <sstream>

namespace terrain {
namespace {

/// What a setter gets besides the value.
struct SetContext {
    const ConfigEntry& entry;
    const std::filesystem::path& baseDirectory;  ///< for relative input paths; empty = as given
    std::vector<std::string>& warnings;
};

struct OptionSpec {
    std::string_view key;
    std::string_view group;
    std::string doc;       ///< what it does, for the config file
    std::string expected;  ///< the valid values, for errors and the config file
    /// Parses `value` into `options`; false = invalid (the caller reports `expected`).
    std::function<bool(std::string_view value, const SetContext&, TengineOptions&)> set;
    /// The value as a config file writes it; empty for the ignored Direct3D/Cg options.
    std::function<std::string(const TengineOptions&)> get;
};

constexpr std::string_view kGroupMap = "Map and level of detail";
constexpr std::string_view kGroupDetail = "Detail synthesis (paper 3.3, 3.4)";
constexpr std::string_view kGroupCamera = "Camera";
constexpr std::string_view kGroupDisplay = "Display";
constexpr std::string_view kGroupVideo = "Demo and video mode";

std::string lowerCase(std::string_view text)
{
    std::string lower(text);
    for (char& c : lower) {
        if (c >= 'A' && c <= 'Z') {
            c = static_cast<char>(c - 'A' + 'a');
        }
    }
    return lower;
}

std::optional<bool> parseBool(std::string_view text)
{
    std::string lower = lowerCase(text);
    if (lower == "true" || lower == "1" || lower == "yes" || lower == "on") {
        return true;
    }
    if (lower == "false" || lower == "0" || lower == "no" || lower == "off") {
        return false;
    }
    return std::nullopt;
}

/// A real interval; open ends exclude the bound, infinite bounds are left out of the text.
struct Interval {
    double min = -std::numeric_limits<double>::infinity();
    double max = std::numeric_limits<double>::infinity();
    bool minOpen = false;
    bool maxOpen = false;

    bool contains(double v) const { return (minOpen ? v > min : v >= min) && (maxOpen ? v < max : v <= max); }
    std::string text() const
    {
        bool hasMin = std::isfinite(min), hasMax = std::isfinite(max);
        if (hasMin && hasMax) {
            return std::string("in ") + (minOpen ? "(" : "[") + formatNumber(min) + ", " + formatNumber(max) +
                   (maxOpen ? ")" : "]");
        }
        if (hasMin) {
            return (minOpen ? "> " : ">= ") + formatNumber(min);
        }
        if (hasMax) {
            return (maxOpen ? "< " : "<= ") + formatNumber(max);
        }
        return "";
    }
};

Interval atLeast(double min)
{
    return {min, std::numeric_limits<double>::infinity(), false, false};
}
Interval above(double min)
{
    return {min, std::numeric_limits<double>::infinity(), true, false};
}
Interval closedInterval(double min, double max)
{
    return {min, max, false, false};
}
Interval openInterval(double min, double max)
{
    return {min, max, true, true};
}

std::string withUnit(std::string text, std::string_view unit)
{
    return unit.empty() ? text : text + " (" + std::string(unit) + ")";
}

OptionSpec realOption(std::string_view key, std::string_view group, std::string doc, double TengineOptions::*member,
                      Interval range, std::string_view unit)
{
    std::string expected = withUnit("a number" + (range.text().empty() ? "" : " " + range.text()), unit);
    return {key,
            group,
            std::move(doc),
            std::move(expected),
            [member, range](std::string_view value, const SetContext&, TengineOptions& o) {
                auto v = parseDouble(value);
                if (!v.ok() || !range.contains(*v)) {
                    return false;
                }
                o.*member = *v;
                return true;
            },
            [member](const TengineOptions& o) { return formatNumber(o.*member); }};
}

std::optional<int> parseInt(std::string_view text, long long min, long long max)
{
    auto v = parseInteger(text);
    if (!v.ok() || *v < min || *v > max) {
        return std::nullopt;
    }
    return static_cast<int>(*v);
}

std::string integerRangeText(long long min, long long max)
{
    if (max == INT_MAX) {
        return "an integer >= " + std::to_string(min);
    }
    return "an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]";
}

OptionSpec intOption(std::string_view key, std::string_view group, std::string doc, int TengineOptions::*member,
                     long long min, long long max, std::string_view unit)
{
    return {key,
            group,
            std::move(doc),
            withUnit(integerRangeText(min, max), unit),
            [member, min, max](std::string_view value, const SetContext&, TengineOptions& o) {
                auto v = parseInt(value, min, max);
                if (!v) {
                    return false;
                }
                o.*member = *v;
                return true;
            },
            [member](const TengineOptions& o) { return std::to_string(o.*member); }};
}

OptionSpec boolOption(std::string_view key, std::string_view group, std::string doc, bool TengineOptions::*member)
{
    return {key,
            group,
            std::move(doc),
            "true or false (also yes/no, on/off, 1/0)",
            [member](std::string_view value, const SetContext&, TengineOptions& o) {
                auto v = parseBool(value);
                if (!v) {
                    return false;
                }
                o.*member = *v;
                return true;
            },
            [member](const TengineOptions& o) { return std::string(o.*member ? "true" : "false"); }};
}

/// How a relative path from a config file is taken.
enum class PathKind {
    Input,   ///< relative to the config file's directory
    Output,  ///< relative to the working directory
};

OptionSpec pathOption(std::string_view key, std::string_view group, std::string doc,
                      std::filesystem::path TengineOptions::*member, PathKind kind, std::string expected)
{
    return {key,
            group,
            std::move(doc),
            std::move(expected),
            [member, kind](std::string_view value, const SetContext& context, TengineOptions& o) {
                std::filesystem::path path(value);
                if (kind == PathKind::Input && !path.empty() && path.is_relative()) {
                    path = context.baseDirectory / path;
                }
                o.*member = path;
                return true;
            },
            [member](const TengineOptions& o) { return (o.*member).string(); }};
}

/// Splits "a, b, c" into exactly `n` numbers.
std::optional<std::vector<double>> parseNumberList(std::string_view text, std::size_t n)
{
    std::vector<double> values;
    while (true) {
        std::size_t comma = text.find(',');
        std::string_view part = text.substr(0, comma);
        std::size_t first = part.find_first_not_of(" \t");
        std::size_t last = part.find_last_not_of(" \t");
        part = first == std::string_view::npos ? std::string_view() : part.substr(first, last - first + 1);
        auto v = parseDouble(part);
        if (!v.ok()) {
            return std::nullopt;
        }
        values.push_back(*v);
        if (comma == std::string_view::npos) {
            break;
        }
        text.remove_prefix(comma + 1);
    }
    if (values.size() != n) {
        return std::nullopt;
    }
    return values;
}

/// The map and the level of detail.
void addMapOptions(std::vector<OptionSpec>& t)
{
    using O = TengineOptions;
    t.push_back(pathOption("map_file", kGroupMap,
                           "The terrain map (.map) made by prep. A map file given on the command line replaces it. "
                           "Relative paths are taken from this config file's directory.",
                           &O::mapFile, PathKind::Input, "a path (empty: none; then the command line must name one)"));
    t.push_back(realOption("lod_error", kGroupMap,
                           "tau of the level-of-detail selection (eq. 3.3): the largest screen-space error allowed. "
                           "Smaller is sharper and slower.",
                           &O::lodError, above(0), "pixels"));
    t.push_back(realOption("lod_minimum_spacing", kGroupMap,
                           "No node is refined below this sample spacing; limits how far detail synthesis goes.",
                           &O::lodMinimumSpacing, atLeast(0), "metres"));
    t.push_back({"dynamic_texture_size", kGroupMap,
                 "The paper's width and height of the texture that diffuse lighting is burnt into for each node: "
                 "each node gets a normal map of this many texels a side (one more for a power of two, so "
                 "corner texels sit on the corners), made on the worker threads from the surface one level "
                 "below the node (up to 2x the node's samples a side) or two (up to 4x), as synthesis makes those "
                 "levels, so the lighting shows detail finer than the triangles. Each level below costs about 4x "
                 "the synthesis of a node (DynamicNodeBench). 0: no normal maps, lit by the vertex normals.",
                 "0, or a power of two or a power of two plus one, in [16, 4096] (texels)",
                 [](std::string_view value, const SetContext&, O& o) {
                     auto v = parseInt(value, 0, 4096);
                     if (!v || !(*v == 0 || (*v >= 16 && (isPowerOfTwo(*v) || isPowerOfTwoPlusOne(*v))))) {
                         return false;
                     }
                     o.dynamicTextureSize = *v;
                     return true;
                 },
                 [](const O& o) { return std::to_string(o.dynamicTextureSize); }});
    t.push_back(intOption("vertex_cache_size", kGroupMap,
                          "Size of the GPU's post-transform vertex cache that the zigzag index order is built for "
                          "(3.2.10).",
                          &O::vertexCacheSize, 4, 64, "vertices"));
    t.push_back(intOption("memory_budget", kGroupMap,
                          "Memory for resident nodes, GPU and CPU together: the node cache holds as many nodes as "
                          "it pays for (each node's GPU slot plus its CPU data, measured on the map's root; the "
                          "log says how many), at most as many as the node pools hold (16 texture arrays of the GPU's "
                          "GL_MAX_ARRAY_TEXTURE_LAYERS). More keeps "
                          "more detail around. When the selection wants more than the cache holds, the nodes with "
                          "the largest screen-space error are refined first and frames.csv's cache_short counts "
                          "the groups left out. 0: 1/16 of the machine's memory, between 128 MiB and 4 GiB.",
                          &O::memoryBudget, 0, 1 << 20, "MiB"));
    t.push_back({"quad_cache_size", kGroupMap,
                 "How many nodes the node cache holds, instead of what memory_budget pays for (for comparisons "
                 "at a fixed count). At least a node and its four children; 0: from memory_budget.",
                 "0, or an integer >= 5 (nodes)",
                 [](std::string_view value, const SetContext&, O& o) {
                     auto v = parseInt(value, 0, INT_MAX);
                     if (!v || (*v != 0 && *v < 5)) {
                         return false;
                     }
                     o.quadCacheSize = *v;
                     return true;
                 },
                 [](const O& o) { return std::to_string(o.quadCacheSize); }});
    t.push_back({"reader", kGroupMap,
                 "How the map file is read: 'stream' reads each node with a file read, 'memory_mapped' maps the "
                 "whole file.",
                 "stream or memory_mapped",
                 [](std::string_view value, const SetContext&, O& o) {
                     if (value == "stream") {
                         o.reader = ReaderKind::Stream;
                     } else if (value == "memory_mapped") {
                         o.reader = ReaderKind::MemoryMapped;
                     } else {
                         return false;
                     }
                     return true;
                 },
                 [](const O& o) { return std::string(o.reader == ReaderKind::Stream ? "stream" : "memory_mapped"); }});
    t.push_back(intOption("worker_threads", kGroupMap,
                          "Threads that read and decode nodes. 0 loads on the render thread (stutters; for "
                          "debugging).",
                          &O::workerThreads, 0, 256, "threads"));
    t.push_back(intOption("request_queue_size", kGroupMap,
                          "How many node loads may wait at once; the nearest are asked for first and stale ones "
                          "cancelled.",
                          &O::requestQueueSize, 1, 4096, "node groups"));
    t.push_back(
        boolOption("visibility_lod", kGroupMap,
                   "Visibility-driven level of detail (Ozak & Demir): the renderer counts every drawn node's "
                   "visible pixels, and terrain that has shown none for visibility_hidden_frames frames (behind "
                   "a ridge) is neither refined nor synthesized. Needs OpenGL 4.3.",
                   &O::visibilityLod));
    t.push_back(intOption("visibility_hidden_frames", kGroupMap,
                          "With visibility_lod: measured frames without a visible pixel before a node counts as "
                          "hidden (twice as many each time it shows again, up to 8x).",
                          &O::visibilityHiddenFrames, 1, 64, "frames"));
    t.push_back(realOption("visibility_reveal_seconds", kGroupMap,
                           "With visibility_lod: when hidden terrain comes into view, each level of detail it gains "
                           "morphs in over this long, a level after the other, instead of popping in.",
                           &O::visibilityRevealSeconds, above(0), "seconds"));
}

/// Detail synthesis below the data.
void addDetailOptions(std::vector<OptionSpec>& t)
{
    using O = TengineOptions;
    t.push_back(boolOption("detail_create_new_nodes", kGroupDetail,
                           "Create dynamic nodes below the map's finest level by subdivision.",
                           &O::detailCreateNewNodes));
    t.push_back(realOption("detail_subdivision_factor", kGroupDetail,
                           "omega of the 4-point subdivision rule: 0 is linear interpolation, 1 Kobbelt's "
                           "interpolatory subdivision.",
                           &O::detailSubdivisionFactor, closedInterval(0, 2), ""));
    t.push_back(boolOption("detail_add_material", kGroupDetail,
                           "Add the material's fractal displacement to subdivided nodes.", &O::detailAddMaterial));
    t.push_back(boolOption("detail_roughness", kGroupDetail,
                           "Continue the terrain's own roughness below the map's finest level: noise whose amplitude "
                           "follows the power law prep measured around each static leaf, from the data's spacing "
                           "down to where the materials' octaves take over (maps of format 5; older maps have "
                           "none).",
                           &O::detailRoughness));
    t.push_back(intOption("detail_material_type", kGroupDetail,
                          "Which built-in material covers the terrain when detail_materials is empty: 0 soft "
                          "grass/soil (grass.mat), 1 ridged rock (rock.mat).",
                          &O::detailMaterialType, 0, 1, ""));
    t.push_back({"detail_subdivision_scheme", kGroupDetail,
                 "How dynamic nodes subdivide their parent: kobbelt (interpolatory 4-point rule), bilinear or "
                 "catmull-clark (both through OpenSubdiv; catmull-clark is approximating, so parents and "
                 "children do not nest exactly).",
                 "kobbelt, bilinear or catmull-clark",
                 [](std::string_view value, const SetContext&, O& o) {
                     if (value != "kobbelt" && value != "bilinear" && value != "catmull-clark") {
                         return false;
                     }
                     o.detailSubdivisionScheme = std::string(value);
                     return true;
                 },
                 [](const O& o) { return o.detailSubdivisionScheme; }});
    t.push_back({"detail_materials", kGroupDetail,
                 "Several materials placed over the terrain by their slope and height rules and blended "
                 "(materials/README.md): .mat files separated by commas, the first is the ground. Relative "
                 "paths are taken from this config file's directory. Empty: detail_material_type alone.",
                 "empty or .mat paths separated by commas (at most 4)",
                 [](std::string_view value, const SetContext& context, O& o) {
                     std::vector<std::filesystem::path> files;
                     while (!value.empty()) {
                         const std::size_t comma = value.find(',');
                         std::string_view part = value.substr(0, comma);
                         const std::size_t first = part.find_first_not_of(" \t");
                         const std::size_t last = part.find_last_not_of(" \t");
                         if (first == std::string_view::npos) {
                             return false;
                         }
                         std::filesystem::path path(part.substr(first, last - first + 1));
                         files.push_back(path.is_relative() ? context.baseDirectory / path : path);
                         value = comma == std::string_view::npos ? std::string_view() : value.substr(comma + 1);
                     }
                     if (files.size() > 4) {
                         return false;
                     }
                     o.detailMaterials = std::move(files);
                     return true;
                 },
                 [](const O& o) {
                     std::string text;
                     for (const auto& file : o.detailMaterials) {
                         text += (text.empty() ? "" : ", ") + file.string();
                     }
                     return text;
                 }});
    t.push_back(pathOption("material_path", kGroupDetail,
                           "Directory of the built-in materials grass.mat and rock.mat. Empty: the materials/ "
                           "directory of this build.",
                           &O::materialPath, PathKind::Input, "a directory (empty: built in)"));
    t.push_back(realOption("detail_velocity_limit", kGroupDetail,
                           "No new dynamic nodes while the camera moves faster than this many of their sample "
                           "spacings per second (3.4.4): fine detail is not perceptible at speed. 0: no limit.",
                           &O::detailVelocityLimit, atLeast(0), "samples per second"));
}

/// The camera.
void addCameraOptions(std::vector<OptionSpec>& t)
{
    using O = TengineOptions;
    t.push_back(realOption("camera_fov", kGroupCamera, "Vertical field of view.", &O::cameraFov, openInterval(1, 179),
                           "degrees"));
    t.push_back(realOption("camera_z_near", kGroupCamera, "Distance to the near clipping plane.", &O::cameraZNear,
                           above(0), "metres"));
    t.push_back(realOption("camera_z_far", kGroupCamera, "Distance to the far clipping plane.", &O::cameraZFar,
                           above(0), "metres"));
    // The relations are checked by validate().
    t.back().expected = "a number > camera_z_near, at most 2^24 times it (metres)";
    t.push_back(realOption("camera_min_clearance", kGroupCamera,
                           "In free flight the camera stays at least this high above the surface being drawn "
                           "(demo and video mode fly their path as given, with a warning where it goes below).",
                           &O::cameraMinClearance, atLeast(0), "metres"));
    t.push_back(pathOption("camera_path", kGroupCamera,
                           "Camera path file (lines 'time x y z yaw pitch') flown in demo and video mode. Relative "
                           "paths are taken from this config file's directory.",
                           &O::cameraPath, PathKind::Input, "a path (empty: none)"));
    t.push_back({"camera_position", kGroupCamera,
                 "Where the camera starts when no path is flown, world metres (x east, y north, z up). Empty: "
                 "where it sees the whole terrain, looking at its centre with camera_yaw and camera_pitch (at least "
                 "5 degrees down).",
                 "empty or three numbers 'x, y, z' (metres)",
                 [](std::string_view value, const SetContext&, O& o) {
                     if (value.empty()) {
                         o.cameraPosition.reset();
                         return true;
                     }
                     auto v = parseNumberList(value, 3);
                     if (!v) {
                         return false;
                     }
                     o.cameraPosition = glm::dvec3((*v)[0], (*v)[1], (*v)[2]);
                     return true;
                 },
                 [](const O& o) {
                     if (!o.cameraPosition) {
                         return std::string();
                     }
                     const glm::dvec3& p = *o.cameraPosition;
                     return formatNumber(p.x) + ", " + formatNumber(p.y) + ", " + formatNumber(p.z);
                 }});
    t.push_back(realOption("camera_yaw", kGroupCamera,
                           "Start heading when no path is flown: 0 looks north, positive turns east.", &O::cameraYaw,
                           closedInterval(-360, 360), "degrees"));
    t.push_back(realOption("camera_pitch", kGroupCamera, "Start pitch when no path is flown: positive looks up.",
                           &O::cameraPitch, closedInterval(-90, 90), "degrees"));
}

/// The window, what is drawn and how (render and LOD modes, compression).
void addDisplayOptions(std::vector<OptionSpec>& t)
{
    using O = TengineOptions;
    t.push_back(intOption("window_width", kGroupDisplay, "Window width.", &O::windowWidth, 16, 16384, "pixels"));
    t.push_back(intOption("window_height", kGroupDisplay, "Window height.", &O::windowHeight, 16, 16384, "pixels"));
    t.push_back(boolOption("draw_user_interface", kGroupDisplay,
                           "Draw the on-screen statistics and help. Costs a little frame time.",
                           &O::drawUserInterface));
    t.push_back(boolOption("draw_sky", kGroupDisplay, "Draw the sky; off clears to clear_color.", &O::drawSky));
    t.push_back(boolOption("wireframe", kGroupDisplay, "Draw the terrain's triangles as lines.", &O::wireframe));
    t.push_back(boolOption("geomorph", kGroupDisplay,
                           "Morph geometry, normals and textures between detail levels (eq. 3.4-3.6). Off shows "
                           "the popping morphing prevents, for comparison.",
                           &O::geomorph));
    t.push_back(boolOption("node_texture_compression", kGroupDisplay,
                           "Keep the nodes' colour textures on the GPU as DXT1 (S3TC): 2.3 KB instead of 12.7 KB a "
                           "65 x 65 node. Off by default: Mesa's llvmpipe decodes DXT1 in software, which cost about "
                           "15% of frame time in RenderBench. With shadows the colours carry the sun's visibility in "
                           "alpha and stay RGBA8 (16.9 KB): this option then changes nothing.",
                           &O::nodeTextureCompression));
    t.push_back({"normal_map_compression", kGroupDisplay,
                 "Keep the nodes' normal maps (dynamic_texture_size) as RGTC2 blocks, on the GPU and in the node "
                 "cache: 1 byte a texel instead of RG8's 2 (17 KB instead of 33 KB a 129 x 129 map), the frames "
                 "within a grey level of RG8's on average. A GPU decodes RGTC2 for free; Mesa's llvmpipe decodes it "
                 "in software, about 13 ms more a 1280 x 720 frame in RenderBench. auto: RGTC2 unless the GL "
                 "rasterizes in software.",
                 "auto, or true or false (also yes/no, on/off, 1/0)",
                 [](std::string_view value, const SetContext&, O& o) {
                     if (lowerCase(value) == "auto") {
                         o.normalMapCompression = O::Compression::Auto;
                         return true;
                     }
                     auto v = parseBool(value);
                     if (!v) {
                         return false;
                     }
                     o.normalMapCompression = *v ? O::Compression::On : O::Compression::Off;
                     return true;
                 },
                 [](const O& o) {
                     switch (o.normalMapCompression) {
                         case O::Compression::On:
                             return std::string("true");
                         case O::Compression::Off:
                             return std::string("false");
                         case O::Compression::Auto:
                             break;
                     }
                     return std::string("auto");
                 }});
    t.push_back({"render_mode", kGroupDisplay,
                 "How nodes become triangles: chunks draws every selected node's template mesh in full (3.2.9); "
                 "tessellation and blocks cut each node into blocks of 8 x 8 quads, each as coarse as its share of "
                 "tau allows: tessellation by the GPU's tessellator (needs OpenGL 4.0), blocks from index lists of "
                 "the template mesh made on the CPU each frame for the same blocks (needs OpenGL 4.3). Both draw "
                 "6-11x fewer triangles than chunks within the same measured error on the demo paths. Blocks is the "
                 "default: the same surface without the tessellator's collapsed cells and extra skirt triangles, and "
                 "llvmpipe draws the demo path 1.35x faster than with tessellation shaders. Without OpenGL 4.3 blocks "
                 "are tessellated, and without 4.0 chunks are drawn, with a line saying so.",
                 "chunks, tessellation or blocks",
                 [](std::string_view value, const SetContext&, TengineOptions& o) {
                     const std::string v = lowerCase(value);
                     if (v != "chunks" && v != "tessellation" && v != "blocks") {
                         return false;
                     }
                     o.tessellation = v != "chunks";
                     o.blockIndices = v == "blocks";
                     return true;
                 },
                 [](const TengineOptions& o) {
                     return std::string(!o.tessellation ? "chunks" : o.blockIndices ? "blocks" : "tessellation");
                 }});
    t.push_back({"lod_mode", kGroupDisplay,
                 "How the level of detail is chosen: quadtree selects chunked-quadtree nodes by their errors (the "
                 "paper; render_mode applies); clipmap draws seed 002's geometry clipmaps instead: nested n x n "
                 "grids around the viewer, one per quadtree level, from the same nodes and synthesis, blended to "
                 "the coarser level near each perimeter (a baseline: docs/methods.md compares them).",
                 "quadtree or clipmap",
                 [](std::string_view value, const SetContext&, TengineOptions& o) {
                     const std::string v = lowerCase(value);
                     if (v != "quadtree" && v != "clipmap") {
                         return false;
                     }
                     o.clipmap = v == "clipmap";
                     return true;
                 },
                 [](const TengineOptions& o) { return std::string(o.clipmap ? "clipmap" : "quadtree"); }});
    t.push_back({"clipmap_samples", kGroupDisplay,
                 "With lod_mode = clipmap: samples per side of each level's grid, n = 2^k - 1 (seed 002 uses 255).",
                 "an integer 2^k - 1 in [15, 1023]",
                 [](std::string_view value, const SetContext&, TengineOptions& o) {
                     auto v = parseInt(value, kMinClipmapSamples, kMaxClipmapSamples);
                     if (!v || !isValidClipmapSize(*v)) {
                         return false;
                     }
                     o.clipmapSamples = *v;
                     return true;
                 },
                 [](const TengineOptions& o) { return std::to_string(o.clipmapSamples); }});
    t.push_back(realOption("clipmap_finest_spacing", kGroupDisplay,
                           "With lod_mode = clipmap: the finest level's sample spacing is the first at or above this "
                           "(levels below the map's data are synthesized as dynamic nodes; never below "
                           "lod_minimum_spacing, nor below the data without detail_create_new_nodes).",
                           &O::clipmapFinestSpacing, above(0), "metres"));
    t.push_back(realOption("clipmap_morph_seconds", kGroupDisplay,
                           "With lod_mode = clipmap: where a node arrives after its samples were drawn upsampled from "
                           "the coarser level, its heights, colours and normals morph in over this long instead of "
                           "popping (0: at once). Video mode loads before drawing, so recordings rarely show it.",
                           &O::clipmapMorphSeconds, atLeast(0), "seconds"));
    t.push_back(realOption(
        "tessellation_error_share", kGroupDisplay,
        "With render_mode = tessellation or blocks: the part of lod_error the blocks inside a node may spend; "
        "the nodes are selected for the rest, so the drawn surface stays within lod_error.",
        &O::tessellationShare, openInterval(0, 1), ""));
}

/// The sun, the air and the shadows; the shader and log files.
void addLightOptions(std::vector<OptionSpec>& t)
{
    using O = TengineOptions;
    t.push_back(realOption("sun_azimuth", kGroupDisplay, "Direction the sunlight comes from: 0 north, 90 east.",
                           &O::sunAzimuth, closedInterval(0, 360), "degrees"));
    t.push_back(realOption("sun_elevation", kGroupDisplay, "Height of the sun above the horizon.", &O::sunElevation,
                           closedInterval(-90, 90), "degrees"));
    t.push_back(
        realOption("haze_distance", kGroupDisplay,
                   "With atmosphere = false: at distance d the terrain keeps exp(-d / haze_distance) of its own "
                   "colour. 0 turns haze off.",
                   &O::hazeDistance, atLeast(0), "metres"));
    t.push_back(boolOption("shadows", kGroupDisplay,
                           "Terrain shadows and sky visibility: the sun hidden behind the relief (soft, from the "
                           "horizons of every node's surface over the static map) and the sky hidden in valleys "
                           "(lod_mode = clipmap: for the sun the session starts with).",
                           &O::shadows));
    t.push_back(boolOption("atmosphere", kGroupDisplay,
                           "A physically based sky and air: sunlight and skylight through an atmosphere of Rayleigh "
                           "and Mie scattering, aerial perspective with distance (in place of haze_distance and "
                           "clear_color's haze), HDR and a filmic tone map. false: the gradient sky and haze.",
                           &O::atmosphere));
    t.push_back(realOption("exposure", kGroupDisplay,
                           "With atmosphere = true: what the tone map multiplies radiance by (radiance relative to the "
                           "sun's irradiance above the air); larger is brighter.",
                           &O::exposure, openInterval(0, 1e6), ""));
    t.push_back({"clear_color", kGroupDisplay, "Background colour where nothing is drawn (and the haze colour).",
                 "three numbers 'r, g, b', each in [0, 1]",
                 [](std::string_view value, const SetContext&, O& o) {
                     auto v = parseNumberList(value, 3);
                     if (!v || std::any_of(v->begin(), v->end(), [](double c) { return c < 0 || c > 1; })) {
                         return false;
                     }
                     o.clearColor = glm::vec3(static_cast<float>((*v)[0]), static_cast<float>((*v)[1]),
                                              static_cast<float>((*v)[2]));
                     return true;
                 },
                 [](const O& o) {
                     return formatNumber(o.clearColor.r) + ", " + formatNumber(o.clearColor.g) + ", " +
                            formatNumber(o.clearColor.b);
                 }});
    t.push_back(pathOption("shader_path", kGroupDisplay,
                           "Directory with the GLSL programs (terrain, sky, text). Relative paths in a config file are "
                           "taken from that file's directory.",
                           &O::shaderPath, PathKind::Input,
                           "a directory path (empty: the shaders/ directory this build came with)"));
    t.push_back(pathOption("log_file", kGroupDisplay,
                           "Also write the log to this file. Relative paths are taken from the working directory.",
                           &O::logFile, PathKind::Output, "a path (empty: log to stderr only)"));
}

/// Demo and video mode.
void addVideoOptions(std::vector<OptionSpec>& t)
{
    using O = TengineOptions;
    t.push_back(boolOption("demo_mode", kGroupVideo,
                           "Fly camera_path over and over (needs camera_path). Demo and video mode exclude each other: "
                           "setting one to true turns the other off (the later setting wins, and says so).",
                           &O::demoMode));
    t.push_back(boolOption("video_mode", kGroupVideo,
                           "Fly camera_path once at frames_per_second, saving every frame to image_path (needs "
                           "camera_path).",
                           &O::videoMode));
    t.push_back(intOption("frames_per_second", kGroupVideo, "Frames per second of camera-path time in video mode.",
                          &O::framesPerSecond, 1, 240, ""));
    t.push_back(pathOption("image_path", kGroupVideo,
                           "Directory for the video frames (created if missing). Relative paths are taken from the "
                           "working directory.",
                           &O::imagePath, PathKind::Output, "a directory path"));
    t.push_back(intOption("video_frames", kGroupVideo, "Stop video mode after this many frames; 0 = the whole path.",
                          &O::videoFrames, 0, INT_MAX, "frames"));
    t.push_back(intOption("video_save_every", kGroupVideo,
                          "Save every Nth video frame as a PNG (frames 0, N, 2N, ...; names keep the frame number); "
                          "0 saves none, only frames.csv (long soak runs). An MP4 needs every frame: 1.",
                          &O::videoSaveEvery, 0, INT_MAX, "frames"));
    t.push_back(boolOption("video_ffmpeg", kGroupVideo,
                           "After video mode, make an MP4 of the frames when ffmpeg is on the PATH.", &O::videoFfmpeg));
    t.push_back(intOption("video_measure_error_every", kGroupVideo,
                          "Measure the screen-space error of what every Nth video frame shows (its own depth "
                          "decides what shows), as tengine-tool error does, into frames.csv (error_max_px, "
                          "error_p99_px) and a summary line; slow: seconds a frame. 0 measures nothing.",
                          &O::videoMeasureErrorEvery, 0, INT_MAX, "frames"));
}

std::vector<OptionSpec> makeOptionTable()
{
    std::vector<OptionSpec> t;
    addMapOptions(t);
    addDetailOptions(t);
    addCameraOptions(t);
    addDisplayOptions(t);
    addLightOptions(t);
    addVideoOptions(t);
    return t;
}

/// The paper's Direct3D/Cg options: accepted so its configs load, with warnings where they ask for
/// something we do not do.
std::vector<OptionSpec> makeIgnoredOptionTable()
{
    std::vector<OptionSpec> t;
    t.push_back({"render",
                 "",
                 "3D API: 'gl' (the only one here) or 'dx' (Direct3D: warned about and ignored).",
                 "gl or dx",
                 [](std::string_view value, const SetContext& c, TengineOptions&) {
                     if (value == "dx") {
                         c.warnings.push_back(c.entry.location() +
                                              ": render = dx is ignored: only OpenGL is supported");
                         return true;
                     }
                     return value == "gl";
                 },
                 {}});
    t.push_back({"memory",
                 "",
                 "GL memory scheme: 'gl_std' and 'gl_vbo' are accepted (vertex buffer objects are always used); "
                 "'gl_var' (NVIDIA VAR) is warned about and ignored.",
                 "gl_std, gl_vbo or gl_var",
                 [](std::string_view value, const SetContext& c, TengineOptions&) {
                     if (value == "gl_var") {
                         c.warnings.push_back(c.entry.location() +
                                              ": memory = gl_var is ignored: vertex buffer objects are used");
                         return true;
                     }
                     return value == "gl_std" || value == "gl_vbo";
                 },
                 {}});
    t.push_back({"cg_profile",
                 "",
                 "Cg profile (arb, nv20, nv30): any value is warned about and ignored.",
                 "any value",
                 [](std::string_view value, const SetContext& c, TengineOptions&) {
                     c.warnings.push_back(c.entry.location() + ": cg_profile = " + std::string(value) +
                                          " is ignored: Cg is not used");
                     return true;
                 },
                 {}});
    return t;
}

const std::vector<OptionSpec>& optionTable()
{
    static const std::vector<OptionSpec> table = makeOptionTable();
    return table;
}

const std::vector<OptionSpec>& ignoredOptionTable()
{
    static const std::vector<OptionSpec> table = makeIgnoredOptionTable();
    return table;
}

const OptionSpec* findOption(std::string_view key)
{
    for (const auto* table : {&optionTable(), &ignoredOptionTable()}) {
        for (const OptionSpec& spec : *table) {
            if (spec.key == key) {
                return &spec;
            }
        }
    }
    return nullptr;
}

std::size_t editDistance(std::string_view a, std::string_view b)
{
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) {
        row[j] = j;
    }
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diagonal = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            std::size_t substitution = diagonal + (a[i - 1] == b[j - 1] ? 0 : 1);
            diagonal = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, substitution});
        }
    }
    return row[b.size()];
}

/// The known key nearest to `key`, when it is near enough to be a typo: at most a third of the key's
/// letters wrong, and never more than 3.
std::optional<std::string_view> closestKey(std::string_view key)
{
    const std::size_t limit = std::clamp<std::size_t>(key.size() / 3, 1, 3);
    std::optional<std::string_view> best;
    std::size_t bestDistance = limit + 1;
    for (const auto* table : {&optionTable(), &ignoredOptionTable()}) {
        for (const OptionSpec& spec : *table) {
            std::size_t d = editDistance(key, spec.key);
            if (d < bestDistance) {
                bestDistance = d;
                best = spec.key;
            }
        }
    }
    return best;
}

Status applyEntry(const ConfigEntry& entry, const std::filesystem::path& baseDirectory, TengineOptions& options,
                  std::vector<std::string>& warnings)
{
    const OptionSpec* spec = findOption(entry.key);
    if (!spec) {
        std::string warning = entry.location() + ": unknown option '" + entry.key + "' ignored";
        if (auto suggestion = closestKey(entry.key)) {
            warning += " (did you mean '" + std::string(*suggestion) + "'?)";
        }
        warnings.push_back(std::move(warning));
        return {};
    }
    SetContext context{entry, baseDirectory, warnings};
    if (!spec->set(entry.value, context, options)) {
        return makeError(entry.location(), ": invalid value '", entry.value, "' for ", entry.key, ": expected ",
                         spec->expected);
    }
    // Demo and video mode exclude each other: the later of the two settings wins, and says so.
    if (options.demoMode && options.videoMode && (entry.key == "video_mode" || entry.key == "demo_mode")) {
        const bool video = entry.key == "video_mode";
        (video ? options.demoMode : options.videoMode) = false;
        warnings.push_back(entry.location() + ": " + entry.key + " = true turns " +
                           (video ? "demo_mode" : "video_mode") + " off (of the two, the later setting wins)");
    }
    return {};
}

/// Wraps `text` into "# " comment lines of at most `width` characters.
void writeComment(std::ostringstream& out, std::string_view text, std::size_t width = 100)
{
    std::string line = "#";
    std::istringstream words{std::string(text)};
    std::string word;
    while (words >> word) {
        if (line.size() > 1 && line.size() + 1 + word.size() > width) {
            out << line << "\n";
            line = "#";
        }
        line += " " + word;
    }
    out << line << "\n";
}

/// `key = value`, quoting values a plain line would change (comments, surrounding spaces).
void writeSetting(std::ostringstream& out, std::string_view prefix, std::string_view key, const std::string& value)
{
    out << prefix << key << " =";
    if (value.empty()) {
        out << "\n";
        return;
    }
    bool quote =
        value.find('#') != std::string::npos || value.front() == ' ' || value.back() == ' ' || value.front() == '"';
    out << " " << (quote ? "\"" : "") << value << (quote ? "\"" : "") << "\n";
}

/// The most camera_z_far / camera_z_near a 24-bit depth buffer resolves to the far plane: 2^24.
constexpr double kMaxDepthRange = 16777216.0;

Status validate(const TengineOptions& o)
{
    if (!(o.cameraZFar > o.cameraZNear)) {
        return makeError("camera_z_far (", formatNumber(o.cameraZFar), ") must be greater than camera_z_near (",
                         formatNumber(o.cameraZNear), ")");
    }
    // A 24-bit depth buffer tells a point at distance d from the far plane while 2 near / d > 2^-24: beyond
    // that ratio the far terrain (all of it, past a point) lands on the cleared depth and is not drawn.
    if (!(o.cameraZFar / o.cameraZNear <= kMaxDepthRange)) {
        return makeError("camera_z_far / camera_z_near is ", formatNumber(o.cameraZFar / o.cameraZNear),
                         ": the depth buffer cannot tell distances apart beyond ", formatNumber(kMaxDepthRange),
                         " (the far terrain would not be drawn); raise camera_z_near or lower camera_z_far");
    }
    if (o.demoMode && o.cameraPath.empty()) {
        return makeError("demo_mode needs a camera_path");
    }
    if (o.videoMode && o.cameraPath.empty()) {
        return makeError("video_mode needs a camera_path");
    }
    if (o.videoMeasureErrorEvery > 0 && (!o.videoMode || o.demoMode)) {
        return makeError(
            "video_measure_error_every measures video frames: it needs video_mode = true (and "
            "demo_mode = false)");
    }
    return {};
}

}  // namespace

Status applyConfig(const ConfigFile& config, TengineOptions& options, std::vector<std::string>& warnings)
{
    for (const ConfigEntry& entry : config.entries()) {
        TERRAIN_TRY(applyEntry(entry, config.directory(), options, warnings));
    }
    return {};
}

Status applySetting(std::string_view keyEqualsValue, TengineOptions& options, std::vector<std::string>& warnings)
{
    auto entry = ConfigFile::parseEntry(keyEqualsValue, "--set", 0);
    TERRAIN_TRY(entry);
    // A config may hold keys of other versions (a warning); a --set was typed for this run: an unknown key is
    // an error.
    if (!findOption(entry->key)) {
        std::string message = "--set: unknown option '" + entry->key + "'";
        if (auto suggestion = closestKey(entry->key)) {
            message += " (did you mean '" + std::string(*suggestion) + "'?)";
        }
        return Error{message + " (see configs/tengine.cfg for every option)"};
    }
    return applyEntry(*entry, {}, options, warnings);
}

Status validateTengineOptions(const TengineOptions& options)
{
    return validate(options);
}

namespace {

enum class ArgumentKind { Map, Config, Unknown };

/// A map when the file starts with the map signature or is named .map (opening it then says what is wrong with
/// it), a config when it is named .cfg; otherwise it has to parse as a config.
ArgumentKind classifyArgument(const std::string& arg)
{
    if (arg.ends_with(".map")) {
        return ArgumentKind::Map;
    }
    std::ifstream in(arg, std::ios::binary);
    if (!in) {
        return arg.ends_with(".cfg") ? ArgumentKind::Config : ArgumentKind::Unknown;
    }
    std::array<char, kMapMagic.size()> head{};
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    if (in.gcount() == static_cast<std::streamsize>(head.size()) &&
        std::equal(head.begin(), head.end(), kMapMagic.begin(),
                   [](char a, std::uint8_t b) { return static_cast<std::uint8_t>(a) == b; })) {
        return ArgumentKind::Map;
    }
    return arg.ends_with(".cfg") ? ArgumentKind::Config : ArgumentKind::Unknown;
}

}  // namespace

Expected<ParsedCommandLine> parseTengineCommandLine(const std::vector<std::string>& arguments)
{
    ParsedCommandLine result;
    std::optional<std::filesystem::path> mapArgument;
    for (std::size_t i = 0; i < arguments.size(); ++i) {
        const std::string& arg = arguments[i];
        if (arg == "--help" || arg == "-h") {
            result.help = true;
            return result;
        }
        if (arg == "--print-config") {
            result.printConfig = true;
        } else if (arg == "--set" || arg.starts_with("--set=")) {
            std::string setting;
            if (arg == "--set") {
                if (i + 1 >= arguments.size()) {
                    return makeError("--set needs a value: --set key=value");
                }
                setting = arguments[++i];
            } else {
                setting = arg.substr(6);
            }
            TERRAIN_TRY(applySetting(setting, result.options, result.warnings));
        } else if (arg.size() > 1 && arg.front() == '-') {
            return makeError("unknown argument '", arg, "' (see --help)");
        } else {
            // A map by its signature, a config by parsing (any name); anything else is an error naming it.
            if (std::error_code ec; std::filesystem::is_directory(arg, ec)) {
                return makeError("'", arg, "' is a directory, not a map or a config file");
            }
            const ArgumentKind kind = classifyArgument(arg);
            if (kind == ArgumentKind::Map) {
                if (mapArgument) {
                    return makeError("two maps on the command line, '", mapArgument->string(), "' and '", arg,
                                     "': give one");
                }
                mapArgument = arg;
                continue;
            }
            auto config = ConfigFile::load(arg);
            if (!config.ok()) {
                if (kind == ArgumentKind::Config) {
                    return config.error();
                }
                return makeError("'", arg, "' is neither a map (it does not start with the map signature) nor a ",
                                 "config file (", config.error().message, ")");
            }
            TERRAIN_TRY(applyConfig(*config, result.options, result.warnings));
            result.configFiles.emplace_back(arg);
        }
    }
    if (mapArgument) {
        result.options.mapFile = *mapArgument;
    }
    TERRAIN_TRY(validate(result.options));
    return result;
}

Expected<ParsedCommandLine> parseTengineCommandLine(int argc, char** argv)
{
    std::vector<std::string> arguments;
    for (int i = 1; i < argc; ++i) {
        arguments.emplace_back(argv[i]);
    }
    return parseTengineCommandLine(arguments);
}

std::string tengineUsage()
{
    return R"(usage: tengine [FILE.cfg | FILE.map | --set key=value]... [--print-config] [--help]

Renders a terrain map made by prep (paper 4.4.2).

  FILE.cfg          a configuration file ('option = value' lines; see configs/tengine.cfg for every
                    option with its default). Files are read in order; later ones override earlier ones.
                    Any name works: a file that is not a map must parse as a config.
  FILE.map          the terrain map (known by its signature, or by the name .map); overrides map_file.
                    One at most.
  --set key=value   set one option, in command-line order with the .cfg files (a later one wins)
  --print-config    print the resulting options as a config file and exit
  --help            this text
)";
}

const std::vector<std::string_view>& tengineOptionKeys()
{
    static const std::vector<std::string_view> keys = [] {
        std::vector<std::string_view> k;
        for (const OptionSpec& spec : optionTable()) {
            k.push_back(spec.key);
        }
        return k;
    }();
    return keys;
}

const std::vector<std::string_view>& ignoredTengineOptionKeys()
{
    static const std::vector<std::string_view> keys = [] {
        std::vector<std::string_view> k;
        for (const OptionSpec& spec : ignoredOptionTable()) {
            k.push_back(spec.key);
        }
        return k;
    }();
    return keys;
}

std::string formatTengineOption(const TengineOptions& options, std::string_view key)
{
    const OptionSpec* spec = findOption(key);
    TERRAIN_EXPECTS(spec && spec->get, "formatTengineOption: key must be one of tengineOptionKeys()");
    return spec->get(options);
}

std::string tengineConfigText(const TengineOptions& options)
{
    std::ostringstream out;
    out << "# tengine configuration (paper 4.3, Appendix A). Syntax: 'option = value'; '#' starts a comment;\n"
           "# quote a value (\"...\") to keep spaces or '#'. Files given later on the command line, and\n"
           "# --set key=value, override earlier ones. Every option is listed with its default value.\n"
           "#\n"
           "# This file is checked against the code by a unit test (TengineOptionsTest); regenerate it with\n"
           "#     tengine --print-config > configs/tengine.cfg\n";
    std::string_view group;
    for (const OptionSpec& spec : optionTable()) {
        if (spec.group != group) {
            group = spec.group;
            out << "\n# ==== " << group << " ====\n";
        }
        out << "\n";
        writeComment(out, spec.doc);
        writeComment(out, "Valid: " + spec.expected + ".");
        writeSetting(out, "", spec.key, spec.get(options));
    }
    out << "\n# ==== Direct3D / Cg options of the paper's viewer (accepted for compatibility) ====\n";
    const std::pair<std::string_view, std::string> examples[] = {
        {"render", "gl"}, {"memory", "gl_vbo"}, {"cg_profile", "arb"}};
    for (const auto& [key, example] : examples) {
        const OptionSpec* spec = findOption(key);
        TERRAIN_ASSERT(spec);
        out << "\n";
        writeComment(out, spec->doc);
        writeSetting(out, "# ", key, example);
    }
    return out.str();
}

std::filesystem::path recordedCameraPathFile(const TengineOptions& options)
{
    return options.cameraPath.empty() ? std::filesystem::path("recorded.path")
                                      : std::filesystem::path(options.cameraPath.string() + ".recorded");
}

Status checkOutputsAreNotInputs(const ParsedCommandLine& parsed,
                                const std::vector<std::filesystem::path>& materialFiles)
{
    const TengineOptions& o = parsed.options;
    std::vector<InputFile> inputs = {{"map", o.mapFile}, {"camera path", o.cameraPath}};
    for (const auto& config : parsed.configFiles) {
        inputs.push_back({"config file", config});
    }
    for (const auto& material : materialFiles) {
        inputs.push_back({"material", material});
    }
    if (!o.logFile.empty()) {
        TERRAIN_TRY(refuseInputAsOutput("log (log_file)", o.logFile, inputs));
    }
    TERRAIN_TRY(refuseInputAsOutput("recorded camera keyframes", recordedCameraPathFile(o), inputs));
    if (o.videoMode && !o.demoMode) {
        TERRAIN_TRY(refuseInputAsOutput("video frames (image_path)", o.imagePath, inputs));
        // An input inside image_path under one of the names a recording writes would be replaced.
        for (const InputFile& input : inputs) {
            const std::string name = input.path.filename().string();
            if (!input.path.empty() && VideoRecorder::isRecorderFileName(name)) {
                TERRAIN_TRY(refuseInputAsOutput("video mode's " + name, o.imagePath / name, std::span(&input, 1)));
            }
        }
    }
    return {};
}

}  // namespace terrain
