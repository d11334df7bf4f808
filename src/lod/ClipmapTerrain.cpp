// Clipmap ring data from the quadtree's resident nodes (seed 002's toroidal updates; ClipmapTerrain.h).
#include "lod/ClipmapTerrain.h"

#include "core/Check.h"
#include "light/Horizon.h"
#include "quadtree/ChunkGeometry.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace terrain {

ClipmapTerrain::ClipmapTerrain(const ClipmapLayout& layout, int chunkSize, int textureSize, bool materials,
                               int normalMapTexels, double morphSeconds, std::optional<ClipmapSun> sun)
    : mSamples(layout.samples()),
      mChunk(chunkSize),
      mTexture(textureSize),
      mNormalTexels(normalMapTexels),
      mNormalPerCell(normalMapTexels > 0 ? std::max(1, (normalMapTexels - 1) / (chunkSize - 1)) : 0),
      mMorphSeconds(morphSeconds),
      mSun(sun),
      mRings(static_cast<std::size_t>(layout.ringCount()))
{
    TERRAIN_EXPECTS(chunkSize >= 3 && textureSize >= 2, "chunks have at least 3 samples and textures 2 texels");
    TERRAIN_EXPECTS(normalMapTexels == 0 || normalMapTexels >= 2, "a normal map has at least 2 texels a side");
    TERRAIN_EXPECTS(morphSeconds >= 0.0, "the morph takes no negative time");
    const auto normalSide = static_cast<std::size_t>(mNormalPerCell) * static_cast<std::size_t>(mSamples);
    const auto samples = static_cast<std::size_t>(mSamples) * static_cast<std::size_t>(mSamples);
    for (ClipmapRing& ring : mRings) {
        ring.heights.assign(samples, 0.0f);
        ring.morph.assign(2 * samples, kNoMorph);
        for (std::size_t i = 0; i < samples; ++i) {
            ring.morph[2 * i] = 0.0f;  // the height, as it starts
        }
        ring.colour.assign(samples * 4, 255);
        ring.previousColour = ring.colour;
        ring.sky.assign(samples * 2, 255);
        if (materials) {
            ring.materials.assign(samples * 4, 0);
            ring.previousMaterials = ring.materials;
        }
        // Flat (0, 0, 1) until filled.
        ring.normals.assign(normalSide * normalSide * 2, 0);
        ring.previousNormals = ring.normals;
    }
}

void ClipmapTerrain::clearChanges()
{
    for (ClipmapRing& ring : mRings) {
        ring.changed.clear();
    }
}

std::size_t ClipmapTerrain::upsampledNodes() const
{
    std::size_t count = 0;
    for (const ClipmapRing& ring : mRings) {
        count += ring.upsampled.size();
    }
    return count;
}

std::size_t ClipmapTerrain::bytes() const
{
    std::size_t total = 0;
    for (const ClipmapRing& ring : mRings) {
        total += (ring.heights.size() + ring.morph.size()) * sizeof(float) + 2 * ring.colour.size() +
                 2 * ring.materials.size() + ring.sky.size() + 2 * ring.normals.size();
    }
    return total;
}

float ClipmapTerrain::morphDone(int ring, std::size_t t) const
{
    // As shaders/clipmap.vert computes it, in float.
    if (mMorphSeconds <= 0.0) {
        return 1.0f;
    }
    const float since = mRings[static_cast<std::size_t>(ring)].morph[2 * t + 1];
    return std::clamp((clock() - since) / static_cast<float>(mMorphSeconds), 0.0f, 1.0f);
}

float ClipmapTerrain::drawnSample(int ring, std::size_t t) const
{
    const ClipmapRing& data = mRings[static_cast<std::size_t>(ring)];
    const float done = morphDone(ring, t);
    const float previous = data.morph[2 * t];
    // Exactly the height once the morph is over (previous + (h - previous) * 1 need not be h in float).
    return done >= 1.0f ? data.heights[t] : previous + (data.heights[t] - previous) * done;
}

namespace {

LatticeRect windowRect(const ClipmapWindow& w, int n)
{
    return {w.x0, w.y0, w.x0 + n, w.y0 + n};
}

LatticeRect intersect(const LatticeRect& a, const LatticeRect& b)
{
    return {std::max(a.x0, b.x0), std::max(a.y0, b.y0), std::min(a.x1, b.x1), std::min(a.y1, b.y1)};
}

/// The samples of node `id`'s square (edges included) in its level's grid.
LatticeRect nodeSquare(const NodeId& id, int chunk)
{
    const std::int64_t cells = chunk - 1;
    return {std::int64_t{id.x} * cells, std::int64_t{id.y} * cells, (std::int64_t{id.x} + 1) * cells + 1,
            (std::int64_t{id.y} + 1) * cells + 1};
}

/// The level-grid samples nodeSampleAt() maps to node `id` or its edges: its square, extended without bound
/// on the sides where it is the terrain's last node (outside samples are clamped to the terrain).
LatticeRect nodeRegion(const NodeId& id, int chunk)
{
    constexpr std::int64_t kFar = std::int64_t{1} << 40;
    const std::uint32_t last = (1u << id.level) - 1;
    LatticeRect r = nodeSquare(id, chunk);
    r.x0 = id.x == 0 ? -kFar : r.x0;
    r.y0 = id.y == 0 ? -kFar : r.y0;
    r.x1 = id.x == last ? kFar : r.x1;
    r.y1 = id.y == last ? kFar : r.y1;
    return r;
}

/// a / b rounded down (b > 0).
std::int64_t floorDiv(std::int64_t a, std::int64_t b)
{
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/// fill()'s per-sample states for the normal texels, besides a restarted morph's fraction done in [0, 1].
constexpr float kKept = -1.0f;
constexpr float kReset = -2.0f;

/// An 8-bit channel (colour and weights UNORM, normals SNORM) on its way from `previous` to `current`, `done` of
/// the way, as the GL blends the texels.
template <typename Channel>
Channel mixed(Channel previous, Channel current, float done)
{
    return static_cast<Channel>(std::lround(previous + (current - previous) * done));
}

}  // namespace

namespace {

/// One of a ring's 8-bit layers: `channels` bytes a sample, sample t's at current[t stride + c], what they were
/// drawn as when its morph started at previous[t stride + c]; `coarser` the coarser ring's current layer (null
/// for the coarsest ring).
struct ByteLayer {
    std::uint8_t* current;
    std::uint8_t* previous;
    const std::uint8_t* coarser;
    std::size_t stride;
    int channels;
};

/// The bytes of a sample over all its ByteLayers.
constexpr int kSampleBytes = 9;

/// Sets what sample t's bytes were drawn as when its morph started: `drawn` (the layers' bytes in order), or
/// with null their current values (no morph).
void setPrevious(const std::vector<ByteLayer>& layers, std::size_t t, const std::uint8_t* drawn)
{
    int b = 0;
    for (const ByteLayer& layer : layers) {
        for (int c = 0; c < layer.channels; ++c, ++b) {
            const std::size_t i = t * layer.stride + static_cast<std::size_t>(c);
            layer.previous[i] = drawn ? drawn[b] : layer.current[i];
        }
    }
}

}  // namespace

void ClipmapTerrain::fill(const ClipmapLayout& layout, int r, LatticeRect rect, const ResidentNodeLookup& resident,
                          Fill how)
{
    const int n = mSamples;
    ClipmapRing& ring = mRings[static_cast<std::size_t>(r)];
    rect = intersect(rect, windowRect(layout.window(r), n));
    if (rect.empty()) {
        return;
    }
    const int level = layout.window(r).level;
    const int w = windowSize(mChunk);
    const ClipmapRing* up = r + 1 < ringCount() ? &mRings[static_cast<std::size_t>(r + 1)] : nullptr;
    const bool morphs = how == Fill::kSeen && mMorphSeconds > 0.0;
    // The 8-bit layers in nodeBytes()'s order: colour, sky visibility, material weights.
    std::vector<ByteLayer> layers{
        {ring.colour.data(), ring.previousColour.data(), up ? up->colour.data() : nullptr, 4, 4},
        {ring.sky.data(), ring.sky.data() + 1, up ? up->sky.data() : nullptr, 2, 1}};
    if (!ring.materials.empty()) {
        layers.push_back(
            {ring.materials.data(), ring.previousMaterials.data(), up ? up->materials.data() : nullptr, 4, 4});
    }
    // The coarser ring's bilinear value at level-grid sample (gx, gy) of byte c of a sample of `layer` (stride
    // 1 for the heights, as floats): its window holds the point, windows nest.
    auto coarseValue = [&](const auto* layer, std::size_t stride, int c, std::int64_t gx, std::int64_t gy) {
        const std::int64_t cx = gx >> 1, cy = gy >> 1, dx = gx & 1, dy = gy & 1;
        float value = 0.0f;
        for (std::int64_t j = 0; j <= dy; ++j) {
            for (std::int64_t i = 0; i <= dx; ++i) {
                const std::size_t u = static_cast<std::size_t>(toroidalTexel(cy + j, n)) * n + toroidalTexel(cx + i, n);
                value += (dx ? 0.5f : 1.0f) * (dy ? 0.5f : 1.0f) * static_cast<float>(layer[u * stride + c]);
            }
        }
        return value;
    };
    // Per sample of `rect` (row-major), for its normal texels: how far its morph had gone when it restarted
    // (in [0, 1]), kReset when its morph was cleared, kKept when it was left as it was.
    std::vector<float> state(static_cast<std::size_t>(rect.area()), kKept);
    // Node lookups are per node, not per sample: the last one is kept. The nodes' sun visibility (sun, sky a
    // sample) is derived once a node in this fill (rows cross the same nodes again).
    NodeId lastId{-1, 0, 0};
    NodePtr node;
    std::unordered_map<std::uint64_t, std::vector<std::uint8_t>> visibilities;
    const std::vector<std::uint8_t>* visibility = nullptr;
    for (std::int64_t gy = rect.y0; gy < rect.y1; ++gy) {
        for (std::int64_t gx = rect.x0; gx < rect.x1; ++gx) {
            const NodeSample at = nodeSampleAt(level, gx, gy, mChunk);
            if (!(at.id == lastId)) {
                lastId = at.id;
                node = resident(at.id);
                visibility = sunVisibility(node.get(), visibilities);
            }
            const std::size_t t = static_cast<std::size_t>(toroidalTexel(gy, n)) * n + toroidalTexel(gx, n);
            // What the sample is drawn as now, before it changes: where a morph starts from.
            const float done = morphDone(r, t);
            const float drawn = drawnSample(r, t);
            const float heightBefore = ring.heights[t];
            std::array<std::uint8_t, kSampleBytes> fresh{};
            const std::array<bool, 3> have =
                nodeBytes(node.get(), visibility, at.u - kBorder, at.v - kBorder, !ring.materials.empty(), fresh);
            if (node) {
                ring.heights[t] = node->heights.height(static_cast<std::size_t>(at.v) * w + at.u);
            } else if (up) {
                ring.heights[t] = coarseValue(up->heights.data(), 1, 0, gx, gy);
            }
            bool changed = ring.heights[t] != heightBefore;
            std::array<std::uint8_t, kSampleBytes> drawnBytes{};
            int b = 0;
            for (std::size_t l = 0; l < layers.size(); ++l) {
                const ByteLayer& layer = layers[l];
                for (int c = 0; c < layer.channels; ++c, ++b) {
                    std::uint8_t& current = layer.current[t * layer.stride + c];
                    drawnBytes[b] = mixed(layer.previous[t * layer.stride + c], current, done);
                    if (have[l] || up) {  // else kept: nothing to take it from
                        const std::uint8_t value = have[l] ? fresh[b]
                                                           : static_cast<std::uint8_t>(std::lround(
                                                                 coarseValue(layer.coarser, layer.stride, c, gx, gy)));
                        changed = changed || value != current;
                        current = value;
                    }
                }
            }
            const std::size_t k = static_cast<std::size_t>((gy - rect.y0) * (rect.x1 - rect.x0) + (gx - rect.x0));
            if (morphs && (changed || done >= 1.0f)) {
                // A sample of a node that arrives morphs from what is drawn: changed ones, and unchanged ones
                // from themselves (their normal texels may change); unchanged ones on their way keep going.
                ring.morph[2 * t] = drawn;
                ring.morph[2 * t + 1] = clock();
                setPrevious(layers, t, drawnBytes.data());
                state[k] = done;
            } else if (how == Fill::kEntered || (how == Fill::kUnseen && changed)) {
                // No morph: entered samples are new to the window (at its perimeter, where the transition blend
                // draws the coarser ring anyway; their texel may hold another sample's morph), and samples
                // filled in the update that upsampled them were never drawn. Unchanged samples keep a morph
                // under way (a neighbour's edge).
                ring.morph[2 * t] = ring.heights[t];
                ring.morph[2 * t + 1] = kNoMorph;
                setPrevious(layers, t, nullptr);
                state[k] = kReset;
            }
            if (!node) {
                ring.upsampled.emplace(at.id.key(), ClipmapRing::Upsampled{at.id, mNow});
            }
        }
    }
    if (mNormalPerCell > 0) {
        fillNormals(layout, r, rect, resident, state);
    }
    ring.changed.push_back(rect);
}

const std::vector<std::uint8_t>* ClipmapTerrain::sunVisibility(
    const NodeData* node, std::unordered_map<std::uint64_t, std::vector<std::uint8_t>>& cache) const
{
    if (!mSun || !node || node->horizons.size < 2) {
        return nullptr;
    }
    auto [it, made] = cache.try_emplace(node->id.key());
    if (made) {
        it->second.resize(static_cast<std::size_t>(mChunk) * static_cast<std::size_t>(mChunk) * 2);
        latticeVisibility(node->horizons, mSun->azimuth, mSun->elevation, kShadowSoftness, mChunk, it->second, 2, 0);
    }
    return &it->second;
}

std::array<bool, 3> ClipmapTerrain::nodeBytes(const NodeData* node, const std::vector<std::uint8_t>* visibility, int u,
                                              int v, bool materials, std::span<std::uint8_t> out) const
{
    std::array<bool, 3> have{};
    if (!node) {
        return have;
    }
    const std::size_t sample = static_cast<std::size_t>(v) * static_cast<std::size_t>(mChunk) + u;
    // The colour: the texel nearest the sample (textures have T x T texels over the node's square, corners on
    // corners), and the sun's visibility.
    have[0] = !node->texture.empty();
    if (have[0]) {
        const int tx = static_cast<int>(std::lround(u * (mTexture - 1.0) / (mChunk - 1)));
        const int ty = static_cast<int>(std::lround(v * (mTexture - 1.0) / (mChunk - 1)));
        const std::size_t k = (static_cast<std::size_t>(ty) * mTexture + tx) * 3;
        std::copy_n(node->texture.begin() + static_cast<std::ptrdiff_t>(k), 3, out.begin());
        out[3] = visibility ? (*visibility)[sample * 2] : 255;
    }
    have[1] = true;
    out[4] = visibility ? (*visibility)[sample * 2 + 1] : 255;
    have[2] = materials && !node->materialWeights.empty();
    if (have[2]) {
        std::copy_n(node->materialWeights.begin() + static_cast<std::ptrdiff_t>(sample * 4), 4, out.begin() + 5);
    }
    return have;
}

void ClipmapTerrain::fillNormals(const ClipmapLayout& layout, int r, const LatticeRect& rect,
                                 const ResidentNodeLookup& resident, const std::vector<float>& state)
{
    // Each sample's block of q x q texels (the cell north-east of it); a texel takes its node's normal map
    // texel there (nearest when the maps have fewer texels than the node has cells), or, where the node is
    // not resident, the mean of the coarser ring's texels around the same point.
    const int q = mNormalPerCell;
    const int side = q * mSamples;
    const int level = layout.window(r).level;
    const int cells = mChunk - 1;
    const int mapCells = mNormalTexels - 1;
    ClipmapRing& ring = mRings[static_cast<std::size_t>(r)];
    const ClipmapRing* up = r + 1 < ringCount() ? &mRings[static_cast<std::size_t>(r + 1)] : nullptr;
    NodeId lastId{-1, 0, 0};
    NodePtr node;
    for (std::int64_t ty = rect.y0 * q; ty < rect.y1 * q; ++ty) {
        for (std::int64_t tx = rect.x0 * q; tx < rect.x1 * q; ++tx) {
            const std::int64_t gx = floorDiv(tx, q), gy = floorDiv(ty, q);  // windows reach past the terrain
            const std::int64_t fx = tx - gx * q, fy = ty - gy * q;
            const NodeSample at = nodeSampleAt(level, gx, gy, mChunk);
            if (!(at.id == lastId)) {
                lastId = at.id;
                node = resident(at.id);
            }
            const std::size_t t =
                (static_cast<std::size_t>(toroidalTexel(ty, side)) * side + toroidalTexel(tx, side)) * 2;
            const float sampleState =
                state[static_cast<std::size_t>((gy - rect.y0) * (rect.x1 - rect.x0) + (gx - rect.x0))];
            if (sampleState >= 0.0f) {
                // Its sample's morph restarted: the texel's starts from what is drawn.
                for (int c = 0; c < 2; ++c) {
                    ring.previousNormals[t + c] = mixed(ring.previousNormals[t + c], ring.normals[t + c], sampleState);
                }
            }
            if (node && !node->normalMap.empty()) {
                // Position in the node's cells, then in its map's texels (clamped: outside the terrain).
                const double px = (at.u - kBorder) + static_cast<double>(fx) / q;
                const double py = (at.v - kBorder) + static_cast<double>(fy) / q;
                const int mx = std::clamp(static_cast<int>(std::lround(px * mapCells / cells)), 0, mapCells);
                const int my = std::clamp(static_cast<int>(std::lround(py * mapCells / cells)), 0, mapCells);
                const std::size_t k = (static_cast<std::size_t>(my) * mNormalTexels + mx) * 2;
                ring.normals[t] = node->normalMap[k];
                ring.normals[t + 1] = node->normalMap[k + 1];
            } else if (up) {
                // The coarser ring's texel grid has the same q per (coarser) cell: this point is at texel t / 2.
                int sum[2] = {0, 0};
                int count = 0;
                for (std::int64_t j = ty >> 1; j <= (ty + 1) >> 1; ++j) {
                    for (std::int64_t i = tx >> 1; i <= (tx + 1) >> 1; ++i) {
                        const std::size_t u =
                            (static_cast<std::size_t>(toroidalTexel(j, side)) * side + toroidalTexel(i, side)) * 2;
                        sum[0] += up->normals[u];
                        sum[1] += up->normals[u + 1];
                        ++count;
                    }
                }
                ring.normals[t] = static_cast<std::int8_t>(sum[0] / count);
                ring.normals[t + 1] = static_cast<std::int8_t>(sum[1] / count);
            }
            if (sampleState == kReset) {
                ring.previousNormals[t] = ring.normals[t];
                ring.previousNormals[t + 1] = ring.normals[t + 1];
            }
        }
    }
}

void ClipmapTerrain::update(const ClipmapLayout& layout, const std::vector<std::vector<LatticeRect>>& entered,
                            const ResidentNodeLookup& resident, double now)
{
    TERRAIN_EXPECTS(static_cast<int>(entered.size()) == ringCount(), "one list of entered samples per ring");
    TERRAIN_EXPECTS(mFirst || now >= mNow, "the clipmap's clock never goes back");
    if (mFirst) {
        mEpoch = now;
        mFirst = false;
    }
    mNow = now;
    const int n = mSamples;
    bool coarserChanged = false;
    for (int r = ringCount() - 1; r >= 0; --r) {
        ClipmapRing& ring = mRings[static_cast<std::size_t>(r)];
        const std::size_t changedBefore = ring.changed.size();
        const LatticeRect window = windowRect(layout.window(r), n);
        // Upsampled nodes: forget those the window left; fill again those that arrived, or all of them when
        // the coarser ring they were upsampled from changed.
        // The samples of a node upsampled at an earlier update were drawn: their change morphs.
        std::vector<ClipmapRing::Upsampled> refill;
        for (auto it = ring.upsampled.begin(); it != ring.upsampled.end();) {
            const NodeId id = it->second.id;
            if (intersect(nodeRegion(id, mChunk), window).empty()) {
                it = ring.upsampled.erase(it);
            } else if (coarserChanged || resident(id)) {
                refill.push_back(it->second);
                it = ring.upsampled.erase(it);
            } else {
                ++it;
            }
        }
        for (const LatticeRect& rect : entered[static_cast<std::size_t>(r)]) {
            fill(layout, r, rect, resident, Fill::kEntered);
        }
        std::sort(refill.begin(), refill.end(), [](const ClipmapRing::Upsampled& a, const ClipmapRing::Upsampled& b) {
            return a.id.key() < b.id.key();
        });
        for (const ClipmapRing::Upsampled& node : refill) {
            fill(layout, r, nodeRegion(node.id, mChunk), resident, node.since < now ? Fill::kSeen : Fill::kUnseen);
            if (auto again = ring.upsampled.find(node.id.key()); again != ring.upsampled.end()) {
                // Still missing (upsampled again from the coarser ring that changed): drawn since `since`.
                again->second.since = node.since;
            }
        }
        if (ring.changed.size() != changedBefore) {
            // Over the heights and where morphs start (a box that holds every height drawn until they end).
            float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
            for (float h : ring.heights) {
                lo = std::min(lo, h);
                hi = std::max(hi, h);
            }
            for (std::size_t i = 0; i < ring.morph.size(); i += 2) {
                if (morphDone(r, i / 2) < 1.0f) {
                    lo = std::min(lo, ring.morph[i]);
                    hi = std::max(hi, ring.morph[i]);
                }
            }
            ring.zMin = lo;
            ring.zMax = hi;
        }
        coarserChanged = ring.changed.size() != changedBefore;
    }
}

double ClipmapTerrain::heightAt(const ClipmapLayout& layout, int ring, double x, double y) const
{
    const ClipmapWindow& w = layout.window(ring);
    const double s = layout.spacing(ring);
    const double n1 = mSamples - 1.0;
    const double gx = std::clamp((x - layout.worldX(ring, 0.0)) / s - static_cast<double>(w.x0), 0.0, n1);
    const double gy = std::clamp((y - layout.worldY(ring, 0.0)) / s - static_cast<double>(w.y0), 0.0, n1);
    const auto i = static_cast<std::int64_t>(std::min(std::floor(gx), n1 - 1.0));
    const auto j = static_cast<std::int64_t>(std::min(std::floor(gy), n1 - 1.0));
    const double fx = gx - static_cast<double>(i), fy = gy - static_cast<double>(j);
    auto at = [&](std::int64_t a, std::int64_t b) {
        return double{drawnSample(ring, static_cast<std::size_t>(toroidalTexel(w.y0 + b, mSamples)) * mSamples +
                                            toroidalTexel(w.x0 + a, mSamples))};
    };
    return (1 - fy) * ((1 - fx) * at(i, j) + fx * at(i + 1, j)) +
           fy * ((1 - fx) * at(i, j + 1) + fx * at(i + 1, j + 1));
}

std::optional<double> ClipmapTerrain::ringSurface(const ClipmapLayout& layout, int ring, double x, double y) const
{
    const int n = mSamples;
    const ClipmapWindow& w = layout.window(ring);
    const double s = layout.spacing(ring);
    const double gx = (x - layout.worldX(ring, 0.0)) / s - static_cast<double>(w.x0);
    const double gy = (y - layout.worldY(ring, 0.0)) / s - static_cast<double>(w.y0);
    if (!(gx >= 0.0 && gy >= 0.0 && gx <= n - 1.0 && gy <= n - 1.0)) {
        return std::nullopt;
    }
    const bool coarser = ring + 1 < ringCount();
    auto sample = [&](int r, std::int64_t ax, std::int64_t ay) {
        return double{drawnSample(r, static_cast<std::size_t>(toroidalTexel(ay, n)) * n + toroidalTexel(ax, n))};
    };
    // A vertex as the vertex program makes it.
    auto vertex = [&](std::int64_t li, std::int64_t lj) {
        const std::int64_t ax = w.x0 + li, ay = w.y0 + lj;
        const double z = sample(ring, ax, ay);
        if (!coarser) {
            return z;
        }
        const double alpha = layout.blend(ring, static_cast<double>(ax), static_cast<double>(ay));
        const int up = ring + 1;
        const std::int64_t cx = ax >> 1, cy = ay >> 1;
        const double fx = (ax & 1) ? 0.5 : 0.0, fy = (ay & 1) ? 0.5 : 0.0;
        const double below = (1 - fy) * ((1 - fx) * sample(up, cx, cy) + fx * sample(up, cx + 1, cy)) +
                             fy * ((1 - fx) * sample(up, cx, cy + 1) + fx * sample(up, cx + 1, cy + 1));
        return z + alpha * (below - z);
    };
    const auto i = static_cast<std::int64_t>(std::min(std::floor(gx), n - 2.0));
    const auto j = static_cast<std::int64_t>(std::min(std::floor(gy), n - 2.0));
    const double fx = gx - static_cast<double>(i), fy = gy - static_cast<double>(j);
    const double v00 = vertex(i, j), v11 = vertex(i + 1, j + 1);
    if (fx >= fy) {
        const double v10 = vertex(i + 1, j);
        return v00 + fx * (v10 - v00) + fy * (v11 - v10);
    }
    const double v01 = vertex(i, j + 1);
    return v00 + fy * (v01 - v00) + fx * (v11 - v01);
}

std::optional<double> ClipmapTerrain::drawnHeight(const ClipmapLayout& layout, int firstRing, double x, double y) const
{
    for (int ring = firstRing; ring < ringCount(); ++ring) {
        if (auto z = ringSurface(layout, ring, x, y)) {
            return z;
        }
    }
    return std::nullopt;
}

std::vector<NodeId> ClipmapTerrain::wanted(const ClipmapLayout& layout, int firstRing) const
{
    std::vector<NodeId> ids;
    const std::int64_t cells = mChunk - 1;
    for (int r = ringCount() - 1; r >= firstRing; --r) {
        const ClipmapWindow& w = layout.window(r);
        const std::int64_t last = (std::int64_t{1} << w.level) - 1;
        const std::int64_t x0 = std::clamp<std::int64_t>(w.x0 / cells - 1, 0, last);
        const std::int64_t y0 = std::clamp<std::int64_t>(w.y0 / cells - 1, 0, last);
        const std::int64_t x1 = std::clamp<std::int64_t>((w.x0 + mSamples - 1) / cells, 0, last);
        const std::int64_t y1 = std::clamp<std::int64_t>((w.y0 + mSamples - 1) / cells, 0, last);
        for (std::int64_t y = y0; y <= y1; ++y) {
            for (std::int64_t x = x0; x <= x1; ++x) {
                const NodeId id{w.level, static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y)};
                if (!intersect(nodeSquare(id, mChunk), windowRect(w, mSamples)).empty()) {
                    ids.push_back(id);
                }
            }
        }
    }
    return ids;
}

}  // namespace terrain
