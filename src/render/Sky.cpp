#include "render/Sky.h"

#include "render/FrameSetup.h"
#include "render/ShaderContract.h"

#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>

namespace terrain {

Expected<Sky> Sky::create(const std::filesystem::path& shaderDirectory, const LightingModel& lighting)
{
    std::vector<std::string> defines;
    if (lighting.atmosphere) {
        defines.emplace_back("ATMOSPHERE");
    }
    auto program = ShaderProgram::load(shaderDirectory, "sky", defines);
    TERRAIN_TRY(program);
    Sky sky;
    sky.mProgram = std::move(program.value());
    contract::bindSamplerUnits(sky.mProgram, contract::kSkySamplers);
    sky.mEmptyVao = gl::VertexArray::create();
    if (lighting.atmosphere) {
        auto tables = AtmosphereTextures::create(shaderDirectory);
        TERRAIN_TRY(tables);
        sky.mTables = std::move(tables.value());
    }
    return sky;
}

void Sky::prepare(const Camera& camera, const SceneStyle& style)
{
    if (mTables) {
        mTables->update(camera, style);
    }
}

void Sky::bindAerialTable(int unit) const
{
    if (mTables) {
        mTables->bindAerial(unit);
    }
}

void Sky::setSkylight(const ShaderProgram& program) const
{
    if (mTables && mTables->multipleScattering()) {
        setMultipleScatteringUniforms(program, *mTables->multipleScattering());
    }
}

void Sky::draw(const Camera& camera, const SceneStyle& style) const
{
    if (mTables) {
        mTables->bindSky(contract::kSkySamplers[0].unit);
    }
    const glm::mat4 viewProjection(camera.projection() * camera.viewRotation());
    const glm::mat4 inverse = glm::inverse(viewProjection);
    mProgram.use();
    glUniformMatrix4fv(mProgram.uniform("uInverseViewProjection"), 1, GL_FALSE, glm::value_ptr(inverse));
    glUniform3fv(mProgram.uniform("uHazeColour"), 1, glm::value_ptr(style.hazeColour));
    glUniform3fv(mProgram.uniform("uZenithColour"), 1, glm::value_ptr(style.zenithColour));
    const glm::vec3 sun = glm::normalize(style.sunDirection);
    glUniform3fv(mProgram.uniform("uSunDirection"), 1, glm::value_ptr(sun));
    glUniform3fv(mProgram.uniform("uSunColour"), 1, glm::value_ptr(style.sunColour));
    setAtmosphereUniforms(mProgram, camera, style);
    // At the far plane, where the depth test passes only what nothing was drawn over (the depth's clear value).
    glDepthMask(GL_FALSE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LEQUAL);
    glBindVertexArray(mEmptyVao.name());
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
}

}  // namespace terrain
