// shaders/atmosphere.glsl against its reference, light/Atmosphere.h: a probe program evaluates the shaders'
// sums (what fills the air tables: in-scattered light, sky radiance) and transmittance for cases the C++ model
// evaluates in double, into a float framebuffer; they agree to float's precision. Then the tables the renderer
// fills (render/AtmosphereTextures.h) are read through the terrain's and the sky's lookups and compared with
// the C++ tables (light/AtmosphereTables.h), which AtmosphereTablesTest holds to the model: so the frames show
// the model the tests measure.
#include "GlTestSupport.h"
#include "TestSupport.h"

#include "light/Atmosphere.h"
#include "light/AtmosphereTables.h"
#include "render/AtmosphereTextures.h"
#include "render/FrameSetup.h"
#include "render/GlWindow.h"
#include "render/ShaderProgram.h"

#include <gtest/gtest.h>
#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

namespace terrain {
namespace {

using test::direction;

constexpr double kPi = std::numbers::pi;
constexpr int kCases = 64;  // the probe's uniform arrays
constexpr int kRows = 4;    // what the probe computes per case (kProbeFragment)

const char* kProbeVertex = R"(#version 330 core
void main()
{
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2) * 2.0 - 1.0;
    gl_Position = vec4(p, 0.0, 1.0);
}
)";

// Row 0: the in-scattered light of the segment to the case's point; row 1: its transmittance; row 2: the sky's
// radiance in the case's direction; row 3: the sky's irradiance at the case's point. Column: the case. With
// LOOKUP: what the terrain's vertex programs take (airAt): rows 0 and 2 from the tables, row 1 the sunlight at the
// case's point.
const char* kProbeFragment = R"(#version 330 core
#include "atmosphere.glsl"
uniform vec3 uRelative[64];
uniform vec3 uSun;
out vec4 fragColour;
void main()
{
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 relative = uRelative[p.x];
    vec3 view = normalize(relative);
#ifdef LOOKUP
    vec3 value = p.y == 0 ? aerialPerspective(vec3(0.0), relative, uSun)
               : p.y == 1 ? airAt(relative, uSun).sunlight
                          : skyRadiance(view, uSun);
#else
    vec3 value = p.y == 0 ? aerialSum(view, length(relative), uSun)
               : p.y == 1 ? airAt(relative, uSun).transmittance
                          : skySum(view, uSun);
#endif
    value = p.y == 3 ? airAt(relative, uSun).skylight : value;
    fragColour = vec4(value, 1.0);
}
)";

// The cases: segments of 300 m to 150 km at pitches from -25 to +3 degrees, all around, not through the ground.
std::vector<glm::dvec3> probeCases(double altitude)
{
    std::vector<glm::dvec3> cases;
    for (int k = 0; k < kCases; ++k) {
        const double distance = 300.0 * std::pow(500.0, (k % 16) / 15.0);
        const double pitch = -25.0 + 28.0 * ((k * 7) % 13) / 12.0;
        glm::dvec3 relative = direction(k * 47.0, pitch) * distance;
        if (altitude + relative.z < -400.0) {
            relative = direction(k * 47.0, 1.0) * distance;
        }
        cases.push_back(relative);
    }
    return cases;
}

/// A kCases x kRows float framebuffer the probe draws into, and its reading.
class ProbeTarget {
public:
    ProbeTarget()
    {
        glGenFramebuffers(1, &mFramebuffer);
        glGenRenderbuffers(1, &mColour);
        glBindRenderbuffer(GL_RENDERBUFFER, mColour);
        glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA32F, kCases, kRows);
        glBindFramebuffer(GL_FRAMEBUFFER, mFramebuffer);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, mColour);
        glGenVertexArrays(1, &mVao);
    }
    ~ProbeTarget()
    {
        glDeleteVertexArrays(1, &mVao);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glDeleteRenderbuffers(1, &mColour);
        glDeleteFramebuffers(1, &mFramebuffer);
    }
    bool complete() const { return glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE; }
    /// Runs `program` (in use, its uniforms set) over the cases in `cases` with the sun in `sun`.
    void draw(const ShaderProgram& program, const std::vector<glm::dvec3>& cases, const glm::dvec3& sun)
    {
        std::vector<float> relatives;
        for (const glm::dvec3& r : cases) {
            relatives.insert(relatives.end(), {float(r.x), float(r.y), float(r.z)});
        }
        glUniform3fv(program.uniform("uRelative"), kCases, relatives.data());
        const glm::vec3 sunFloat(sun);
        glUniform3fv(program.uniform("uSun"), 1, glm::value_ptr(sunFloat));
        glBindFramebuffer(GL_FRAMEBUFFER, mFramebuffer);
        glViewport(0, 0, kCases, kRows);
        glDisable(GL_DEPTH_TEST);
        glBindVertexArray(mVao);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        mPixels.assign(static_cast<std::size_t>(kCases) * kRows * 4, 0.0f);
        glReadPixels(0, 0, kCases, kRows, GL_RGBA, GL_FLOAT, mPixels.data());
    }
    double at(int row, int k, int c) const { return mPixels[(static_cast<std::size_t>(row) * kCases + k) * 4 + c]; }

private:
    GLuint mFramebuffer = 0, mColour = 0, mVao = 0;
    std::vector<float> mPixels;
};

Expected<ShaderProgram> loadProbe(const test::ScratchDir& dir, const std::vector<std::string>& defines)
{
    std::filesystem::copy_file(std::filesystem::path(TERRAIN_SHADER_DIR) / "atmosphere.glsl", dir / "atmosphere.glsl",
                               std::filesystem::copy_options::overwrite_existing);
    std::ofstream(dir / "probe.vert") << kProbeVertex;
    std::ofstream(dir / "probe.frag") << kProbeFragment;
    return ShaderProgram::load(dir.path(), "probe", defines);
}

TEST(AtmosphereGLTest, TheShadersAirIsTheModels)
{
    auto window = test::openHiddenWindow(64, 64);
    ASSERT_TRUE(window.ok()) << window.error().message;
    test::ScratchDir dir;
    auto program = loadProbe(dir, {"ATMOSPHERE"});
    ASSERT_TRUE(program.ok()) << program.error().message;
    ProbeTarget target;
    ASSERT_TRUE(target.complete());

    const AtmosphereModel air;
    std::size_t compared = 0;
    for (double sunElevation : {4.0, 35.0, 70.0}) {
        const glm::dvec3 sun = direction(135.0, sunElevation);
        for (double altitude : {300.0, 2500.0, 4200.0}) {
            const std::vector<glm::dvec3> cases = probeCases(altitude);
            SceneStyle style;
            style.sunDirection = glm::vec3(sun);
            Camera camera;
            camera.position = {0.0, 0.0, altitude};
            program->use();
            setAtmosphereUniforms(*program, camera, style);
            const MultipleScattering multiple = multipleScattering(air, std::asin(sun.z));
            setMultipleScatteringUniforms(*program, multiple);
            target.draw(*program, cases, sun);
            for (int k = 0; k < kCases; ++k) {
                const glm::dvec3 relative(glm::vec3(cases[k]));  // what the shader was given
                const AerialPerspective reference =
                    aerialPerspective(air, altitude, relative, sun, kAerialSamples, &multiple);
                const glm::dvec3 sky =
                    skyRadiance(air, altitude, glm::normalize(relative), sun, kSkySamples, &multiple);
                const glm::dvec3 skylight = multiple.irradianceAt(altitude + relative.z);
                for (int c = 0; c < 3; ++c) {
                    const std::string where = "sun " + std::to_string(sunElevation) + ", altitude " +
                                              std::to_string(altitude) + ", case " + std::to_string(k) + ", channel " +
                                              std::to_string(c);
                    EXPECT_NEAR(target.at(0, k, c), reference.inscattered[c], 2e-3 * reference.inscattered[c] + 1e-7)
                        << where;
                    EXPECT_NEAR(target.at(1, k, c), reference.transmittance[c],
                                2e-3 * reference.transmittance[c] + 1e-6)
                        << where;
                    EXPECT_NEAR(target.at(2, k, c), sky[c], 2e-3 * sky[c] + 1e-7) << where;
                    EXPECT_NEAR(target.at(3, k, c), skylight[c], 1e-3 * skylight[c] + 1e-7) << where;
                    ++compared;
                }
            }
        }
    }
    EXPECT_EQ(compared, 9u * kCases * 3);
}

TEST(AtmosphereGLTest, TheRenderersTablesAreTheCppTables)
{
    auto window = test::openHiddenWindow(64, 64);
    ASSERT_TRUE(window.ok()) << window.error().message;
    test::ScratchDir dir;
    auto program = loadProbe(dir, {"ATMOSPHERE", "LOOKUP"});
    ASSERT_TRUE(program.ok()) << program.error().message;
    auto textures = AtmosphereTextures::create(TERRAIN_SHADER_DIR);
    ASSERT_TRUE(textures.ok()) << textures.error().message;
    ProbeTarget target;
    ASSERT_TRUE(target.complete());

    const AtmosphereModel air;
    std::size_t compared = 0;
    double worst = 0.0;
    for (double sunElevation : {4.0, 35.0}) {
        const glm::dvec3 sun = direction(135.0, sunElevation);
        // On the fills' altitude lattice (tableAltitudes: multiples of 60 m), and between two of its altitudes, where
        // the frame's tables are interpolated between the lattice's (render/AtmosphereTextures.h): both new, both
        // held, one held (a step up), neither held; the first altitude of the second sun is summed directly.
        for (double altitude : {300.0, 4200.0, 1234.5, 1221.0, 1275.0, 1190.0}) {
            SceneStyle style;
            style.sunDirection = glm::vec3(sun);
            Camera camera;
            camera.position = {0.0, 0.0, altitude};
            camera.farPlane = 80000.0;  // cases beyond the range read its last slice
            textures->update(camera, style);
            textures->bindAerial(0);
            textures->bindSky(1);
            program->use();
            glUniform1i(program->uniform("uAerialTable"), 0);
            glUniform1i(program->uniform("uSkyTable"), 1);
            setAtmosphereUniforms(*program, camera, style);
            const std::vector<glm::dvec3> cases = probeCases(altitude);
            target.draw(*program, cases, sun);
            ASSERT_TRUE(textures->multipleScattering().has_value());
            // The renderer's psi_ms is the model's for the style's sun and air.
            EXPECT_EQ(
                *textures->multipleScattering(),
                multipleScattering(air, std::asin(std::clamp(double{glm::normalize(glm::vec3(sun)).z}, -1.0, 1.0))));
            const AtmosphereTables tables(air, altitude, glm::dvec3(glm::normalize(glm::vec3(sun))),
                                          aerialTableRange(camera), &*textures->multipleScattering());
            for (int k = 0; k < kCases; ++k) {
                const glm::dvec3 relative(glm::vec3(cases[k]));
                const glm::dvec3 view = glm::normalize(relative);
                const glm::dvec3 inscattered = tables.inscattered(view, glm::length(relative));
                const glm::dvec3 sky = tables.sky(view);
                const glm::dvec3 sunlight = sunTransmittance(air, altitude + relative.z, std::asin(sun.z));
                for (int c = 0; c < 3; ++c) {
                    const std::string where = "sun " + std::to_string(sunElevation) + ", altitude " +
                                              std::to_string(altitude) + ", case " + std::to_string(k) + ", channel " +
                                              std::to_string(c);
                    EXPECT_NEAR(target.at(0, k, c), inscattered[c], 5e-3 * inscattered[c] + 1e-7) << where;
                    EXPECT_NEAR(target.at(1, k, c), sunlight[c], 2e-3 * sunlight[c] + 1e-6) << where;
                    EXPECT_NEAR(target.at(2, k, c), sky[c], 5e-3 * sky[c] + 1e-7) << where;
                    worst = std::max({worst, std::abs(target.at(0, k, c) / inscattered[c] - 1.0),
                                      std::abs(target.at(2, k, c) / sky[c] - 1.0)});
                    ++compared;
                }
            }
        }
    }
    EXPECT_EQ(compared, 12u * kCases * 3);
    std::printf("largest difference between the GL and C++ tables: %.4f\n", worst);
}

}  // namespace
}  // namespace terrain
