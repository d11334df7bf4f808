// shaders/atmosphere.glsl against its reference, light/Atmosphere.h: a probe program evaluates the shaders'
// aerial perspective (transmittance and in-scattered light) and sky radiance for cases the C++ model evaluates
// in double, into a float framebuffer. They agree to float's precision, so the frames show the model the tests
// measure.
#include "GlTestSupport.h"
#include "TestSupport.h"

#include "light/Atmosphere.h"
#include "render/FrameSetup.h"
#include "render/GlWindow.h"
#include "render/ShaderProgram.h"

#include <gtest/gtest.h>
#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

namespace terrain {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kCases = 64;  // the probe's uniform arrays

glm::dvec3 direction(double azimuthDegrees, double elevationDegrees)
{
    const double a = azimuthDegrees * kPi / 180.0, e = elevationDegrees * kPi / 180.0;
    return {std::sin(a) * std::cos(e), std::cos(a) * std::cos(e), std::sin(e)};
}

const char* kProbeVertex = R"(#version 330 core
void main()
{
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2) * 2.0 - 1.0;
    gl_Position = vec4(p, 0.0, 1.0);
}
)";

// Row 0: aerialPerspective of radiance 0 (the in-scattered light); row 1: of radiance 1 (transmittance + it);
// row 2: skyRadiance in the case's direction. Column: the case.
const char* kProbeFragment = R"(#version 330 core
#include "atmosphere.glsl"
uniform vec3 uRelative[64];
uniform vec3 uSun;
out vec4 fragColour;
void main()
{
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 relative = uRelative[p.x];
    vec3 value = p.y == 0 ? aerialPerspective(vec3(0.0), relative, uSun)
               : p.y == 1 ? aerialPerspective(vec3(1.0), relative, uSun)
                          : skyRadiance(normalize(relative), uSun);
    fragColour = vec4(value, 1.0);
}
)";

TEST(AtmosphereGLTest, TheShadersAirIsTheModels)
{
    auto window = test::openHiddenWindow(64, 64);
    ASSERT_TRUE(window.ok()) << window.error().message;
    test::ScratchDir dir;
    std::filesystem::copy_file(std::filesystem::path(TERRAIN_SHADER_DIR) / "atmosphere.glsl", dir / "atmosphere.glsl");
    std::ofstream(dir / "probe.vert") << kProbeVertex;
    std::ofstream(dir / "probe.frag") << kProbeFragment;
    auto program = ShaderProgram::load(dir.path(), "probe", {"ATMOSPHERE"});
    ASSERT_TRUE(program.ok()) << program.error().message;

    GLuint framebuffer = 0, colour = 0;
    glGenFramebuffers(1, &framebuffer);
    glGenRenderbuffers(1, &colour);
    glBindRenderbuffer(GL_RENDERBUFFER, colour);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA32F, kCases, 3);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, colour);
    ASSERT_EQ(glCheckFramebufferStatus(GL_FRAMEBUFFER), static_cast<GLenum>(GL_FRAMEBUFFER_COMPLETE));
    GLuint vao = 0;
    glGenVertexArrays(1, &vao);

    const AtmosphereModel air;
    std::size_t compared = 0;
    for (double sunElevation : {4.0, 35.0, 70.0}) {
        const glm::dvec3 sun = direction(135.0, sunElevation);
        for (double altitude : {300.0, 2500.0, 4200.0}) {
            // The cases: segments of 300 m to 150 km at pitches from -25 to +3 degrees, all around.
            std::vector<glm::dvec3> cases;
            for (int k = 0; k < kCases; ++k) {
                const double distance = 300.0 * std::pow(500.0, (k % 16) / 15.0);
                const double pitch = -25.0 + 28.0 * ((k * 7) % 13) / 12.0;
                glm::dvec3 relative = direction(k * 47.0, pitch) * distance;
                if (altitude + relative.z < -400.0) {
                    relative = direction(k * 47.0, 1.0) * distance;  // not through the ground
                }
                cases.push_back(relative);
            }
            SceneStyle style;
            style.sunDirection = glm::vec3(sun);
            Camera camera;
            camera.position = {0.0, 0.0, altitude};
            program->use();
            setAtmosphereUniforms(*program, camera, style);
            std::vector<float> relatives;
            for (const glm::dvec3& r : cases) {
                relatives.insert(relatives.end(), {float(r.x), float(r.y), float(r.z)});
            }
            glUniform3fv(program->uniform("uRelative"), kCases, relatives.data());
            const glm::vec3 sunFloat(sun);
            glUniform3fv(program->uniform("uSun"), 1, glm::value_ptr(sunFloat));
            glViewport(0, 0, kCases, 3);
            glDisable(GL_DEPTH_TEST);
            glBindVertexArray(vao);
            glDrawArrays(GL_TRIANGLES, 0, 3);
            std::vector<float> pixels(static_cast<std::size_t>(kCases) * 3 * 4);
            glReadPixels(0, 0, kCases, 3, GL_RGBA, GL_FLOAT, pixels.data());
            auto at = [&](int row, int k, int c) {
                return double{pixels[(static_cast<std::size_t>(row) * kCases + k) * 4 + c]};
            };
            for (int k = 0; k < kCases; ++k) {
                const glm::dvec3 relative(glm::vec3(cases[k]));  // what the shader was given
                const AerialPerspective reference = aerialPerspective(air, altitude, relative, sun);
                const glm::dvec3 sky = skyRadiance(air, altitude, glm::normalize(relative), sun);
                for (int c = 0; c < 3; ++c) {
                    const std::string where = "sun " + std::to_string(sunElevation) + ", altitude " +
                                              std::to_string(altitude) + ", case " + std::to_string(k) + ", channel " +
                                              std::to_string(c);
                    EXPECT_NEAR(at(0, k, c), reference.inscattered[c], 2e-3 * reference.inscattered[c] + 1e-7) << where;
                    EXPECT_NEAR(at(1, k, c) - at(0, k, c), reference.transmittance[c],
                                2e-3 * reference.transmittance[c] + 1e-6)
                        << where;
                    EXPECT_NEAR(at(2, k, c), sky[c], 2e-3 * sky[c] + 1e-7) << where;
                    ++compared;
                }
            }
        }
    }
    EXPECT_EQ(compared, 9u * kCases * 3);
    glDeleteVertexArrays(1, &vao);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteRenderbuffers(1, &colour);
    glDeleteFramebuffers(1, &framebuffer);
}

}  // namespace
}  // namespace terrain
