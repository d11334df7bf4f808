// Drawing the selected chunks: template mesh (3.2.9, eq. 3.7), geomorphing (3.2.8, eq. 3.4-3.6), skirts
// (3.2.6), zigzag index buffer (3.2.10), front to back (3.2.11), node data in pools (4.2.3).
#include "render/TerrainRenderer.h"

#include "heightfield/Image.h"
#include "lod/NodeTextures.h"
#include "lod/TessellationLevels.h"
#include "quadtree/ChunkGeometry.h"
#include "render/ShaderContract.h"
#include "render/TemplateMesh.h"
#include "render/ZigzagIndexBuffer.h"

#include <glm/gtc/type_ptr.hpp>
#include <glm/mat2x2.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>

namespace terrain {

namespace {

/// A texture array of `layers` layers of size x size texels, one mip level, uninitialised, left bound to
/// GL_TEXTURE_2D_ARRAY: one of the node pools.
gl::Texture createLayers(GLenum internalFormat, int size, GLsizei layers, GLenum format, GLenum type, GLint filter)
{
    gl::Texture texture = gl::Texture::create();
    glBindTexture(GL_TEXTURE_2D_ARRAY, texture.name());
    glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, static_cast<GLint>(internalFormat), size, size, layers, 0, format, type,
                 nullptr);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAX_LEVEL, 0);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, filter);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, filter);
    return texture;
}

/// Points the per-instance attributes contract::kNodeLocation .. + texels - 1 of the bound vertex array at
/// `buffer`'s node constants (a NodeInstance, then a layer origin per detail layer: `texels` vec4s a node),
/// starting at node `first`.
void pointNodeConstants(const gl::Buffer& buffer, int texels, std::size_t first)
{
    const auto stride = static_cast<GLsizei>(texels * 4 * sizeof(float));
    glBindBuffer(GL_ARRAY_BUFFER, buffer.name());
    for (int k = 0; k < texels; ++k) {
        const std::size_t offset =
            (first * static_cast<std::size_t>(texels) + static_cast<std::size_t>(k)) * 4 * sizeof(float);
        glVertexAttribPointer(static_cast<GLuint>(contract::kNodeLocation + k), 4, GL_FLOAT, GL_FALSE, stride,
                              reinterpret_cast<const void*>(offset));
    }
    glBindBuffer(GL_ARRAY_BUFFER, 0);
}

/// Enables the node constants as per-instance attributes of the bound vertex array (terrain.vert and
/// terrain_tess.vert: locations contract::kNodeLocation ..), from the first node on.
void enableNodeConstants(const gl::Buffer& buffer, int texels)
{
    for (int k = 0; k < texels; ++k) {
        const auto location = static_cast<GLuint>(contract::kNodeLocation + k);
        glEnableVertexAttribArray(location);
        glVertexAttribDivisor(location, 1);
    }
    pointNodeConstants(buffer, texels, 0);
}

}  // namespace

Expected<std::unique_ptr<TerrainRenderer>> TerrainRenderer::create(const std::filesystem::path& shaderDirectory,
                                                                   const MapHeader& header, int vertexCacheSize,
                                                                   const PoolOptions& pools,
                                                                   const MaterialSet* materials)
{
    const std::size_t slots = pools.slots;
    TERRAIN_EXPECTS(slots >= 1, "the pools need at least one slot");
    std::unique_ptr<TerrainRenderer> r(new TerrainRenderer(header));
    GLint maxLayers = 0;
    glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &maxLayers);
    if (slots > maxSlots()) {
        return makeError("a node cache of ", slots, " nodes is more than the node pools hold on this GPU (",
                         kMaxPoolArrays, " texture arrays of GL_MAX_ARRAY_TEXTURE_LAYERS ", maxLayers,
                         " layers, a layer per node): a smaller memory_budget or quad_cache_size fits");
    }
    TERRAIN_EXPECTS(pools.layersPerArray <= static_cast<std::size_t>(maxLayers),
                    "an array of at most GL_MAX_ARRAY_TEXTURE_LAYERS layers");
    {
        // As few arrays as the layers allow, the slots spread evenly over them.
        const std::size_t most = pools.layersPerArray > 0 ? pools.layersPerArray : static_cast<std::size_t>(maxLayers);
        const std::size_t arrays = (slots + most - 1) / most;
        r->mLayersPerArray = (slots + arrays - 1) / arrays;
        r->mArrays.resize(arrays);
    }
    if (materials) {
        auto layers = DetailLayers::create(*materials);
        TERRAIN_TRY(layers);
        r->mDetail = std::move(layers).value();
    }
    r->mNodeTexels = contract::kNodeInstanceVec4s + r->mDetail.count();
    const bool padded = header.validWidth < header.gridSize() || header.validHeight < header.gridSize();
    std::vector<std::string> defines;
    if (padded) {
        defines.emplace_back("CLIP_TO_VALID");
    }
    TERRAIN_EXPECTS(pools.normalMapTexels == 0 || pools.normalMapTexels >= 2, "a normal map has >= 2 texels a side");
    r->mNormalTexels = pools.normalMapTexels;
    if (r->mNormalTexels > 0) {
        defines.emplace_back("NORMAL_MAP");
    }
    for (std::string& define : r->mDetail.defines()) {
        defines.push_back(std::move(define));
    }
    r->mPixelCounts = pools.pixelCounts;
    if (r->mPixelCounts) {
        if (!pixelCountsSupported()) {
            return makeError(
                "visibility_lod needs OpenGL 4.3 (or GL_ARB_shader_storage_buffer_object and "
                "GL_ARB_shader_image_load_store) to count visible pixels; this GL has neither");
        }
        defines.emplace_back("PIXEL_COUNTS");
        for (CountFrame& frame : r->mCountFrames) {
            frame.buffer = gl::Buffer::create();
            frame.depth = gl::Buffer::create();
        }
    }
    r->mTessellation = pools.tessellation;
    r->mExtent = extentOf(header);
    if (r->mTessellation) {
        if (!tessellationSupported()) {
            return makeError("render_mode = tessellation needs OpenGL 4.0 tessellation shaders; this GL has none");
        }
        TERRAIN_EXPECTS((header.chunkSize - 1) % kTessellationBlockQuads == 0,
                        "tessellation blocks must tile the node");
        r->mBlocks = static_cast<int>(header.chunkSize - 1) / kTessellationBlockQuads;
    }
    auto loadProgram = [&](const std::vector<std::string>& with) {
        return r->mTessellation
                   ? ShaderProgram::loadTessellation(shaderDirectory, "terrain_tess", "terrain", with, {"vRelative"})
                   : ShaderProgram::load(shaderDirectory, "terrain", with);
    };
    auto terrain = loadProgram(defines);
    TERRAIN_TRY(terrain);
    r->mPrograms.push_back(std::move(terrain.value()));
    if (!r->mDetail.empty()) {
        // Nodes beyond every layer's fade are drawn by the variant without the detail texture loop: llvmpipe
        // runs a loop or branch for every fragment even where no fragment needs it (measured on the demo at
        // 1280 x 720: about 40 ms a frame with one program and a per-node branch).
        defines.emplace_back("DETAIL_TINT_ONLY");
        auto far = loadProgram(defines);
        TERRAIN_TRY(far);
        r->mPrograms.push_back(std::move(far.value()));
    }
    for (ShaderProgram& program : r->mPrograms) {
        program.use();
        contract::bindSamplerUnits(program, contract::kTerrainSamplers);
        glUniform1i(program.uniform("uBlocks"), r->mBlocks);
        glUniform1i(program.uniform("uBlockQuads"), kTessellationBlockQuads);
    }
    if (!r->mDetail.empty()) {
        for (ShaderProgram& program : r->mPrograms) {
            r->mDetail.setUniforms(program, contract::terrain_units::kDetail);
        }
    }
    auto sky = Sky::create(shaderDirectory);
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
    glEnableVertexAttribArray(contract::kGridLocation);
    glVertexAttribIPointer(contract::kGridLocation, 2, GL_UNSIGNED_SHORT, sizeof(TemplateVertex),
                           reinterpret_cast<const void*>(offsetof(TemplateVertex, i)));
    glEnableVertexAttribArray(contract::kSkirtLocation);
    glVertexAttribIPointer(contract::kSkirtLocation, 1, GL_UNSIGNED_BYTE, sizeof(TemplateVertex),
                           reinterpret_cast<const void*>(offsetof(TemplateVertex, skirt)));
    // Per-instance node constants from the frame's constants buffer, a node's texels apart.
    r->mConstantsBuffer = gl::Buffer::create();
    enableNodeConstants(r->mConstantsBuffer, r->mNodeTexels);
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
    if (r->mTessellation) {
        // One patch vertex per block and per border block side, numbered (terrain_tess.vert); the node
        // constants per instance, as for the chunks.
        const int b = r->mBlocks;
        std::vector<float> ids(static_cast<std::size_t>(b * b + 4 * b));
        for (std::size_t k = 0; k < ids.size(); ++k) {
            ids[k] = static_cast<float>(k);
        }
        r->mPatchVao = gl::VertexArray::create();
        r->mPatchIds = gl::Buffer::create();
        glBindVertexArray(r->mPatchVao.name());
        glBindBuffer(GL_ARRAY_BUFFER, r->mPatchIds.name());
        glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(ids.size() * sizeof(float)), ids.data(), GL_STATIC_DRAW);
        glEnableVertexAttribArray(contract::kPatchLocation);
        glVertexAttribPointer(contract::kPatchLocation, 1, GL_FLOAT, GL_FALSE, sizeof(float), nullptr);
        enableNodeConstants(r->mConstantsBuffer, r->mNodeTexels);
        glBindVertexArray(0);
        r->mLevelsBuffer = gl::Buffer::create();
        glBindBuffer(GL_TEXTURE_BUFFER, r->mLevelsBuffer.name());
        glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(b * b * sizeof(std::uint16_t)), nullptr,
                     GL_STREAM_DRAW);
        r->mLevelsTexture = gl::Texture::create();
        glBindTexture(GL_TEXTURE_BUFFER, r->mLevelsTexture.name());
        glTexBuffer(GL_TEXTURE_BUFFER, GL_R16UI, r->mLevelsBuffer.name());
        glBindTexture(GL_TEXTURE_BUFFER, 0);
        glBindBuffer(GL_TEXTURE_BUFFER, 0);
    }

    // The pools, allocated once: a layer per slot.
    const int w = n + 2;  // the surface with a 1-sample border: own normals at the edges need it
    const int m = (n + 1) / 2;
    const int t = static_cast<int>(header.textureSize);
    r->mDxt1 = pools.compressColour && epoxy_has_gl_extension("GL_EXT_texture_compression_s3tc");
    r->mColourLayerSize = r->mDxt1 ? blockLayerSize(t) : t;
    r->mSlotBytes = poolSlotBytes(header, {pools.normalMapTexels, pools.compressNormals, r->mDxt1, r->mDetail.count()});
    r->mRgtc2 = r->mNormalTexels > 0 && pools.compressNormals;
    r->mNormalLayerSize = r->mRgtc2 ? blockLayerSize(r->mNormalTexels) : r->mNormalTexels;
    auto clampToEdge = [] {
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    };
    auto createBlockLayers = [](GLenum format, int size, GLsizei layers, std::size_t layerBytes) {
        gl::Texture texture = gl::Texture::create();
        glBindTexture(GL_TEXTURE_2D_ARRAY, texture.name());
        glCompressedTexImage3D(GL_TEXTURE_2D_ARRAY, 0, format, size, size, layers, 0,
                               static_cast<GLsizei>(layerBytes * static_cast<std::size_t>(layers)), nullptr);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAX_LEVEL, 0);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        return texture;
    };
    for (std::size_t a = 0; a < r->mArrays.size(); ++a) {
        PoolArrays& pool = r->mArrays[a];
        const auto layers = static_cast<GLsizei>(std::min(r->mLayersPerArray, slots - a * r->mLayersPerArray));
        pool.heights = createLayers(GL_R16, w, layers, GL_RED, GL_UNSIGNED_SHORT, GL_NEAREST);
        if (r->mNormalTexels == 0) {
            // The vertex normals' parent part; with normal maps the fragment program lights by those instead.
            pool.parentNormals = createLayers(GL_RG8_SNORM, m, layers, GL_RG, GL_BYTE, GL_NEAREST);
        }
        pool.colour = r->mDxt1 ? createBlockLayers(GL_COMPRESSED_RGB_S3TC_DXT1_EXT, r->mColourLayerSize, layers,
                                                   r->mSlotBytes.colour)
                               : createLayers(GL_RGB8, t, layers, GL_RGB, GL_UNSIGNED_BYTE, GL_LINEAR);
        clampToEdge();
        if (!r->mDetail.empty()) {
            pool.weights = createLayers(GL_RGBA4, n, layers, GL_RGBA, GL_UNSIGNED_SHORT_4_4_4_4, GL_NEAREST);
        }
        if (r->mNormalTexels > 0) {
            // RGTC is core since OpenGL 3.0: every context this renderer runs on decodes it.
            pool.normalMaps = r->mRgtc2
                                  ? createBlockLayers(GL_COMPRESSED_SIGNED_RG_RGTC2, r->mNormalLayerSize, layers,
                                                      r->mSlotBytes.normalMap)
                                  : createLayers(GL_RG8_SNORM, r->mNormalTexels, layers, GL_RG, GL_BYTE, GL_LINEAR);
            clampToEdge();
        }
    }
    r->mSlotHeights.assign(slots, {0.0f, 0.0f});
    TERRAIN_ASSERT(r->mSlotBytes.constants == static_cast<std::size_t>(r->mNodeTexels) * 4 * sizeof(float));
    r->mSlotData.resize(slots);
    r->mFreeSlots.resize(r->mArrays.size());
    for (std::size_t k = slots; k-- > 0;) {
        r->mFreeSlots[static_cast<std::size_t>(r->arrayOf(static_cast<int>(k)))].push_back(
            static_cast<int>(k));  // the array's first slot on top
    }
    if (GLenum error = glGetError(); error != GL_NO_ERROR) {
        return makeError("allocating the node pools for ", slots, " nodes (", r->mSlotBytes.total(),
                         " bytes each) failed: GL error ", error,
                         " (out of GPU memory? a smaller memory_budget or quad_cache_size needs less)");
    }
    return r;
}

void TerrainRenderer::release(const NodeId& id)
{
    auto it = mSlotOf.find(id.key());
    if (it == mSlotOf.end()) {
        return;
    }
    mSlotData[static_cast<std::size_t>(it->second)].reset();
    mFreeSlots[static_cast<std::size_t>(arrayOf(it->second))].push_back(it->second);
    mSlotOf.erase(it);
}

int TerrainRenderer::slotFor(const NodePtr& node, RenderStats& stats, int preferredArray)
{
    auto [it, inserted] = mSlotOf.try_emplace(node->id.key(), -1);
    if (!inserted && mSlotData[static_cast<std::size_t>(it->second)] == node) {
        return it->second;
    }
    if (inserted) {
        // The preferred array's free slots, else those of the array with the most.
        std::vector<int>* free = &mFreeSlots[0];
        for (std::vector<int>& candidate : mFreeSlots) {
            if (candidate.size() > free->size()) {
                free = &candidate;
            }
        }
        if (preferredArray >= 0 && !mFreeSlots[static_cast<std::size_t>(preferredArray)].empty()) {
            free = &mFreeSlots[static_cast<std::size_t>(preferredArray)];
        }
        TERRAIN_EXPECTS(!free->empty(),
                        "more nodes drawn than the pools have slots: size them by the cache's capacity and release "
                        "what the cache evicts (TerrainStreamer::onEvict)");
        it->second = free->back();
        free->pop_back();
    }
    // A new node, or the cache holds a different copy of this one now: copy it into its slot.
    const int slot = it->second;
    mSlotData[static_cast<std::size_t>(slot)] = node;
    const PoolArrays& pool = mArrays[static_cast<std::size_t>(arrayOf(slot))];
    const int layer = layerOf(slot);
    const int n = static_cast<int>(mHeader.chunkSize);
    const int w = windowSize(n);
    const int m = (n + 1) / 2;
    const int t = static_cast<int>(mHeader.textureSize);
    std::vector<float> surface(node->heights.base.size());
    node->heights.surface(surface);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    // The window's inner (N + 2)^2 (one sample of its 2-sample border) as 16-bit codes over the node's range.
    static_assert(kBorder == 2, "quantizeHeightsR16 keeps one sample of a 2-sample border");
    (void)w;
    const QuantizedHeights heights = quantizeHeightsR16(surface, n);
    mSlotHeights[static_cast<std::size_t>(slot)] = {heights.lo, heights.range};
    glBindTexture(GL_TEXTURE_2D_ARRAY, pool.heights.name());
    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, n + 2, n + 2, 1, GL_RED, GL_UNSIGNED_SHORT,
                    heights.codes.data());
    if (pool.parentNormals) {
        const std::vector<std::int8_t> normals = parentNormalsRg8(surface, n, node->spacing);
        glBindTexture(GL_TEXTURE_2D_ARRAY, pool.parentNormals.name());
        glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, m, m, 1, GL_RG, GL_BYTE, normals.data());
    }
    glBindTexture(GL_TEXTURE_2D_ARRAY, pool.colour.name());
    if (mDxt1) {
        const std::vector<std::uint8_t> blocks = compressDxt1(node->texture, t);
        glCompressedTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, mColourLayerSize, mColourLayerSize, 1,
                                  GL_COMPRESSED_RGB_S3TC_DXT1_EXT, static_cast<GLsizei>(blocks.size()), blocks.data());
    } else {
        glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, t, t, 1, GL_RGB, GL_UNSIGNED_BYTE, node->texture.data());
    }
    if (pool.weights) {
        std::vector<std::uint16_t> weights(static_cast<std::size_t>(n) * n, 0);
        if (!node->materialWeights.empty()) {
            weights = packWeightsRgba4(node->materialWeights);
        }
        glBindTexture(GL_TEXTURE_2D_ARRAY, pool.weights.name());
        glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, n, n, 1, GL_RGBA, GL_UNSIGNED_SHORT_4_4_4_4,
                        weights.data());
    }
    if (pool.normalMaps) {
        const auto texels = static_cast<std::size_t>(mNormalTexels);
        glBindTexture(GL_TEXTURE_2D_ARRAY, pool.normalMaps.name());
        if (mRgtc2) {
            // The blocks as the source made them on its thread, else encoded here.
            std::vector<std::uint8_t> encoded;
            if (node->normalMapBlocks.empty()) {
                TERRAIN_EXPECTS(
                    node->normalMap.size() == texels * texels * 2,
                    "with normal maps every node needs one of the pools' size (DetailPolicy::normalMapSize)");
                encoded = compressRgtc2(node->normalMap, mNormalTexels);
            }
            const std::vector<std::uint8_t>& blocks = encoded.empty() ? node->normalMapBlocks : encoded;
            TERRAIN_EXPECTS(blocks.size() == mSlotBytes.normalMap,
                            "a node's RGTC2 normal map must be of the pools' size (DetailPolicy::normalMapSize)");
            glCompressedTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, mNormalLayerSize, mNormalLayerSize, 1,
                                      GL_COMPRESSED_SIGNED_RG_RGTC2, static_cast<GLsizei>(blocks.size()),
                                      blocks.data());
        } else {
            TERRAIN_EXPECTS(node->normalMap.size() == texels * texels * 2,
                            "uncompressed normal map pools need RG8 normal maps (DetailPolicy::compressNormalMaps off) "
                            "of the pools' size (DetailPolicy::normalMapSize)");
            glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, mNormalTexels, mNormalTexels, 1, GL_RG, GL_BYTE,
                            node->normalMap.data());
        }
    }
    ++stats.uploads;
    return slot;
}

std::size_t TerrainRenderer::maxSlots()
{
    GLint layers = 0;
    glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &layers);
    return static_cast<std::size_t>(std::max(layers, 0)) * kMaxPoolArrays;
}

bool TerrainRenderer::softwareRasterizer()
{
    const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const std::string name = renderer ? renderer : "";
    return name.find("llvmpipe") != std::string::npos || name.find("softpipe") != std::string::npos ||
           name.find("swrast") != std::string::npos;
}

bool TerrainRenderer::tessellationSupported()
{
    GLint major = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    return major >= 4;
}

bool TerrainRenderer::pixelCountsSupported()
{
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    return major > 4 || (major == 4 && minor >= 3) ||
           (epoxy_has_gl_extension("GL_ARB_shader_storage_buffer_object") &&
            epoxy_has_gl_extension("GL_ARB_shader_image_load_store"));
}

std::vector<float> TerrainRenderer::readDepth(int width, int height)
{
    TERRAIN_EXPECTS(width > 0 && height > 0, "a depth buffer of at least one pixel");
    std::vector<float> depth(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadPixels(0, 0, width, height, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
    return depth;
}

bool TerrainRenderer::takePixelCounts(PixelCounts& out, std::uint64_t lag)
{
    CountFrame* oldest = nullptr;
    for (CountFrame& f : mCountFrames) {
        if (f.frame != 0 && f.frame + lag <= mFrame && (oldest == nullptr || f.frame < oldest->frame)) {
            oldest = &f;
        }
    }
    if (oldest == nullptr) {
        return false;
    }
    out.frame = oldest->frame;
    out.nodes.swap(oldest->nodes);
    oldest->nodes.clear();
    oldest->frame = 0;
    out.pixels.assign(out.nodes.size(), 0);
    out.camera = oldest->camera;
    out.depth.clear();
    if (oldest->fence) {
        // Two frames late the GL has long finished: this returns at once, except on a GL that queues more.
        while (!oldest->fence.wait(1'000'000'000)) {
        }
        oldest->fence.reset();
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, oldest->buffer.name());
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0,
                           static_cast<GLsizeiptr>(out.pixels.size() * sizeof(std::uint32_t)), out.pixels.data());
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        if (oldest->hasDepth) {
            out.depth.resize(static_cast<std::size_t>(out.camera.viewportWidth) * out.camera.viewportHeight);
            glBindBuffer(GL_PIXEL_PACK_BUFFER, oldest->depth.name());
            glGetBufferSubData(GL_PIXEL_PACK_BUFFER, 0, static_cast<GLsizeiptr>(out.depth.size() * sizeof(float)),
                               out.depth.data());
            glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
        }
    }
    return true;
}

RenderStats TerrainRenderer::draw(const LodSelection& selection, const ResidentNodeLookup& resident,
                                  const Camera& camera, const SceneStyle& style, double blockPixels,
                                  std::vector<glm::vec3>* feedback, const BoxOccluded& occluded)
{
    TERRAIN_EXPECTS(feedback == nullptr || mTessellation, "transform feedback is for the tessellation mode");
    TERRAIN_EXPECTS(!mTessellation || blockPixels > 0.0, "tessellation mode needs a block error budget > 0 pixels");
    RenderStats stats;
    ++mFrame;
    CountFrame* counting = nullptr;
    if (mPixelCounts) {
        counting = &mCountFrames[mFrame % mCountFrames.size()];
        if (counting->frame != 0) {
            ++mDroppedCounts;  // three frames old and never taken
        }
        counting->frame = mFrame;
        counting->nodes.clear();
        counting->fence.reset();
        counting->hasDepth = false;
        counting->camera = camera;
    }
    glViewport(0, 0, camera.viewportWidth, camera.viewportHeight);
    glClearColor(style.clearColour.r, style.clearColour.g, style.clearColour.b, 1.0f);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (style.drawSky) {
        mSky.draw(camera, style);
    }

    // The frame's nodes: slots (uploading what is new) and constants. In the selection's (front to back)
    // order, the nodes with detail layers first, then those beyond every layer's fade (shaders/terrain.frag
    // fades each layer out by 40 repeats away; the coarsest fades last), which the second program draws; within
    // each program, grouped by the pool arrays of the node and its parent (one group while the pools have one).
    const int texels = mNodeTexels;
    const bool split = mPrograms.size() > 1;
    const double fade = mDetail.fadeDistance();
    mFrameNodes.clear();
    for (int pass = 0; pass < (split ? 2 : 1); ++pass) {
        for (const SelectedNode& selected : selection.nodes) {
            const bool near = !split || selected.distance < fade;
            if (near != (pass == 0)) {
                continue;
            }
            NodePtr node = resident(selected.id);
            TERRAIN_EXPECTS(node != nullptr, "every selected node must be resident");
            // The parent's texture for textural morphing (eq. 3.6); the root morphs to itself.
            NodePtr parent = selected.id.isRoot() ? node : resident(selected.id.parent());
            TERRAIN_EXPECTS(parent != nullptr, "a selected node's parent must be resident");
            const int parentSlot = parent == node ? -1 : slotFor(parent, stats);
            const int slot = slotFor(node, stats, parentSlot < 0 ? -1 : arrayOf(parentSlot));
            mFrameNodes.push_back(
                {&selected, node.get(), parent.get(), slot, parentSlot < 0 ? slot : parentSlot, pass});
        }
    }
    auto drawGroup = [this](const FrameNode& f) {
        return std::array<int, 3>{f.program, arrayOf(f.slot), arrayOf(f.parentSlot)};
    };
    if (mArrays.size() > 1) {
        std::stable_sort(mFrameNodes.begin(), mFrameNodes.end(),
                         [&](const FrameNode& a, const FrameNode& b) { return drawGroup(a) < drawGroup(b); });
    }
    mConstants.assign(mFrameNodes.size() * static_cast<std::size_t>(texels) * 4, 0.0f);
    std::size_t count = 0;
    std::uint64_t tessellatedTriangles = 0;
    mCodes.clear();
    for (const FrameNode& f : mFrameNodes) {
        const SelectedNode& selected = *f.selected;
        const NodeData& node = *f.node;
        (node.isStatic ? stats.staticNodes : stats.dynamicNodes) += 1;
        float* c = mConstants.data() + count * static_cast<std::size_t>(texels) * 4;
        contract::NodeInstance instance;
        instance.originX = static_cast<float>(selected.cameraRelativeOrigin.x);
        instance.originY = static_cast<float>(selected.cameraRelativeOrigin.y);
        instance.spacing = static_cast<float>(selected.size / (mHeader.chunkSize - 1));
        instance.morph = selected.id.isRoot() || !style.geomorph ? 1.0f : selected.morph;
        // Skirts hang the parent's delta_c deep: a leaf's own delta_c is zero, yet it can meet a coarser
        // neighbour whose edge lies up to that far away (3.2.6).
        instance.skirtDepth = std::max(f.parent->deltaC, node.deltaC) + static_cast<float>(mHeader.heightStep);
        instance.layer = static_cast<float>(layerOf(f.slot));
        instance.parentLayer = static_cast<float>(layerOf(f.parentSlot));
        instance.lowest = mSlotHeights[static_cast<std::size_t>(f.slot)][0];
        instance.heightRange = mSlotHeights[static_cast<std::size_t>(f.slot)][1];
        instance.quadrantX = (selected.id.x & 1) ? 0.5f : 0.0f;
        instance.quadrantY = (selected.id.y & 1) ? 0.5f : 0.0f;
        std::memcpy(c, &instance, sizeof instance);
        if (split && f.program == static_cast<int>(kNear)) {
            // The node's corner in repeats of each layer (and of its turned copy), reduced to [0, 1).
            const glm::dvec2 corner = glm::dvec2(selected.cameraRelativeOrigin) + glm::dvec2(camera.position);
            for (int k = 0; k < mDetail.count(); ++k) {
                const glm::vec4 origin = mDetail.origin(k, corner);
                for (int i = 0; i < 4; ++i) {
                    c[4 * (contract::kNodeInstanceVec4s + k) + i] = origin[i];
                }
            }
        }
        if (mTessellation) {
            TERRAIN_EXPECTS(node.tessellation != nullptr,
                            "tessellation mode needs nodes made with their tessellation errors "
                            "(DetailPolicy::tessellationBlockQuads)");
            // Hidden nodes' blocks all at their coarsest; in the others, hidden blocks away from visible ones.
            const BlockLevels levels =
                drawnBlockLevels(*node.tessellation, mExtent.box(selected.id, node.zMin, node.zMax), camera,
                                 blockPixels, selected.hidden, occluded);
            stats.occludedBlocks += static_cast<std::size_t>(levels.occludedBlocks);
            const int b = levels.blocksPerSide;
            for (int k = 0; k < b * b; ++k) {
                mCodes.push_back(levels.code(k));
                (levels.culled[static_cast<std::size_t>(k)] == 0 ? stats.blocks : stats.culledBlocks) += 1;
            }
            tessellatedTriangles += levels.triangles();
        }
        if (counting) {
            counting->nodes.push_back(selected.id);
        }
        ++count;
    }
    stats.nodes = count;
    stats.triangles = mTessellation ? tessellatedTriangles : count * mTrianglesPerNode;
    stats.gpuNodes = mSlotOf.size();
    if (count == 0) {
        return stats;
    }
    glBindBuffer(GL_ARRAY_BUFFER, mConstantsBuffer.name());
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(mConstants.size() * sizeof(float)), mConstants.data(),
                 GL_STREAM_DRAW);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    if (mTessellation) {
        glBindBuffer(GL_TEXTURE_BUFFER, mLevelsBuffer.name());
        glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(mCodes.size() * sizeof(std::uint16_t)), mCodes.data(),
                     GL_STREAM_DRAW);
        glBindBuffer(GL_TEXTURE_BUFFER, 0);
        glActiveTexture(GL_TEXTURE0 + contract::terrain_units::kLevels);
        glBindTexture(GL_TEXTURE_BUFFER, mLevelsTexture.name());
        glActiveTexture(GL_TEXTURE0);
        glPatchParameteri(GL_PATCH_VERTICES, 1);
    }

    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
    glPolygonMode(GL_FRONT_AND_BACK, style.wireframe ? GL_LINE : GL_FILL);

    const glm::mat4 viewProjection(camera.projection() * camera.viewRotation());
    for (ShaderProgram& program : mPrograms) {
        program.use();
        glUniformMatrix4fv(program.uniform("uViewProjection"), 1, GL_FALSE, glm::value_ptr(viewProjection));
        glUniform1f(program.uniform("uHeightBase"), static_cast<float>(mHeader.heightOffset - camera.position.z));
        glUniform1f(program.uniform("uInverseCells"), 1.0f / static_cast<float>(mHeader.chunkSize - 1));
        glUniform1f(program.uniform("uTexels"), static_cast<float>(mHeader.textureSize));
        glUniform1f(program.uniform("uLayerTexels"), static_cast<float>(mColourLayerSize));
        glUniform1f(program.uniform("uNormalTexels"), static_cast<float>(mNormalTexels));
        glUniform1f(program.uniform("uNormalLayerTexels"), static_cast<float>(mNormalLayerSize));
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
    mDetail.bind(contract::terrain_units::kDetail);
    glActiveTexture(GL_TEXTURE0);

    if (counting) {
        // One counter a node, zeroed; the fragment program adds each visible fragment to its node's.
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, counting->buffer.name());
        if (counting->capacity < count) {
            counting->capacity = std::max<std::size_t>(count, 2 * counting->capacity);
            glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(counting->capacity * sizeof(std::uint32_t)),
                         nullptr, GL_DYNAMIC_READ);
        }
        const std::vector<std::uint32_t> zeros(count, 0);
        glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, static_cast<GLsizeiptr>(count * sizeof(std::uint32_t)),
                        zeros.data());
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, counting->buffer.name());
    }
    glBindVertexArray(mTessellation ? mPatchVao.name() : mTemplateVao.name());
    if (feedback) {
        if (!mFeedback) {
            mFeedback = gl::Buffer::create();
        }
        glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, mFeedback.name());
        glBufferData(GL_TRANSFORM_FEEDBACK_BUFFER, static_cast<GLsizeiptr>(stats.triangles * 3 * sizeof(glm::vec3)),
                     nullptr, GL_STREAM_READ);
        glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, 0);
    }
    std::size_t captured = 0;  // triangles
    const auto patches = static_cast<GLsizei>(mBlocks * mBlocks + 4 * mBlocks);
    for (std::size_t first = 0; first < count;) {
        // A draw: the consecutive nodes of one program and pair of arrays.
        const std::array<int, 3> group = drawGroup(mFrameNodes[first]);
        std::size_t last = first + 1;
        while (last < count && drawGroup(mFrameNodes[last]) == group) {
            ++last;
        }
        const PoolArrays& own = mArrays[static_cast<std::size_t>(group[1])];
        const PoolArrays& parents = mArrays[static_cast<std::size_t>(group[2])];
        namespace units = contract::terrain_units;
        const std::pair<int, const gl::Texture*> bindings[] = {{units::kColour, &own.colour},
                                                               {units::kHeights, &own.heights},
                                                               {units::kWeights, &own.weights},
                                                               {units::kParentNormals, &own.parentNormals},
                                                               {units::kNormalMaps, &own.normalMaps},
                                                               {units::kParentColour, &parents.colour},
                                                               {units::kParentNormalMaps, &parents.normalMaps}};
        for (const auto& [unit, texture] : bindings) {
            if (*texture) {
                glActiveTexture(static_cast<GLenum>(GL_TEXTURE0 + unit));
                glBindTexture(GL_TEXTURE_2D_ARRAY, texture->name());
            }
        }
        glActiveTexture(GL_TEXTURE0);
        ShaderProgram& program = mPrograms[static_cast<std::size_t>(group[0])];
        program.use();
        // The instances' constants start at `first`: the per-instance attributes are pointed there.
        pointNodeConstants(mConstantsBuffer, texels, first);
        glUniform1i(program.uniform("uFirstInstance"), static_cast<GLint>(first));
        if (mTessellation) {
            GLuint query = 0, generated = 0;
            if (feedback) {
                // Each draw's triangles after the previous one's (feedback cannot span a program change).
                glBindBufferRange(GL_TRANSFORM_FEEDBACK_BUFFER, 0, mFeedback.name(),
                                  static_cast<GLintptr>(captured * 3 * sizeof(glm::vec3)),
                                  static_cast<GLsizeiptr>((stats.triangles - captured) * 3 * sizeof(glm::vec3)));
                glGenQueries(1, &query);
                glGenQueries(1, &generated);
                glBeginQuery(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN, query);
                glBeginQuery(GL_PRIMITIVES_GENERATED, generated);
                glBeginTransformFeedback(GL_TRIANGLES);
            }
            glDrawArraysInstanced(GL_PATCHES, 0, patches, static_cast<GLsizei>(last - first));
            if (feedback) {
                glEndTransformFeedback();
                glEndQuery(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN);
                glEndQuery(GL_PRIMITIVES_GENERATED);
                GLuint written = 0, made = 0;
                glGetQueryObjectuiv(query, GL_QUERY_RESULT, &written);
                glGetQueryObjectuiv(generated, GL_QUERY_RESULT, &made);
                glDeleteQueries(1, &query);
                glDeleteQueries(1, &generated);
                stats.generatedTriangles += made;
                glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, 0);
                captured += written;
            }
        } else {
            glDrawElementsInstanced(GL_TRIANGLES, mIndexCount, mIndexType, nullptr, static_cast<GLsizei>(last - first));
        }
        ++stats.drawCalls;
        first = last;
    }
    glBindVertexArray(0);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    if (counting) {
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
        // The counters are read by glGetBufferSubData (takePixelCounts) once the fence says the draws are done.
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        // The depth too, into a buffer (no wait here): what the nodes not drawn are tested against.
        const auto pixels = static_cast<std::size_t>(camera.viewportWidth) * camera.viewportHeight;
        glBindBuffer(GL_PIXEL_PACK_BUFFER, counting->depth.name());
        if (counting->depthPixels != pixels) {
            glBufferData(GL_PIXEL_PACK_BUFFER, static_cast<GLsizeiptr>(pixels * sizeof(float)), nullptr,
                         GL_STREAM_READ);
            counting->depthPixels = pixels;
        }
        glPixelStorei(GL_PACK_ALIGNMENT, 4);
        glReadPixels(0, 0, camera.viewportWidth, camera.viewportHeight, GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
        glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
        counting->hasDepth = true;
        counting->fence = gl::Fence::place();
    }
    if (feedback) {
        feedback->resize(captured * 3);
        glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, mFeedback.name());
        glGetBufferSubData(GL_TRANSFORM_FEEDBACK_BUFFER, 0, static_cast<GLsizeiptr>(captured * 3 * sizeof(glm::vec3)),
                           feedback->data());
        glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, 0);
    }
    return stats;
}

}  // namespace terrain
