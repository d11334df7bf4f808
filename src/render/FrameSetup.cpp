// The frame setup the terrain renderers share (FrameSetup.h).
#include "render/FrameSetup.h"

#include "light/AtmosphereTables.h"

#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace terrain {

void beginSceneFrame(const Camera& camera, const SceneStyle& style, Sky& sky, SkyOrder order)
{
    sky.prepare(camera, style);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    glViewport(0, 0, camera.viewportWidth, camera.viewportHeight);
    glClearColor(style.clearColour.r, style.clearColour.g, style.clearColour.b, 1.0f);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (style.drawSky && order == SkyOrder::BeforeTerrain) {
        sky.draw(camera, style);
    }
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glPolygonMode(GL_FRONT_AND_BACK, style.wireframe ? GL_LINE : GL_FILL);
}

void endSceneFrame(const Camera& camera, const SceneStyle& style, const Sky& sky, SkyOrder order)
{
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    if (style.drawSky && order == SkyOrder::AfterTerrain) {
        sky.draw(camera, style);
    }
}

glm::dvec4 validRectangle(const MapHeader& header)
{
    const double s = header.sampleSpacing;
    return {header.originX + header.validX0 * s, header.originY + header.validY0 * s,
            header.originX + (header.validX0 + header.validWidth - 1.0) * s,
            header.originY + (header.validY0 + header.validHeight - 1.0) * s};
}

void setAtmosphereUniforms(const ShaderProgram& program, const Camera& camera, const SceneStyle& style)
{
    const AtmosphereModel& air = style.air;
    const glm::vec3 rayleigh(air.rayleighScattering);
    glUniform3fv(program.uniform("uRayleighScattering"), 1, glm::value_ptr(rayleigh));
    glUniform1f(program.uniform("uRayleighHeight"), static_cast<float>(air.rayleighHeight));
    glUniform1f(program.uniform("uMieScattering"), static_cast<float>(air.mieScattering));
    glUniform1f(program.uniform("uMieExtinction"), static_cast<float>(air.mieExtinction));
    glUniform1f(program.uniform("uMieHeight"), static_cast<float>(air.mieHeight));
    glUniform1f(program.uniform("uMieAnisotropy"), static_cast<float>(air.mieAnisotropy));
    glUniform1f(program.uniform("uTopScaleHeights"), static_cast<float>(air.topScaleHeights));
    glUniform1f(program.uniform("uCameraAltitude"), static_cast<float>(camera.position.z));
    glUniform2f(program.uniform("uCameraDensities"),
                static_cast<float>(std::exp(-camera.position.z / air.rayleighHeight)),
                static_cast<float>(std::exp(-camera.position.z / air.mieHeight)));
    glUniform1f(program.uniform("uExposure"), style.exposure);
    const double sunElevation = std::asin(std::clamp(double{glm::normalize(style.sunDirection).z}, -1.0, 1.0));
    glUniform1f(program.uniform("uSunAirMass"), static_cast<float>(airMass(sunElevation)));
    glUniform1f(program.uniform("uAerialRange"), static_cast<float>(aerialTableRange(camera)));
}

void setMultipleScatteringUniforms(const ShaderProgram& program, const MultipleScattering& multiple)
{
    std::array<glm::vec3, kMultipleScatteringAltitudes> psi{}, irradiance{};
    for (std::size_t i = 0; i < psi.size(); ++i) {
        psi[i] = glm::vec3(multiple.psi[i]);
        irradiance[i] = glm::vec3(multiple.irradiance[i]);
    }
    glUniform3fv(program.uniform("uMultipleScattering"), kMultipleScatteringAltitudes, glm::value_ptr(psi[0]));
    glUniform3fv(program.uniform("uSkyIrradiance"), kMultipleScatteringAltitudes, glm::value_ptr(irradiance[0]));
    glUniform1f(program.uniform("uMultipleScatteringTop"), static_cast<float>(multiple.top));
}

void setSceneUniforms(const ShaderProgram& program, const Camera& camera, const SceneStyle& style,
                      const MapHeader& header)
{
    program.use();
    const glm::mat4 viewProjection(camera.projection() * camera.viewRotation());
    glUniformMatrix4fv(program.uniform("uViewProjection"), 1, GL_FALSE, glm::value_ptr(viewProjection));
    glUniform1f(program.uniform("uHeightBase"), static_cast<float>(header.heightOffset - camera.position.z));
    const glm::vec3 sun = glm::normalize(style.sunDirection);
    glUniform3fv(program.uniform("uSunDirection"), 1, glm::value_ptr(sun));
    glUniform3fv(program.uniform("uSunColour"), 1, glm::value_ptr(style.sunColour));
    glUniform3fv(program.uniform("uAmbient"), 1, glm::value_ptr(style.ambient));
    glUniform3fv(program.uniform("uHazeColour"), 1, glm::value_ptr(style.hazeColour));
    glUniform1f(program.uniform("uHazeDistance"), style.hazeDistance);
    glUniform1i(program.uniform("uWireframe"), style.wireframe ? 1 : 0);
    setAtmosphereUniforms(program, camera, style);
    const glm::dvec4 valid = validRectangle(header);
    const double slack = 1e-3 * header.sampleSpacing;
    glUniform4f(program.uniform("uValidRect"), static_cast<float>(valid.x - camera.position.x - slack),
                static_cast<float>(valid.y - camera.position.y - slack),
                static_cast<float>(valid.z - camera.position.x + slack),
                static_cast<float>(valid.w - camera.position.y + slack));
}

}  // namespace terrain
