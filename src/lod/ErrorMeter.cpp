#include "lod/ErrorMeter.h"

#include "lod/TessellationLevels.h"

#include "core/Check.h"
#include "core/Frustum.h"
#include "lod/HeightQuery.h"
#include "quadtree/ChunkGeometry.h"

#include <algorithm>
#include <cmath>

namespace terrain {

namespace {

/// Where a descendant's samples fall in an ancestor's local grid: sample (i, j) of `node` is at
/// (offsetX + i * scale, offsetY + j * scale) in the ancestor's samples. Exact (dyadic).
struct LocalMap {
    double offsetX = 0.0, offsetY = 0.0, scale = 1.0;

    static LocalMap of(const NodeId& node, const NodeId& ancestor, int chunkSize)
    {
        const int k = node.level - ancestor.level;
        TERRAIN_ASSERT(k >= 0);
        const double n1 = chunkSize - 1.0;
        const double scale = std::ldexp(1.0, -k);
        const double dx = static_cast<double>(node.x) - std::ldexp(static_cast<double>(ancestor.x), k);
        const double dy = static_cast<double>(node.y) - std::ldexp(static_cast<double>(ancestor.y), k);
        return {dx * n1 * scale, dy * n1 * scale, scale};
    }
};

/// A refined node being checked for "bought nothing".
struct RefinedNode {
    NodePtr node;
    double worst = 0.0;
    bool measured = false;
};

/// Whether `node` is `ancestor` or lies below it.
bool descends(const NodeId& node, const NodeId& ancestor)
{
    const int k = node.level - ancestor.level;
    return k >= 0 && (node.x >> k) == ancestor.x && (node.y >> k) == ancestor.y;
}

/// The mean (from `sum` of the points' errors) and 99th percentile of `out`'s measured points.
void summarize(FrameError& out, double sum)
{
    if (out.points > 0) {
        out.meanPixels = sum / static_cast<double>(out.points);
        std::vector<float> sorted = out.pixels;
        const auto at = static_cast<std::size_t>(0.99 * static_cast<double>(sorted.size() - 1));
        std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(at), sorted.end());
        out.p99Pixels = sorted[at];
    }
}

}  // namespace

VerticalSegmentProjector::VerticalSegmentProjector(const Camera& camera)
    : mMatrix(camera.projection() * camera.viewRotation()),
      mEye(camera.position),
      mHalfWidth(0.5 * camera.viewportWidth),
      mHalfHeight(0.5 * camera.viewportHeight),
      mNear(camera.nearPlane)
{
}

double VerticalSegmentProjector::pixels(double x, double y, double z, double dz) const
{
    const glm::dvec4 a = mMatrix * glm::dvec4(x - mEye.x, y - mEye.y, z - mEye.z, 1.0);
    if (!(a.w > 0.0) || std::abs(a.x) > a.w || std::abs(a.y) > a.w || std::abs(a.z) > a.w) {
        return -1.0;
    }
    glm::dvec4 b = a + dz * mMatrix[2];  // the clip position is linear in z
    if (b.w < mNear) {
        // The segment leaves through the near plane (a.w >= near inside the frustum): clip it there.
        const double t = (a.w - mNear) / (a.w - b.w);
        b = a + t * (b - a);
    }
    const double dx = (b.x / b.w - a.x / a.w) * mHalfWidth;
    const double dy = (b.y / b.w - a.y / a.w) * mHalfHeight;
    return std::sqrt(dx * dx + dy * dy);
}

ErrorMeter::ErrorMeter(const MapHeader& header, NodeSource& source, const ErrorMeterOptions& options)
    : mHeader(header), mExtent(extentOf(header)), mSource(source), mOptions(options)
{
    TERRAIN_EXPECTS(options.convergencePixels > 0.0, "the reference's convergence threshold must be > 0 pixels");
    TERRAIN_EXPECTS(options.maxDepthBelow >= 0, "maxDepthBelow must be >= 0");
}

Expected<const ChildNodes*> ErrorMeter::children(const NodeData& parent)
{
    const std::uint64_t key = parent.id.key();
    auto it = mCache.find(key);
    if (it == mCache.end()) {
        auto group = mSource.loadChildren(parent);
        TERRAIN_TRY(group);
        ++mGroupsMade;
        it = mCache.emplace(key, CachedGroup{std::move(group).value(), 0}).first;
    }
    it->second.used = mStamp;
    return &it->second.nodes;
}

void ErrorMeter::trimCache()
{
    if (mCache.size() <= mOptions.cachedGroups) {
        return;
    }
    std::vector<std::pair<std::uint64_t, std::uint64_t>> byUse;  // (last use, key)
    byUse.reserve(mCache.size());
    for (const auto& [key, group] : mCache) {
        byUse.emplace_back(group.used, key);
    }
    const std::size_t excess = mCache.size() - mOptions.cachedGroups;
    std::nth_element(byUse.begin(), byUse.begin() + static_cast<std::ptrdiff_t>(excess), byUse.end());
    for (std::size_t k = 0; k < excess; ++k) {
        mCache.erase(byUse[k].second);
    }
}

/// The frame's projector and frustum with the map's grid.
struct ErrorMeter::View {
    View(const MapHeader& header, const QuadtreeExtent& mapExtent, const Camera& camera)
        : projector(camera),
          frustum(Frustum::fromCamera(camera)),
          extent(mapExtent),
          n(static_cast<int>(header.chunkSize)),
          w(windowSize(n)),
          offset(header.heightOffset)
    {
    }

    double worldX(const NodeId& id, int i) const
    {
        return extent.originX +
               (static_cast<double>(id.x) + static_cast<double>(i) / (n - 1)) * extent.nodeSize(id.level);
    }
    double worldY(const NodeId& id, int j) const
    {
        return extent.originY +
               (static_cast<double>(id.y) + static_cast<double>(j) / (n - 1)) * extent.nodeSize(id.level);
    }
    double sample(const NodeData& node, int i, int j) const
    {
        return node.heights.height(static_cast<std::size_t>(j + kBorder) * w + i + kBorder);
    }

    /// Largest projected change from `parent`'s surface to `child`'s over the child's samples in view.
    double change(const NodeData& child, const NodeData& parent) const
    {
        const LocalMap local = LocalMap::of(child.id, parent.id, n);
        double worst = 0.0;
        for (int j = 0; j < n; ++j) {
            const double y = worldY(child.id, j);
            for (int i = 0; i < n; ++i) {
                const double zc = sample(child, i, j);
                const double zp =
                    nodeSurfaceAt(parent, n, local.offsetX + i * local.scale, local.offsetY + j * local.scale);
                worst = std::max(worst, projector.pixels(worldX(child.id, i), y, offset + zc, zp - zc));
            }
        }
        return worst;
    }

    VerticalSegmentProjector projector;
    Frustum frustum;
    const QuadtreeExtent& extent;
    int n, w;
    double offset;
};

Status ErrorMeter::referenceLeaves(const View& view, const NodePtr& from, int maxDepthBelow,
                                   std::vector<NodePtr>& leaves)
{
    std::vector<std::pair<NodePtr, int>> stack;  // (node, levels below `from`)
    stack.emplace_back(from, 0);
    while (!stack.empty()) {
        auto [at, depth] = stack.back();
        stack.pop_back();
        if (!at->hasChildren || depth >= maxDepthBelow) {
            leaves.push_back(at);
            continue;
        }
        auto group = children(*at);
        TERRAIN_TRY(group);
        for (const NodePtr& child : **group) {
            if (!view.frustum.intersects(mExtent.box(child->id, child->zMin, child->zMax))) {
                continue;
            }
            // Static levels are the data: always followed. Dynamic ones until they stop changing.
            const bool leaf =
                !child->hasChildren || (!child->isStatic && view.change(*child, *at) < mOptions.convergencePixels);
            if (leaf) {
                leaves.push_back(child);
            } else {
                stack.emplace_back(child, depth + 1);
            }
        }
    }
    return {};
}

Expected<FrameError> ErrorMeter::measure(const DrawList& frame, const ResidentNodeLookup& resident, double tauPixels,
                                         const MeasuredVisibility& visibility)
{
    const bool tessellated = frame.tessellated();
    std::vector<float> blended;  // tessellation mode: the node's samples as the shaders blend them
    TERRAIN_EXPECTS(tauPixels > 0.0, "tau must be > 0 pixels");
    const Camera& camera = frame.camera;
    camera.expectValid();
    const View view(mHeader, mExtent, camera);
    const VerticalSegmentProjector& projector = view.projector;
    const int n = view.n;
    const double offset = view.offset;

    FrameError out;
    out.nodes = frame.nodes.size();
    double sum = 0.0;
    std::unordered_map<std::uint64_t, RefinedNode> refined;
    std::vector<NodePtr> leaves;
    std::vector<RefinedNode*> ancestors;
    std::vector<LocalMap> inAncestors;

    for (const DrawnNode& drawnNode : frame.nodes) {
        ++mStamp;
        const SelectedNode& selected = drawnNode.selected;
        const NodePtr& node = drawnNode.node;
        const bool morphs = !selected.id.isRoot() && selected.morph < 1.0f;
        const NodePtr& parent = drawnNode.parent;
        leaves.clear();
        TERRAIN_TRY(referenceLeaves(view, node, mOptions.maxDepthBelow, leaves));
        out.referenceNodes += leaves.size();

        // The refined nodes above it, checked while they may still be within tau.
        ancestors.clear();
        for (NodeId up = selected.id; !up.isRoot();) {
            up = up.parent();
            auto [it, inserted] = refined.try_emplace(up.key());
            if (inserted) {
                it->second.node = resident(up);
            }
            if (it->second.node && it->second.worst <= tauPixels) {
                ancestors.push_back(&it->second);
            }
        }

        const float f = selected.morph;
        const BlockLevels& levels = drawnNode.levels;
        if (tessellated) {
            blended = morphedSamples(*node, n, selected.id.isRoot() ? 1.0f : f);
            out.tessellatedTriangles += levels.triangles();
        }
        double ownWorst = -1.0;  // metres, own surface; stays < 0 without a point in view
        for (const NodePtr& leaf : leaves) {
            out.deepestReference = std::max(out.deepestReference, leaf->id.level);
            const LocalMap inNode = LocalMap::of(leaf->id, selected.id, n);
            const LocalMap inParent = morphs ? LocalMap::of(leaf->id, parent->id, n) : LocalMap{};
            inAncestors.clear();
            for (RefinedNode* a : ancestors) {
                inAncestors.push_back(LocalMap::of(leaf->id, a->node->id, n));
            }
            for (int j = 0; j < n; ++j) {
                const double y = view.worldY(leaf->id, j);
                const double ly = inNode.offsetY + j * inNode.scale;
                for (int i = 0; i < n; ++i) {
                    const double x = view.worldX(leaf->id, i);
                    const double ref = view.sample(*leaf, i, j);
                    const double lx = inNode.offsetX + i * inNode.scale;
                    double z = nodeSurfaceAt(*node, n, lx, ly);
                    const double own = std::abs(ref - z);
                    if (tessellated) {
                        const auto [first, second] = tessellatedHeights(blended, n, levels, lx, ly);
                        z = std::abs(ref - first) >= std::abs(ref - second) ? first : second;
                    } else if (morphs) {
                        const double zp = nodeSurfaceAt(*parent, n, inParent.offsetX + i * inParent.scale,
                                                        inParent.offsetY + j * inParent.scale);
                        z = f * z + (1.0 - f) * zp;
                    }
                    const double px = projector.pixels(x, y, offset + z, ref - z);
                    if (px < 0.0) {
                        continue;  // outside the view frustum
                    }
                    if (visibility.shows && !visibility.shows(glm::dvec3(x, y, offset + z))) {
                        continue;  // hidden in the frame measured
                    }
                    ownWorst = std::max(ownWorst, own);
                    out.pixels.push_back(static_cast<float>(px));
                    sum += px;
                    if (px > out.maxPixels || out.points == 0) {
                        out.maxPixels = px;
                        out.maxMetres = std::abs(ref - z);
                        out.worstNode = selected.id;
                        out.worstX = x;
                        out.worstY = y;
                    }
                    ++out.points;
                    for (std::size_t k = 0; k < ancestors.size(); ++k) {
                        RefinedNode* a = ancestors[k];
                        if (a->worst > tauPixels) {
                            continue;
                        }
                        const LocalMap& inA = inAncestors[k];
                        const double za =
                            nodeSurfaceAt(*a->node, n, inA.offsetX + i * inA.scale, inA.offsetY + j * inA.scale);
                        a->worst = std::max(a->worst, projector.pixels(x, y, offset + za, ref - za));
                        a->measured = true;
                    }
                }
            }
        }
        if (ownWorst >= 0.0) {
            out.bounds.push_back({selected.id, node->isStatic, node->deltaC, ownWorst});
        }
        trimCache();
    }
    for (const auto& [key, r] : refined) {
        if (r.node && r.measured) {
            ++out.refined;
            out.refinedWithinTau += r.worst <= tauPixels ? 1 : 0;
        }
    }
    summarize(out, sum);
    return out;
}

Expected<FrameError> ErrorMeter::measureSurface(const DrawnSurface& drawn, const Camera& camera,
                                                const MeasuredVisibility& visibility)
{
    camera.expectValid();
    const View view(mHeader, mExtent, camera);
    const int n = view.n;
    if (!mRoot) {
        auto root = mSource.loadRoot();
        TERRAIN_TRY(root);
        mRoot = std::move(root.value());
    }
    ++mStamp;
    std::vector<NodePtr> leaves;
    TERRAIN_TRY(referenceLeaves(view, mRoot, mOptions.maxDepthBelow, leaves));
    FrameError out;
    out.referenceNodes = leaves.size();
    double sum = 0.0;
    for (const NodePtr& leaf : leaves) {
        out.deepestReference = std::max(out.deepestReference, leaf->id.level);
        for (int j = 0; j < n; ++j) {
            const double y = view.worldY(leaf->id, j);
            for (int i = 0; i < n; ++i) {
                const double x = view.worldX(leaf->id, i);
                const std::optional<double> z = drawn(x, y);
                if (!z) {
                    continue;
                }
                const double ref = view.sample(*leaf, i, j);
                const double px = view.projector.pixels(x, y, view.offset + *z, ref - *z);
                if (px < 0.0 || (visibility.shows && !visibility.shows(glm::dvec3(x, y, view.offset + *z)))) {
                    continue;
                }
                out.pixels.push_back(static_cast<float>(px));
                sum += px;
                if (px > out.maxPixels || out.points == 0) {
                    out.maxPixels = px;
                    out.maxMetres = std::abs(ref - *z);
                    out.worstNode = leaf->id;
                    out.worstX = x;
                    out.worstY = y;
                }
                ++out.points;
            }
        }
    }
    trimCache();
    summarize(out, sum);
    return out;
}

Expected<OracleSelection> ErrorMeter::oracle(const Camera& camera, double tauPixels, int blocks)
{
    TERRAIN_EXPECTS(tauPixels > 0.0, "tau must be > 0 pixels");
    TERRAIN_EXPECTS(blocks >= 0 && blocks <= 64, "the oracle's blocks per side must be in [0, 64]");
    camera.expectValid();
    const View view(mHeader, mExtent, camera);
    const int n = view.n;
    if (!mRoot) {
        auto root = mSource.loadRoot();
        TERRAIN_TRY(root);
        mRoot = std::move(root).value();
    }
    ++mStamp;
    OracleSelection out;
    if (!view.frustum.intersects(mExtent.box(mRoot->id, mRoot->zMin, mRoot->zMax))) {
        return out;
    }
    // One reference for the whole frame. Its convergence test compares a child with its parent only, so the
    // leaves below any node are the ones a reference made from that node would have (measure() starts at a
    // selected node and always looks at its children: it may follow a dynamic level a little further).
    std::vector<NodePtr> leaves;
    TERRAIN_TRY(referenceLeaves(view, mRoot, NodeId::kMaxLevel, leaves));
    // Deeper leaves lie nearer the camera, where a coarse node's error is largest: looked at first, they find a
    // node over tau after few points.
    std::stable_sort(leaves.begin(), leaves.end(),
                     [](const NodePtr& a, const NodePtr& b) { return a->id.level > b->id.level; });

    struct Visit {
        NodePtr node;
        std::vector<NodePtr> leaves;  ///< the reference leaves in view below it (or it)
    };
    std::vector<Visit> stack;
    stack.push_back({mRoot, std::move(leaves)});
    // Pixels per metre of a bound at lodDistance 1 (eq. 3.3: refined when lodDistance < deltaC * C).
    const double boundPixels = tauPixels * lodDistanceFactor(camera, tauPixels);
    const double k = verticalErrorFactor(camera);
    std::vector<double> blockMetres(static_cast<std::size_t>(blocks * blocks));
    while (!stack.empty()) {
        Visit visit = std::move(stack.back());
        stack.pop_back();
        const NodeData& node = *visit.node;
        double worst = -1.0;        // pixels, over the points in view; stays < 0 without one
        double worstPixels = -1.0;  // the same at the points' own distances, for blocks > 0
        std::fill(blockMetres.begin(), blockMetres.end(), -1.0);
        const double blockSide = blocks > 0 ? (n - 1.0) / blocks : 1.0;
        for (const NodePtr& leaf : visit.leaves) {
            // A reference leaf never lies above a visited node: a node is refined only when over tau, and a
            // reference leaf is within any tau of itself.
            const LocalMap inNode = LocalMap::of(leaf->id, node.id, n);
            for (int j = 0; j < n && worst <= tauPixels; ++j) {
                const double y = view.worldY(leaf->id, j);
                const double ly = inNode.offsetY + j * inNode.scale;
                for (int i = 0; i < n; ++i) {
                    const double ref = view.sample(*leaf, i, j);
                    const double lx = inNode.offsetX + i * inNode.scale;
                    const double z = nodeSurfaceAt(node, n, lx, ly);
                    const double px = view.projector.pixels(view.worldX(leaf->id, i), y, view.offset + z, ref - z);
                    if (blocks == 0 || px < 0.0) {
                        worst = std::max(worst, px);
                        continue;
                    }
                    worst = std::max(worst, 0.0);
                    worstPixels = std::max(worstPixels, px);
                    // A point on a block edge belongs to the blocks on both sides.
                    const int bi0 = std::max(0, static_cast<int>(std::ceil(lx / blockSide)) - 1);
                    const int bi1 = std::min(blocks - 1, static_cast<int>(std::floor(lx / blockSide)));
                    const int bj0 = std::max(0, static_cast<int>(std::ceil(ly / blockSide)) - 1);
                    const int bj1 = std::min(blocks - 1, static_cast<int>(std::floor(ly / blockSide)));
                    for (int bj = bj0; bj <= bj1; ++bj) {
                        for (int bi = bi0; bi <= bi1; ++bi) {
                            double& b = blockMetres[static_cast<std::size_t>(bj * blocks + bi)];
                            b = std::max(b, std::abs(ref - z));
                        }
                    }
                }
            }
            if (worst > tauPixels) {
                break;
            }
        }
        if (blocks > 0 && worst >= 0.0) {
            const double size = mExtent.nodeSize(node.id.level) / blocks;
            const Aabb box = mExtent.box(node.id, node.zMin, node.zMax);
            for (int bj = 0; bj < blocks; ++bj) {
                for (int bi = 0; bi < blocks; ++bi) {
                    const double metres = blockMetres[static_cast<std::size_t>(bj * blocks + bi)];
                    if (metres < 0.0) {
                        continue;
                    }
                    const Aabb block{{box.lo.x + bi * size, box.lo.y + bj * size, box.lo.z},
                                     {box.lo.x + (bi + 1) * size, box.lo.y + (bj + 1) * size, box.hi.z}};
                    worst = std::max(worst, metres * boundPixels / lodDistance(camera, k, block));
                }
            }
        }
        if (worst < 0.0) {
            continue;  // nothing of it in view
        }
        if (worst <= tauPixels || !node.hasChildren) {
            out.maxPixels = std::max(out.maxPixels, worst);
            out.overTau += worst > tauPixels ? 1 : 0;
            out.nodes.push_back(std::move(visit.node));
            continue;
        }
        auto group = children(node);
        TERRAIN_TRY(group);
        for (const NodePtr& child : **group) {
            Visit below{child, {}};
            for (const NodePtr& leaf : visit.leaves) {
                if (descends(leaf->id, child->id)) {
                    below.leaves.push_back(leaf);
                }
            }
            if (!below.leaves.empty()) {
                stack.push_back(std::move(below));
            }
        }
        out.refinedWithinTau += blocks > 0 && worstPixels <= tauPixels ? 1 : 0;
        out.refined.push_back(std::move(visit.node));
    }
    trimCache();
    return out;
}

}  // namespace terrain
