// The frame's air tables on the GPU (light/AtmosphereTables.h gives their layout and is their reference): the
// aerial table, a 3D texture the terrain's fragment programs read their in-scattered light from, and the sky
// table, a 2D texture the sky reads. Filled by shaders/atmosphere_table.frag, one draw per slice, whenever the
// viewer's altitude, the sun, the air or the table's range changed since the last fill. The light scattered
// more than once (light/Atmosphere.h, multipleScattering) is made on the CPU whenever the sun's elevation or the
// air changed, and handed to the filling programs as uniforms.
#pragma once

#include "core/Camera.h"
#include "core/Expected.h"
#include "light/Atmosphere.h"
#include "render/GlObjects.h"
#include "render/ShaderProgram.h"

#include <glm/vec3.hpp>

#include <filesystem>
#include <optional>

namespace terrain {

struct SceneStyle;

class AtmosphereTextures {
public:
    AtmosphereTextures() = default;
    /// Loads the filling programs from `shaderDirectory` and makes the textures (half floats, linear
    /// filtering, clamped). Needs a current GL context.
    static Expected<AtmosphereTextures> create(const std::filesystem::path& shaderDirectory);

    /// Fills the tables for `camera` (its altitude and aerialTableRange) and the sun and air of `style`, unless
    /// they hold them already. Leaves the bound framebuffer, the viewport, blending, depth testing and face
    /// culling as they were; the polygon mode is left filled.
    void update(const Camera& camera, const SceneStyle& style);

    /// Binds the aerial table (a 3D texture) to texture unit `unit`, and the sky table (2D) to `unit`.
    void bindAerial(int unit) const;
    void bindSky(int unit) const;

    /// psi_ms of the last fill (for the sun and air of its SceneStyle; none before the first).
    const std::optional<MultipleScattering>& multipleScattering() const { return mMultiple; }

private:
    /// What the tables were filled for.
    struct Filled {
        float altitude = 0.0f;
        glm::vec3 sun{0.0f};
        float range = 0.0f;
        AtmosphereModel air;
        bool operator==(const Filled&) const = default;
    };

    ShaderProgram mAerialProgram;
    ShaderProgram mSkyProgram;
    gl::Texture mAerial;
    gl::Texture mSky;
    gl::Framebuffer mFramebuffer;
    gl::VertexArray mEmptyVao;
    std::optional<Filled> mFilled;
    /// psi_ms, and the sun's elevation (radians) and the air it was made for.
    std::optional<MultipleScattering> mMultiple;
    double mMultipleElevation = 0.0;
    AtmosphereModel mMultipleAir;
};

}  // namespace terrain
