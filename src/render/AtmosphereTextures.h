// The frame's air tables on the GPU (light/AtmosphereTables.h gives their layout and is their reference): the
// aerial table, a 3D texture the terrain's vertex programs read their in-scattered light from, and the sky
// table, a 2D texture the sky reads. The tables are filled by shaders/atmosphere_table.frag (one draw per slice) at
// the two altitudes of a lattice around the viewer (tableAltitudes), whenever the viewer leaves their interval or
// the sun, the air or the table's range change, and kept; the frame's tables are their linear interpolation at the
// viewer's altitude (the same program with BLEND_TABLES, a fetch from each), made when the altitude changes: a
// flight integrates a table when it crosses an altitude step, not every frame. While the sun, the air or the range
// change from one update to the next, the frame's tables are summed directly. The light scattered
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
    /// What tables were filled for.
    struct Filled {
        double altitude = 0.0;
        glm::vec3 sun{0.0f};
        float range = 0.0f;
        AtmosphereModel air;
        bool operator==(const Filled&) const = default;
    };
    /// A pair of tables (aerial 3D, sky 2D) of the tables' sizes and format.
    struct Tables {
        gl::Texture aerial;
        gl::Texture sky;
        std::optional<Filled> filled;
    };
    static Tables createTables();
    /// Sums the air into `tables` for `filled` (its altitude as the viewer's). Expects the filling state set.
    void integrate(Tables& tables, const Camera& camera, const SceneStyle& style, const Filled& filled);
    /// The frame's tables, `weight` of the way from `lower` to `upper`.
    void blend(const Tables& lower, const Tables& upper, float weight);

    ShaderProgram mAerialProgram;
    ShaderProgram mSkyProgram;
    ShaderProgram mAerialBlend;
    ShaderProgram mSkyBlend;
    Tables mFrame;       ///< what the frame reads
    Tables mLattice[2];  ///< tables at lattice altitudes, kept while the viewer stays between them
    gl::Framebuffer mFramebuffer;
    gl::VertexArray mEmptyVao;
    std::optional<Filled> mLastKey;  ///< the last update's sun, range and air (altitude 0)
    /// psi_ms, and the sun's elevation (radians) and the air it was made for.
    std::optional<MultipleScattering> mMultiple;
    double mMultipleElevation = 0.0;
    AtmosphereModel mMultipleAir;
};

}  // namespace terrain
