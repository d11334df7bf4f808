// Materials (synthesis/Material.h, paper 3.4.5): the shipped .mat files and detail textures, parsing with
// "file:line" errors and warnings, and the blend of several materials: weights in [0, 1] summing to 1,
// continuous in slope and height, and a displacement without seams where materials meet.
#include "TestSupport.h"
#include "heightfield/Image.h"
#include "synthesis/DetailTexture.h"
#include "synthesis/Material.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>

namespace terrain {
namespace {

const std::filesystem::path kMaterials = TERRAIN_MATERIALS_DIR;

Material parseOk(const std::string& text, std::vector<std::string>& warnings, const std::string& name = "test.mat")
{
    auto config = ConfigFile::parse(text, name);
    EXPECT_TRUE(config.ok());
    auto material = parseMaterial(*config, warnings);
    EXPECT_TRUE(material.ok()) << (material.ok() ? "" : material.error().message);
    return material.ok() ? std::move(material).value() : Material{};
}

/// The detail textures shipped in materials/ and the parameters that made them. Regenerate with
/// TERRAIN_WRITE_DETAIL_TEXTURES=1 ./tests/unit_tests --gtest_filter=Material.ShippedDetailTextures*
struct ShippedTexture {
    const char* file;
    FractalParams params;
};

std::vector<ShippedTexture> shippedTextures()
{
    FractalParams grass;
    grass.octaves = 5;
    grass.gain = 0.6;
    grass.wavelength = 1.0;
    grass.seed = 3;
    FractalParams rock = grass;
    rock.type = FractalType::Ridged;
    rock.gain = 0.55;
    rock.seed = 7;
    return {{"grass_detail.png", grass}, {"rock_detail.png", rock}};
}
constexpr int kShippedTextureSize = 128;

TEST(Material, ShippedDetailTexturesMatchTheirGeneratorAndAreSmall)
{
    for (const ShippedTexture& t : shippedTextures()) {
        SCOPED_TRACE(t.file);
        Image made = makeDetailTexture(t.params, kShippedTextureSize);
        if (std::getenv("TERRAIN_WRITE_DETAIL_TEXTURES") != nullptr) {
            ASSERT_TRUE(writePngImage(kMaterials / t.file, made).ok());
        }
        auto shipped = readPngImage(kMaterials / t.file, 1);
        ASSERT_TRUE(shipped.ok()) << shipped.error().message;
        EXPECT_EQ(shipped->pixels, made.pixels);
        EXPECT_LT(std::filesystem::file_size(kMaterials / t.file), 64u * 1024u);
        // Tileable: the wrap from the last column to the first is no bigger a step than typical neighbours.
        double wrapStep = 0;
        double innerStep = 0;
        for (int y = 0; y < made.height; ++y) {
            wrapStep += std::abs(made.pixel(made.width - 1, y)[0] - made.pixel(0, y)[0]);
            innerStep += std::abs(made.pixel(made.width / 2 - 1, y)[0] - made.pixel(made.width / 2, y)[0]);
        }
        EXPECT_LT(wrapStep, 2.0 * innerStep + made.height);
    }
}

TEST(Material, ShippedMaterialsLoadWithoutWarnings)
{
    std::vector<std::string> warnings;
    auto set = MaterialSet::load({kMaterials / "grass.mat", kMaterials / "rock.mat"}, warnings);
    ASSERT_TRUE(set.ok()) << set.error().message;
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    const Material& grass = set->materials()[0];
    const Material& rock = set->materials()[1];
    EXPECT_EQ(grass.name, "grass");
    EXPECT_EQ(grass.kind, DisplacementKind::Fbm);
    EXPECT_EQ(rock.name, "rock");
    EXPECT_EQ(rock.kind, DisplacementKind::Ridged);
    EXPECT_EQ(rock.fractal.type, FractalType::Ridged);
    for (const Material* m : {&grass, &rock}) {
        ASSERT_EQ(m->detailTextures.size(), 1u);
        EXPECT_TRUE(readPngImage(m->detailTextures[0], 1).ok());
        ASSERT_NE(m->displacement, nullptr);
    }
    // Steep ground is rock, flat ground grass.
    double w[2];
    set->weights(60.0, 100.0, w);
    EXPECT_EQ(w[1], 1.0);
    set->weights(5.0, 100.0, w);
    EXPECT_EQ(w[0], 1.0);
}

TEST(Material, ParsesEveryKey)
{
    test::ScratchDir dir;
    std::ofstream(dir / "detail.png") << "not checked here";
    Image gray{8, 8, 1, std::vector<std::uint8_t>(64, 100)};
    ASSERT_TRUE(writePngImage(dir / "basis.png", gray).ok());
    std::ofstream(dir / "full.mat") << "name = cliff\n"
                                       "displacement = bitmap-ridged\n"
                                       "bitmap = basis.png\n"
                                       "octaves = 5\n"
                                       "lacunarity = 2.5\n"
                                       "gain = 0.6\n"
                                       "wavelength = 12.5\n"
                                       "amplitude = 4\n"
                                       "seed = 99\n"
                                       "ridge_offset = 0.9\n"
                                       "ridge_feedback = 1.5\n"
                                       "cache = fractal\n"
                                       "detail_texture = detail.png\n"
                                       "detail_texture = detail.png\n"
                                       "detail_texture_size = 3\n"
                                       "tint = 0.1, 0.2, 0.3\n"
                                       "slope = 20, 70\n"
                                       "slope_blend = 4\n"
                                       "height = -10, 500.5\n"
                                       "height_blend = 25\n";
    std::vector<std::string> warnings;
    auto m = loadMaterial(dir / "full.mat", warnings);
    ASSERT_TRUE(m.ok()) << m.error().message;
    EXPECT_TRUE(warnings.empty());
    EXPECT_EQ(m->name, "cliff");
    EXPECT_EQ(m->kind, DisplacementKind::BitmapRidged);
    EXPECT_EQ(m->bitmap, dir.path() / "basis.png");
    EXPECT_EQ(m->fractal.octaves, 5);
    EXPECT_EQ(m->fractal.lacunarity, 2.5);
    EXPECT_EQ(m->fractal.gain, 0.6);
    EXPECT_EQ(m->fractal.wavelength, 12.5);
    EXPECT_EQ(m->fractal.amplitude, 4.0);
    EXPECT_EQ(m->fractal.seed, 99u);
    EXPECT_EQ(m->fractal.ridgeOffset, 0.9);
    EXPECT_EQ(m->fractal.ridgeFeedback, 1.5);
    EXPECT_EQ(m->fractal.cache, FractalCache::Fractal);
    EXPECT_EQ(m->detailTextures.size(), 2u);
    EXPECT_EQ(m->detailTextureSize, 3.0);
    EXPECT_EQ(m->tint, (std::array<float, 3>{0.1f, 0.2f, 0.3f}));
    EXPECT_EQ(m->placement.slopeMin, 20.0);
    EXPECT_EQ(m->placement.slopeMax, 70.0);
    EXPECT_EQ(m->placement.slopeBlend, 4.0);
    EXPECT_EQ(m->placement.heightMin, -10.0);
    EXPECT_EQ(m->placement.heightMax, 500.5);
    EXPECT_EQ(m->placement.heightBlend, 25.0);
    ASSERT_NE(m->displacement, nullptr);
    EXPECT_LE(std::abs(m->displacementAt(3.0, 4.0)), 4.0);
}

TEST(Material, DefaultsAndUnknownKeysWarn)
{
    std::vector<std::string> warnings;
    Material m = parseOk("displacment = fbm\n# comment\namplitude = 1\n", warnings, "dir/soil.mat");
    EXPECT_EQ(m.name, "soil");
    EXPECT_EQ(m.kind, DisplacementKind::None);
    EXPECT_EQ(m.displacement, nullptr);
    EXPECT_EQ(m.displacementAt(1.0, 2.0), 0.0);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0], "dir/soil.mat:1: unknown material option 'displacment' ignored");
}

TEST(Material, InvalidValuesNameFileLineAndKey)
{
    struct Bad {
        const char* line;
        const char* says;
    };
    const Bad bad[] = {
        {"displacement = perlin", "expected none, fbm, ridged, bitmap-fbm or bitmap-ridged"},
        {"octaves = 0", "expected an integer in [1, 24]"},
        {"octaves = 8.5", "expected an integer in [1, 24]"},
        {"lacunarity = 1", "expected a number in [1.1, 8]"},
        {"gain = 0", "expected a number in (0, 1]"},
        {"gain = x", "expected a number in (0, 1]"},
        {"wavelength = -3", "expected a positive number"},
        {"amplitude = -1", "expected a number in [0, 10000] metres"},
        {"seed = -4", "expected a non-negative integer"},
        {"ridge_offset = 3", "expected a number in [0.5, 1.5]"},
        {"ridge_feedback = 9", "expected a number in [0, 8]"},
        {"cache = always", "expected none, basis or fractal"},
        {"bitmap = missing.png", "no such file"},
        {"detail_texture = missing.png", "no such file"},
        {"detail_texture =", "expected a file name"},
        {"detail_texture_size = 0", "expected a positive number"},
        {"tint = 1, 1", "expected 'r, g, b', each in [0, 1]"},
        {"tint = 1, 2, 0", "expected 'r, g, b', each in [0, 1]"},
        {"slope = 50, 20", "expected 'min, max' with min <= max, degrees in [0, 90]"},
        {"slope = 0, 100", "expected 'min, max' with min <= max, degrees in [0, 90]"},
        {"slope_blend = 0", "expected a number in [0.001, 90] degrees"},
        {"height = a, b", "expected 'min, max' with min <= max, metres"},
        {"height_blend = 0", "expected a number in [0.001, 100000] metres"},
        {"name =", "expected a name"},
        {"colour = 1, 1", "expected 'r, g, b', each in [0, 1]"},
        {"colour = 0.5, nan, 0.5", "expected 'r, g, b', each in [0, 1]"},
        {"colour_cover = 1.5", "expected a number in [0, 1]"},
        {"blend_height = -1", "expected a number in [0, 10000] metres"},
        {"curvature = 10, -10", "expected 'min, max' with min <= max, degrees in [-90, 90]"},
        {"curvature = -100, 0", "expected 'min, max' with min <= max, degrees in [-90, 90]"},
        {"curvature_blend = 0", "expected a number in [0.001, 90] degrees"},
        {"variation = 5, 100", "expected 'amount, wavelength'"},
        {"variation = 1, 0.5", "expected 'amount, wavelength'"},
        {"variation = 1", "expected 'amount, wavelength'"},
        {"variation = inf, 100", "expected 'amount, wavelength'"},
    };
    for (const Bad& b : bad) {
        std::vector<std::string> warnings;
        auto config = ConfigFile::parse(std::string("# first line\nname = x\n") + b.line + "\n", "bad.mat");
        ASSERT_TRUE(config.ok());
        auto m = parseMaterial(*config, warnings);
        ASSERT_FALSE(m.ok()) << b.line;
        const std::string& message = m.error().message;
        std::string key(b.line, std::strcspn(b.line, " ="));
        EXPECT_EQ(message.rfind("bad.mat:3: " + key + " = ", 0), 0u) << message;
        EXPECT_NE(message.find(b.says), std::string::npos) << message;
    }
    // Found by fuzzing: a file name longer than the system allows threw std::filesystem_error.
    for (const char* key : {"bitmap", "detail_texture"}) {
        std::vector<std::string> warnings;
        auto config = ConfigFile::parse(std::string(key) + " = " + std::string(300, 'x') + ".png\n", "long.mat");
        ASSERT_TRUE(config.ok());
        auto m = parseMaterial(*config, warnings);
        ASSERT_FALSE(m.ok()) << key;
        EXPECT_EQ(m.error().message.rfind("long.mat:1: " + std::string(key) + " = ", 0), 0u) << m.error().message;
        EXPECT_NE(m.error().message.find("no such file"), std::string::npos) << m.error().message;
        EXPECT_NE(m.error().message.find("File name too long"), std::string::npos) << m.error().message;
    }
}

TEST(Material, BitmapDisplacementNeedsABitmap)
{
    std::vector<std::string> warnings;
    auto config = ConfigFile::parse("amplitude = 2\ndisplacement = bitmap-fbm\n", "b.mat");
    ASSERT_TRUE(config.ok());
    auto m = parseMaterial(*config, warnings);
    ASSERT_FALSE(m.ok());
    EXPECT_EQ(m.error().message,
              "b.mat:2: displacement = bitmap-fbm needs a 'bitmap = file.png' (a square, tileable gray PNG)");
}

TEST(Material, BitmapMustBeSquare)
{
    test::ScratchDir dir;
    ASSERT_TRUE(writePngImage(dir / "wide.png", Image{16, 8, 1, std::vector<std::uint8_t>(128, 0)}).ok());
    std::ofstream(dir / "w.mat") << "displacement = bitmap-fbm\nbitmap = wide.png\n";
    std::vector<std::string> warnings;
    auto m = loadMaterial(dir / "w.mat", warnings);
    ASSERT_FALSE(m.ok());
    EXPECT_NE(m.error().message.find("is 16 x 8; a bitmap basis must be square"), std::string::npos)
        << m.error().message;
}

/// grass (ground) / rock on slopes 30+ blend 10 / snow above 1000 m blend 100.
MaterialSet threeMaterials()
{
    std::vector<std::string> warnings;
    std::vector<Material> ms;
    ms.push_back(parseOk("name = grass\ndisplacement = fbm\namplitude = 0.5\nwavelength = 20\nseed = 1\n", warnings));
    ms.push_back(
        parseOk("name = rock\ndisplacement = ridged\namplitude = 3\nwavelength = 30\nseed = 2\n"
                "slope = 30, 90\nslope_blend = 10\n",
                warnings));
    ms.push_back(
        parseOk("name = snow\ndisplacement = fbm\namplitude = 0.2\nwavelength = 50\nseed = 3\n"
                "height = 1000, 9000\nheight_blend = 100\n",
                warnings));
    return MaterialSet(std::move(ms));
}

TEST(Material, WeightsSumToOneAndAreContinuous)
{
    MaterialSet set = threeMaterials();
    double previous[3] = {0, 0, 0};
    double w[3];
    // Walk slope and height together across every border (slope 20..30, height 900..1000) in small steps.
    const int steps = 20000;
    double maxJump = 0;
    for (int i = 0; i <= steps; ++i) {
        double t = static_cast<double>(i) / steps;
        double slope = 90.0 * t;
        double height = 2000.0 * t;
        set.weights(slope, height, w);
        double sum = 0;
        for (int m = 0; m < 3; ++m) {
            EXPECT_GE(w[m], 0.0);
            EXPECT_LE(w[m], 1.0);
            sum += w[m];
            if (i > 0) {
                maxJump = std::max(maxJump, std::abs(w[m] - previous[m]));
            }
            previous[m] = w[m];
        }
        EXPECT_NEAR(sum, 1.0, 1e-12);
    }
    // smoothstep's slope is 1.5 / blend: 1.5 / 10 degrees * 0.0045 degrees per step, plus the height part.
    EXPECT_LT(maxJump, 1.5 / 10.0 * 90.0 / steps + 1.5 / 100.0 * 2000.0 / steps + 1e-12);
    set.weights(10.0, 0.0, w);
    EXPECT_EQ(w[0], 1.0);
    set.weights(45.0, 0.0, w);
    EXPECT_EQ(w[1], 1.0);
    set.weights(45.0, 1500.0, w);
    EXPECT_EQ(w[2], 1.0);
    set.weights(25.0, 0.0, w);  // half way into rock's blend: smoothstep(0.5) = 0.5
    EXPECT_DOUBLE_EQ(w[1], 0.5);
    EXPECT_DOUBLE_EQ(w[0], 0.5);
}

TEST(Material, SurfaceContinuousAcrossMaterialBorders)
{
    // A ramp whose slope (from the base height field) rises from 10 to 50 degrees over 100 m: walking
    // it in 1 mm steps, the blended displacement never jumps, though rock's and grass's differ by metres.
    MaterialSet set = threeMaterials();
    const double h = 0.001;
    double previous = 0;
    double maxStep = 0;
    for (int i = 0; i <= 100000; ++i) {
        double x = 12'345.0 + i * h;
        double slope = 10.0 + 40.0 * (i * h) / 100.0;
        double d = set.displacement(x, 777.0, slope, 200.0);
        if (i > 0) {
            maxStep = std::max(maxStep, std::abs(d - previous));
        }
        previous = d;
    }
    // Rock's displacement changes by at most ~3 m * 4 * sum(freq) per metre (FractalTest's bound), i.e. a
    // few centimetres per millimetre at worst; a seam would be a jump of metres.
    EXPECT_LT(maxStep, 0.05);
}

TEST(Material, GridBitIdenticalToPointAndSkipsUnusedMaterials)
{
    MaterialSet set = threeMaterials();
    const int n = 69;
    std::vector<float> slope(n * n);
    std::vector<float> height(n * n);
    for (int k = 0; k < n * n; ++k) {
        slope[k] = static_cast<float>(15.0 + 30.0 * (k % n) / n);     // grass to rock across the window
        height[k] = static_cast<float>(900.0 + 200.0 * (k / n) / n);  // and into snow
    }
    std::vector<float> grid(n * n);
    set.displacementGrid(SampleGrid{500'000.0, 250'000.0, 0, 0, 0.125, n, n}, slope, height, grid);
    int mismatches = 0;
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            int k = j * n + i;
            float point = set.displacement(500'000.0 + i * 0.125, 250'000.0 + j * 0.125, slope[k], height[k]);
            mismatches += std::memcmp(&point, &grid[k], sizeof(float)) != 0;
        }
    }
    EXPECT_EQ(mismatches, 0);
}

}  // namespace
}  // namespace terrain
