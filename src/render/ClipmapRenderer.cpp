// Seed 002's GPU geometry clipmap drawing (ClipmapRenderer.h).
#include "render/ClipmapRenderer.h"

#include "core/Aabb.h"
#include "core/Check.h"
#include "core/Frustum.h"
#include "render/FrameSetup.h"
#include "render/ShaderContract.h"
#include "render/TextureArrays.h"

#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <string>
#include <vector>

namespace terrain {

namespace {

/// A ring texture array: a layer per ring, toroidal addressing (a texel's neighbour across the texture's edge is
/// the next sample of the window).
TextureArrayFormat ringFormat(GLenum internalFormat, GLenum format, GLenum type, GLint filter)
{
    return {internalFormat, format, type, filter, GL_REPEAT};
}

}  // namespace

ClipmapRenderer::Mesh ClipmapRenderer::makeMesh(const std::vector<GLint>& vertices,
                                                const std::vector<std::uint32_t>& indices)
{
    Mesh m;
    m.vao = gl::VertexArray::create();
    m.vertices = gl::Buffer::create();
    m.indices = gl::Buffer::create();
    glBindVertexArray(m.vao.name());
    glBindBuffer(GL_ARRAY_BUFFER, m.vertices.name());
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(GLint)), vertices.data(),
                 GL_STATIC_DRAW);
    glEnableVertexAttribArray(contract::kGridLocation);
    glVertexAttribIPointer(contract::kGridLocation, 2, GL_INT, 0, nullptr);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.indices.name());
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)),
                 indices.data(), GL_STATIC_DRAW);
    glBindVertexArray(0);
    m.count = static_cast<GLsizei>(indices.size());
    return m;
}

Expected<std::unique_ptr<ClipmapRenderer>> ClipmapRenderer::create(const std::filesystem::path& shaderDirectory,
                                                                   const MapHeader& header, const ClipmapLayout& layout,
                                                                   const MaterialSet* materials,
                                                                   int normalTexelsPerCell,
                                                                   const LightingModel& lighting)
{
    std::unique_ptr<ClipmapRenderer> r(new ClipmapRenderer(header));
    if (materials) {
        auto layers = DetailLayers::create(*materials);
        TERRAIN_TRY(layers);
        r->mDetail = std::move(layers).value();
    }
    std::vector<std::string> defines = r->mDetail.defines();
    if (lighting.atmosphere) {
        defines.emplace_back("ATMOSPHERE");
    }
    if (normalTexelsPerCell > 0) {
        defines.emplace_back("NORMAL_MAP");
    }
    auto near = ShaderProgram::load(shaderDirectory, "clipmap", defines);
    TERRAIN_TRY(near);
    r->mPrograms.push_back(std::move(near.value()));
    if (!r->mDetail.empty()) {
        // Pieces beyond every layer's fade are drawn without the layers (as TerrainRenderer does).
        const std::vector<std::string> detail = r->mDetail.defines();
        std::erase_if(defines, [&](const std::string& d) { return std::ranges::find(detail, d) != detail.end(); });
        auto far = ShaderProgram::load(shaderDirectory, "clipmap", defines);
        TERRAIN_TRY(far);
        r->mPrograms.push_back(std::move(far.value()));
    }
    auto sky = Sky::create(shaderDirectory, lighting);
    TERRAIN_TRY(sky);
    r->mSky = std::move(sky.value());
    const int n = layout.samples();
    r->mSamples = n;
    r->mHeights = createTextureArray(ringFormat(GL_R32F, GL_RED, GL_FLOAT, GL_NEAREST), n, layout.ringCount());
    r->mMorph = createTextureArray(ringFormat(GL_RG32F, GL_RG, GL_FLOAT, GL_NEAREST), n, layout.ringCount());
    r->mColour = createTextureArray(ringFormat(GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, GL_LINEAR), n, layout.ringCount());
    r->mPreviousColour =
        createTextureArray(ringFormat(GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, GL_LINEAR), n, layout.ringCount());
    r->mSkyVisibility =
        createTextureArray(ringFormat(GL_RG8, GL_RG, GL_UNSIGNED_BYTE, GL_NEAREST), n, layout.ringCount());
    r->mTextureBytes = static_cast<std::size_t>(n) * n * layout.ringCount() * 22;
    if (!r->mDetail.empty()) {
        r->mMaterials =
            createTextureArray(ringFormat(GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, GL_LINEAR), n, layout.ringCount());
        r->mPreviousMaterials =
            createTextureArray(ringFormat(GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, GL_LINEAR), n, layout.ringCount());
        r->mTextureBytes += static_cast<std::size_t>(n) * n * layout.ringCount() * 8;
    }
    r->mNormalPerCell = normalTexelsPerCell;
    if (normalTexelsPerCell > 0) {
        const int side = normalTexelsPerCell * n;
        r->mNormals = createTextureArray(ringFormat(GL_RG8_SNORM, GL_RG, GL_BYTE, GL_LINEAR), side, layout.ringCount());
        r->mPreviousNormals =
            createTextureArray(ringFormat(GL_RG8_SNORM, GL_RG, GL_BYTE, GL_LINEAR), side, layout.ringCount());
        r->mTextureBytes += static_cast<std::size_t>(side) * side * layout.ringCount() * 4;
    }
    for (const ShaderProgram& program : r->mPrograms) {
        contract::bindSamplerUnits(program, contract::kClipmapSamplers);
        glUniform1f(program.uniform("uNormalTexelsPerCell"), static_cast<float>(normalTexelsPerCell));
        glUniform1i(program.uniform("uSamples"), n);
        if (!r->mDetail.empty()) {
            r->mDetail.setUniforms(program, contract::clipmap_units::kDetail);
        }
    }

    // The perimeter's zero-area triangles: (2k, 2k + 1, 2k + 2) along each side.
    std::vector<GLint> vertices;
    auto side = [&](int x0, int y0, int dx, int dy) {
        for (int k = 0; k + 2 < n; k += 2) {
            for (int t = 0; t < 3; ++t) {
                vertices.push_back(x0 + dx * (k + t));
                vertices.push_back(y0 + dy * (k + t));
            }
        }
    };
    side(0, 0, 1, 0);
    side(n - 1, 0, 0, 1);
    side(n - 1, n - 1, -1, 0);
    side(0, n - 1, 0, -1);
    std::vector<std::uint32_t> indices(vertices.size() / 2);
    for (std::size_t i = 0; i < indices.size(); ++i) {
        indices[i] = static_cast<std::uint32_t>(i);
    }
    r->mPerimeter = makeMesh(vertices, indices);
    return r;
}

const ClipmapRenderer::Mesh& ClipmapRenderer::footprint(std::int64_t w, std::int64_t h)
{
    auto it = mFootprints.find({w, h});
    if (it != mFootprints.end()) {
        return it->second;
    }
    std::vector<GLint> vertices;
    for (std::int64_t j = 0; j <= h; ++j) {
        for (std::int64_t i = 0; i <= w; ++i) {
            vertices.push_back(static_cast<GLint>(i));
            vertices.push_back(static_cast<GLint>(j));
        }
    }
    std::vector<std::uint32_t> indices;
    auto at = [w](std::int64_t i, std::int64_t j) { return static_cast<std::uint32_t>(j * (w + 1) + i); };
    for (std::int64_t j = 0; j < h; ++j) {
        for (std::int64_t i = 0; i < w; ++i) {
            // South-west to north-east diagonal, as the quadtree's template (quadtree/TemplateTriangulation.h).
            indices.insert(indices.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            indices.insert(indices.end(), {at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    }
    Mesh m = makeMesh(vertices, indices);
    m.triangles = static_cast<std::uint64_t>(w * h * 2);
    return mFootprints.emplace(std::pair{w, h}, std::move(m)).first->second;
}

void ClipmapRenderer::upload(const ClipmapTerrain& terrain, int ring, ClipmapStats& stats)
{
    const int n = mSamples;
    const ClipmapRing& data = terrain.ring(ring);
    // One layer's texels of lattice rectangle [x0, x1) x [y0, y1) of a toroidal side x side grid, split where
    // they wrap around the texture's edges; `texels` points at the layer's texel (0, 0).
    auto layer = [ring](const gl::Texture& texture, int side, std::int64_t x0, std::int64_t y0, std::int64_t x1,
                        std::int64_t y1, GLenum format, GLenum type, const void* texels, std::size_t texelBytes) {
        glBindTexture(GL_TEXTURE_2D_ARRAY, texture.name());
        glPixelStorei(GL_UNPACK_ROW_LENGTH, side);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        const int tx = toroidalTexel(x0, side), ty = toroidalTexel(y0, side);
        const int w = static_cast<int>(x1 - x0), h = static_cast<int>(y1 - y0);
        const int xs[2][2] = {{tx, std::min(w, side - tx)}, {0, w - std::min(w, side - tx)}};
        const int ys[2][2] = {{ty, std::min(h, side - ty)}, {0, h - std::min(h, side - ty)}};
        for (const auto& [y, rows] : ys) {
            for (const auto& [x, columns] : xs) {
                if (rows > 0 && columns > 0) {
                    const std::size_t first = (static_cast<std::size_t>(y) * side + x) * texelBytes;
                    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, x, y, ring, columns, rows, 1, format, type,
                                    static_cast<const std::uint8_t*>(texels) + first);
                }
            }
        }
    };
    TERRAIN_EXPECTS(!mMaterials || !data.materials.empty(), "with detail layers the rings keep material weights");
    TERRAIN_EXPECTS(!mNormals || terrain.normalTexelsPerCell() == mNormalPerCell,
                    "with normal maps the rings keep them at the renderer's texels a cell");
    for (const LatticeRect& rect : terrain.changed(ring)) {
        layer(mHeights, n, rect.x0, rect.y0, rect.x1, rect.y1, GL_RED, GL_FLOAT, data.heights.data(), 4);
        layer(mMorph, n, rect.x0, rect.y0, rect.x1, rect.y1, GL_RG, GL_FLOAT, data.morph.data(), 8);
        layer(mColour, n, rect.x0, rect.y0, rect.x1, rect.y1, GL_RGBA, GL_UNSIGNED_BYTE, data.colour.data(), 4);
        layer(mPreviousColour, n, rect.x0, rect.y0, rect.x1, rect.y1, GL_RGBA, GL_UNSIGNED_BYTE,
              data.previousColour.data(), 4);
        layer(mSkyVisibility, n, rect.x0, rect.y0, rect.x1, rect.y1, GL_RG, GL_UNSIGNED_BYTE, data.sky.data(), 2);
        if (mMaterials) {
            layer(mMaterials, n, rect.x0, rect.y0, rect.x1, rect.y1, GL_RGBA, GL_UNSIGNED_BYTE, data.materials.data(),
                  4);
            layer(mPreviousMaterials, n, rect.x0, rect.y0, rect.x1, rect.y1, GL_RGBA, GL_UNSIGNED_BYTE,
                  data.previousMaterials.data(), 4);
        }
        if (mNormals) {
            const int q = mNormalPerCell;
            layer(mNormals, q * n, rect.x0 * q, rect.y0 * q, rect.x1 * q, rect.y1 * q, GL_RG, GL_BYTE,
                  data.normals.data(), 2);
            layer(mPreviousNormals, q * n, rect.x0 * q, rect.y0 * q, rect.x1 * q, rect.y1 * q, GL_RG, GL_BYTE,
                  data.previousNormals.data(), 2);
        }
        stats.uploadedSamples += static_cast<std::size_t>(rect.area());
    }
    glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
}

void ClipmapRenderer::bindRingTextures() const
{
    namespace units = contract::clipmap_units;
    const std::pair<int, const gl::Texture*> bindings[] = {{units::kHeights, &mHeights},
                                                           {units::kColour, &mColour},
                                                           {units::kMaterials, &mMaterials},
                                                           {units::kNormals, &mNormals},
                                                           {units::kMorph, &mMorph},
                                                           {units::kPreviousColour, &mPreviousColour},
                                                           {units::kPreviousMaterials, &mPreviousMaterials},
                                                           {units::kPreviousNormals, &mPreviousNormals},
                                                           {units::kSkyVisibility, &mSkyVisibility}};
    for (const auto& [unit, texture] : bindings) {
        if (*texture) {
            glActiveTexture(static_cast<GLenum>(GL_TEXTURE0 + unit));
            glBindTexture(GL_TEXTURE_2D_ARRAY, texture->name());
        }
    }
    glActiveTexture(GL_TEXTURE0);
    mDetail.bind(units::kDetail);
    mSky.bindAerialTable(units::kAerialTable);
}

ClipmapStats ClipmapRenderer::draw(const ClipmapLayout& layout, const ClipmapTerrain& terrain, int firstRing,
                                   const Camera& camera, const SceneStyle& style)
{
    TERRAIN_EXPECTS(layout.samples() == mSamples && terrain.ringCount() == layout.ringCount(),
                    "the layout and terrain must be the renderer's");
    ClipmapStats stats;
    for (int ring = 0; ring < layout.ringCount(); ++ring) {
        upload(terrain, ring, stats);
    }
    beginSceneFrame(camera, style, mSky, SkyOrder::AfterTerrain);
    glDisable(GL_CULL_FACE);
    const glm::dvec4 valid = validRectangle(mHeader);
    const double vx0 = valid.x, vy0 = valid.y, vx1 = valid.z, vy1 = valid.w;
    for (const ShaderProgram& program : mPrograms) {
        setSceneUniforms(program, camera, style, mHeader);
        mSky.setSkylight(program);
        mDetail.setCameraUniforms(program, camera.position);
        glUniform1f(program.uniform("uNow"), terrain.clock());
        // A morph of no time is over at once (the shader divides by it).
        glUniform1f(program.uniform("uMorphSeconds"), static_cast<float>(std::max(terrain.morphSeconds(), 1e-6)));
    }
    bindRingTextures();
    const Frustum frustum = Frustum::fromCamera(camera);
    const double fade = mDetail.fadeDistance();
    const int n = mSamples;
    const double w = layout.transitionWidth();
    for (int ring = firstRing; ring < layout.ringCount(); ++ring) {
        const ClipmapWindow& win = layout.window(ring);
        const bool coarser = ring + 1 < layout.ringCount();
        const double s = layout.spacing(ring);
        const double x0 = layout.worldX(ring, static_cast<double>(win.x0));
        const double y0 = layout.worldY(ring, static_cast<double>(win.y0));
        for (std::size_t p = 0; p < mPrograms.size(); ++p) {
            const ShaderProgram& program = mPrograms[p];
            program.use();
            glUniform1i(program.uniform("uRing"), ring);
            glUniform1i(program.uniform("uHasCoarser"), coarser ? 1 : 0);
            glUniform2i(program.uniform("uWindowTexel"), toroidalTexel(win.x0, n), toroidalTexel(win.y0, n));
            if (coarser) {
                const ClipmapWindow& up = layout.window(ring + 1);
                glUniform2i(program.uniform("uCoarseTexel"), toroidalTexel(up.x0, n), toroidalTexel(up.y0, n));
                glUniform2i(program.uniform("uCoarseOffset"), static_cast<GLint>(win.x0 / 2 - up.x0),
                            static_cast<GLint>(win.y0 / 2 - up.y0));
            }
            glUniform2f(program.uniform("uWindowOffset"), static_cast<float>(x0 - camera.position.x),
                        static_cast<float>(y0 - camera.position.y));
            glUniform1f(program.uniform("uSpacing"), static_cast<float>(s));
            glUniform2f(program.uniform("uViewer"), static_cast<float>((camera.position.x - x0) / s),
                        static_cast<float>((camera.position.y - y0) / s));
            glUniform1f(program.uniform("uBlendStart"), static_cast<float>((n - 1) / 2.0 - w - 1.0));
            glUniform1f(program.uniform("uBlendWidth"), static_cast<float>(w));
            if (p == kNear && !mDetail.empty()) {
                // Each layer's coordinates at the window origin, reduced to [0, 1) in double.
                for (int k = 0; k < mDetail.count(); ++k) {
                    const glm::vec4 origin = mDetail.origin(k, {x0, y0});
                    glUniform4fv(program.uniform(("uLayerOrigin[" + std::to_string(k) + "]").c_str()), 1,
                                 glm::value_ptr(origin));
                }
            }
        }
        // The ring's heights, with the coarser ring's it may blend to.
        const ClipmapRing& data = terrain.ring(ring);
        double zLo = data.zMin, zHi = data.zMax;
        if (coarser) {
            zLo = std::min<double>(zLo, terrain.ring(ring + 1).zMin);
            zHi = std::max<double>(zHi, terrain.ring(ring + 1).zMax);
        }
        // Pieces of the ring the finer ring drawn does not cover (the finest drawn ring: all of its window).
        std::vector<ClipmapPiece> pieces = layout.pieces(ring);
        if (ring == firstRing && ring > 0) {
            // The rings below firstRing are not drawn: fill the hole with this ring's own cells.
            const LatticeRect hole = layout.hole(ring);
            pieces.push_back({ClipmapPieceKind::kBlock, hole});
        }
        bool drewRing = false;
        for (const ClipmapPiece& piece : pieces) {
            Aabb box;
            box.lo = {x0 + static_cast<double>(piece.cells.x0) * s, y0 + static_cast<double>(piece.cells.y0) * s,
                      mHeader.heightOffset + zLo};
            box.hi = {x0 + static_cast<double>(piece.cells.x1) * s, y0 + static_cast<double>(piece.cells.y1) * s,
                      mHeader.heightOffset + zHi};
            const bool outside = box.hi.x < vx0 || box.lo.x > vx1 || box.hi.y < vy0 || box.lo.y > vy1;
            if (outside || !frustum.intersects(box)) {
                ++stats.culledPieces;
                continue;
            }
            const Mesh& mesh = footprint(piece.cells.x1 - piece.cells.x0, piece.cells.y1 - piece.cells.y0);
            // The detail layers' program where any of the piece lies within their fade.
            const glm::dvec3 nearest = glm::clamp(camera.position, box.lo, box.hi);
            const bool near = glm::distance(nearest, camera.position) < fade;
            const ShaderProgram& program = mPrograms[near || mPrograms.size() == 1 ? kNear : kFar];
            program.use();
            glUniform2i(program.uniform("uPieceOrigin"), static_cast<GLint>(piece.cells.x0),
                        static_cast<GLint>(piece.cells.y0));
            glBindVertexArray(mesh.vao.name());
            glDrawElements(GL_TRIANGLES, mesh.count, GL_UNSIGNED_INT, nullptr);
            stats.triangles += mesh.triangles;
            ++stats.pieces;
            drewRing = true;
        }
        if (drewRing && coarser) {
            // Zero-area triangles: any program draws them.
            const ShaderProgram& program = mPrograms[mPrograms.size() - 1];
            program.use();
            glUniform2i(program.uniform("uPieceOrigin"), 0, 0);
            glBindVertexArray(mPerimeter.vao.name());
            glDrawElements(GL_TRIANGLES, mPerimeter.count, GL_UNSIGNED_INT, nullptr);
        }
        stats.rings += drewRing ? 1 : 0;
    }
    glBindVertexArray(0);
    endSceneFrame(camera, style, mSky, SkyOrder::AfterTerrain);
    return stats;
}

}  // namespace terrain
