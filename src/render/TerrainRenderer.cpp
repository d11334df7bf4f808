// Drawing the selected chunks: template mesh (3.2.9, eq. 3.7), geomorphing (3.2.8, eq. 3.4-3.6), skirts
// (3.2.6), zigzag index buffer (3.2.10), front to back (3.2.11), node data in pools (4.2.3).
#include "render/TerrainRenderer.h"

#include "gpudata/TemplateMesh.h"
#include "gpudata/ZigzagIndexBuffer.h"
#include "heightfield/Image.h"
#include "light/Horizon.h"
#include "lod/NodeTextures.h"
#include "lod/TessellationLevels.h"
#include "quadtree/ChunkGeometry.h"
#include "render/FrameSetup.h"
#include "render/ShaderContract.h"
#include "render/TextureArrays.h"

#include <glm/geometric.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>

namespace terrain {

namespace {

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
                                                                   const MaterialSet* materials,
                                                                   const LightingModel& lighting)
{
    TERRAIN_EXPECTS(pools.slots >= 1, "the pools need at least one slot");
    TERRAIN_EXPECTS(pools.normalMapTexels == 0 || pools.normalMapTexels >= 2, "a normal map has >= 2 texels a side");
    std::unique_ptr<TerrainRenderer> r(new TerrainRenderer(header));
    if (materials) {
        auto layers = DetailLayers::create(*materials);
        TERRAIN_TRY(layers);
        r->mDetail = std::move(layers).value();
    }
    r->mNodeTexels = contract::kNodeInstanceVec4s + r->mDetail.count();
    std::vector<std::string> defines;
    if (header.validWidth < header.gridSize() || header.validHeight < header.gridSize()) {
        defines.emplace_back("CLIP_TO_VALID");
    }
    r->mNormalTexels = pools.normalMapTexels;
    if (r->mNormalTexels > 0) {
        defines.emplace_back("NORMAL_MAP");
    }
    for (std::string& define : r->mDetail.defines()) {
        defines.push_back(std::move(define));
    }
    if (pools.pixelCounts) {
        if (!pixelCountsSupported()) {
            return makeError(
                "visibility_lod needs OpenGL 4.3 (or GL_ARB_shader_storage_buffer_object and "
                "GL_ARB_shader_image_load_store) to count visible pixels; this GL has neither");
        }
        defines.emplace_back("PIXEL_COUNTS");
        r->mCounter = PixelCounter::create();
        // Counting needs early fragment tests, under which the padding's discarded fragments write depth.
        if (std::find(defines.begin(), defines.end(), "CLIP_TO_VALID") != defines.end()) {
            r->mSkyOrder = SkyOrder::BeforeTerrain;
        }
    }
    r->mTessellation = pools.tessellation;
    if (r->mTessellation) {
        if (!tessellationSupported()) {
            return makeError("render_mode = tessellation needs OpenGL 4.0 tessellation shaders; this GL has none");
        }
        TERRAIN_EXPECTS((header.chunkSize - 1) % kTessellationBlockQuads == 0,
                        "tessellation blocks must tile the node");
        r->mBlocks = static_cast<int>(header.chunkSize - 1) / kTessellationBlockQuads;
    }
    TERRAIN_EXPECTS(!pools.blockIndices || pools.tessellation, "block indices draw the tessellation mode's blocks");
    r->mBlockIndices = pools.blockIndices;
    if (r->mBlockIndices) {
        if (!multiDrawIndirectSupported()) {
            return makeError(
                "render_mode = blocks needs OpenGL 4.3 (indirect draws with base instances); this GL has "
                "none");
        }
        r->mBlockTriangles.emplace(static_cast<int>(header.chunkSize), kTessellationBlockQuads);
    }
    if (lighting.atmosphere) {
        defines.emplace_back("ATMOSPHERE");
    }
    r->mShadows = pools.shadows;
    if (r->mShadows) {
        defines.emplace_back("SHADOWS");
    }
    TERRAIN_TRY(r->createPrograms(shaderDirectory, std::move(defines), lighting));
    r->createTemplateMesh(vertexCacheSize);
    if (r->mTessellation && !r->mBlockIndices) {
        r->createPatches();
    }
    if (r->mBlockIndices) {
        r->mCommandsBuffer = gl::Buffer::create();
    }
    TERRAIN_TRY(r->createPools(pools));
    return r;
}

Status TerrainRenderer::createPrograms(const std::filesystem::path& shaderDirectory, std::vector<std::string> defines,
                                       const LightingModel& lighting)
{
    auto loadProgram = [&](const std::vector<std::string>& with) {
        if (mTessellation && !mBlockIndices) {
            return ShaderProgram::loadTessellation(shaderDirectory, "terrain_tess", "terrain", with, {"vRelative"});
        }
        return ShaderProgram::load(shaderDirectory, "terrain", with,
                                   mBlockIndices ? std::vector<std::string>{"vRelative"} : std::vector<std::string>{});
    };
    auto terrain = loadProgram(defines);
    TERRAIN_TRY(terrain);
    mPrograms.push_back(std::move(terrain.value()));
    if (!mDetail.empty()) {
        // Nodes beyond every layer's fade are drawn by the program without the detail layers (their ground colours
        // are in the node's colours): llvmpipe runs a loop or branch for every fragment even where no fragment
        // needs it (measured on the demo at 1280 x 720: about 40 ms a frame with one program and a per-node
        // branch).
        const std::vector<std::string> detail = mDetail.defines();
        std::erase_if(defines, [&](const std::string& d) { return std::ranges::find(detail, d) != detail.end(); });
        auto far = loadProgram(defines);
        TERRAIN_TRY(far);
        mPrograms.push_back(std::move(far.value()));
    }
    for (ShaderProgram& program : mPrograms) {
        program.use();
        contract::bindSamplerUnits(program, contract::kTerrainSamplers);
        glUniform1i(program.uniform("uBlocks"), mBlocks);
        glUniform1i(program.uniform("uBlockQuads"), kTessellationBlockQuads);
        if (!mDetail.empty()) {
            mDetail.setUniforms(program, contract::terrain_units::kDetail);
        }
    }
    auto sky = Sky::create(shaderDirectory, lighting);
    TERRAIN_TRY(sky);
    mSky = std::move(sky.value());
    return {};
}

void TerrainRenderer::createTemplateMesh(int vertexCacheSize)
{
    const int n = static_cast<int>(mHeader.chunkSize);
    mMesh = buildTemplateMesh(n);
    const std::vector<std::uint32_t> indices = buildZigzagIndices(n, vertexCacheSize, /*withSkirts=*/true);
    mTrianglesPerNode = indices.size() / 3;
    mIndexCount = static_cast<GLsizei>(indices.size());
    const bool narrow = indexTypeFor(mMesh.vertices.size()) == IndexType::kUint16;
    mIndexType = narrow ? GL_UNSIGNED_SHORT : GL_UNSIGNED_INT;

    mTemplateVao = gl::VertexArray::create();
    mTemplateVertices = gl::Buffer::create();
    mTemplateIndices = gl::Buffer::create();
    glBindVertexArray(mTemplateVao.name());
    glBindBuffer(GL_ARRAY_BUFFER, mTemplateVertices.name());
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(mMesh.vertices.size() * sizeof(TemplateVertex)),
                 mMesh.vertices.data(), GL_STATIC_DRAW);
    glEnableVertexAttribArray(contract::kGridLocation);
    glVertexAttribIPointer(contract::kGridLocation, 2, GL_UNSIGNED_SHORT, sizeof(TemplateVertex),
                           reinterpret_cast<const void*>(offsetof(TemplateVertex, i)));
    glEnableVertexAttribArray(contract::kSkirtLocation);
    glVertexAttribIPointer(contract::kSkirtLocation, 1, GL_UNSIGNED_BYTE, sizeof(TemplateVertex),
                           reinterpret_cast<const void*>(offsetof(TemplateVertex, skirt)));
    // Per-instance node constants from the frame's constants buffer, a node's texels apart.
    mConstantsBuffer = gl::Buffer::create();
    enableNodeConstants(mConstantsBuffer, mNodeTexels);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, mTemplateIndices.name());
    if (narrow) {
        const std::vector<std::uint16_t> shortIndices = narrowIndices(indices);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(shortIndices.size() * sizeof(std::uint16_t)),
                     shortIndices.data(), GL_STATIC_DRAW);
    } else {
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)),
                     indices.data(), GL_STATIC_DRAW);
    }
    glBindVertexArray(0);
}

void TerrainRenderer::createPatches()
{
    // One patch vertex per block and per border block side, numbered (terrain_tess.vert); the node constants
    // per instance, as for the chunks.
    const int b = mBlocks;
    std::vector<float> ids(static_cast<std::size_t>(b * b + 4 * b));
    for (std::size_t k = 0; k < ids.size(); ++k) {
        ids[k] = static_cast<float>(k);
    }
    mPatchVao = gl::VertexArray::create();
    mPatchIds = gl::Buffer::create();
    glBindVertexArray(mPatchVao.name());
    glBindBuffer(GL_ARRAY_BUFFER, mPatchIds.name());
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(ids.size() * sizeof(float)), ids.data(), GL_STATIC_DRAW);
    glEnableVertexAttribArray(contract::kPatchLocation);
    glVertexAttribPointer(contract::kPatchLocation, 1, GL_FLOAT, GL_FALSE, sizeof(float), nullptr);
    enableNodeConstants(mConstantsBuffer, mNodeTexels);
    glBindVertexArray(0);
    mLevelsBuffer = gl::Buffer::create();
    glBindBuffer(GL_TEXTURE_BUFFER, mLevelsBuffer.name());
    glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(b * b * sizeof(std::uint16_t)), nullptr, GL_STREAM_DRAW);
    mLevelsTexture = gl::Texture::create();
    glBindTexture(GL_TEXTURE_BUFFER, mLevelsTexture.name());
    glTexBuffer(GL_TEXTURE_BUFFER, GL_R16UI, mLevelsBuffer.name());
    glBindTexture(GL_TEXTURE_BUFFER, 0);
    glBindBuffer(GL_TEXTURE_BUFFER, 0);
}

Status TerrainRenderer::createPools(const PoolOptions& pools)
{
    const std::size_t slots = pools.slots;
    GLint maxLayers = 0;
    glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &maxLayers);
    if (slots > maxSlots()) {
        return makeError("a node cache of ", slots, " nodes is more than the node pools hold on this GPU (",
                         kMaxPoolArrays, " texture arrays of GL_MAX_ARRAY_TEXTURE_LAYERS ", maxLayers,
                         " layers, a layer per node): a smaller memory_budget or quad_cache_size fits");
    }
    TERRAIN_EXPECTS(pools.layersPerArray <= static_cast<std::size_t>(maxLayers),
                    "an array of at most GL_MAX_ARRAY_TEXTURE_LAYERS layers");
    // As few arrays as the layers allow, the slots spread evenly over them.
    const std::size_t most = pools.layersPerArray > 0 ? pools.layersPerArray : static_cast<std::size_t>(maxLayers);
    const std::size_t arrays = (slots + most - 1) / most;
    mLayersPerArray = (slots + arrays - 1) / arrays;
    mArrays.resize(arrays);

    const int n = static_cast<int>(mHeader.chunkSize);
    const int w = n + 2;  // the surface with a 1-sample border: own normals at the edges need it
    const int m = (n + 1) / 2;
    const int t = static_cast<int>(mHeader.textureSize);
    // With shadows the colour layers carry the sun's visibility in alpha (fillLight): RGBA8, not DXT1.
    mDxt1 = pools.compressColour && !pools.shadows && epoxy_has_gl_extension("GL_EXT_texture_compression_s3tc");
    mColourLayerSize = mDxt1 ? blockLayerSize(t) : t;
    mSlotBytes =
        poolSlotBytes(mHeader, {pools.normalMapTexels, pools.compressNormals, mDxt1, mDetail.count(), pools.shadows});
    mRgtc2 = mNormalTexels > 0 && pools.compressNormals;
    mNormalLayerSize = mRgtc2 ? blockLayerSize(mNormalTexels) : mNormalTexels;
    const TextureArrayFormat heights{GL_R16, GL_RED, GL_UNSIGNED_SHORT, GL_NEAREST};
    const TextureArrayFormat parentNormals{GL_RG8_SNORM, GL_RG, GL_BYTE, GL_NEAREST};
    const TextureArrayFormat colour =
        mDxt1
            ? TextureArrayFormat{GL_COMPRESSED_RGB_S3TC_DXT1_EXT, 0, 0, GL_LINEAR, GL_CLAMP_TO_EDGE, mSlotBytes.colour}
        : pools.shadows ? TextureArrayFormat{GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, GL_LINEAR, GL_CLAMP_TO_EDGE}
                        : TextureArrayFormat{GL_RGB8, GL_RGB, GL_UNSIGNED_BYTE, GL_LINEAR, GL_CLAMP_TO_EDGE};
    const TextureArrayFormat weights{GL_RGBA4, GL_RGBA, GL_UNSIGNED_SHORT_4_4_4_4, GL_NEAREST};
    // RGTC is core since OpenGL 3.0: every context this renderer runs on decodes it.
    const TextureArrayFormat normalMaps =
        mRgtc2
            ? TextureArrayFormat{GL_COMPRESSED_SIGNED_RG_RGTC2, 0, 0, GL_LINEAR, GL_CLAMP_TO_EDGE, mSlotBytes.normalMap}
            : TextureArrayFormat{GL_RG8_SNORM, GL_RG, GL_BYTE, GL_LINEAR, GL_CLAMP_TO_EDGE};
    for (std::size_t a = 0; a < mArrays.size(); ++a) {
        PoolArrays& pool = mArrays[a];
        const auto layers = static_cast<int>(std::min(mLayersPerArray, slots - a * mLayersPerArray));
        pool.heights = createTextureArray(heights, w, layers);
        if (mNormalTexels == 0) {
            // The vertex normals' parent part; with normal maps the fragment program lights by those instead.
            pool.parentNormals = createTextureArray(parentNormals, m, layers);
        }
        pool.colour = createTextureArray(colour, mColourLayerSize, layers);
        if (!mDetail.empty()) {
            pool.weights = createTextureArray(weights, n, layers);
        }
        if (mNormalTexels > 0) {
            pool.normalMaps = createTextureArray(normalMaps, mNormalLayerSize, layers);
        }
        if (mShadows) {
            pool.light = createTextureArray({GL_RG8, GL_RG, GL_UNSIGNED_BYTE, GL_NEAREST, GL_CLAMP_TO_EDGE}, n, layers);
        }
    }
    mSlotHeights.assign(slots, {0.0f, 0.0f});
    TERRAIN_ASSERT(mSlotBytes.constants == static_cast<std::size_t>(mNodeTexels) * 4 * sizeof(float));
    mSlotData.resize(slots);
    if (GLenum error = glGetError(); error != GL_NO_ERROR) {
        return makeError("allocating the node pools for ", slots, " nodes (", mSlotBytes.total(),
                         " bytes each) failed: GL error ", error,
                         " (out of GPU memory? a smaller memory_budget or quad_cache_size needs less)");
    }
    return {};
}

void TerrainRenderer::fillLight(int slot)
{
    const NodeData& node = *mSlotData[static_cast<std::size_t>(slot)];
    const int n = static_cast<int>(mHeader.chunkSize);
    const int t = static_cast<int>(mHeader.textureSize);
    const auto samples = static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
    const auto texels = static_cast<std::size_t>(t) * static_cast<std::size_t>(t);
    // The sun's and sky's visibility at the colour's texels (the sun's goes into the colour's alpha, fetched
    // with the colour), the sky's of the node and of its parent's surface at the node's samples (the vertex
    // programs read those).
    std::vector<std::uint8_t> atTexels(texels * 2, 255), own(samples * 2, 255), parent(samples * 2, 255);
    if (node.horizons.size >= 2 && node.parentHorizons.size >= 2) {
        // The sun's direction angle from +x towards +y and its elevation, as the horizons measure them.
        const double azimuth = std::atan2(double{mSun.y}, double{mSun.x});
        const double elevation = std::asin(std::clamp(double{mSun.z}, -1.0, 1.0));
        latticeVisibility(node.horizons, azimuth, elevation, kShadowSoftness, t, atTexels, 2, 0);
        if (t == n) {
            own = atTexels;
        } else {
            latticeVisibility(node.horizons, azimuth, elevation, kShadowSoftness, n, own, 2, 0);
        }
        latticeVisibility(node.parentHorizons, azimuth, elevation, kShadowSoftness, n, parent, 2, 0);
    }
    std::vector<std::uint8_t> sky(samples * 2);
    for (std::size_t k = 0; k < samples; ++k) {
        sky[2 * k] = own[2 * k + 1];
        sky[2 * k + 1] = parent[2 * k + 1];
    }
    TERRAIN_EXPECTS(node.texture.size() >= texels * 3, "a node's colours hold T x T RGB texels");
    std::vector<std::uint8_t> rgba(texels * 4);
    for (std::size_t k = 0; k < texels; ++k) {
        std::copy_n(node.texture.data() + 3 * k, 3, rgba.data() + 4 * k);
        rgba[4 * k + 3] = atTexels[2 * k];
    }
    const PoolArrays& pool = mArrays[static_cast<std::size_t>(arrayOf(slot))];
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glBindTexture(GL_TEXTURE_2D_ARRAY, pool.colour.name());
    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layerOf(slot), t, t, 1, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    glBindTexture(GL_TEXTURE_2D_ARRAY, pool.light.name());
    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layerOf(slot), n, n, 1, GL_RG, GL_UNSIGNED_BYTE, sky.data());
}

void TerrainRenderer::fill(int slot, const NodePtr& node, RenderStats& stats)
{
    TERRAIN_EXPECTS(slot >= 0 && static_cast<std::size_t>(slot) < mSlotData.size(),
                    "a node's slot must be within the pools (size them by the node cache's capacity)");
    if (mSlotData[static_cast<std::size_t>(slot)] == node) {
        return;
    }
    // A node new to the slot, or the cache holds a different copy of this one now: copy it into the slot.
    mSlotsHeld += mSlotData[static_cast<std::size_t>(slot)] ? 0 : 1;
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
    if (pool.light) {
        // With the sun's visibility in alpha (fillLight, below).
    } else if (mDxt1) {
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
    if (pool.light) {
        fillLight(slot);
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

bool TerrainRenderer::multiDrawIndirectSupported()
{
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    return major > 4 || (major == 4 && minor >= 3);
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
    return mCounter && mCounter->take(out, mFrame, lag);
}

RenderStats TerrainRenderer::draw(const DrawList& frame, const SceneStyle& style, std::vector<glm::vec3>* feedback)
{
    TERRAIN_EXPECTS(feedback == nullptr || mTessellation, "transform feedback is for the tessellation mode");
    TERRAIN_EXPECTS(mTessellation == frame.tessellated(),
                    "a tessellation mode renderer draws lists with block levels (DrawList::blockPixels > 0), "
                    "a chunk renderer lists without");
    const Camera& camera = frame.camera;
    RenderStats stats;
    ++mFrame;
    if (mCounter) {
        mCounter->begin(mFrame, camera);
    }
    beginSceneFrame(camera, style, mSky, mSkyOrder);
    if (mShadows) {
        // Every held slot's visibility follows the sun when it moves; nodes filled below get it as they come. A
        // style without a sun direction (zero or not finite) keeps the last one.
        const float length = glm::length(style.sunDirection);
        const glm::vec3 sun = std::isfinite(length) && length > 1e-6f ? style.sunDirection / length : mSun;
        if (sun != mSun && sun != glm::vec3(0.0f)) {
            mSun = sun;
            for (std::size_t slot = 0; slot < mSlotData.size(); ++slot) {
                if (mSlotData[slot]) {
                    fillLight(static_cast<int>(slot));
                }
            }
        }
    }
    orderFrameNodes(frame, stats);
    const std::size_t count = mFrameNodes.size();
    stats.nodes = count;
    stats.triangles = mTessellation ? frame.blockTriangles : count * mTrianglesPerNode;
    stats.blocks = frame.blocks;
    stats.culledBlocks = frame.culledBlocks;
    stats.occludedBlocks = frame.occludedBlocks;
    stats.gpuNodes = mSlotsHeld;
    if (count == 0) {
        endSceneFrame(camera, style, mSky, mSkyOrder);
        return stats;
    }
    const std::uint64_t indexed = uploadFrameNodes(frame, style);
    if (mBlockIndices) {
        stats.triangles = indexed;
    }
    setFrameUniforms(camera, style);
    if (mCounter) {
        mCounter->bindCounters();
    }
    if (feedback) {
        if (!mFeedback) {
            mFeedback.emplace();
        }
        mFeedback->begin(stats.triangles);
    }
    drawGroups(stats, feedback ? &*mFeedback : nullptr);
    endSceneFrame(camera, style, mSky, mSkyOrder);
    if (mCounter) {
        mCounter->finish();
    }
    if (feedback) {
        mFeedback->read(*feedback);
    }
    return stats;
}

void TerrainRenderer::orderFrameNodes(const DrawList& frame, RenderStats& stats)
{
    // In the list's (front to back) order, the nodes with detail layers first, then those beyond every layer's
    // fade (shaders/terrain.frag fades each layer out by 40 repeats away; the coarsest fades last), which the
    // second program draws; within each program, grouped by the pool arrays of the node and its parent (one
    // group while the pools have one). Each node's slot is filled (its parent's first) when it holds another.
    const bool split = mPrograms.size() > 1;
    const double fade = mDetail.fadeDistance();
    mFrameNodes.clear();
    for (int pass = 0; pass < (split ? 2 : 1); ++pass) {
        for (const DrawnNode& drawn : frame.nodes) {
            const bool near = !split || drawn.selected.distance < fade;
            if (near != (pass == 0)) {
                continue;
            }
            if (drawn.parentSlot != drawn.slot) {
                fill(drawn.parentSlot, drawn.parent, stats);
            }
            fill(drawn.slot, drawn.node, stats);
            mFrameNodes.push_back({&drawn, pass});
            (drawn.node->isStatic ? stats.staticNodes : stats.dynamicNodes) += 1;
        }
    }
    if (mArrays.size() > 1) {
        auto group = [this](const FrameNode& f) {
            return std::array<int, 3>{f.program, arrayOf(f.drawn->slot), arrayOf(f.drawn->parentSlot)};
        };
        std::stable_sort(mFrameNodes.begin(), mFrameNodes.end(),
                         [&](const FrameNode& a, const FrameNode& b) { return group(a) < group(b); });
    }
    if (mCounter) {
        // In drawing order, the order the shaders count in (each node's place: NodeInstance::index).
        for (const FrameNode& f : mFrameNodes) {
            mCounter->add(f.drawn->selected.id);
        }
    }
}

std::uint64_t TerrainRenderer::uploadFrameNodes(const DrawList& frame, const SceneStyle& style)
{
    const auto texels = static_cast<std::size_t>(mNodeTexels);
    const bool split = mPrograms.size() > 1;
    mConstants.assign(mFrameNodes.size() * texels * 4, 0.0f);
    mCodes.clear();
    mFrameIndices.clear();
    mCommands.clear();
    for (std::size_t k = 0; k < mFrameNodes.size(); ++k) {
        const FrameNode& f = mFrameNodes[k];
        const DrawnNode& drawn = *f.drawn;
        const SelectedNode& selected = drawn.selected;
        float* c = mConstants.data() + k * texels * 4;
        contract::NodeInstance instance;
        instance.originX = static_cast<float>(selected.cameraRelativeOrigin.x);
        instance.originY = static_cast<float>(selected.cameraRelativeOrigin.y);
        instance.spacing = static_cast<float>(selected.size / (mHeader.chunkSize - 1));
        instance.morph = selected.id.isRoot() || !style.geomorph ? 1.0f : selected.morph;
        // Skirts hang the parent's delta_c deep: a leaf's own delta_c is zero, yet it can meet a coarser
        // neighbour whose edge lies up to that far away (3.2.6).
        instance.skirtDepth =
            std::max(drawn.parent->deltaC, drawn.node->deltaC) + static_cast<float>(mHeader.heightStep);
        instance.layer = static_cast<float>(layerOf(drawn.slot));
        instance.parentLayer = static_cast<float>(layerOf(drawn.parentSlot));
        instance.lowest = mSlotHeights[static_cast<std::size_t>(drawn.slot)][0];
        instance.heightRange = mSlotHeights[static_cast<std::size_t>(drawn.slot)][1];
        instance.quadrantX = (selected.id.x & 1) ? 0.5f : 0.0f;
        instance.quadrantY = (selected.id.y & 1) ? 0.5f : 0.0f;
        instance.index = static_cast<float>(k);
        std::memcpy(c, &instance, sizeof instance);
        if (split && f.program == static_cast<int>(kNear)) {
            // The node's corner in each layer's repeats and lattice coordinates, reduced (DetailLayers::origin).
            const glm::dvec2 corner = glm::dvec2(selected.cameraRelativeOrigin) + glm::dvec2(frame.camera.position);
            for (int layer = 0; layer < mDetail.count(); ++layer) {
                const glm::vec4 origin = mDetail.origin(layer, corner);
                for (int i = 0; i < 4; ++i) {
                    c[4 * (contract::kNodeInstanceVec4s + layer) + i] = origin[i];
                }
            }
        }
        if (mBlockIndices) {
            DrawCommand command{0, 1, static_cast<GLuint>(mFrameIndices.size()), 0, static_cast<GLuint>(k)};
            command.count = static_cast<GLuint>(3 * mBlockTriangles->append(drawn.levels, mFrameIndices));
            mCommands.push_back(command);
        } else if (mTessellation) {
            const BlockLevels& levels = drawn.levels;
            const int b = levels.blocksPerSide;
            for (int block = 0; block < b * b; ++block) {
                mCodes.push_back(levels.code(block));
            }
        }
    }
    glBindBuffer(GL_ARRAY_BUFFER, mConstantsBuffer.name());
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(mConstants.size() * sizeof(float)), mConstants.data(),
                 GL_STREAM_DRAW);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    if (mBlockIndices) {
        // The template's vertex array draws the frame's lists (its element buffer), narrowed where the template's
        // vertices fit 16 bits (mIndexType).
        glBindVertexArray(mTemplateVao.name());
        if (mIndexType == GL_UNSIGNED_SHORT) {
            mFrameShortIndices.assign(mFrameIndices.begin(), mFrameIndices.end());
            glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                         static_cast<GLsizeiptr>(mFrameShortIndices.size() * sizeof(std::uint16_t)),
                         mFrameShortIndices.data(), GL_STREAM_DRAW);
        } else {
            glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(mFrameIndices.size() * sizeof(std::uint32_t)),
                         mFrameIndices.data(), GL_STREAM_DRAW);
        }
        glBindVertexArray(0);
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, mCommandsBuffer.name());
        glBufferData(GL_DRAW_INDIRECT_BUFFER, static_cast<GLsizeiptr>(mCommands.size() * sizeof(DrawCommand)),
                     mCommands.data(), GL_STREAM_DRAW);
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
        return mFrameIndices.size() / 3;
    }
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
    return 0;
}

void TerrainRenderer::setFrameUniforms(const Camera& camera, const SceneStyle& style)
{
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
    for (ShaderProgram& program : mPrograms) {
        setSceneUniforms(program, camera, style, mHeader);
        mSky.setSkylight(program);
        mDetail.setCameraUniforms(program, camera.position);
        glUniform1f(program.uniform("uInverseCells"), 1.0f / static_cast<float>(mHeader.chunkSize - 1));
        glUniform1f(program.uniform("uTexels"), static_cast<float>(mHeader.textureSize));
        glUniform1f(program.uniform("uLayerTexels"), static_cast<float>(mColourLayerSize));
        glUniform1f(program.uniform("uNormalTexels"), static_cast<float>(mNormalTexels));
        glUniform1f(program.uniform("uNormalLayerTexels"), static_cast<float>(mNormalLayerSize));
    }
    mDetail.bind(contract::terrain_units::kDetail);
    mSky.bindAerialTable(contract::terrain_units::kAerialTable);
    glActiveTexture(GL_TEXTURE0);
}

void TerrainRenderer::drawGroups(RenderStats& stats, TriangleFeedback* feedback)
{
    auto drawGroup = [this](const FrameNode& f) {
        return std::array<int, 3>{f.program, arrayOf(f.drawn->slot), arrayOf(f.drawn->parentSlot)};
    };
    const std::size_t count = mFrameNodes.size();
    glBindVertexArray(mTessellation && !mBlockIndices ? mPatchVao.name() : mTemplateVao.name());
    if (mBlockIndices) {
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, mCommandsBuffer.name());
    }
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
                                                               {units::kParentNormalMaps, &parents.normalMaps},
                                                               {units::kLight, &own.light}};
        for (const auto& [unit, texture] : bindings) {
            if (*texture) {
                glActiveTexture(static_cast<GLenum>(GL_TEXTURE0 + unit));
                glBindTexture(GL_TEXTURE_2D_ARRAY, texture->name());
            }
        }
        glActiveTexture(GL_TEXTURE0);
        ShaderProgram& program = mPrograms[static_cast<std::size_t>(group[0])];
        program.use();
        const auto instances = static_cast<GLsizei>(last - first);
        if (!mBlockIndices) {
            // Instances count from the group's first node (the control shader's block codes too).
            pointNodeConstants(mConstantsBuffer, mNodeTexels, first);
            glUniform1i(program.uniform("uFirstInstance"), static_cast<GLint>(first));
        }
        if (mBlockIndices) {
            // A command a node, its constants at its base instance (the attributes count from node 0).
            pointNodeConstants(mConstantsBuffer, mNodeTexels, 0);
            const auto* commands = reinterpret_cast<const void*>(first * sizeof(DrawCommand));
            if (feedback) {
                feedback->beginDraw();
            }
            glMultiDrawElementsIndirect(GL_TRIANGLES, mIndexType, commands, instances, 0);
            if (feedback) {
                feedback->endDraw(stats.generatedTriangles);
            }
            ++stats.drawCalls;
        } else if (mTessellation && feedback) {
            // Every patch of every node in one draw: the captured triangles come node by node, in the list's order.
            glUniform1i(program.uniform("uFirstPatch"), 0);
            feedback->beginDraw();
            glDrawArraysInstanced(GL_PATCHES, 0, patches, instances);
            feedback->endDraw(stats.generatedTriangles);
            ++stats.drawCalls;
        } else if (mTessellation) {
            stats.drawCalls += drawPatchRanges(program, first, last, patches);
        } else {
            glDrawElementsInstanced(GL_TRIANGLES, mIndexCount, mIndexType, nullptr, instances);
            ++stats.drawCalls;
        }
        first = last;
    }
    if (mBlockIndices) {
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
    }
    glBindVertexArray(0);
}

int TerrainRenderer::drawPatchRanges(ShaderProgram& program, std::size_t first, std::size_t last, int patches)
{
    // Mesa's draw module (llvmpipe) grows its tessellation output with a reallocation per patch, for each
    // instance: the copying grows with the square of the patches an instance draws. So the group's nodes are drawn
    // kNodesPerRun at a time, and each run's patches kPatchesPerDraw at a time (patch ranges in order), which
    // keeps the nodes nearly front to back. The drawn order then depends on the runs, which can differ with the
    // pool arrays' grouping; terrain.tese keeps the skirts behind any surface at equal depth, so no pixel depends
    // on it. The first patch comes as a uniform with `first` 0: llvmpipe fetches the wrong patches for a
    // GL_PATCHES draw with `first` above 0.
    const GLint firstPatch = program.uniform("uFirstPatch");
    const GLint firstInstance = program.uniform("uFirstInstance");
    int draws = 0;
    for (std::size_t run = first; run < last; run += kNodesPerRun) {
        const std::size_t end = std::min(last, run + kNodesPerRun);
        pointNodeConstants(mConstantsBuffer, mNodeTexels, run);
        glUniform1i(firstInstance, static_cast<GLint>(run));
        for (int patch = 0; patch < patches; patch += kPatchesPerDraw) {
            glUniform1i(firstPatch, patch);
            glDrawArraysInstanced(GL_PATCHES, 0, std::min(kPatchesPerDraw, patches - patch),
                                  static_cast<GLsizei>(end - run));
            ++draws;
        }
    }
    return draws;
}

}  // namespace terrain
