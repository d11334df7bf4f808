// `tengine-tool error`: the screen-space error the viewer draws, measured (lod/ErrorMeter.h) frame by frame
// from a camera or along a camera path, with the viewer's own options (config files and --set), its
// materials and morph factors, and the loader run to completion every frame (no velocity limit).
#pragma once

#include "apps/TengineOptions.h"
#include "core/Camera.h"
#include "core/Expected.h"
#include "quadtree/MapFile.h"

#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace terrain {

struct ErrorCommand {
    TengineOptions options;             ///< the viewer's, from the configs and --set (lod_error = --tau)
    std::vector<std::string> warnings;  ///< from reading the configs
    std::optional<Camera> camera;       ///< --camera: one frame
    std::filesystem::path path;         ///< --path: a frame every 1 / fps seconds of path
    double fps = 0.0;                   ///< --fps, else frames_per_second
    bool levels = false;                ///< --levels: a table of bounds against measured errors per level
    bool oracle = false;                ///< --oracle: the fewest nodes within tau by measured errors, per frame
    int oracleBlocks = 0;               ///< --oracle=B: by B x B blocks' metres projected as bounds (0: pixels)
    bool pops = false;                  ///< --pops: tessellation blocks' level switches between frames, no error
    Camera lens;                        ///< viewport, field of view, near and far planes
};

/// The value of --camera, "X,Y,Z,YAW,PITCH" (metres and degrees; yaw 0 looks north, pitch in [-90, 90]),
/// into `camera`'s position and orientation.
Status parseCameraArgument(const std::string& value, Camera& camera);

/// Parses `error`'s arguments after the map: CONFIG.cfg files and --set key=value (applied in order, as
/// tengine does), --camera X,Y,Z,YAW,PITCH or --path FILE (exactly one), --tau T, --size WxH, --fov DEG,
/// --fps F, --levels, --oracle[=B], --pops. `mapFile` becomes the options' map_file. Errors name the argument and what
/// was wrong.
Expected<ErrorCommand> parseErrorCommand(const std::filesystem::path& mapFile, const std::vector<std::string>& args);

/// Runs the measurement on `map`, printing a line per frame and the summary to `out` and warnings to `err`.
/// `builtInMaterials` is where the built-in materials live. Returns 0, or 1 after printing an error (a
/// camera outside the terrain, a node that cannot be read, a material that cannot be loaded).
int runErrorCommand(const MapFile& map, const ErrorCommand& command, const std::filesystem::path& builtInMaterials,
                    std::FILE* out, std::FILE* err);

}  // namespace terrain
