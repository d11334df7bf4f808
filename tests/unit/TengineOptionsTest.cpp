// tengine's options (paper Appendix A) and command line (4.4.2): every option's valid and invalid
// values, the documented defaults in configs/tengine.cfg, the override order of config files, --set and
// the map argument, and warnings for unknown keys and the paper's Direct3D/Cg options.
#include "TestSupport.h"
#include "apps/TengineOptions.h"
#include "quadtree/MapFormat.h"

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <iterator>
#include <set>
#include <sstream>

namespace terrain {
namespace {

const std::filesystem::path kDefaultConfig = std::filesystem::path(TERRAIN_CONFIGS_DIR) / "tengine.cfg";

bool contains(const std::string& text, const std::string& what)
{
    return text.find(what) != std::string::npos;
}

/// Applies `setting` to default options; fails the test on an error.
TengineOptions withSetting(const std::string& setting, std::vector<std::string>* warningsOut = nullptr)
{
    TengineOptions options;
    std::vector<std::string> warnings;
    Status status = applySetting(setting, options, warnings);
    EXPECT_TRUE(status.ok()) << setting << ": " << (status.ok() ? "" : status.error().message);
    if (warningsOut) {
        *warningsOut = warnings;
    }
    return options;
}

/// The error applying `setting` gives ("" when it was accepted, which fails the caller's EXPECT).
std::string settingError(const std::string& setting)
{
    TengineOptions options;
    std::vector<std::string> warnings;
    Status status = applySetting(setting, options, warnings);
    return status.ok() ? "" : status.error().message;
}

// ---- Defaults ----

TEST(TengineOptions, DefaultsAreTheDocumentedOnes)
{
    TengineOptions o;
    EXPECT_TRUE(o.mapFile.empty());
    EXPECT_EQ(o.lodError, 2.0);
    EXPECT_EQ(o.lodMinimumSpacing, 0.01);
    EXPECT_EQ(o.dynamicTextureSize, 128);
    EXPECT_EQ(o.vertexCacheSize, 16);
    EXPECT_EQ(o.quadCacheSize, 0);
    EXPECT_EQ(o.memoryBudget, 0);
    EXPECT_EQ(o.reader, ReaderKind::MemoryMapped);
    EXPECT_EQ(o.workerThreads, 1);
    EXPECT_EQ(o.requestQueueSize, 8);
    EXPECT_FALSE(o.visibilityLod);
    EXPECT_EQ(o.visibilityHiddenFrames, 4);
    EXPECT_EQ(o.visibilityRevealSeconds, 0.1);
    EXPECT_TRUE(o.detailCreateNewNodes);
    EXPECT_EQ(o.detailSubdivisionFactor, 1.0);
    EXPECT_TRUE(o.detailAddMaterial);
    EXPECT_EQ(o.detailMaterialType, 0);
    EXPECT_EQ(o.cameraFov, 60.0);
    EXPECT_EQ(o.cameraZNear, 1.0);
    EXPECT_EQ(o.cameraZFar, 200000.0);
    EXPECT_TRUE(o.cameraPath.empty());
    EXPECT_FALSE(o.cameraPosition.has_value());
    EXPECT_EQ(o.windowWidth, 1280);
    EXPECT_EQ(o.windowHeight, 720);
    EXPECT_TRUE(o.drawUserInterface);
    EXPECT_TRUE(o.drawSky);
    EXPECT_FALSE(o.wireframe);
    EXPECT_EQ(o.sunAzimuth, 135.0);
    EXPECT_EQ(o.sunElevation, 35.0);
    EXPECT_EQ(o.hazeDistance, 60000.0);
    EXPECT_TRUE(o.logFile.empty());
    EXPECT_FALSE(o.demoMode);
    EXPECT_FALSE(o.videoMode);
    EXPECT_EQ(o.framesPerSecond, 30);
    EXPECT_EQ(o.imagePath, "frames");
    EXPECT_EQ(o.videoFrames, 0);
    EXPECT_EQ(o.videoSaveEvery, 1);
    EXPECT_TRUE(o.videoFfmpeg);
    EXPECT_TRUE(validateTengineOptions(o).ok());
}

// ---- Valid values: one or more per key, each checked on the field it must set ----

struct ValidCase {
    const char* setting;
    std::function<bool(const TengineOptions&)> holds;
};

const std::vector<ValidCase>& validCases()
{
    using O = TengineOptions;
    static const std::vector<ValidCase> cases = {
        {"map_file=other/terrain.map", [](const O& o) { return o.mapFile == "other/terrain.map"; }},
        {"lod_error=0.5", [](const O& o) { return o.lodError == 0.5; }},
        {"lod_error=1e-3", [](const O& o) { return o.lodError == 0.001; }},
        {"lod_minimum_spacing=0", [](const O& o) { return o.lodMinimumSpacing == 0.0; }},
        {"lod_minimum_spacing=0.25", [](const O& o) { return o.lodMinimumSpacing == 0.25; }},
        {"dynamic_texture_size=0", [](const O& o) { return o.dynamicTextureSize == 0; }},
        {"dynamic_texture_size=16", [](const O& o) { return o.dynamicTextureSize == 16; }},
        {"dynamic_texture_size=17", [](const O& o) { return o.dynamicTextureSize == 17; }},
        {"dynamic_texture_size=257", [](const O& o) { return o.dynamicTextureSize == 257; }},
        {"dynamic_texture_size=4096", [](const O& o) { return o.dynamicTextureSize == 4096; }},
        {"vertex_cache_size=4", [](const O& o) { return o.vertexCacheSize == 4; }},
        {"vertex_cache_size=64", [](const O& o) { return o.vertexCacheSize == 64; }},
        {"quad_cache_size=5", [](const O& o) { return o.quadCacheSize == 5; }},
        {"quad_cache_size=0", [](const O& o) { return o.quadCacheSize == 0; }},
        {"quad_cache_size=100000", [](const O& o) { return o.quadCacheSize == 100000; }},
        {"memory_budget=0", [](const O& o) { return o.memoryBudget == 0; }},
        {"memory_budget=256", [](const O& o) { return o.memoryBudget == 256; }},
        {"reader=stream", [](const O& o) { return o.reader == ReaderKind::Stream; }},
        {"worker_threads=0", [](const O& o) { return o.workerThreads == 0; }},
        {"worker_threads=8", [](const O& o) { return o.workerThreads == 8; }},
        {"request_queue_size=1", [](const O& o) { return o.requestQueueSize == 1; }},
        {"visibility_lod=yes", [](const O& o) { return o.visibilityLod; }},
        {"visibility_hidden_frames=12", [](const O& o) { return o.visibilityHiddenFrames == 12; }},
        {"visibility_reveal_seconds=0.5", [](const O& o) { return o.visibilityRevealSeconds == 0.5; }},
        {"video_measure_error_every=25", [](const O& o) { return o.videoMeasureErrorEvery == 25; }},
        {"detail_create_new_nodes=false", [](const O& o) { return !o.detailCreateNewNodes; }},
        {"detail_subdivision_factor=0", [](const O& o) { return o.detailSubdivisionFactor == 0.0; }},
        {"detail_subdivision_factor=2", [](const O& o) { return o.detailSubdivisionFactor == 2.0; }},
        {"detail_add_material=no", [](const O& o) { return !o.detailAddMaterial; }},
        {"detail_roughness=off", [](const O& o) { return !o.detailRoughness; }},
        {"detail_material_type=1", [](const O& o) { return o.detailMaterialType == 1; }},
        {"detail_subdivision_scheme=catmull-clark",
         [](const O& o) { return o.detailSubdivisionScheme == "catmull-clark"; }},
        {"detail_subdivision_scheme=bilinear", [](const O& o) { return o.detailSubdivisionScheme == "bilinear"; }},
        {"detail_materials=a.mat, /m/b.mat",
         [](const O& o) {
             return o.detailMaterials == std::vector<std::filesystem::path>{"a.mat", "/m/b.mat"};
         }},
        {"material_path=my/materials", [](const O& o) { return o.materialPath == "my/materials"; }},
        {"detail_velocity_limit=0", [](const O& o) { return o.detailVelocityLimit == 0.0; }},
        {"detail_velocity_limit=12.5", [](const O& o) { return o.detailVelocityLimit == 12.5; }},
        {"camera_fov=1.5", [](const O& o) { return o.cameraFov == 1.5; }},
        {"camera_fov=178.9", [](const O& o) { return o.cameraFov == 178.9; }},
        {"camera_z_near=0.1", [](const O& o) { return o.cameraZNear == 0.1; }},
        {"camera_min_clearance=0.5", [](const O& o) { return o.cameraMinClearance == 0.5; }},
        {"camera_z_far=5000", [](const O& o) { return o.cameraZFar == 5000.0; }},
        {"camera_path=demos/flight.path", [](const O& o) { return o.cameraPath == "demos/flight.path"; }},
        {"camera_position=100, -2.5,3e3",
         [](const O& o) { return o.cameraPosition == glm::dvec3(100.0, -2.5, 3000.0); }},
        {"camera_yaw=-90", [](const O& o) { return o.cameraYaw == -90.0; }},
        {"camera_pitch=90", [](const O& o) { return o.cameraPitch == 90.0; }},
        {"camera_pitch=-90", [](const O& o) { return o.cameraPitch == -90.0; }},
        {"window_width=640", [](const O& o) { return o.windowWidth == 640; }},
        {"window_height=480", [](const O& o) { return o.windowHeight == 480; }},
        {"draw_user_interface=off", [](const O& o) { return !o.drawUserInterface; }},
        {"draw_sky=0", [](const O& o) { return !o.drawSky; }},
        {"wireframe=on", [](const O& o) { return o.wireframe; }},
        {"sun_azimuth=0", [](const O& o) { return o.sunAzimuth == 0.0; }},
        {"sun_azimuth=360", [](const O& o) { return o.sunAzimuth == 360.0; }},
        {"sun_elevation=-5", [](const O& o) { return o.sunElevation == -5.0; }},
        {"haze_distance=0", [](const O& o) { return o.hazeDistance == 0.0; }},
        {"atmosphere=false", [](const O& o) { return !o.atmosphere; }},
        {"shadows=false", [](const O& o) { return !o.shadows; }},
        {"exposure=0.25", [](const O& o) { return o.exposure == 0.25; }},
        {"clear_color=0, 0.5,1", [](const O& o) { return o.clearColor == glm::vec3(0.0f, 0.5f, 1.0f); }},
        {"geomorph=off", [](const O& o) { return !o.geomorph; }},
        {"node_texture_compression=on", [](const O& o) { return o.nodeTextureCompression; }},
        {"normal_map_compression=auto", [](const O& o) { return o.normalMapCompression == O::Compression::Auto; }},
        {"normal_map_compression=off", [](const O& o) { return o.normalMapCompression == O::Compression::Off; }},
        {"normal_map_compression=on", [](const O& o) { return o.normalMapCompression == O::Compression::On; }},
        {"render_mode=tessellation", [](const O& o) { return o.tessellation && !o.blockIndices; }},
        {"render_mode=BLOCKS", [](const O& o) { return o.tessellation && o.blockIndices; }},
        {"render_mode=Chunks", [](const O& o) { return !o.tessellation; }},
        {"lod_mode=quadtree", [](const O& o) { return !o.clipmap; }},
        {"lod_mode=Clipmap", [](const O& o) { return o.clipmap; }},
        {"clipmap_samples=31", [](const O& o) { return o.clipmapSamples == 31; }},
        {"clipmap_samples=1023", [](const O& o) { return o.clipmapSamples == 1023; }},
        {"clipmap_finest_spacing=0.5", [](const O& o) { return o.clipmapFinestSpacing == 0.5; }},
        {"clipmap_morph_seconds=0", [](const O& o) { return o.clipmapMorphSeconds == 0.0; }},
        {"clipmap_morph_seconds=1.5", [](const O& o) { return o.clipmapMorphSeconds == 1.5; }},
        {"tessellation_error_share=0.25", [](const O& o) { return o.tessellationShare == 0.25; }},
        {"shader_path=my/shaders", [](const O& o) { return o.shaderPath == "my/shaders"; }},
        {"log_file=logs/tengine.log", [](const O& o) { return o.logFile == "logs/tengine.log"; }},
        {"demo_mode=true", [](const O& o) { return o.demoMode; }},
        {"video_mode=YES", [](const O& o) { return o.videoMode; }},
        {"frames_per_second=1", [](const O& o) { return o.framesPerSecond == 1; }},
        {"frames_per_second=240", [](const O& o) { return o.framesPerSecond == 240; }},
        {"image_path=out dir/frames", [](const O& o) { return o.imagePath == "out dir/frames"; }},
        {"video_frames=300", [](const O& o) { return o.videoFrames == 300; }},
        {"video_save_every=0", [](const O& o) { return o.videoSaveEvery == 0; }},
        {"video_save_every=25", [](const O& o) { return o.videoSaveEvery == 25; }},
        {"video_ffmpeg=false", [](const O& o) { return !o.videoFfmpeg; }},
    };
    return cases;
}

std::string keyOf(const std::string& setting)
{
    return setting.substr(0, setting.find('='));
}

TEST(TengineOptions, EveryValidValueSetsItsField)
{
    for (const ValidCase& c : validCases()) {
        SCOPED_TRACE(c.setting);
        std::vector<std::string> warnings;
        TengineOptions o = withSetting(c.setting, &warnings);
        EXPECT_TRUE(c.holds(o));
        EXPECT_TRUE(warnings.empty());
        // Only this key changed: writing the default back gives the defaults again.
        std::string key = keyOf(c.setting);
        EXPECT_TRUE(applySetting(key + "=" + formatTengineOption(TengineOptions{}, key), o, warnings).ok());
        EXPECT_EQ(o, TengineOptions{});
    }
}

TEST(TengineOptions, EveryKeyHasAValidCaseThatChangesIt)
{
    std::set<std::string> changed;
    for (const ValidCase& c : validCases()) {
        std::string key = keyOf(c.setting);
        if (withSetting(c.setting) != TengineOptions{}) {
            changed.insert(key);
        }
    }
    for (std::string_view key : tengineOptionKeys()) {
        EXPECT_TRUE(changed.count(std::string(key))) << key << " has no valid case that changes it";
    }
}

TEST(TengineOptions, FormattedValuesReadBackExactly)
{
    // Every valid case's options, written with formatTengineOption and read back, are the same options.
    for (const ValidCase& c : validCases()) {
        SCOPED_TRACE(c.setting);
        TengineOptions set = withSetting(c.setting);
        TengineOptions readBack;
        std::vector<std::string> warnings;
        for (std::string_view key : tengineOptionKeys()) {
            std::string setting = std::string(key) + "=\"" + formatTengineOption(set, key) + "\"";
            ASSERT_TRUE(applySetting(setting, readBack, warnings).ok()) << setting;
        }
        EXPECT_EQ(readBack, set);
    }
}

TEST(TengineOptions, BooleansAcceptTheUsualSpellings)
{
    for (const char* yes : {"true", "1", "yes", "on", "TRUE", "Yes", "On"}) {
        SCOPED_TRACE(yes);
        EXPECT_TRUE(withSetting(std::string("wireframe=") + yes).wireframe);
    }
    for (const char* no : {"false", "0", "no", "off", "False", "NO", "OFF"}) {
        SCOPED_TRACE(no);
        EXPECT_FALSE(withSetting(std::string("draw_sky=") + no).drawSky);
    }
    EXPECT_EQ(settingError("draw_sky=2"),
              "--set: invalid value '2' for draw_sky: expected true or false (also yes/no, on/off, 1/0)");
    EXPECT_EQ(settingError("draw_sky="),
              "--set: invalid value '' for draw_sky: expected true or false (also yes/no, on/off, 1/0)");
    EXPECT_NE(settingError("draw_sky=truee"), "");
    EXPECT_NE(settingError("draw_sky=y"), "");
}

// ---- Invalid values: the error names the source, key, value and what is expected ----

TEST(TengineOptions, InvalidValuesAreErrorsSayingWhatIsExpected)
{
    struct Case {
        const char* setting;
        const char* expected;  ///< the text after "expected "
    };
    const Case cases[] = {
        {"lod_error=0", "a number > 0 (pixels)"},
        {"lod_error=-1", "a number > 0 (pixels)"},
        {"lod_error=abc", "a number > 0 (pixels)"},
        {"lod_error=2px", "a number > 0 (pixels)"},
        {"lod_error=nan", "a number > 0 (pixels)"},
        {"lod_error=inf", "a number > 0 (pixels)"},
        {"lod_error=", "a number > 0 (pixels)"},
        {"lod_minimum_spacing=-0.01", "a number >= 0 (metres)"},
        {"dynamic_texture_size=8", "0, or a power of two or a power of two plus one, in [16, 4096] (texels)"},
        {"dynamic_texture_size=100", "0, or a power of two or a power of two plus one, in [16, 4096] (texels)"},
        {"dynamic_texture_size=4097", "0, or a power of two or a power of two plus one, in [16, 4096] (texels)"},
        {"dynamic_texture_size=128.0", "0, or a power of two or a power of two plus one, in [16, 4096] (texels)"},
        {"vertex_cache_size=3", "an integer in [4, 64] (vertices)"},
        {"vertex_cache_size=65", "an integer in [4, 64] (vertices)"},
        {"quad_cache_size=4", "0, or an integer >= 5 (nodes)"},
        {"quad_cache_size=-1", "0, or an integer >= 5 (nodes)"},
        {"quad_cache_size=99999999999", "0, or an integer >= 5 (nodes)"},
        {"memory_budget=-1", "an integer in [0, 1048576] (MiB)"},
        {"memory_budget=1e9", "an integer in [0, 1048576] (MiB)"},
        {"reader=mmap", "stream or memory_mapped"},
        {"reader=Stream", "stream or memory_mapped"},
        {"worker_threads=-1", "an integer in [0, 256] (threads)"},
        {"request_queue_size=0", "an integer in [1, 4096] (node groups)"},
        {"visibility_lod=sometimes", "true or false (also yes/no, on/off, 1/0)"},
        {"visibility_hidden_frames=0", "an integer in [1, 64] (frames)"},
        {"visibility_reveal_seconds=0", "a number > 0 (seconds)"},
        {"video_measure_error_every=-1", "an integer >= 0 (frames)"},
        {"detail_create_new_nodes=maybe", "true or false (also yes/no, on/off, 1/0)"},
        {"detail_subdivision_factor=2.01", "a number in [0, 2]"},
        {"detail_subdivision_factor=-0.1", "a number in [0, 2]"},
        {"detail_add_material=", "true or false (also yes/no, on/off, 1/0)"},
        {"detail_roughness=maybe", "true or false (also yes/no, on/off, 1/0)"},
        {"detail_material_type=2", "an integer in [0, 1]"},
        {"detail_material_type=-1", "an integer in [0, 1]"},
        {"detail_subdivision_scheme=loop", "kobbelt, bilinear or catmull-clark"},
        {"detail_materials=a.mat,,b.mat", "empty or .mat paths separated by commas (at most 4)"},
        {"detail_materials=a.mat,b.mat,c.mat,d.mat,e.mat", "empty or .mat paths separated by commas (at most 4)"},
        {"detail_velocity_limit=-1", "a number >= 0 (samples per second)"},
        {"camera_fov=1", "a number in (1, 179) (degrees)"},
        {"camera_fov=179", "a number in (1, 179) (degrees)"},
        {"camera_z_near=0", "a number > 0 (metres)"},
        {"camera_min_clearance=-1", "a number >= 0 (metres)"},
        {"camera_z_far=-5", "a number > camera_z_near, at most 2^24 times it (metres)"},
        {"camera_position=1, 2", "empty or three numbers 'x, y, z' (metres)"},
        {"camera_position=1, 2, 3, 4", "empty or three numbers 'x, y, z' (metres)"},
        {"camera_position=1, two, 3", "empty or three numbers 'x, y, z' (metres)"},
        {"camera_position=1 2 3", "empty or three numbers 'x, y, z' (metres)"},
        {"camera_yaw=361", "a number in [-360, 360] (degrees)"},
        {"camera_pitch=90.5", "a number in [-90, 90] (degrees)"},
        {"window_width=15", "an integer in [16, 16384] (pixels)"},
        {"window_height=16385", "an integer in [16, 16384] (pixels)"},
        {"draw_user_interface=x", "true or false (also yes/no, on/off, 1/0)"},
        {"wireframe=2", "true or false (also yes/no, on/off, 1/0)"},
        {"geomorph=maybe", "true or false (also yes/no, on/off, 1/0)"},
        {"node_texture_compression=2", "true or false (also yes/no, on/off, 1/0)"},
        {"normal_map_compression=maybe", "auto, or true or false (also yes/no, on/off, 1/0)"},
        {"render_mode=triangles", "chunks, tessellation or blocks"},
        {"lod_mode=rings", "quadtree or clipmap"},
        {"clipmap_samples=256", "an integer 2^k - 1 in [15, 1023]"},
        {"clipmap_samples=7", "an integer 2^k - 1 in [15, 1023]"},
        {"clipmap_samples=2047", "an integer 2^k - 1 in [15, 1023]"},
        {"clipmap_finest_spacing=0", "a number > 0 (metres)"},
        {"clipmap_morph_seconds=-0.1", "a number >= 0 (seconds)"},
        {"tessellation_error_share=1", "a number in (0, 1)"},
        {"draw_sky=maybe", "true or false (also yes/no, on/off, 1/0)"},
        {"sun_azimuth=-1", "a number in [0, 360] (degrees)"},
        {"sun_elevation=91", "a number in [-90, 90] (degrees)"},
        {"haze_distance=-1", "a number >= 0 (metres)"},
        {"atmosphere=2", "true or false (also yes/no, on/off, 1/0)"},
        {"shadows=none", "true or false (also yes/no, on/off, 1/0)"},
        {"exposure=0", "a number in (0, 1000000)"},
        {"clear_color=1, 1, 1.5", "three numbers 'r, g, b', each in [0, 1]"},
        {"clear_color=0.5", "three numbers 'r, g, b', each in [0, 1]"},
        {"clear_color=", "three numbers 'r, g, b', each in [0, 1]"},
        {"demo_mode=2", "true or false (also yes/no, on/off, 1/0)"},
        {"video_mode=sometimes", "true or false (also yes/no, on/off, 1/0)"},
        {"frames_per_second=0", "an integer in [1, 240]"},
        {"frames_per_second=241", "an integer in [1, 240]"},
        {"frames_per_second=29.97", "an integer in [1, 240]"},
        {"video_frames=-1", "an integer >= 0 (frames)"},
        {"video_save_every=-1", "an integer >= 0 (frames)"},
        {"video_save_every=2.5", "an integer >= 0 (frames)"},
        {"video_ffmpeg=auto", "true or false (also yes/no, on/off, 1/0)"},
        {"render=vulkan", "gl or dx"},
        {"memory=gl_foo", "gl_std, gl_vbo or gl_var"},
    };
    std::set<std::string> keysWithInvalidCases;
    for (const Case& c : cases) {
        SCOPED_TRACE(c.setting);
        std::string key = keyOf(c.setting);
        std::string value = std::string(c.setting).substr(key.size() + 1);
        EXPECT_EQ(settingError(c.setting),
                  "--set: invalid value '" + value + "' for " + key + ": expected " + c.expected);
        keysWithInvalidCases.insert(key);
    }
    // Every key that can be invalid has a case: all but the paths, which take any text.
    for (std::string_view key : tengineOptionKeys()) {
        bool isPath = key == "map_file" || key == "camera_path" || key == "log_file" || key == "image_path" ||
                      key == "shader_path" || key == "material_path";
        EXPECT_EQ(keysWithInvalidCases.count(std::string(key)) == 1, !isPath) << key;
    }
}

TEST(TengineOptions, ConfigErrorsNameTheFileAndLine)
{
    auto config = ConfigFile::parse("lod_error = 3\n\ncamera_fov = 200  # too wide\nwireframe = true\n", "view.cfg");
    ASSERT_TRUE(config.ok());
    TengineOptions options;
    std::vector<std::string> warnings;
    Status status = applyConfig(*config, options, warnings);
    ASSERT_FALSE(status.ok());
    EXPECT_EQ(status.error().message,
              "view.cfg:3: invalid value '200' for camera_fov: expected a number in (1, 179) "
              "(degrees)");
    EXPECT_EQ(options.lodError, 3.0);  // applied before the error
    EXPECT_FALSE(options.wireframe);   // not applied after it
}

TEST(TengineOptions, LaterEntriesInOneFileWin)
{
    auto config = ConfigFile::parse("lod_error = 3\nlod_error = 4\n", "a.cfg");
    ASSERT_TRUE(config.ok());
    TengineOptions options;
    std::vector<std::string> warnings;
    ASSERT_TRUE(applyConfig(*config, options, warnings).ok());
    EXPECT_EQ(options.lodError, 4.0);
    EXPECT_TRUE(warnings.empty());
}

TEST(TengineOptions, CameraPositionCanBeUnsetAgain)
{
    TengineOptions o = withSetting("camera_position = 1,2,3");
    ASSERT_TRUE(o.cameraPosition.has_value());
    std::vector<std::string> warnings;
    ASSERT_TRUE(applySetting("camera_position =", o, warnings).ok());
    EXPECT_FALSE(o.cameraPosition.has_value());
}

// ---- Warnings ----

TEST(TengineOptions, UnknownKeysWarnWithTheClosestKnownKey)
{
    struct Case {
        const char* text;
        const char* warning;
    };
    const Case cases[] = {
        {"lod_eror = 3", "a.cfg:1: unknown option 'lod_eror' ignored (did you mean 'lod_error'?)"},
        {"camera_fow = 3", "a.cfg:1: unknown option 'camera_fow' ignored (did you mean 'camera_fov'?)"},
        {"windowwidth = 3", "a.cfg:1: unknown option 'windowwidth' ignored (did you mean 'window_width'?)"},
        {"cg_profil = arb", "a.cfg:1: unknown option 'cg_profil' ignored (did you mean 'cg_profile'?)"},
        {"fullscreen = 1", "a.cfg:1: unknown option 'fullscreen' ignored"},
        {"xy = 1", "a.cfg:1: unknown option 'xy' ignored"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.text);
        auto config = ConfigFile::parse(c.text, "a.cfg");
        ASSERT_TRUE(config.ok());
        TengineOptions options;
        std::vector<std::string> warnings;
        ASSERT_TRUE(applyConfig(*config, options, warnings).ok());
        EXPECT_EQ(options, TengineOptions{});
        ASSERT_EQ(warnings.size(), 1u);
        EXPECT_EQ(warnings[0], c.warning);
    }
    // A --set was typed for this run: an unknown key there is an error, not a warning.
    TengineOptions options;
    std::vector<std::string> warnings;
    const Status set = applySetting("lod_eror=3", options, warnings);
    ASSERT_FALSE(set.ok());
    EXPECT_EQ(
        set.error().message,
        "--set: unknown option 'lod_eror' (did you mean 'lod_error'?) (see configs/tengine.cfg for every option)");
    EXPECT_EQ(options, TengineOptions{});
}

TEST(TengineOptions, DirectXAndCgOptionsAreAcceptedWithWarnings)
{
    struct Case {
        const char* setting;
        const char* warning;  ///< "" = accepted silently
    };
    const Case cases[] = {
        {"render=gl", ""},
        {"render=dx", "--set: render = dx is ignored: only OpenGL is supported"},
        {"memory=gl_std", ""},
        {"memory=gl_vbo", ""},
        {"memory=gl_var", "--set: memory = gl_var is ignored: vertex buffer objects are used"},
        {"cg_profile=nv30", "--set: cg_profile = nv30 is ignored: Cg is not used"},
        {"cg_profile=anything", "--set: cg_profile = anything is ignored: Cg is not used"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.setting);
        std::vector<std::string> warnings;
        EXPECT_EQ(withSetting(c.setting, &warnings), TengineOptions{});
        if (std::string(c.warning).empty()) {
            EXPECT_TRUE(warnings.empty());
        } else {
            ASSERT_EQ(warnings.size(), 1u);
            EXPECT_EQ(warnings[0], c.warning);
        }
    }
}

// ---- configs/tengine.cfg: every key, set to exactly the default ----

TEST(TengineOptions, DefaultConfigFileSetsEveryKeyToItsDefault)
{
    auto config = ConfigFile::load(kDefaultConfig);
    ASSERT_TRUE(config.ok()) << config.error().message;

    // Every key appears exactly once, and nothing else does.
    std::multiset<std::string> keys;
    for (const ConfigEntry& e : config->entries()) {
        keys.insert(e.key);
    }
    for (std::string_view key : tengineOptionKeys()) {
        EXPECT_EQ(keys.count(std::string(key)), 1u) << key << " must appear once in " << kDefaultConfig;
    }
    EXPECT_EQ(keys.size(), tengineOptionKeys().size());

    // Start from options where every key differs from its default: the file must set each one back.
    TengineOptions options;
    std::vector<std::string> warnings;
    for (const ValidCase& c : validCases()) {
        ASSERT_TRUE(applySetting(c.setting, options, warnings).ok());
    }
    for (std::string_view key : tengineOptionKeys()) {
        if (key == "demo_mode") {
            continue;  // video_mode = true, set after it, turned it off: the two exclude each other
        }
        ASSERT_NE(formatTengineOption(options, key), formatTengineOption(TengineOptions{}, key)) << key;
    }
    warnings.clear();
    Status status = applyConfig(*config, options, warnings);
    ASSERT_TRUE(status.ok()) << status.error().message;
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    EXPECT_EQ(options, TengineOptions{});

    // The Direct3D/Cg options are documented as commented-out examples.
    std::ifstream in(kDefaultConfig);
    std::stringstream text;
    text << in.rdbuf();
    for (std::string_view key : ignoredTengineOptionKeys()) {
        EXPECT_TRUE(contains(text.str(), "\n# " + std::string(key) + " = ")) << key;
    }
}

TEST(TengineOptions, DefaultConfigFileIsTheRenderedText)
{
    std::ifstream in(kDefaultConfig);
    std::stringstream text;
    text << in.rdbuf();
    std::string expected = tengineConfigText();
    if (text.str() != expected) {
        std::filesystem::path out = std::filesystem::temp_directory_path() / "tengine.cfg.expected";
        std::ofstream(out) << expected;
        ADD_FAILURE() << kDefaultConfig << " differs from tengineConfigText(); the expected text is in " << out
                      << " (or run: tengine --print-config > configs/tengine.cfg)";
    }
}

// ---- Command line (paper 4.4.2) ----

class TengineOptionsCommandLine : public ::testing::Test {
protected:
    std::string write(const std::string& name, const std::string& text)
    {
        std::filesystem::path path = mDir / name;
        std::filesystem::create_directories(path.parent_path());
        std::ofstream(path) << text;
        return path.string();
    }
    Expected<ParsedCommandLine> parse(std::vector<std::string> args) { return parseTengineCommandLine(args); }
    ParsedCommandLine parseOk(std::vector<std::string> args)
    {
        auto parsed = parseTengineCommandLine(args);
        EXPECT_TRUE(parsed.ok()) << (parsed.ok() ? "" : parsed.error().message);
        return parsed.ok() ? std::move(parsed).value() : ParsedCommandLine{};
    }

    test::ScratchDir mDir;
};

TEST_F(TengineOptionsCommandLine, NoArgumentsGiveTheDefaults)
{
    ParsedCommandLine parsed = parseOk({});
    EXPECT_EQ(parsed.options, TengineOptions{});
    EXPECT_TRUE(parsed.warnings.empty());
    EXPECT_TRUE(parsed.configFiles.empty());
    EXPECT_FALSE(parsed.help);
    EXPECT_FALSE(parsed.printConfig);
}

TEST_F(TengineOptionsCommandLine, LaterConfigFilesOverrideEarlierOnes)
{
    std::string a = write("a.cfg", "lod_error = 3\ncamera_fov = 50\n");
    std::string b = write("b.cfg", "lod_error = 4\nwireframe = yes\n");
    ParsedCommandLine ab = parseOk({a, b});
    EXPECT_EQ(ab.options.lodError, 4.0);
    EXPECT_EQ(ab.options.cameraFov, 50.0);
    EXPECT_TRUE(ab.options.wireframe);
    EXPECT_EQ(ab.configFiles, (std::vector<std::filesystem::path>{a, b}));
    EXPECT_EQ(parseOk({b, a}).options.lodError, 3.0);
}

TEST_F(TengineOptionsCommandLine, SetAppliesInCommandLineOrder)
{
    std::string a = write("a.cfg", "lod_error = 3\n");
    EXPECT_EQ(parseOk({a, "--set", "lod_error=5"}).options.lodError, 5.0);
    EXPECT_EQ(parseOk({a, "--set=lod_error=5"}).options.lodError, 5.0);
    EXPECT_EQ(parseOk({"--set", "lod_error=5", a}).options.lodError, 3.0);
    EXPECT_EQ(parseOk({"--set", "lod_error=5", "--set", "lod_error = 6"}).options.lodError, 6.0);
    EXPECT_EQ(parseOk({"--set", "image_path=\"a # b\""}).options.imagePath, "a # b");
}

TEST_F(TengineOptionsCommandLine, MapArgumentOverridesMapFile)
{
    std::string a = write("a.cfg", "map_file = /maps/from_config.map\n");
    EXPECT_EQ(parseOk({a}).options.mapFile, "/maps/from_config.map");
    EXPECT_EQ(parseOk({"x.map", a}).options.mapFile, "x.map");
    EXPECT_EQ(parseOk({a, "x.map"}).options.mapFile, "x.map");
    EXPECT_FALSE(parse({"x.map", "y.map"}).ok()) << "two maps are an error";
    EXPECT_EQ(parseOk({"x.map", "--set", "map_file=z.map"}).options.mapFile, "x.map");
}

TEST_F(TengineOptionsCommandLine, InputPathsAreRelativeToTheConfigFileOutputsToTheWorkingDirectory)
{
    std::string cfg = write("demos/flight.cfg",
                            "map_file = data/valley.map\ncamera_path = flight.path\nlog_file = run.log\n"
                            "image_path = frames/flight\n");
    ParsedCommandLine parsed = parseOk({cfg});
    EXPECT_EQ(parsed.options.mapFile, mDir.path() / "demos/data/valley.map");
    EXPECT_EQ(parsed.options.cameraPath, mDir.path() / "demos/flight.path");
    EXPECT_EQ(parsed.options.logFile, "run.log");
    EXPECT_EQ(parsed.options.imagePath, "frames/flight");
    // Absolute paths and --set paths are used as given.
    std::string absolute = write("abs.cfg", "camera_path = /paths/p.path\n");
    EXPECT_EQ(parseOk({absolute}).options.cameraPath, "/paths/p.path");
    EXPECT_EQ(parseOk({"--set", "camera_path=p.path"}).options.cameraPath, "p.path");
}

TEST_F(TengineOptionsCommandLine, WarningsFromAllSourcesAreCollected)
{
    std::string a = write("a.cfg", "render = dx\nlod_eror = 1\n");
    ParsedCommandLine parsed = parseOk({a, "--set", "cg_profile=arb"});
    ASSERT_EQ(parsed.warnings.size(), 3u);
    EXPECT_EQ(parsed.warnings[0], a + ":1: render = dx is ignored: only OpenGL is supported");
    EXPECT_EQ(parsed.warnings[1], a + ":2: unknown option 'lod_eror' ignored (did you mean 'lod_error'?)");
    EXPECT_EQ(parsed.warnings[2], "--set: cg_profile = arb is ignored: Cg is not used");
}

TEST_F(TengineOptionsCommandLine, Errors)
{
    std::string syntax = write("syntax.cfg", "a = 1\nnot a setting\n");
    std::string invalid = write("invalid.cfg", "vertex_cache_size = 100\n");
    struct Case {
        std::vector<std::string> args;
        std::string message;
    };
    const Case cases[] = {
        {{syntax}, syntax + ":2: expected 'key = value', found 'not a setting' (no '=')"},
        {{invalid},
         invalid + ":1: invalid value '100' for vertex_cache_size: expected an integer in [4, 64] (vertices)"},
        {{(mDir / "missing.cfg").string()}, (mDir / "missing.cfg").string() + ": cannot open configuration file"},
        {{"--set"}, "--set needs a value: --set key=value"},
        {{"--set", "lod_error"}, "--set: expected 'key = value', found 'lod_error' (no '=')"},
        {{"--set", "lod_error=0"}, "--set: invalid value '0' for lod_error: expected a number > 0 (pixels)"},
        {{"--fullscreen"}, "unknown argument '--fullscreen' (see --help)"},
        {{"-x", "a.map"}, "unknown argument '-x' (see --help)"},
        // Relations between options are checked once everything is applied.
        {{"--set", "camera_z_far=0.5"}, "camera_z_far (0.5) must be greater than camera_z_near (1)"},
        {{"--set", "camera_z_near=10", "--set", "camera_z_far=10"},
         "camera_z_far (10) must be greater than camera_z_near (10)"},
        // Accepted before, drawing nothing: the depth buffer cannot resolve such a range.
        {{"--set", "camera_z_far=1e300"},
         "camera_z_far / camera_z_near is 1e+300: the depth buffer cannot tell distances apart beyond 16777216 "
         "(the far terrain would not be drawn); raise camera_z_near or lower camera_z_far"},
        {{"--set", "camera_z_near=1e-30"},
         "camera_z_far / camera_z_near is 2e+35: the depth buffer cannot tell distances apart beyond 16777216 "
         "(the far terrain would not be drawn); raise camera_z_near or lower camera_z_far"},
        {{"--set", "demo_mode=on"}, "demo_mode needs a camera_path"},
        {{"--set", "video_mode=on"}, "video_mode needs a camera_path"},
        {{"--set", "video_measure_error_every=5"},
         "video_measure_error_every measures video frames: it needs video_mode = true (and demo_mode = false)"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.args.front());
        auto parsed = parse(c.args);
        ASSERT_FALSE(parsed.ok());
        EXPECT_EQ(parsed.error().message, c.message);
    }
}

TEST_F(TengineOptionsCommandLine, RelationsAreCheckedAfterEverySourceIsApplied)
{
    // Far beyond the default far plane: fine once both are set, whatever the order.
    ParsedCommandLine parsed = parseOk({"--set", "camera_z_near=300000", "--set", "camera_z_far=1e6"});
    EXPECT_EQ(parsed.options.cameraZNear, 300000.0);
    EXPECT_EQ(parsed.options.cameraZFar, 1e6);
}

TEST_F(TengineOptionsCommandLine, OfDemoAndVideoModeTheLaterWinsWithAWarning)
{
    // A config's demo mode, then video mode asked for on the command line: a video (it looped forever before).
    std::string demo = write("demo.cfg", "camera_path = p.path\ndemo_mode = true\n");
    ParsedCommandLine video = parseOk({demo, "--set", "video_mode=1"});
    EXPECT_TRUE(video.options.videoMode);
    EXPECT_FALSE(video.options.demoMode);
    ASSERT_EQ(video.warnings.size(), 1u);
    EXPECT_EQ(video.warnings[0], "--set: video_mode = true turns demo_mode off (of the two, the later setting wins)");
    ParsedCommandLine back =
        parseOk({"--set", "camera_path=p.path", "--set", "video_mode=1", "--set", "demo_mode=yes"});
    EXPECT_TRUE(back.options.demoMode);
    EXPECT_FALSE(back.options.videoMode);
    ASSERT_EQ(back.warnings.size(), 1u);
    EXPECT_EQ(back.warnings[0], "--set: demo_mode = true turns video_mode off (of the two, the later setting wins)");
    // Turning one off leaves the other as it is.
    ParsedCommandLine off = parseOk({demo, "--set", "video_mode=0"});
    EXPECT_TRUE(off.options.demoMode);
    EXPECT_TRUE(off.warnings.empty());
}

TEST_F(TengineOptionsCommandLine, ArgumentsAreMapsByTheirSignatureAndConfigsByParsing)
{
    // A config under any name is read as one.
    std::string settings = write("settings.txt", "lod_error = 3\n");
    ParsedCommandLine config = parseOk({settings});
    EXPECT_EQ(config.options.lodError, 3.0);
    ASSERT_EQ(config.configFiles.size(), 1u);
    // A map by its signature, whatever its name.
    std::string map = write("terrain.bin", std::string(kMapMagic.begin(), kMapMagic.end()) + "rest");
    EXPECT_EQ(parseOk({map}).options.mapFile, map);
    // A file that is neither (a recording's CSV) is an error naming it, never taken as the map.
    std::string csv = write("rec/frames.csv", "frame,time_s,fps\n0,0,12\n");
    auto taken = parse({csv, "terrain.map"});
    ASSERT_FALSE(taken.ok());
    EXPECT_NE(taken.error().message.find("'" + csv + "' is neither a map"), std::string::npos) << taken.error().message;
    auto missing = parse({(mDir / "nothing").string()});
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.error().message.find((mDir / "nothing").string()), std::string::npos) << missing.error().message;
    // A directory is neither (it read as an empty config).
    auto directory = parse({mDir.path().string()});
    ASSERT_FALSE(directory.ok());
    std::string expected = mDir.path().string();
    expected.insert(0, 1, '\'').append("' is a directory, not a map or a config file");
    EXPECT_EQ(directory.error().message, expected);
    // Two maps: an error, not the last one silently.
    auto two = parse({map, "other.map"});
    ASSERT_FALSE(two.ok());
    EXPECT_EQ(two.error().message, "two maps on the command line, '" + map + "' and 'other.map': give one");
}

TEST_F(TengineOptionsCommandLine, HelpAndPrintConfig)
{
    ParsedCommandLine help = parseOk({"--help", "--fullscreen"});
    EXPECT_TRUE(help.help);
    EXPECT_TRUE(parseOk({"-h"}).help);
    EXPECT_TRUE(contains(tengineUsage(), "--set key=value"));
    EXPECT_TRUE(contains(tengineUsage(), ".cfg"));

    ParsedCommandLine print = parseOk({"--set", "lod_error=7", "--print-config"});
    EXPECT_TRUE(print.printConfig);
    EXPECT_TRUE(contains(tengineConfigText(print.options), "\nlod_error = 7\n"));
}

TEST_F(TengineOptionsCommandLine, ArgcArgvSkipsTheProgramName)
{
    std::string a = write("a.cfg", "lod_error = 3\n");
    std::vector<std::string> storage = {"tengine", a, "terrain.map"};
    std::vector<char*> argv;
    for (std::string& s : storage) {
        argv.push_back(s.data());
    }
    auto parsed = parseTengineCommandLine(static_cast<int>(argv.size()), argv.data());
    ASSERT_TRUE(parsed.ok()) << parsed.error().message;
    EXPECT_EQ(parsed->options.lodError, 3.0);
    EXPECT_EQ(parsed->options.mapFile, "terrain.map");
}

}  // namespace
}  // namespace terrain

namespace terrain {
namespace {

// ---- Outputs never overwrite inputs ----

TEST(TengineOutputsTest, AnOutputNamingAnInputIsRefusedNamingBoth)
{
    test::ScratchDir dir;
    for (const char* name : {"terrain.map", "demo.cfg", "demo.path", "grass.mat"}) {
        std::ofstream(dir / name) << "x\n";
    }
    std::filesystem::create_symlink(dir / "demo.cfg", dir / "link.cfg");
    std::filesystem::create_directory(dir / "frames");
    std::ofstream(dir / "frames" / "frames.csv") << "x\n";
    ParsedCommandLine parsed;
    parsed.options.mapFile = dir / "terrain.map";
    parsed.options.cameraPath = dir / "demo.path";
    parsed.configFiles = {dir / "demo.cfg", dir / "frames" / "frames.csv"};
    const std::vector<std::filesystem::path> materials = {dir / "grass.mat"};
    ASSERT_TRUE(checkOutputsAreNotInputs(parsed, materials).ok()) << "nothing clashes yet";
    EXPECT_EQ(recordedCameraPathFile(parsed.options), dir / "demo.path.recorded");

    struct Case {
        const char* what;
        std::function<void(TengineOptions&)> set;
        std::string named;  ///< the input the message must name
    };
    const std::vector<Case> cases = {
        {"log_file = the map", [&](TengineOptions& o) { o.logFile = dir / "terrain.map"; }, "map"},
        {"log_file = a config through a link", [&](TengineOptions& o) { o.logFile = dir / "link.cfg"; }, "config file"},
        {"log_file = a material", [&](TengineOptions& o) { o.logFile = dir / "grass.mat"; }, "material"},
        {"log_file = the camera path", [&](TengineOptions& o) { o.logFile = dir / "demo.path"; }, "camera path"},
        {"image_path = the map",
         [&](TengineOptions& o) {
             o.videoMode = true;
             o.imagePath = dir / "terrain.map";
         },
         "map"},
        {"a config where video mode writes frames.csv",
         [&](TengineOptions& o) {
             o.videoMode = true;
             o.imagePath = dir / "frames";
         },
         "config file"},
        {"recorded keyframes = a config", [&](TengineOptions& o) { o.cameraPath = dir / "demo"; }, ""},
    };
    for (const Case& c : cases) {
        ParsedCommandLine p = parsed;
        c.set(p.options);
        if (std::string(c.what).starts_with("recorded")) {
            // camera_path "demo" would record into "demo.recorded": make that a config file.
            std::ofstream(dir / "demo.recorded") << "x\n";
            p.configFiles.push_back(dir / "demo.recorded");
        }
        const Status status = checkOutputsAreNotInputs(p, materials);
        ASSERT_FALSE(status.ok()) << c.what;
        EXPECT_TRUE(contains(status.error().message, "refusing")) << c.what << ": " << status.error().message;
        EXPECT_TRUE(contains(status.error().message, c.named)) << c.what << ": " << status.error().message;
    }
    // The same image_path outside video mode writes nothing there.
    ParsedCommandLine free = parsed;
    free.options.imagePath = dir / "terrain.map";
    EXPECT_TRUE(checkOutputsAreNotInputs(free, materials).ok());
}

}  // namespace
}  // namespace terrain
