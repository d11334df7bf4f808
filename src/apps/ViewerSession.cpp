#include "apps/ViewerSession.h"

#include "apps/DetailSetup.h"
#include "lod/HeightQuery.h"
#include "lod/NodeHorizons.h"
#include "lod/TessellationLevels.h"
#include "synthesis/NormalMap.h"

#include <algorithm>
#include <cmath>

namespace terrain {

namespace {

/// How far around a box the previous frame's depth must hide it (DepthOcclusion): the image moves in the frames
/// between that depth and the one drawn with it (TerrainRenderer::kPixelCountLag), most at silhouettes a low
/// flight crosses.
constexpr int kOcclusionMarginPixels = 8;
/// The most samples a side of the height grid the shadows' horizons are searched over (staticHeightGrid): 16 MiB.
constexpr int kHorizonGridSide = 2049;

/// lod_mode = clipmap: the finest ring's quadtree level, the deepest whose spacing is at least
/// clipmap_finest_spacing (and lod_minimum_spacing), below the map's data only with synthesis.
int clipmapFinestLevel(const TengineOptions& o, const MapHeader& header, bool synthesis)
{
    const double limit = std::max(o.clipmapFinestSpacing, o.lodMinimumSpacing);
    const int deepest = synthesis ? NodeId::kMaxLevel : static_cast<int>(header.levels) - 1;
    int level = 0;
    while (level < deepest && header.spacingAt(level + 1) >= limit) {
        ++level;
    }
    return level;
}

/// What the viewer's node at a level holds, as a charge against the node cache's byte budget, for the viewer and
/// the error tool alike (so both hold the same nodes, though the tool's make no textures or horizons): `baseBytes`
/// (a static root's CPU data without horizons: at least a dynamic node's) plus, with shadows, the horizon lattices
/// of its level (its own and its parent's quarter, horizonLatticeSize over the grid of staticHeightGrid).
NodeCharge viewerNodeCharge(const MapHeader& header, std::size_t baseBytes, bool shadows, int azimuths)
{
    if (!shadows) {
        return [baseBytes](const NodeData&) { return baseBytes; };
    }
    const int n = static_cast<int>(header.chunkSize);
    const double gridSpacing = header.spacingAt(staticHeightGridLevel(header, kHorizonGridSide));
    return [=](const NodeData& node) {
        const int level = node.id.level;
        const int own = horizonLatticeSize(n, header.spacingAt(level), gridSpacing);
        const int parent = level > 0 ? (horizonLatticeSize(n, header.spacingAt(level - 1), gridSpacing) - 1) / 2 + 1
                                     : (own - 1) / 2 + 1;
        return baseBytes + static_cast<std::size_t>((own * own + parent * parent) * azimuths);
    };
}

}  // namespace

ViewerSession::ViewerSession(const TengineOptions& options, SessionUse use, std::function<void(const std::string&)> log)
    : mOptions(options), mUse(use), mLog(std::move(log))
{
}

ViewerSession::~ViewerSession() = default;

Expected<std::unique_ptr<ViewerSession>> ViewerSession::open(const TengineOptions& options,
                                                             const std::filesystem::path& materialsDirectory,
                                                             SessionUse use,
                                                             std::function<void(const std::string&)> log,
                                                             const MapFile* map)
{
    std::unique_ptr<ViewerSession> session(new ViewerSession(options, use, std::move(log)));
    if (map) {
        session->mMap = map;
    } else {
        auto opened = MapFile::open(options.mapFile, options.reader);
        TERRAIN_TRY(opened);
        session->mOwnedMap = std::move(opened).value();
        session->mMap = session->mOwnedMap.get();
    }
    const MapHeader& header = session->header();
    const int cells = static_cast<int>(header.chunkSize) - 1;
    // Normal maps are drawn, not measured.
    if (use == SessionUse::View && options.dynamicTextureSize > 0 &&
        normalMapCells(options.dynamicTextureSize) > cells << kMaxNormalMapDepth) {
        return makeError("dynamic_texture_size ", options.dynamicTextureSize, " is more than ", 1 << kMaxNormalMapDepth,
                         "x the ", cells, " cells of ", session->mMap->name(),
                         "'s nodes: normal maps sample the surface at most that many levels below a node, and more "
                         "texels would only interpolate it (at most ",
                         cells << kMaxNormalMapDepth, ")");
    }
    auto synthesis = session->openSynthesis(materialsDirectory);
    TERRAIN_TRY(synthesis);
    return session;
}

Status ViewerSession::openSynthesis(const std::filesystem::path& materialsDirectory)
{
    // Detail synthesis (3.4): the synthesizer dynamic nodes are made with, null when it is off.
    std::vector<std::string> warnings;
    auto synthesizer = makeDetailSynthesizer(mOptions, header(), materialsDirectory, warnings);
    for (const auto& warning : warnings) {
        mLog("warning: " + warning);
    }
    TERRAIN_TRY(synthesizer);
    mSynthesizer = std::move(synthesizer).value();
    if (!mSynthesizer) {
        return {};
    }
    if (!header().hasDetailErrors()) {
        mLog("warning: " + mMap->name() +
             " has no estimates of the detail error below its leaves (made by an older prep): no dynamic nodes; "
             "run prep again to get them");
        return {};
    }
    auto recipe = viewerDetailRecipe(mOptions, *mSynthesizer, materialsDirectory);
    TERRAIN_TRY(recipe);
    const auto files = synthesizedMaterialFiles(mOptions, *mSynthesizer, materialsDirectory);
    if (auto mismatch = detailRecipeMismatch(header(), mMap->name(), *recipe, files)) {
        mLog("warning: " + *mismatch);
    }
    return {};
}

const MaterialSet* ViewerSession::materials() const
{
    return mSynthesizer ? mSynthesizer->settings().materials.get() : nullptr;
}

void ViewerSession::openClipmap()
{
    const TengineOptions& o = mOptions;
    const bool synthesis = mSynthesizer && header().hasDetailErrors();
    const int finest = clipmapFinestLevel(o, header(), synthesis);
    mClipmapLayout.emplace(extentOf(header()), static_cast<int>(header().chunkSize), o.clipmapSamples, finest, 0);
    const MaterialSet* set = materials();
    const bool detailTextures = set && std::any_of(set->materials().begin(), set->materials().end(),
                                                   [](const Material& m) { return !m.detailTextures.empty(); });
    const int normalTexels = o.dynamicTextureSize > 0 ? normalMapTexels(o.dynamicTextureSize) : 0;
    // The sun's visibility in the rings' colours, for the session's sun (sun_azimuth: clockwise from north).
    std::optional<ClipmapSun> sun;
    if (o.shadows) {
        const double azimuth = o.sunAzimuth * kRadiansPerDegree;
        sun = ClipmapSun{std::atan2(std::cos(azimuth), std::sin(azimuth)), o.sunElevation * kRadiansPerDegree};
    }
    mClipmap = std::make_unique<ClipmapTerrain>(*mClipmapLayout, static_cast<int>(header().chunkSize),
                                                static_cast<int>(header().textureSize), detailTextures, normalTexels,
                                                o.clipmapMorphSeconds, sun);
}

Status ViewerSession::startStreaming(const GlCapabilities& gl)
{
    TERRAIN_EXPECTS(!mStreamer, "the session streams already");
    const TengineOptions& o = mOptions;
    const bool view = mUse == SessionUse::View;
    const bool clipmap = o.clipmap && view;
    mTessellation = o.tessellation && !clipmap;
    mBlockIndices = mTessellation && o.blockIndices;
    if (mBlockIndices && !gl.multiDrawIndirect) {
        mLog(std::string("warning: render_mode = blocks needs OpenGL 4.3 (indirect draws with base instances), which "
                         "this GL lacks: ") +
             (gl.tessellation ? "drawing the blocks by tessellation shaders" : "drawing chunks"));
        mBlockIndices = false;
        mTessellation = gl.tessellation;
    }
    if (mTessellation && !mBlockIndices && !gl.tessellation) {
        mLog(
            "warning: render_mode = tessellation needs OpenGL 4.0 tessellation shaders, which this GL lacks: "
            "drawing chunks");
        mTessellation = false;
    }
    mCountPixels = view && o.visibilityLod && gl.pixelCounts;
    if (view && o.visibilityLod && clipmap) {
        mLog("warning: lod_mode = clipmap draws no quadtree selection: visibility_lod has no effect");
        mCountPixels = false;
    } else if (view && o.visibilityLod && !gl.pixelCounts) {
        mLog(
            "warning: visibility_lod needs OpenGL 4.3 (or GL_ARB_shader_storage_buffer_object and "
            "GL_ARB_shader_image_load_store) to count visible pixels, which this GL lacks: refining all in view");
    }
    if (clipmap) {
        openClipmap();
    }
    if (mCountPixels) {
        mVisibility.emplace(o.visibilityHiddenFrames);
    }
    mRgtc2 = compressNormalMaps(o, gl.softwareRasterizer) && !clipmap;
    mBlockPixels = mTessellation ? o.lodError * o.tessellationShare : 0.0;
    mNodePixels = mTessellation ? o.lodError * (1.0 - o.tessellationShare) : o.lodError;
    const int blockQuads = mTessellation ? kTessellationBlockQuads : 0;
    // The cache holds what the viewer's would: its nodes' CPU bytes are those of the viewer's source (a static
    // root, which holds its height codes too, costs at least what a dynamic node does).
    DetailPolicy viewerPolicy{mSynthesizer.get(), o.lodMinimumSpacing, blockQuads, o.dynamicTextureSize, true, mRgtc2};
    // The renderer's pools hold the quadtree's shadows; the clipmap's rings hold the sun's visibility themselves.
    mShadows = o.shadows && !clipmap && view;
    if (o.shadows && view) {
        std::vector<std::string> unreadable;
        auto grid = staticHeightGrid(*mMap, kHorizonGridSide, &unreadable);
        TERRAIN_TRY(grid);
        if (!unreadable.empty()) {
            // The loading threads report each node as they meet it; here only that the shadows make do.
            mLog("warning: shadows: " + std::to_string(unreadable.size()) +
                 " static node(s) could not be read; the horizons use their parents' heights there");
        }
        viewerPolicy.horizonGrid = std::make_shared<const HeightGrid>(std::move(grid).value());
    }
    mSource = std::make_unique<TerrainNodeSource>(
        *mMap, view ? viewerPolicy : DetailPolicy{mSynthesizer.get(), o.lodMinimumSpacing, blockQuads});
    auto root = view ? mSource->loadRoot() : TerrainNodeSource(*mMap, viewerPolicy).loadRoot();
    TERRAIN_TRY(root);
    // Every node is charged what the viewer's node at its level holds. The slots are sized for the deepest
    // level's (the first dynamic level's, or the leaves' without dynamic nodes): most nodes of a detailed view are
    // there, and the static nodes no finer than the horizon grid, with a point a sample, are fewer. The cache's
    // byte budget holds whatever the mix (NodeCache: larger nodes leave slots empty).
    const NodeCharge charge = viewerNodeCharge(
        header(), residentBytes(**root) - (*root)->horizons.codes.capacity() - (*root)->parentHorizons.codes.capacity(),
        o.shadows, viewerPolicy.horizonOptions.azimuths);
    NodeData deepest;
    deepest.id.level = static_cast<int>(header().levels) - (o.detailCreateNewNodes ? 0 : 1);
    const std::size_t nodeBytes = charge(deepest);
    mCache = chooseCacheSize(o, header(), materials(), gl.s3tc, mRgtc2, nodeBytes, clipmap ? SIZE_MAX : gl.maxSlots);

    StreamerOptions streamerOptions;
    streamerOptions.cacheSize = mCache.nodes;
    streamerOptions.cacheBytes = mCache.cpuBytes;
    streamerOptions.cacheCharge = charge;
    streamerOptions.queueLimit = static_cast<std::size_t>(o.requestQueueSize);
    streamerOptions.workers = o.workerThreads;
    streamerOptions.velocityLimit = view ? o.detailVelocityLimit : 0.0;  // measured: loaded to completion
    streamerOptions.revealSeconds = o.visibilityRevealSeconds;
    auto streamer = TerrainStreamer::create(*mSource, extentOf(header()), streamerOptions);
    TERRAIN_TRY(streamer);
    mStreamer = std::move(streamer).value();
    mStreamer->onLoadError([this](const std::string& message) {
        if (mLoadErrors++ == 0) {
            mFirstLoadError = message;
        }
        mLog(message);
    });
    if (!view || o.videoMeasureErrorEvery > 0) {
        // The reference nodes are the viewer's surfaces without the bounds, normal maps and tessellation errors
        // they do not need.
        mReferenceSource = std::make_unique<TerrainNodeSource>(
            *mMap, DetailPolicy{mSynthesizer.get(), o.lodMinimumSpacing, 0, 0, false});
        mMeter =
            std::make_unique<ErrorMeter>(header(), *mReferenceSource, ErrorMeterOptions{o.lodError / 8.0, 1024, 16});
    }
    return {};
}

FrameVisibility ViewerSession::takeVisibility(PixelCountSource* counts, const Camera& camera, double clock,
                                              BoxOccluded& occluded)
{
    FrameVisibility visibility;
    if (!mVisibility || counts == nullptr) {
        return visibility;
    }
    while (counts->takePixelCounts(mPixelCounts)) {
        const PixelCounts& c = mPixelCounts;
        mVisibility->record(c.frame, c.nodes, c.pixels);
        mOcclusion.reset();
        if (!c.depth.empty()) {
            mOcclusion.emplace(c.depth, c.camera.viewportWidth, c.camera.viewportHeight, c.camera,
                               kOcclusionMarginPixels);
        }
    }
    const TerrainStreamer& streamer = *mStreamer;
    const double moved = mOcclusion ? glm::length(camera.position - mOcclusion->eye()) : 0.0;
    visibility.hidden = hiddenFrom(
        *mVisibility, mOcclusion ? &*mOcclusion : nullptr, streamer.tree(),
        [&streamer](const NodeId& id) { return streamer.childrenResident(id); }, moved);
    visibility.time = clock;
    if (mOcclusion) {
        occluded = [&occlusion = *mOcclusion, moved](const Aabb& box) { return occlusion.occluded(box, moved); };
    }
    return visibility;
}

FrameStats ViewerSession::advance(const Camera& camera, double clock, double speed, Settle settle,
                                  PixelCountSource* counts)
{
    TERRAIN_EXPECTS(mStreamer, "advance() before startStreaming()");
    if (mClipmap) {
        return advanceClipmap(camera, clock, settle);
    }
    BoxOccluded occluded;
    const FrameVisibility visibility = takeVisibility(counts, camera, clock, occluded);
    FrameStats stats = mStreamer->settle(settle, camera, mNodePixels, speed, visibility);
    if (!mOptions.geomorph) {  // the renderer then draws every node at its own detail
        mUnmorphed = unmorphed(mStreamer->selection());
    }
    mDrawList = makeDrawList(drawnSelection(), *mStreamer, camera, mBlockPixels, std::move(occluded));
    return stats;
}

FrameStats ViewerSession::advanceClipmap(const Camera& camera, double clock, Settle settle)
{
    ClipmapLayout& layout = *mClipmapLayout;
    ClipmapTerrain& clipmap = *mClipmap;
    clipmap.clearChanges();  // the previous frame drew them
    TerrainStreamer& streamer = *mStreamer;
    const ResidentNodeLookup resident = [&streamer](const NodeId& id) { return streamer.node(id); };
    auto entered = layout.moveTo(camera.position.x, camera.position.y);
    // The ground below from the rings as they are (the finest one covers the viewer).
    auto firstRing = [&] {
        const double ground = header().heightOffset + clipmap.heightAt(layout, 0, camera.position.x, camera.position.y);
        return layout.finestActiveRing(std::max(0.0, camera.position.z - ground));
    };
    auto select = [&] {
        mClipmapFirstRing = firstRing();
        const FrameStats stats = streamer.updateFor(clipmap.wanted(layout, mClipmapFirstRing));
        clipmap.update(layout, entered, resident, clock);
        for (auto& rects : entered) {  // the windows moved once: later rounds only fill
            rects.clear();
        }
        return stats;
    };
    // The rings just filled may put the ground nearer than it seemed (the first frame's were empty).
    return streamer.settle(settle, select, [&] { return firstRing() != mClipmapFirstRing; });
}

const LodSelection& ViewerSession::drawnSelection() const
{
    return mOptions.geomorph ? mStreamer->selection() : mUnmorphed;
}

std::optional<double> ViewerSession::drawnHeightAt(double x, double y) const
{
    if (mClipmap) {
        return header().heightOffset + mClipmap->heightAt(*mClipmapLayout, 0, x, y);
    }
    return terrain::drawnHeightAt(*mStreamer, header(), x, y);
}

Expected<FrameError> ViewerSession::measureDrawn(const Camera& camera, const MeasuredVisibility& visibility)
{
    TERRAIN_EXPECTS(mMeter, "measureDrawn() without an error meter");
    if (mClipmap) {
        // lod_mode = clipmap: the rings' surface as drawn, against the same reference.
        return mMeter->measureSurface(
            [this](double x, double y) { return mClipmap->drawnHeight(*mClipmapLayout, mClipmapFirstRing, x, y); },
            camera, visibility);
    }
    const TerrainStreamer& streamer = *mStreamer;
    return mMeter->measure(
        mDrawList, [&streamer](const NodeId& id) { return streamer.node(id); }, mOptions.lodError, visibility);
}

}  // namespace terrain
