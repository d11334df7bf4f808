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

AtmosphereTextures::Tables AtmosphereTextures::createTables()
{
    Tables t;
    t.aerial = gl::Texture::create();
    glBindTexture(GL_TEXTURE_3D, t.aerial.name());
    glTexImage3D(GL_TEXTURE_3D, 0, GL_RGBA16F, kAerialTableAzimuths, kAerialTableElevations, kAerialTableDistances, 0,
                 GL_RGBA, GL_FLOAT, nullptr);
    setTableParameters(GL_TEXTURE_3D);
    glBindTexture(GL_TEXTURE_3D, 0);
    t.sky = gl::Texture::create();
    glBindTexture(GL_TEXTURE_2D, t.sky.name());
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16F, kSkyTableAzimuths, kSkyTableElevations, 0, GL_RGBA, GL_FLOAT, nullptr);
    setTableParameters(GL_TEXTURE_2D);
    glBindTexture(GL_TEXTURE_2D, 0);
    return t;
}

Expected<AtmosphereTextures> AtmosphereTextures::create(const std::filesystem::path& shaderDirectory)
{
    AtmosphereTextures t;
    auto aerial = ShaderProgram::load(shaderDirectory, "atmosphere_table");
    TERRAIN_TRY(aerial);
    auto sky = ShaderProgram::load(shaderDirectory, "atmosphere_table", {"SKY_TABLE"});
    TERRAIN_TRY(sky);
    auto aerialBlend = ShaderProgram::load(shaderDirectory, "atmosphere_table", {"BLEND_TABLES"});
    TERRAIN_TRY(aerialBlend);
    auto skyBlend = ShaderProgram::load(shaderDirectory, "atmosphere_table", {"SKY_TABLE", "BLEND_TABLES"});
    TERRAIN_TRY(skyBlend);
    t.mAerialProgram = std::move(aerial.value());
    t.mSkyProgram = std::move(sky.value());
    t.mAerialBlend = std::move(aerialBlend.value());
    t.mSkyBlend = std::move(skyBlend.value());
    for (ShaderProgram* program : {&t.mAerialBlend, &t.mSkyBlend}) {
        program->use();
        glUniform1i(program->uniform("uLower"), 0);
        glUniform1i(program->uniform("uUpper"), 1);
    }
    glUseProgram(0);
    t.mFrame = createTables();
    t.mLattice[0] = createTables();
    t.mLattice[1] = createTables();
    t.mFramebuffer = gl::Framebuffer::create();
    t.mEmptyVao = gl::VertexArray::create();

    GLint previous = 0;
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &previous);
    glBindFramebuffer(GL_FRAMEBUFFER, t.mFramebuffer.name());
    glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, t.mFrame.aerial.name(), 0, 0);
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
    const Filled wanted{camera.position.z, glm::normalize(style.sunDirection),
                        static_cast<float>(aerialTableRange(camera)), style.air};
    if (mFrame.filled && *mFrame.filled == wanted) {
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
    const TableAltitudes at = tableAltitudes(wanted.altitude, style.air);
    std::array<Filled, 2> ends{wanted, wanted};
    ends[0].altitude = at.lower;
    ends[1].altitude = at.upper;
    auto holding = [this](const Filled& f) -> Tables* {
        for (Tables& t : mLattice) {
            if (t.filled && *t.filled == f) {
                return &t;
            }
        }
        return nullptr;
    };
    std::array<Tables*, 2> tables{holding(ends[0]), holding(ends[1])};
    Filled key = wanted;  // what the tables are for but the altitude
    key.altitude = 0.0;
    const bool moving = mLastKey && !(*mLastKey == key);
    mLastKey = key;
    if (at.upper == at.lower || (!tables[0] && !tables[1] && moving)) {
        // The viewer's own tables: where there is no lattice (an altitude not finite or too large), and while the
        // sun, the air or the range change from one update to the next, where the lattice's would be new every
        // frame: two sums a frame instead of one.
        integrate(mFrame, camera, style, wanted);
    } else {
        // The lattice tables at the two altitudes, made where neither holds one (a step up or down keeps the other).
        for (int k = 0; k < 2; ++k) {
            if (!tables[static_cast<std::size_t>(k)]) {
                Tables* free = &mLattice[0] == tables[static_cast<std::size_t>(1 - k)] ? &mLattice[1] : &mLattice[0];
                integrate(*free, camera, style, ends[static_cast<std::size_t>(k)]);
                tables[static_cast<std::size_t>(k)] = free;
            }
        }
        blend(*tables[0], *tables[1], static_cast<float>(at.weight));
        mFrame.filled = wanted;
    }

    glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(previous));
    glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
    for (const auto& [capability, enabled] : capabilities) {
        if (enabled) {
            glEnable(capability);
        }
    }
}

void AtmosphereTextures::integrate(Tables& tables, const Camera& camera, const SceneStyle& style, const Filled& filled)
{
    Camera at = camera;
    at.position.z = filled.altitude;
    auto setUniforms = [&](const ShaderProgram& program) {
        program.use();
        setAtmosphereUniforms(program, at, style);
        glUniform3fv(program.uniform("uSunDirection"), 1, glm::value_ptr(filled.sun));
        setMultipleScatteringUniforms(program, *mMultiple);
    };
    setUniforms(mAerialProgram);
    glViewport(0, 0, kAerialTableAzimuths, kAerialTableElevations);
    for (int slice = 0; slice < kAerialTableDistances; ++slice) {
        glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, tables.aerial.name(), 0, slice);
        glUniform1i(mAerialProgram.uniform("uSlice"), slice);
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    setUniforms(mSkyProgram);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tables.sky.name(), 0);
    glViewport(0, 0, kSkyTableAzimuths, kSkyTableElevations);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    tables.filled = filled;
}

void AtmosphereTextures::blend(const Tables& lower, const Tables& upper, float weight)
{
    auto bindBoth = [&](GLenum target, const gl::Texture& a, const gl::Texture& b) {
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(target, a.name());
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(target, b.name());
        glActiveTexture(GL_TEXTURE0);
    };
    mAerialBlend.use();
    glUniform1f(mAerialBlend.uniform("uWeight"), weight);
    bindBoth(GL_TEXTURE_3D, lower.aerial, upper.aerial);
    glViewport(0, 0, kAerialTableAzimuths, kAerialTableElevations);
    for (int slice = 0; slice < kAerialTableDistances; ++slice) {
        glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, mFrame.aerial.name(), 0, slice);
        glUniform1i(mAerialBlend.uniform("uSlice"), slice);
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    mSkyBlend.use();
    glUniform1f(mSkyBlend.uniform("uWeight"), weight);
    bindBoth(GL_TEXTURE_2D, lower.sky, upper.sky);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, mFrame.sky.name(), 0);
    glViewport(0, 0, kSkyTableAzimuths, kSkyTableElevations);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    // Units 0 and 1 as the frame's programs expect to find them: nothing of the air bound.
    for (GLenum target : {GL_TEXTURE_3D, GL_TEXTURE_2D}) {
        bindBoth(target, gl::Texture{}, gl::Texture{});
    }
}

void AtmosphereTextures::bindAerial(int unit) const
{
    glActiveTexture(static_cast<GLenum>(GL_TEXTURE0 + unit));
    glBindTexture(GL_TEXTURE_3D, mFrame.aerial.name());
    glActiveTexture(GL_TEXTURE0);
}

void AtmosphereTextures::bindSky(int unit) const
{
    glActiveTexture(static_cast<GLenum>(GL_TEXTURE0 + unit));
    glBindTexture(GL_TEXTURE_2D, mFrame.sky.name());
    glActiveTexture(GL_TEXTURE0);
}

}  // namespace terrain
