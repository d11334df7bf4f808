// Detail texture layers of the materials (DetailLayers.h).
#include "render/DetailLayers.h"

#include "core/Check.h"
#include "heightfield/Image.h"
#include "synthesis/DetailTexture.h"

#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace terrain {

namespace {

/// Repeats to the coordinates of the tiling's triangle lattice (shaders/detail.glsl, uLatticeFromRepeats):
/// equilateral triangles skewed onto the integer lattice, 2 sqrt 3 to a repeat (Heitz & Neyret 2018's
/// TriangleGrid: each triangle spans about a third of the texture, so the blend keeps its features).
const glm::dmat2 kLatticeFromRepeats =
    2.0 * std::sqrt(3.0) * glm::dmat2(1.0, 0.0, -1.0 / std::sqrt(3.0), 2.0 / std::sqrt(3.0));
/// Lattice vertices count modulo this (shaders/detail.glsl, latticeOffset).
constexpr double kLatticePeriod = 4096.0;

}  // namespace

Expected<DetailLayers> DetailLayers::create(const MaterialSet& materials)
{
    TERRAIN_EXPECTS(materials.materials().size() <= 4, "at most 4 materials");
    DetailLayers d;
    std::vector<Image> images;
    for (std::size_t m = 0; m < materials.materials().size(); ++m) {
        const Material& material = materials.materials()[m];
        double size = material.detailTextureSize;
        for (const auto& file : material.detailTextures) {
            if (static_cast<int>(images.size()) == kMaxLayers) {
                return makeError(material.file, ": too many detail textures (the materials may have ", kMaxLayers,
                                 " in all)");
            }
            auto image = readPngImage(file, 1);
            TERRAIN_TRY(image);
            if (!images.empty() && (image->width != images.front().width || image->height != images.front().height)) {
                return makeError(file.string(), ": detail texture is ", image->width, "x", image->height,
                                 " but the first one is ", images.front().width, "x", images.front().height,
                                 " (all detail textures share one size)");
            }
            images.push_back(gaussianized(image.value()));
            d.mMeans.push_back(meanGray(images.back()));
            d.mSizes.push_back(size);
            d.mMaterial.push_back(static_cast<int>(m));
            size /= 4.0;
        }
    }
    if (images.empty()) {
        return d;
    }
    const int w = images.front().width, h = images.front().height;
    d.mTexture = gl::Texture::create();
    glBindTexture(GL_TEXTURE_2D_ARRAY, d.mTexture.name());
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_R8, w, h, static_cast<GLsizei>(images.size()), 0, GL_RED, GL_UNSIGNED_BYTE,
                 nullptr);
    for (std::size_t k = 0; k < images.size(); ++k) {
        glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, static_cast<GLint>(k), w, h, 1, GL_RED, GL_UNSIGNED_BYTE,
                        images[k].pixels.data());
    }
    glGenerateMipmap(GL_TEXTURE_2D_ARRAY);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_REPEAT);
    return d;
}

double DetailLayers::fadeDistance() const
{
    return empty() ? 0.0 : kFadeRepeats * *std::max_element(mSizes.begin(), mSizes.end());
}

std::vector<std::string> DetailLayers::defines() const
{
    if (empty()) {
        return {};
    }
    return {"DETAIL", "LAYER_COUNT " + std::to_string(mSizes.size())};
}

void DetailLayers::setUniforms(const ShaderProgram& program, int unit) const
{
    program.use();
    glUniform1i(program.uniform("uDetail"), unit);
    for (std::size_t k = 0; k < mSizes.size(); ++k) {
        const std::string index = "[" + std::to_string(k) + "]";
        glm::vec4 mask(0.0f);
        mask[mMaterial[k]] = 1.0f;
        glUniform4fv(program.uniform(("uLayerMaterialMask" + index).c_str()), 1, glm::value_ptr(mask));
        glUniform1f(program.uniform(("uLayerScale" + index).c_str()), static_cast<float>(1.0 / mSizes[k]));
        glUniform1f(program.uniform(("uLayerMean" + index).c_str()), static_cast<float>(mMeans[k]));
    }
    const glm::mat2 lattice(kLatticeFromRepeats);
    glUniformMatrix2fv(program.uniform("uLatticeFromRepeats"), 1, GL_FALSE, glm::value_ptr(lattice));
}

void DetailLayers::bind(int unit) const
{
    if (mTexture) {
        glActiveTexture(static_cast<GLenum>(GL_TEXTURE0 + unit));
        glBindTexture(GL_TEXTURE_2D_ARRAY, mTexture.name());
        glActiveTexture(GL_TEXTURE0);
    }
}

void DetailLayers::setCameraUniforms(const ShaderProgram& program, const glm::dvec3& camera) const
{
    if (empty()) {
        return;
    }
    std::vector<glm::vec4> origins;
    for (int k = 0; k < count(); ++k) {
        origins.push_back(origin(k, {camera.x, camera.z}));
        origins.push_back(origin(k, {camera.y, camera.z}));
    }
    glUniform4fv(program.uniform("uCliffOrigin"), static_cast<GLsizei>(origins.size()), glm::value_ptr(origins[0]));
}

glm::vec4 DetailLayers::origin(int k, glm::dvec2 corner) const
{
    const glm::dvec2 repeats = corner / mSizes[static_cast<std::size_t>(k)];
    const glm::dvec2 fraction = repeats - glm::floor(repeats);
    const glm::dvec2 lattice = kLatticeFromRepeats * repeats;
    const glm::dvec2 reduced = lattice - kLatticePeriod * glm::floor(lattice / kLatticePeriod);
    return {static_cast<float>(fraction.x), static_cast<float>(fraction.y), static_cast<float>(reduced.x),
            static_cast<float>(reduced.y)};
}

}  // namespace terrain
