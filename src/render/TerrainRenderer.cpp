// Drawing the selected chunks: template mesh (3.2.9, eq. 3.7), geomorphing (3.2.8, eq. 3.4-3.6), skirts
// (3.2.6), zigzag index buffer (3.2.10), front to back (3.2.11).
#include "render/TerrainRenderer.h"

#include "heightfield/Image.h"
#include "render/NodeVertexData.h"
#include "render/TemplateMesh.h"
#include "render/ZigzagIndexBuffer.h"

#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <cmath>

namespace terrain {

namespace {

struct DetailLayer {
    Image image;
    int material = 0;
    double size = 1.0;  ///< metres per repeat
};

Expected<std::vector<DetailLayer>> loadDetailLayers(const MaterialSet& materials, int maxLayers)
{
    std::vector<DetailLayer> layers;
    for (std::size_t m = 0; m < materials.materials().size(); ++m) {
        const Material& material = materials.materials()[m];
        double size = material.detailTextureSize;
        for (const auto& file : material.detailTextures) {
            if (static_cast<int>(layers.size()) == maxLayers) {
                return makeError(material.file, ": too many detail textures (the materials may have ", maxLayers,
                                 " in all)");
            }
            auto image = readPngImage(file, 1);
            TERRAIN_TRY(image);
            if (!layers.empty() &&
                (image->width != layers.front().image.width || image->height != layers.front().image.height)) {
                return makeError(file.string(), ": detail texture is ", image->width, "x", image->height,
                                 " but the first one is ", layers.front().image.width, "x", layers.front().image.height,
                                 " (all detail textures share one size)");
            }
            layers.push_back({std::move(image).value(), static_cast<int>(m), size});
            size /= 4.0;
        }
    }
    return layers;
}

}  // namespace

Expected<std::unique_ptr<TerrainRenderer>> TerrainRenderer::create(const std::filesystem::path& shaderDirectory,
                                                                   const MapHeader& header, int vertexCacheSize,
                                                                   const MaterialSet* materials)
{
    std::unique_ptr<TerrainRenderer> r(new TerrainRenderer(header));
    std::vector<DetailLayer> layers;
    if (materials) {
        TERRAIN_EXPECTS(materials->materials().size() <= 4, "at most 4 materials");
        auto loaded = loadDetailLayers(*materials, kMaxDetailLayers);
        TERRAIN_TRY(loaded);
        layers = std::move(loaded).value();
    }
    const bool padded = header.validWidth < header.gridSize() || header.validHeight < header.gridSize();
    std::vector<std::string> defines;
    if (padded) {
        defines.emplace_back("CLIP_TO_VALID");
    }
    if (!layers.empty()) {
        defines.emplace_back("DETAIL");
        defines.emplace_back("LAYER_COUNT " + std::to_string(layers.size()));
    }
    auto terrain = ShaderProgram::load(shaderDirectory, "terrain", defines);
    TERRAIN_TRY(terrain);
    r->mPrograms.push_back(std::move(terrain.value()));
    if (!layers.empty()) {
        // Nodes beyond every layer's fade get the variant without the detail texture loop: on llvmpipe
        // the loop cost a 1280 x 720 frame of the demo about 180 ms even where it ran no iteration.
        defines.emplace_back("DETAIL_TINT_ONLY");
        auto far = ShaderProgram::load(shaderDirectory, "terrain", defines);
        TERRAIN_TRY(far);
        r->mPrograms.push_back(std::move(far.value()));
    }
    if (!layers.empty()) {
        const int w = layers.front().image.width, h = layers.front().image.height;
        r->mDetail = gl::Texture::create();
        glBindTexture(GL_TEXTURE_2D_ARRAY, r->mDetail.name());
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_R8, w, h, static_cast<GLsizei>(layers.size()), 0, GL_RED,
                     GL_UNSIGNED_BYTE, nullptr);
        for (std::size_t k = 0; k < layers.size(); ++k) {
            glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, static_cast<GLint>(k), w, h, 1, GL_RED, GL_UNSIGNED_BYTE,
                            layers[k].image.pixels.data());
        }
        glGenerateMipmap(GL_TEXTURE_2D_ARRAY);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_REPEAT);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_REPEAT);
        for (const DetailLayer& layer : layers) {
            r->mLayerSize.push_back(layer.size);
        }
        for (ShaderProgram& terrainProgram : r->mPrograms) {
            terrainProgram.use();
            glUniform1i(terrainProgram.uniform("uDetail"), 2);
            for (std::size_t k = 0; k < layers.size(); ++k) {
                std::string index = "[";
                index += std::to_string(k);
                index += ']';
                glm::vec4 mask(0.0f);
                mask[layers[k].material] = 1.0f;
                glUniform4fv(terrainProgram.uniform(("uLayerMaterialMask" + index).c_str()), 1, glm::value_ptr(mask));
                glUniform1f(terrainProgram.uniform(("uLayerScale" + index).c_str()),
                            static_cast<float>(1.0 / layers[k].size));
            }
            glm::vec4 tintColumns[3] = {glm::vec4(1.0f), glm::vec4(1.0f), glm::vec4(1.0f)};
            for (std::size_t m = 0; m < materials->materials().size(); ++m) {
                const auto& t = materials->materials()[m].tint;
                glm::vec3 tint(t[0], t[1], t[2]);
                const float luminance = glm::dot(tint, glm::vec3(0.2126f, 0.7152f, 0.0722f));
                tint = luminance > 0.0f ? tint / luminance : glm::vec3(1.0f);
                // A third of the tint: the map's colours (from -t or prep's height colouring) stay the base and
                // the material only shifts them, so a grass tint does not paint a dry valley green.
                constexpr float kTintStrength = 0.35f;
                tint = glm::mix(glm::vec3(1.0f), tint, kTintStrength);
                for (int c = 0; c < 3; ++c) {
                    tintColumns[c][static_cast<int>(m)] = tint[c];
                }
            }
            glUniform4fv(terrainProgram.uniform("uMaterialTintColumns"), 3, glm::value_ptr(tintColumns[0]));
        }
    }
    // Per-node uniform locations of each variant, and the layer that fades out last.
    for (ShaderProgram& program : r->mPrograms) {
        NodeUniforms l{program.uniform("uOrigin"),     program.uniform("uSpacing"),      program.uniform("uMorph"),
                       program.uniform("uSkirtDepth"), program.uniform("uParentOffset"), {}};
        for (std::size_t k = 0; k < r->mLayerSize.size(); ++k) {
            l.layerOrigin.push_back(program.uniform(("uLayerOrigin[" + std::to_string(k) + "]").c_str()));
        }
        r->mLocations.push_back(std::move(l));
    }
    if (!r->mLayerSize.empty()) {
        r->mCoarsestLayer = *std::max_element(r->mLayerSize.begin(), r->mLayerSize.end());
    }
    auto sky = ShaderProgram::load(shaderDirectory, "sky");
    TERRAIN_TRY(sky);
    r->mSky = std::move(sky.value());

    const int n = static_cast<int>(header.chunkSize);
    r->mMesh = buildTemplateMesh(n);
    const TemplateMesh& mesh = r->mMesh;
    const std::vector<std::uint32_t> indices = buildZigzagIndices(n, vertexCacheSize, /*withSkirts=*/true);
    r->mTrianglesPerNode = indices.size() / 3;
    r->mIndexCount = static_cast<GLsizei>(indices.size());
    const bool narrow = indexTypeFor(mesh.vertices.size()) == IndexType::kUint16;
    r->mIndexType = narrow ? GL_UNSIGNED_SHORT : GL_UNSIGNED_INT;

    r->mTemplateVao = gl::VertexArray::create();
    r->mTemplateVertices = gl::Buffer::create();
    r->mTemplateIndices = gl::Buffer::create();
    glBindVertexArray(r->mTemplateVao.name());
    glBindBuffer(GL_ARRAY_BUFFER, r->mTemplateVertices.name());
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(mesh.vertices.size() * sizeof(TemplateVertex)),
                 mesh.vertices.data(), GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribIPointer(0, 2, GL_UNSIGNED_SHORT, sizeof(TemplateVertex),
                           reinterpret_cast<const void*>(offsetof(TemplateVertex, i)));
    glEnableVertexAttribArray(1);
    glVertexAttribIPointer(1, 1, GL_UNSIGNED_BYTE, sizeof(TemplateVertex),
                           reinterpret_cast<const void*>(offsetof(TemplateVertex, skirt)));
    glEnableVertexAttribArray(2);  // the node's data: pointed at each node's buffer when it is drawn
    glEnableVertexAttribArray(3);
    glEnableVertexAttribArray(4);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, r->mTemplateIndices.name());
    if (narrow) {
        const std::vector<std::uint16_t> shortIndices = narrowIndices(indices);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(shortIndices.size() * sizeof(std::uint16_t)),
                     shortIndices.data(), GL_STATIC_DRAW);
    } else {
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)),
                     indices.data(), GL_STATIC_DRAW);
    }
    glBindVertexArray(0);
    r->mEmptyVao = gl::VertexArray::create();
    return r;
}

TerrainRenderer::GpuNode& TerrainRenderer::upload(const NodePtr& node, RenderStats& stats)
{
    auto [it, inserted] = mGpuNodes.try_emplace(node->id.key());
    GpuNode& gpu = it->second;
    if (!inserted && gpu.data == node) {
        gpu.lastFrame = mFrame;
        return gpu;
    }
    // New, or the cache holds a different copy of this node now (evicted and loaded again).
    gpu.data = node;
    gpu.lastFrame = mFrame;
    const int t = static_cast<int>(mHeader.textureSize);
    std::vector<float> surface(node->heights.base.size());
    node->heights.surface(surface);
    const std::vector<NodeVertex> vertices = buildNodeVertices(mMesh, surface, node->spacing, node->materialWeights);
    gpu.vertices = gl::Buffer::create();
    glBindBuffer(GL_ARRAY_BUFFER, gpu.vertices.name());
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(NodeVertex)), vertices.data(),
                 GL_STATIC_DRAW);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    gpu.colour = gl::Texture::create();
    glBindTexture(GL_TEXTURE_2D, gpu.colour.name());
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, t, t, 0, GL_RGB, GL_UNSIGNED_BYTE, node->texture.data());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    ++stats.uploads;
    return gpu;
}

void TerrainRenderer::releaseEvicted(const TerrainStreamer& streamer)
{
    for (auto it = mGpuNodes.begin(); it != mGpuNodes.end();) {
        const GpuNode& gpu = it->second;
        if (gpu.lastFrame != mFrame && streamer.node(gpu.data->id) != gpu.data) {
            it = mGpuNodes.erase(it);  // no longer in the cache: free its textures
        } else {
            ++it;
        }
    }
}

void TerrainRenderer::drawSky(const Camera& camera, const SceneStyle& style)
{
    const glm::mat4 viewProjection(camera.projection() * camera.viewRotation());
    const glm::mat4 inverse = glm::inverse(viewProjection);
    mSky.use();
    glUniformMatrix4fv(mSky.uniform("uInverseViewProjection"), 1, GL_FALSE, glm::value_ptr(inverse));
    glUniform3fv(mSky.uniform("uHazeColour"), 1, glm::value_ptr(style.hazeColour));
    glUniform3fv(mSky.uniform("uZenithColour"), 1, glm::value_ptr(style.zenithColour));
    const glm::vec3 sun = glm::normalize(style.sunDirection);
    glUniform3fv(mSky.uniform("uSunDirection"), 1, glm::value_ptr(sun));
    glUniform3fv(mSky.uniform("uSunColour"), 1, glm::value_ptr(style.sunColour));
    glDepthMask(GL_FALSE);
    glDisable(GL_DEPTH_TEST);
    glBindVertexArray(mEmptyVao.name());
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDepthMask(GL_TRUE);
}

RenderStats TerrainRenderer::draw(const TerrainStreamer& streamer, const Camera& camera, const SceneStyle& style)
{
    ++mFrame;
    RenderStats stats;
    glViewport(0, 0, camera.viewportWidth, camera.viewportHeight);
    glClearColor(style.clearColour.r, style.clearColour.g, style.clearColour.b, 1.0f);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (style.drawSky) {
        drawSky(camera, style);
    }

    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
    glPolygonMode(GL_FRONT_AND_BACK, style.wireframe ? GL_LINE : GL_FILL);

    const glm::mat4 viewProjection(camera.projection() * camera.viewRotation());
    if (!mLayerSize.empty()) {
        glActiveTexture(GL_TEXTURE2);
        glBindTexture(GL_TEXTURE_2D_ARRAY, mDetail.name());
    }
    for (ShaderProgram& program : mPrograms) {
        program.use();
        glUniformMatrix4fv(program.uniform("uViewProjection"), 1, GL_FALSE, glm::value_ptr(viewProjection));
        glUniform1i(program.uniform("uColour"), 0);
        glUniform1i(program.uniform("uParentColour"), 1);
        glUniform1f(program.uniform("uHeightBase"), static_cast<float>(mHeader.heightOffset - camera.position.z));
        glUniform1f(program.uniform("uInverseCells"), 1.0f / static_cast<float>(mHeader.chunkSize - 1));
        glUniform1f(program.uniform("uTexels"), static_cast<float>(mHeader.textureSize));
        const glm::vec3 sun = glm::normalize(style.sunDirection);
        glUniform3fv(program.uniform("uSunDirection"), 1, glm::value_ptr(sun));
        glUniform3fv(program.uniform("uSunColour"), 1, glm::value_ptr(style.sunColour));
        glUniform3fv(program.uniform("uAmbient"), 1, glm::value_ptr(style.ambient));
        glUniform3fv(program.uniform("uHazeColour"), 1, glm::value_ptr(style.hazeColour));
        glUniform1f(program.uniform("uHazeDistance"), style.hazeDistance);
        glUniform1i(program.uniform("uWireframe"), style.wireframe ? 1 : 0);
        // The input's samples, camera-relative (prep's padding is left out).
        const double s = mHeader.sampleSpacing;
        const glm::dvec4 valid{mHeader.originX + mHeader.validX0 * s - camera.position.x,
                               mHeader.originY + mHeader.validY0 * s - camera.position.y,
                               mHeader.originX + (mHeader.validX0 + mHeader.validWidth - 1.0) * s - camera.position.x,
                               mHeader.originY + (mHeader.validY0 + mHeader.validHeight - 1.0) * s - camera.position.y};
        const double slack = 1e-3 * s;  // keep fragments exactly on the last sample
        glUniform4f(program.uniform("uValidRect"), static_cast<float>(valid.x - slack),
                    static_cast<float>(valid.y - slack), static_cast<float>(valid.z + slack),
                    static_cast<float>(valid.w + slack));
    }
    glBindVertexArray(mTemplateVao.name());
    std::size_t current = mPrograms.size();
    for (const SelectedNode& selected : streamer.selection().nodes) {
        NodePtr node = streamer.node(selected.id);
        if (!node) {
            continue;  // cannot happen: selected nodes are resident
        }
        GpuNode& gpu = upload(node, stats);
        // The parent's texture for textural morphing (eq. 3.6); the root morphs to itself.
        NodePtr parent = selected.id.isRoot() ? node : streamer.node(selected.id.parent());
        GpuNode& parentGpu = parent ? upload(parent, stats) : gpu;
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, gpu.colour.name());
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D, parentGpu.colour.name());
        glBindBuffer(GL_ARRAY_BUFFER, gpu.vertices.name());
        glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, sizeof(NodeVertex),
                              reinterpret_cast<const void*>(offsetof(NodeVertex, own)));
        glVertexAttribPointer(3, 4, GL_SHORT, GL_TRUE, sizeof(NodeVertex),
                              reinterpret_cast<const void*>(offsetof(NodeVertex, ownNormal)));
        glVertexAttribPointer(4, 4, GL_UNSIGNED_BYTE, GL_TRUE, sizeof(NodeVertex),
                              reinterpret_cast<const void*>(offsetof(NodeVertex, materialWeights)));
        // The fragment shader fades each layer out by 40 repeats away (shaders/terrain.frag): a node wholly
        // beyond that for every layer (the coarsest fades last) is drawn by the variant without the layers.
        const std::size_t variant =
            mPrograms.size() > 1 && selected.distance >= kDetailFadeRepeats * mCoarsestLayer ? kFar : kNear;
        if (variant != current) {
            mPrograms[variant].use();
            current = variant;
        }
        const NodeUniforms& at = mLocations[variant];
        if (variant == kNear && !mLayerSize.empty()) {
            // The node's corner in repeats of each layer, reduced to [0, 1) in double: texture coordinates
            // stay small and exact however far from the origin the node is.
            const glm::dvec2 corner = glm::dvec2(selected.cameraRelativeOrigin) + glm::dvec2(camera.position);
            for (std::size_t k = 0; k < mLayerSize.size(); ++k) {
                const glm::dvec2 repeats = corner / mLayerSize[k];
                const glm::dvec2 fraction = repeats - glm::floor(repeats);
                glUniform2f(at.layerOrigin[k], static_cast<float>(fraction.x), static_cast<float>(fraction.y));
            }
        }

        glUniform2f(at.origin, static_cast<float>(selected.cameraRelativeOrigin.x),
                    static_cast<float>(selected.cameraRelativeOrigin.y));
        glUniform1f(at.spacing, static_cast<float>(selected.size / (mHeader.chunkSize - 1)));
        glUniform1f(at.morph, selected.id.isRoot() || !style.geomorph ? 1.0f : selected.morph);
        // Skirts hang the parent's delta_c deep: a leaf's own delta_c is zero, yet it can meet a coarser
        // neighbour whose edge lies up to that far away (3.2.6).
        const float skirt = parent ? std::max(parent->deltaC, node->deltaC) : node->deltaC;
        glUniform1f(at.skirt, skirt + static_cast<float>(mHeader.heightStep));
        glUniform2f(at.parentOffset, (selected.id.x & 1) ? 0.5f : 0.0f, (selected.id.y & 1) ? 0.5f : 0.0f);
        glDrawElements(GL_TRIANGLES, mIndexCount, mIndexType, nullptr);

        ++stats.nodes;
        (node->isStatic ? stats.staticNodes : stats.dynamicNodes) += 1;
        stats.triangles += mTrianglesPerNode;
    }
    glBindVertexArray(0);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    releaseEvicted(streamer);
    stats.gpuNodes = mGpuNodes.size();
    return stats;
}

}  // namespace terrain
