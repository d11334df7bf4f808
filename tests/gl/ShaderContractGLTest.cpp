// The C++/GLSL contract (render/ShaderContract.h) against the programs as the GL compiles them: every variant of
// the terrain, tessellation and clipmap programs has its attributes at the contract's locations and every sampler
// it uses at a unit of the contract's table, no two samplers sharing one.
#include "GlTestSupport.h"

#include "render/GlWindow.h"
#include "render/ShaderContract.h"
#include "render/ShaderProgram.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace terrain {
namespace {

const std::filesystem::path kShaders = TERRAIN_SHADER_DIR;

bool isSampler(GLenum type)
{
    switch (type) {
        case GL_SAMPLER_2D:
        case GL_SAMPLER_2D_ARRAY:
        case GL_SAMPLER_BUFFER:
        case GL_INT_SAMPLER_BUFFER:
        case GL_UNSIGNED_INT_SAMPLER_BUFFER:
        case GL_UNSIGNED_INT_SAMPLER_2D_ARRAY:
        case GL_INT_SAMPLER_2D_ARRAY:
            return true;
        default:
            return false;
    }
}

/// Checks `program`'s active attributes and samplers against the contract and `table`; returns how many of each
/// it checked.
std::pair<int, int> expectContract(const ShaderProgram& program, std::span<const contract::SamplerUnit> table,
                                   const std::string& variant)
{
    const std::map<std::string, int> locations = {
        {"aGrid", contract::kGridLocation},
        {"aSkirt", contract::kSkirtLocation},
        {"aPatch", contract::kPatchLocation},
        {"aNode0", contract::kNodeLocation},
        {"aNode1", contract::kNodeLocation + 1},
        {"aNode2", contract::kNodeLocation + 2},
        {"aLayerOrigin", contract::kLayerOriginLocation},
    };
    GLint count = 0;
    glGetProgramiv(program.name(), GL_ACTIVE_ATTRIBUTES, &count);
    int attributes = 0;
    for (GLint k = 0; k < count; ++k) {
        char name[128];
        GLint size = 0;
        GLenum type = 0;
        glGetActiveAttrib(program.name(), static_cast<GLuint>(k), sizeof name, nullptr, &size, &type, name);
        std::string attribute = name;
        if (attribute.starts_with("gl_")) {
            continue;  // built in
        }
        if (attribute.ends_with("[0]")) {
            attribute.resize(attribute.size() - 3);
        }
        const auto it = locations.find(attribute);
        if (it == locations.end()) {
            ADD_FAILURE() << variant << ": attribute " << name << " is not in the contract";
            continue;
        }
        EXPECT_EQ(glGetAttribLocation(program.name(), attribute.c_str()), it->second) << variant << ": " << name;
        if (attribute.starts_with("aNode") || attribute == "aLayerOrigin") {
            EXPECT_EQ(type, static_cast<GLenum>(GL_FLOAT_VEC4)) << variant << ": " << name;
        }
        if (attribute == "aLayerOrigin") {
            // One location a layer, after the node's constants: as TerrainRenderer points them.
            const std::string last = "aLayerOrigin[" + std::to_string(size - 1) + "]";
            EXPECT_EQ(glGetAttribLocation(program.name(), last.c_str()), contract::kLayerOriginLocation + size - 1)
                << variant;
        }
        ++attributes;
    }
    contract::bindSamplerUnits(program, table);
    glGetProgramiv(program.name(), GL_ACTIVE_UNIFORMS, &count);
    std::set<int> units;
    int samplers = 0;
    for (GLint k = 0; k < count; ++k) {
        char name[128];
        GLint size = 0;
        GLenum type = 0;
        glGetActiveUniform(program.name(), static_cast<GLuint>(k), sizeof name, nullptr, &size, &type, name);
        if (!isSampler(type)) {
            continue;
        }
        const auto entry = std::find_if(table.begin(), table.end(),
                                        [&](const contract::SamplerUnit& s) { return std::string(s.uniform) == name; });
        if (entry == table.end()) {
            ADD_FAILURE() << variant << ": sampler " << name << " has no unit in the contract";
            continue;
        }
        GLint unit = -1;
        glGetUniformiv(program.name(), glGetUniformLocation(program.name(), name), &unit);
        EXPECT_EQ(unit, entry->unit) << variant << ": " << name;
        EXPECT_TRUE(units.insert(unit).second) << variant << ": two samplers on unit " << unit;
        ++samplers;
    }
    EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR)) << variant;
    return {attributes, samplers};
}

class ShaderContractGLTest : public ::testing::Test {
protected:
    void SetUp() override
    {
        auto window = test::openHiddenWindow(64, 64);
        ASSERT_TRUE(window.ok()) << window.error().message;
        mWindow = std::move(window).value();
    }
    std::unique_ptr<GlWindow> mWindow;
};

/// The variants the renderers compile (TerrainRenderer::create, ClipmapRenderer::create).
const std::vector<std::vector<std::string>> kVariants = {
    {},
    {"CLIP_TO_VALID"},
    {"NORMAL_MAP"},
    {"DETAIL", "LAYER_COUNT 3"},
    {"NORMAL_MAP", "DETAIL", "LAYER_COUNT 8", "CLIP_TO_VALID"},
    {"ATMOSPHERE"},
    {"NORMAL_MAP", "DETAIL", "LAYER_COUNT 3", "ATMOSPHERE"},
    {"PIXEL_COUNTS", "NORMAL_MAP", "DETAIL", "LAYER_COUNT 2"},
};

std::string describe(const std::string& program, const std::vector<std::string>& defines)
{
    std::string text = program;
    for (const auto& d : defines) {
        text += " " + d;
    }
    return text;
}

TEST_F(ShaderContractGLTest, TerrainProgramsUseTheContractsLocationsAndUnits)
{
    int attributes = 0, samplers = 0;
    for (const auto& defines : kVariants) {
        auto chunks = ShaderProgram::load(kShaders, "terrain", defines);
        ASSERT_TRUE(chunks.ok()) << chunks.error().message;
        const auto [a, s] = expectContract(*chunks, contract::kTerrainSamplers, describe("terrain", defines));
        EXPECT_GE(a, 5) << "aGrid, aSkirt and the node's three";
        attributes += a;
        samplers += s;
        auto tessellated = ShaderProgram::loadTessellation(kShaders, "terrain_tess", "terrain", defines);
        ASSERT_TRUE(tessellated.ok()) << tessellated.error().message;
        const auto [ta, ts] =
            expectContract(*tessellated, contract::kTerrainSamplers, describe("terrain_tess", defines));
        EXPECT_GE(ta, 4) << "aPatch and the node's three";
        EXPECT_GE(ts, 3) << "heights, colour and the block codes at least";
    }
    EXPECT_GT(samplers, 0);
    EXPECT_GT(attributes, 0);
}

TEST_F(ShaderContractGLTest, ClipmapProgramsUseTheContractsLocationsAndUnits)
{
    for (const auto& defines : kVariants) {
        if (!defines.empty() && defines[0] == "PIXEL_COUNTS") {
            continue;  // the clipmap counts no pixels
        }
        auto program = ShaderProgram::load(kShaders, "clipmap", defines);
        ASSERT_TRUE(program.ok()) << program.error().message;
        const auto [a, s] = expectContract(*program, contract::kClipmapSamplers, describe("clipmap", defines));
        EXPECT_EQ(a, 1) << "aGrid";
        EXPECT_GE(s, 4) << "heights, morph, colour and its previous at least";
    }
}

TEST(ShaderContractTest, NodeInstanceIsTheThreeVec4sTheShadersRead)
{
    // aNode0 = (origin x, origin y, spacing, morph), aNode1 = (skirt depth, layer, parent layer, lowest),
    // aNode2 = (quadrant x, quadrant y, height range, 0), as terrain.vert and terrain.tese read them.
    using contract::NodeInstance;
    EXPECT_EQ(offsetof(NodeInstance, originX), 0u);
    EXPECT_EQ(offsetof(NodeInstance, morph), 3 * sizeof(float));
    EXPECT_EQ(offsetof(NodeInstance, skirtDepth), 4 * sizeof(float));
    EXPECT_EQ(offsetof(NodeInstance, parentLayer), 6 * sizeof(float));
    EXPECT_EQ(offsetof(NodeInstance, lowest), 7 * sizeof(float));
    EXPECT_EQ(offsetof(NodeInstance, quadrantX), 8 * sizeof(float));
    EXPECT_EQ(offsetof(NodeInstance, heightRange), 10 * sizeof(float));
    // The shaders read the block codes by the contract's fields: a code decodes to what it was made from.
    BlockLevels levels;
    levels.blocksPerSide = 1;
    levels.blockQuads = kTessellationBlockQuads;
    for (int t = 0; t <= 3; ++t) {
        for (int culled = 0; culled <= 1; ++culled) {
            levels.level = {static_cast<std::uint8_t>(t)};
            levels.snap = {static_cast<std::uint8_t>(t), 3, static_cast<std::uint8_t>(3 - t), 2};
            levels.culled = {static_cast<std::uint8_t>(culled)};
            const int code = levels.code(0);
            EXPECT_EQ(code & kBlockLevelMask, t);
            for (int side = 0; side < 4; ++side) {
                EXPECT_EQ((code >> (kBlockSnapShift + side * kBlockSnapBits)) & ((1 << kBlockSnapBits) - 1),
                          levels.snap[static_cast<std::size_t>(side)]);
            }
            EXPECT_EQ((code & kBlockCulledBit) != 0, culled == 1);
        }
    }
}

}  // namespace
}  // namespace terrain
