// The viewer's session without GL: a map opened with the viewer's options (detail synthesis and the check of its
// recipe against the map's, the node sources, the node cache's capacity, the streamer, the split of tau between
// the selection and the tessellation blocks, the clipmap's rings, the error meter), advanced one frame of LOD at a
// time from a camera and a time passed in. tengine draws what it selects, tengine-tool error measures it, tests
// and benchmarks drive it: all see the same nodes for the same options.
#pragma once

#include "apps/NodeBudget.h"
#include "apps/TengineOptions.h"
#include "core/Camera.h"
#include "core/Expected.h"
#include "lod/ClipmapLayout.h"
#include "lod/ClipmapTerrain.h"
#include "lod/DepthOcclusion.h"
#include "lod/DrawList.h"
#include "lod/ErrorMeter.h"
#include "lod/NodeVisibility.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "quadtree/MapFile.h"
#include "synthesis/DetailSynthesizer.h"

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace terrain {

/// What the GL the nodes are drawn with offers (tengine asks its context). The defaults are those of a software
/// rasterizer of OpenGL 4.5 with no context to ask, what tools that draw nothing take.
struct GlCapabilities {
    bool tessellation = true;                     ///< tessellation shaders (OpenGL 4.0)
    bool multiDrawIndirect = true;                ///< indirect draws with base instances (OpenGL 4.3): blocks
    bool pixelCounts = false;                     ///< counting the pixels each node shows (visibility_lod)
    bool s3tc = true;                             ///< DXT1 colour in the node pools
    bool softwareRasterizer = true;               ///< normal_map_compression = auto keeps RG8 normal maps
    std::size_t maxSlots = kSlotsWithoutContext;  ///< the node pools' most slots
};

/// What the session is for.
enum class SessionUse {
    /// Nodes as the viewer draws them: normal maps, the velocity limit, visibility_lod; the error meter only with
    /// video_measure_error_every.
    View,
    /// Nodes measured, not drawn (tengine-tool error): heights, bounds and tessellation errors without normal maps,
    /// no velocity limit, the error meter always. The cache holds what the viewer's would.
    Measure,
};

class ViewerSession {
public:
    /// Opens `options.mapFile` (or uses `map`, which must then outlive the session) and the detail synthesis of
    /// `options`, the built-in materials in `materialsDirectory`: what needs no GL, so that a bad map or material
    /// is said before a window opens. Warnings (prefixed "warning: ") and, once streaming, load errors go to `log`
    /// as they happen. Errors name the file or option and what was wrong.
    static Expected<std::unique_ptr<ViewerSession>> open(const TengineOptions& options,
                                                         const std::filesystem::path& materialsDirectory,
                                                         SessionUse use, std::function<void(const std::string&)> log,
                                                         const MapFile* map = nullptr);
    /// Opens what depends on the GL the nodes are drawn with: the node sources, the cache's capacity, the
    /// streamer (its root loaded), the clipmap's rings and the error meter. Once, before advance().
    Status startStreaming(const GlCapabilities& gl);
    ~ViewerSession();
    ViewerSession(const ViewerSession&) = delete;
    ViewerSession& operator=(const ViewerSession&) = delete;

    const TengineOptions& options() const { return mOptions; }
    const MapFile& map() const { return *mMap; }
    const MapHeader& header() const { return mMap->header(); }
    /// The synthesizer of dynamic nodes; null when detail synthesis is off.
    const DetailSynthesizer* synthesizer() const { return mSynthesizer.get(); }
    /// The materials dynamic nodes are displaced and coloured with; null without.
    const MaterialSet* materials() const;
    /// The node cache's capacity and how it was chosen (one log line).
    const CacheChoice& cache() const { return mCache; }
    /// render_mode = tessellation or blocks (the blocks' levels are chosen), and the GL draws them.
    bool tessellation() const { return mTessellation; }
    /// render_mode = blocks (tessellation() too), and the GL draws indirect commands with base instances.
    bool blockIndices() const { return mBlockIndices; }
    /// visibility_lod, and the GL counts pixels.
    bool countsPixels() const { return mCountPixels; }
    /// Normal maps as RGTC2 blocks.
    bool compressedNormalMaps() const { return mRgtc2; }
    /// Whether the viewer's nodes carry horizons and the renderer draws shadows (shadows, quadtree modes).
    bool shadows() const { return mShadows; }
    /// The selection's tau: all of lod_error, or in tessellation mode what the blocks leave of it.
    double nodePixels() const { return mNodePixels; }
    /// Tessellation mode: the blocks' part of lod_error; else 0.
    double blockPixels() const { return mBlockPixels; }

    TerrainStreamer& streamer() { return *mStreamer; }
    const TerrainStreamer& streamer() const { return *mStreamer; }
    /// The resident data of a node (what the selection draws); null if not resident.
    NodePtr node(const NodeId& id) const { return mStreamer->node(id); }
    /// The error meter (SessionUse::Measure, or video_measure_error_every); else null.
    ErrorMeter* meter() { return mMeter.get(); }
    /// Load errors so far, and the first one (file and node named); empty when none.
    std::size_t loadErrors() const { return mLoadErrors; }
    const std::string& firstLoadError() const { return mFirstLoadError; }

    /// lod_mode = clipmap (seed 002): the rings' layout and data; null in quadtree mode.
    const ClipmapLayout* clipmapLayout() const { return mClipmapLayout ? &*mClipmapLayout : nullptr; }
    /// The rings' data; what changed in the latest frame is ClipmapTerrain::changed().
    const ClipmapTerrain* clipmap() const { return mClipmap.get(); }
    /// The finest ring drawn in the latest frame.
    int clipmapFirstRing() const { return mClipmapFirstRing; }

    /// One frame of LOD for `camera`, settled as `settle` says. `clock`: seconds on the viewer's clock, never
    /// decreasing (video mode: the frame's time); `speed`: the camera's, metres per second (the velocity limit).
    /// With visibility_lod (countsPixels()), `counts` is what drew the frames so far (the renderer): the pixel
    /// counts and depth it has ready decide which nodes are hidden, and the previous frame's depth which
    /// tessellation blocks are. Quadtree mode selects and makes the frame's draw list (drawList()); clipmap
    /// mode moves the rings' windows with the camera, picks the finest ring worth drawing from its height
    /// above the ground and fills the rings with what arrived (their changes: ClipmapTerrain::changed()).
    FrameStats advance(const Camera& camera, double clock, double speed, Settle settle,
                       PixelCountSource* counts = nullptr);
    /// Quadtree mode: what the latest frame draws (lod/DrawList.h), for the renderer to draw and the meter to
    /// measure.
    const DrawList& drawList() const { return mDrawList; }
    /// What the renderer draws this frame: the selection, at each node's own detail with geomorph off.
    const LodSelection& drawnSelection() const;
    /// The height of the surface drawn at (x, y) (the rings in clipmap mode, else the selection's nodes), metres;
    /// empty outside the terrain or where nothing is resident.
    std::optional<double> drawnHeightAt(double x, double y) const;
    /// The screen-space error of what the latest frame draws (drawList(), or the rings), measured against the
    /// meter's reference at the points `visibility` says the frame shows. Precondition: meter().
    Expected<FrameError> measureDrawn(const Camera& camera, const MeasuredVisibility& visibility = {});

private:
    ViewerSession(const TengineOptions& options, SessionUse use, std::function<void(const std::string&)> log);
    Status openSynthesis(const std::filesystem::path& materialsDirectory);
    void openClipmap();
    FrameStats advanceClipmap(const Camera& camera, double clock, Settle settle);
    /// visibility_lod: takes the counts `counts` has ready; what they hide for the selection at `clock`, and
    /// the latest depth's test of the blocks.
    FrameVisibility takeVisibility(PixelCountSource* counts, const Camera& camera, double clock, BoxOccluded& occluded);

    TengineOptions mOptions;
    SessionUse mUse;
    std::function<void(const std::string&)> mLog;
    std::unique_ptr<MapFile> mOwnedMap;
    const MapFile* mMap = nullptr;
    std::unique_ptr<const DetailSynthesizer> mSynthesizer;
    bool mTessellation = false;
    bool mBlockIndices = false;
    bool mCountPixels = false;
    bool mRgtc2 = false;
    bool mShadows = false;
    double mNodePixels = 0.0;
    double mBlockPixels = 0.0;
    CacheChoice mCache;
    std::unique_ptr<TerrainNodeSource> mSource;
    std::unique_ptr<TerrainStreamer> mStreamer;
    std::unique_ptr<TerrainNodeSource> mReferenceSource;
    std::unique_ptr<ErrorMeter> mMeter;
    std::size_t mLoadErrors = 0;
    std::string mFirstLoadError;
    LodSelection mUnmorphed;  ///< geomorph off: the selection at each node's own detail
    DrawList mDrawList;
    std::optional<NodeVisibility> mVisibility;  ///< visibility_lod: the pixel counts of the frames drawn so far
    PixelCounts mPixelCounts;                   ///< reused for each frame's counts
    std::optional<DepthOcclusion> mOcclusion;   ///< the depth of the latest frame counted
    std::optional<ClipmapLayout> mClipmapLayout;
    std::unique_ptr<ClipmapTerrain> mClipmap;
    int mClipmapFirstRing = 0;
};

}  // namespace terrain
