// The tengine viewer's options (paper Appendix A, 4.3) and its command line (paper 4.4.2).
//
// Every Appendix A option that applies to OpenGL is honoured; the Direct3D/Cg ones (`render`, `memory`,
// `cg_profile`) are accepted with a warning where they ask for something we do not do. Options of our own
// are documented in configs/tengine.cfg, which lists every key with its default (a unit test keeps that
// file and this struct's defaults equal; defaultTengineConfigText() renders it).
//
// Path options: `map_file` and `camera_path` are inputs and, when relative inside a config file, are
// resolved against that file's directory (a demo config can sit next to its map and path). `log_file` and
// `image_path` are outputs and stay relative to the working directory. Paths from `--set` or the command
// line are used as given.
#pragma once

#include "core/ConfigFile.h"
#include "core/Expected.h"
#include "quadtree/MapFile.h"

#include <glm/vec3.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace terrain {

/// Everything a config file can set. Defaults are the documented defaults; ranges are in the comments
/// and in configs/tengine.cfg.
struct TengineOptions {
    // ---- Map and level of detail ----
    std::filesystem::path mapFile;    ///< map_file; the command line's map argument wins
    double lodError = 2.0;            ///< lod_error: tau, pixels, > 0 (eq. 3.3)
    double lodMinimumSpacing = 0.01;  ///< lod_minimum_spacing: metres, >= 0; no finer detail
    int dynamicTextureSize = 128;     ///< dynamic_texture_size: normal map texels, 0 or 2^k(+1) in [16, 4096]
    int vertexCacheSize = 16;         ///< vertex_cache_size: entries, [4, 64] (3.2.10)
    int memoryBudget = 0;             ///< memory_budget: MiB for resident nodes; 0: from the machine
    int quadCacheSize = 0;            ///< quad_cache_size: nodes, >= 5; 0: from memory_budget
    ReaderKind reader = ReaderKind::MemoryMapped;  ///< reader: stream | memory_mapped
    int workerThreads = 1;                         ///< worker_threads: >= 0; 0 loads on the render thread
    int requestQueueSize = 8;                      ///< request_queue_size: node groups waiting, >= 1
    bool visibilityLod = false;                    ///< visibility_lod: hidden terrain is not refined
    int visibilityHiddenFrames = 4;                ///< visibility_hidden_frames: dark frames before hidden, [1, 64]
    double visibilityRevealSeconds = 0.1;          ///< visibility_reveal_seconds: morph-in per level, > 0

    // ---- Detail synthesis (3.3, 3.4) ----
    bool detailCreateNewNodes = true;                 ///< detail_create_new_nodes
    double detailSubdivisionFactor = 1.0;             ///< detail_subdivision_factor: omega in [0, 2]
    bool detailAddMaterial = true;                    ///< detail_add_material
    bool detailRoughness = true;                      ///< detail_roughness
    int detailMaterialType = 0;                       ///< detail_material_type: 0 (grass.mat) or 1 (rock.mat)
    std::string detailSubdivisionScheme = "kobbelt";  ///< detail_subdivision_scheme: kobbelt | bilinear | catmull-clark
    std::vector<std::filesystem::path>
        detailMaterials;                 ///< detail_materials: a material set; empty = detail_material_type
    std::filesystem::path materialPath;  ///< material_path: built-in materials; empty = this build's materials/
    double detailVelocityLimit = 100.0;  ///< detail_velocity_limit: new-node samples per second, >= 0; 0 = off

    // ---- Camera ----
    double cameraFov = 60.0;                   ///< camera_fov: vertical, degrees, in (1, 179)
    double cameraZNear = 1.0;                  ///< camera_z_near: metres, > 0
    double cameraZFar = 200000.0;              ///< camera_z_far: metres, > camera_z_near
    double cameraMinClearance = 2.0;           ///< camera_min_clearance: metres, >= 0; free flight only
    std::filesystem::path cameraPath;          ///< camera_path: empty = none
    std::optional<glm::dvec3> cameraPosition;  ///< camera_position: metres; unset = framing the whole terrain
    double cameraYaw = 0.0;                    ///< camera_yaw: degrees, 0 = north, positive turns east
    double cameraPitch = -45.0;                ///< camera_pitch: degrees in [-90, 90], positive up

    // ---- Display ----
    int windowWidth = 1280;               ///< window_width: pixels, [16, 16384]
    int windowHeight = 720;               ///< window_height: pixels, [16, 16384]
    bool drawUserInterface = true;        ///< draw_user_interface
    bool drawSky = true;                  ///< draw_sky
    bool wireframe = false;               ///< wireframe
    bool geomorph = true;                 ///< geomorph: off draws every node at its own detail (pops)
    bool nodeTextureCompression = false;  ///< node_texture_compression: DXT1 colour textures on the GPU
    /// normal_map_compression: RGTC2 normal maps on the GPU (On), RG8 (Off), or RGTC2 unless the GL rasterizes
    /// in software (Auto: llvmpipe draws RG8 faster; a GPU decodes RGTC2 for free).
    enum class Compression { Auto, On, Off };
    Compression normalMapCompression = Compression::Auto;
    bool tessellation = true;                 ///< render_mode: true tessellation or blocks, false chunks
    bool blockIndices = true;                 ///< render_mode = blocks: the blocks drawn from index lists
    bool clipmap = false;                     ///< lod_mode: false quadtree, true clipmap (seed 002)
    int clipmapSamples = 255;                 ///< clipmap_samples: n = 2^k - 1 in [15, 1023]
    double clipmapFinestSpacing = 1.0;        ///< clipmap_finest_spacing: metres, > 0
    double clipmapMorphSeconds = 0.3;         ///< clipmap_morph_seconds: >= 0
    double tessellationShare = 0.5;           ///< tessellation_error_share: the part of tau the blocks spend
    double sunAzimuth = 135.0;                ///< sun_azimuth: degrees in [0, 360], clockwise from north
    double sunElevation = 35.0;               ///< sun_elevation: degrees in [-90, 90] above the horizon
    double hazeDistance = 60000.0;            ///< haze_distance: metres, >= 0; 0 = no haze
    bool shadows = true;                      ///< shadows: terrain shadows and sky visibility (lod/NodeHorizons.h)
    bool atmosphere = true;                   ///< atmosphere: physically based sky and air (light/Atmosphere.h)
    double exposure = 5.0;                    ///< exposure: the tone map's, of radiance relative to the sun's, > 0
    glm::vec3 clearColor{0.55f, 0.7f, 0.9f};  ///< clear_color: r, g, b in [0, 1]
    std::filesystem::path shaderPath;         ///< shader_path: empty = the shaders/ directory of this build
    std::filesystem::path logFile;            ///< log_file: empty = stderr only

    // ---- Demo and video mode ----
    bool demoMode = false;                       ///< demo_mode: fly camera_path forever; overrides video_mode
    bool videoMode = false;                      ///< video_mode: fly camera_path once, saving frames
    int framesPerSecond = 30;                    ///< frames_per_second: video frames per path second, [1, 240]
    std::filesystem::path imagePath = "frames";  ///< image_path: directory for video frames
    int videoFrames = 0;                         ///< video_frames: >= 0; stop after this many, 0 = whole path
    int videoSaveEvery = 1;                      ///< video_save_every: >= 0; PNG of every Nth frame, 0 = none
    bool videoFfmpeg = true;                     ///< video_ffmpeg: make an MP4 when ffmpeg is on PATH
    int videoMeasureErrorEvery = 0;  ///< video_measure_error_every: >= 0; ErrorMeter on every Nth frame, 0 = none

    bool operator==(const TengineOptions&) const = default;
};

/// Applies every entry of `config` in file order (a later entry wins). Unknown keys and ignored
/// Direct3D/Cg settings append a warning ("file:line: ...") to `warnings`; an invalid value returns an
/// Error "file:line: invalid value 'v' for key: expected ..." and stops (`options` keeps what was applied
/// before it). Checks each value alone; relations between options are validateTengineOptions()'s.
Status applyConfig(const ConfigFile& config, TengineOptions& options, std::vector<std::string>& warnings);

/// Applies one `key=value` (from `--set`), with the rules of applyConfig() except that an unknown key is an
/// error (it was typed for this run); messages name "--set". Setting demo_mode or video_mode to true turns the
/// other off, with a warning (the later of the two wins), in configs too.
Status applySetting(std::string_view keyEqualsValue, TengineOptions& options, std::vector<std::string>& warnings);

/// Checks the rules between options once all are applied: camera_z_far > camera_z_near; demo_mode and
/// video_mode need a camera_path.
Status validateTengineOptions(const TengineOptions& options);

/// The result of the command line.
struct ParsedCommandLine {
    TengineOptions options;
    std::vector<std::string> warnings;               ///< for the app to print or log
    std::vector<std::filesystem::path> configFiles;  ///< the .cfg files read, in order
    bool help = false;                               ///< --help: print tengineUsage() and exit
    bool printConfig = false;                        ///< --print-config: print the resulting options as a config
};

/// Parses tengine's arguments (without the program name), paper 4.4.2: each config file is read and applied,
/// and each `--set key=value` applied, in command-line order, so later ones override earlier ones. An argument
/// is the map when its file starts with the map signature (kMapMagic) or is named .map; it overrides every
/// `map_file` setting, and a second one is an error. Any other argument must be a config file (named .cfg, or
/// parsing as one): what is neither is an error naming it, never dropped. Then validateTengineOptions().
/// `--help` stops parsing. Errors: unknown `-` options, a missing `--set` value, an unknown `--set` key,
/// unreadable configs, syntax errors and invalid values.
Expected<ParsedCommandLine> parseTengineCommandLine(const std::vector<std::string>& arguments);
/// The same for main()'s arguments (argv[0] is skipped).
Expected<ParsedCommandLine> parseTengineCommandLine(int argc, char** argv);

/// The file free flight appends recorded camera keyframes to (key k): camera_path + ".recorded", or
/// "recorded.path" in the working directory when no path is set.
std::filesystem::path recordedCameraPathFile(const TengineOptions& options);

/// Refuses outputs that would overwrite an input (nothing is lost): log_file, the recorded camera
/// keyframes and, in video mode, image_path and the files a recording writes there may not be the map, a
/// config file, the camera path or one of `materialFiles`, through any path or link. The error names both.
Status checkOutputsAreNotInputs(const ParsedCommandLine& parsed,
                                const std::vector<std::filesystem::path>& materialFiles);

/// The --help text.
std::string tengineUsage();

/// Every key TengineOptions holds, in documentation order (the Direct3D/Cg keys are not among them).
const std::vector<std::string_view>& tengineOptionKeys();
/// Keys accepted only for compatibility with the paper's Direct3D/Cg viewer: render, memory, cg_profile.
const std::vector<std::string_view>& ignoredTengineOptionKeys();

/// The value of `key` in `options` as a config file writes it (reads back to the same value). `key` must
/// be one of tengineOptionKeys() (checked precondition).
std::string formatTengineOption(const TengineOptions& options, std::string_view key);

/// `options` as a documented config file: every key grouped, each with what it does and its valid values,
/// and the Direct3D/Cg options as commented-out examples. With default options this is
/// configs/tengine.cfg.
std::string tengineConfigText(const TengineOptions& options = TengineOptions{});

}  // namespace terrain
