// The materials' detail textures (paper 3.4.5) on the GPU, shared by both LOD modes' renderers: gray textures in
// one array, material m's k-th detail_texture repeating every detail_texture_size / 4^k metres (a finer layer of
// the same ground), multiplied over the terrain's colour by the material weights (shaders/detail.glsl). Each
// texture is made Gaussian when loaded (synthesis/DetailTexture.h, gaussianized) and sampled by
// histogram-preserving tiling on a triangle lattice (kLatticeFromRepeats), so it shows no tile; each fades out
// by kFadeRepeats of its repeats from the viewer.
#pragma once

#include "core/Expected.h"
#include "render/GlObjects.h"
#include "render/ShaderProgram.h"
#include "synthesis/Material.h"

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <vector>

namespace terrain {

class DetailLayers {
public:
    /// At most this many layers in all (shaders/detail.glsl, kMaxLayers).
    static constexpr int kMaxLayers = 8;
    /// Repeats of a layer beyond which the fragment program has faded it out (shaders/detail.glsl).
    static constexpr double kFadeRepeats = 40.0;

    /// Loads every material's detail textures (all of one size; at most kMaxLayers; at most 4 materials) into a
    /// texture array. Errors name the file. Materials without detail textures give no layers (empty()).
    static Expected<DetailLayers> create(const MaterialSet& materials);

    bool empty() const { return mSizes.empty(); }
    int count() const { return static_cast<int>(mSizes.size()); }
    /// Metres per repeat of each layer.
    const std::vector<double>& sizes() const { return mSizes; }
    /// Metres from the viewer beyond which every layer has faded out (drawn without the layers).
    double fadeDistance() const;
    /// The shader defines of a program drawing the layers: DETAIL and LAYER_COUNT (none when empty()).
    std::vector<std::string> defines() const;

    /// Sets `program`'s uniforms for the layers (uDetail on texture unit `unit`, masks, scales, means, lattice).
    void setUniforms(const ShaderProgram& program, int unit) const;
    /// Binds the texture array to texture unit `unit`.
    void bind(int unit) const;
    /// Layer k's coordinates at world point `corner` (metres), reduced in double: xy its texture coordinates
    /// modulo 1, zw its lattice coordinates modulo the lattice's period (4096 vertices). Programs add local
    /// metres times the layer's scale to them, so coordinates stay small and exact however far from the origin
    /// the point is, and nodes side by side agree on every lattice vertex.
    glm::vec4 origin(int k, glm::dvec2 corner) const;
    /// Sets `program`'s (in use) per-frame uniforms: uCliffOrigin, each layer's origin() at the camera `camera` on
    /// the vertical planes x-z and y-z, which the cliffs' projections count from (shaders/detail.glsl).
    void setCameraUniforms(const ShaderProgram& program, const glm::dvec3& camera) const;

private:
    gl::Texture mTexture;
    std::vector<double> mSizes;
    std::vector<int> mMaterial;  ///< the material each layer belongs to
    std::vector<double> mMeans;  ///< each layer's mean gray, in [0, 1]
};

}  // namespace terrain
