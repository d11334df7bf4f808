// The sky behind the terrain (shaders/sky.vert, sky.frag): one full-screen triangle shaded from the haze
// colour at the horizon to the zenith colour, with the sun; with the atmosphere, read from the frame's sky table,
// and the owner of the frame's air tables (AtmosphereTextures) the terrain reads too. Both renderers draw it first (the
// quadtree's TerrainRenderer and the clipmap's ClipmapRenderer), with depth writes off.
#pragma once

#include "core/Camera.h"
#include "core/Expected.h"
#include "light/Atmosphere.h"
#include "render/AtmosphereTextures.h"
#include "render/GlObjects.h"
#include "render/ShaderProgram.h"

#include <glm/vec3.hpp>

#include <filesystem>
#include <optional>

namespace terrain {

/// How the scene looks (config options draw_sky, sun_*, haze_distance, clear_color, wireframe).
struct SceneStyle {
    glm::vec3 sunDirection{0.5f, -0.5f, 0.7f};  ///< towards the sun; normalised by the renderer
    glm::vec3 sunColour{1.0f, 0.95f, 0.85f};
    glm::vec3 ambient{0.35f, 0.4f, 0.5f};
    glm::vec3 hazeColour{0.68f, 0.76f, 0.86f};
    glm::vec3 zenithColour{0.25f, 0.45f, 0.8f};
    glm::vec3 clearColour{0.68f, 0.76f, 0.86f};
    float hazeDistance = 60000.0f;  ///< metres
    bool drawSky = true;
    bool wireframe = false;
    bool geomorph = true;  ///< false: every node at its own detail, morph factor 1 (shows popping)
    /// LightingModel::atmosphere: the air's constants, and the exposure the tone map applies to radiance (relative
    /// to the sun's irradiance above the air).
    AtmosphereModel air;
    float exposure = 5.0f;
};

/// How the scene is lit, fixed when the renderers are made (it picks their programs' variant).
struct LightingModel {
    /// A physically based sky and air (light/Atmosphere.h, shaders/atmosphere.glsl: sunlight and skylight through
    /// the air, aerial perspective, HDR and a filmic tone map); false: the gradient sky, ambient light and
    /// exponential haze.
    bool atmosphere = false;
};

class Sky {
public:
    Sky() = default;
    /// Loads the sky program from `shaderDirectory`, the variant of `lighting`. Needs a current GL context.
    static Expected<Sky> create(const std::filesystem::path& shaderDirectory, const LightingModel& lighting = {});
    /// With the atmosphere: brings the frame's air tables up to `camera` and `style` (AtmosphereTextures::update).
    /// Before draw and before the terrain is drawn.
    void prepare(const Camera& camera, const SceneStyle& style);
    /// Draws the sky for `camera` at the far plane: where the depth buffer holds its clear value (1), so after the
    /// terrain only the pixels the terrain left. Leaves depth testing on (less) and depth writes on.
    void draw(const Camera& camera, const SceneStyle& style) const;
    /// With the atmosphere: binds the aerial table the terrain's programs read (uAerialTable) to unit `unit`.
    void bindAerialTable(int unit) const;
    /// With the atmosphere, after prepare: sets the sky's irradiance on the ground for the frame's sun (and psi_ms)
    /// on terrain program `program`, which must be in use (setMultipleScatteringUniforms).
    void setSkylight(const ShaderProgram& program) const;

private:
    ShaderProgram mProgram;
    std::optional<AtmosphereTextures> mTables;  ///< with the atmosphere
    gl::VertexArray mEmptyVao;                  ///< the full-screen triangle needs no attributes
};

}  // namespace terrain
