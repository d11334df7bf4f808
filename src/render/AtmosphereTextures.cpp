// The frame's air tables on the GPU (AtmosphereTextures.h).
#include "render/AtmosphereTextures.h"

#include "light/AtmosphereTables.h"
#include "render/FrameSetup.h"

#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace terrain {

namespace {

void setTableParameters(GLenum target)
{
    glTexParameteri(target, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(target, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(target, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(target, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(target, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
    glTexParameteri(target, GL_TEXTURE_MAX_LEVEL, 0);
}

}  // namespace

Expected<AtmosphereTextures> AtmosphereTextures::create(const std::filesystem::path& shaderDirectory)
{
    AtmosphereTextures t;
    auto aerial = ShaderProgram::load(shaderDirectory, "atmosphere_table");
    TERRAIN_TRY(aerial);
    auto sky = ShaderProgram::load(shaderDirectory, "atmosphere_table", {"SKY_TABLE"});
    TERRAIN_TRY(sky);
    t.mAerialProgram = std::move(aerial.value());
    t.mSkyProgram = std::move(sky.value());
    t.mAerial = gl::Texture::create();
    glBindTexture(GL_TEXTURE_3D, t.mAerial.name());
    glTexImage3D(GL_TEXTURE_3D, 0, GL_RGBA16F, kAerialTableAzimuths, kAerialTableElevations, kAerialTableDistances, 0,
                 GL_RGBA, GL_FLOAT, nullptr);
    setTableParameters(GL_TEXTURE_3D);
    glBindTexture(GL_TEXTURE_3D, 0);
    t.mSky = gl::Texture::create();
    glBindTexture(GL_TEXTURE_2D, t.mSky.name());
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16F, kSkyTableAzimuths, kSkyTableElevations, 0, GL_RGBA, GL_FLOAT, nullptr);
    setTableParameters(GL_TEXTURE_2D);
    glBindTexture(GL_TEXTURE_2D, 0);
    t.mFramebuffer = gl::Framebuffer::create();
    t.mEmptyVao = gl::VertexArray::create();

    GLint previous = 0;
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &previous);
    glBindFramebuffer(GL_FRAMEBUFFER, t.mFramebuffer.name());
    glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, t.mAerial.name(), 0, 0);
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(previous));
    if (status != GL_FRAMEBUFFER_COMPLETE) {
        return makeError("cannot draw into a half-float 3D texture (framebuffer status 0x", std::hex, status,
                         "): the atmosphere's tables need it");
    }
    return t;
}

void AtmosphereTextures::update(const Camera& camera, const SceneStyle& style)
{
    const Filled wanted{static_cast<float>(camera.position.z), glm::normalize(style.sunDirection),
                        static_cast<float>(aerialTableRange(camera)), style.air};
    if (mFilled && *mFilled == wanted) {
        return;
    }
    GLint previous = 0;
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &previous);
    std::array<GLint, 4> viewport{};
    glGetIntegerv(GL_VIEWPORT, viewport.data());
    const std::array<std::pair<GLenum, GLboolean>, 3> capabilities = {{{GL_BLEND, glIsEnabled(GL_BLEND)},
                                                                       {GL_DEPTH_TEST, glIsEnabled(GL_DEPTH_TEST)},
                                                                       {GL_CULL_FACE, glIsEnabled(GL_CULL_FACE)}}};
    for (const auto& [capability, enabled] : capabilities) {
        glDisable(capability);
    }
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    glBindFramebuffer(GL_FRAMEBUFFER, mFramebuffer.name());
    glBindVertexArray(mEmptyVao.name());

    const double sunElevation = std::asin(std::clamp(double{wanted.sun.z}, -1.0, 1.0));
    if (!mMultiple || mMultipleElevation != sunElevation || !(mMultipleAir == style.air)) {
        mMultiple = terrain::multipleScattering(style.air, sunElevation);
        mMultipleElevation = sunElevation;
        mMultipleAir = style.air;
    }
    auto setUniforms = [&](const ShaderProgram& program) {
        program.use();
        setAtmosphereUniforms(program, camera, style);
        glUniform3fv(program.uniform("uSunDirection"), 1, glm::value_ptr(wanted.sun));
        setMultipleScatteringUniforms(program, *mMultiple);
    };
    setUniforms(mAerialProgram);
    glViewport(0, 0, kAerialTableAzimuths, kAerialTableElevations);
    for (int slice = 0; slice < kAerialTableDistances; ++slice) {
        glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, mAerial.name(), 0, slice);
        glUniform1i(mAerialProgram.uniform("uSlice"), slice);
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    setUniforms(mSkyProgram);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, mSky.name(), 0);
    glViewport(0, 0, kSkyTableAzimuths, kSkyTableElevations);
    glDrawArrays(GL_TRIANGLES, 0, 3);

    glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(previous));
    glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
    for (const auto& [capability, enabled] : capabilities) {
        if (enabled) {
            glEnable(capability);
        }
    }
    mFilled = wanted;
}

void AtmosphereTextures::bindAerial(int unit) const
{
    glActiveTexture(static_cast<GLenum>(GL_TEXTURE0 + unit));
    glBindTexture(GL_TEXTURE_3D, mAerial.name());
    glActiveTexture(GL_TEXTURE0);
}

void AtmosphereTextures::bindSky(int unit) const
{
    glActiveTexture(static_cast<GLenum>(GL_TEXTURE0 + unit));
    glBindTexture(GL_TEXTURE_2D, mSky.name());
    glActiveTexture(GL_TEXTURE0);
}

}  // namespace terrain
