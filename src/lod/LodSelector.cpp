// Level-of-detail selection: listing 3.7 (3.4.2) with hierarchical frustum culling (listing 3.4,
// 3.2.12), front-to-back children, child requests (3.2.14-3.2.15) and De Boer's morph factor (eq. 3.5).
#include "lod/LodSelector.h"

#include "core/Check.h"
#include "core/Frustum.h"
#include "quadtree/MapFile.h"

#include <algorithm>
#include <cmath>

namespace terrain {

double QuadtreeExtent::nodeSize(int level) const
{
    return std::ldexp(rootSize, -level);
}

Aabb QuadtreeExtent::box(const NodeId& id, double zMin, double zMax) const
{
    double size = nodeSize(id.level);
    double x0 = originX + static_cast<double>(id.x) * size;
    double y0 = originY + static_cast<double>(id.y) * size;
    return {{x0, y0, zMin}, {x0 + size, y0 + size, zMax}};
}

QuadtreeExtent extentOf(const MapHeader& h)
{
    return {h.originX, h.originY, h.nodeSizeAt(0)};
}

MapLodTree::MapLodTree(const MapFile& map) : mMap(map) {}

QuadtreeExtent MapLodTree::extent() const
{
    const MapHeader& h = mMap.header();
    return {h.originX, h.originY, h.nodeSizeAt(0)};
}

NodeInfo MapLodTree::info(const NodeId& id) const
{
    const DirectoryEntry* e = mMap.find(id);
    TERRAIN_EXPECTS(e != nullptr, "node is not in the map's directory");
    const MapHeader& h = mMap.header();
    return {e->hasChildren, e->deltaC, h.heightOf(e->minCode), h.heightOf(e->maxCode)};
}

LodSelection unmorphed(LodSelection selection)
{
    for (SelectedNode& node : selection.nodes) {
        node.morph = 1.0f;
    }
    return selection;
}

double lodDistanceFactor(const Camera& camera, double tauPixels)
{
    TERRAIN_EXPECTS(tauPixels > 0.0, "the screen-space error threshold tau must be > 0 pixels");
    camera.expectValid();
    return static_cast<double>(camera.viewportHeight) /
           (2.0 * tauPixels * std::abs(std::tan(camera.verticalFov * 0.5)));
}

double verticalErrorFactor(const Camera& camera)
{
    camera.expectValid();
    const double tanV = std::abs(std::tan(camera.verticalFov * 0.5));
    const double tanH = tanV * camera.aspect();
    const double sp = std::sin(camera.pitch), cp = std::cos(camera.pitch);
    double k = 0.0;
    for (double x : {-tanH, tanH}) {
        for (double y : {-tanV, tanV}) {
            const double a = x * sp, b = cp - y * sp;
            k = std::max(k, std::sqrt(a * a + b * b));
        }
    }
    return k;
}

double lodDistance(const Camera& camera, double k, const Aabb& box)
{
    const glm::dvec3 f = camera.forward();
    // The smallest of f . (corner - eye) over the box's corners: per axis the end that f points away from.
    const glm::dvec3 nearest{f.x >= 0.0 ? box.lo.x : box.hi.x, f.y >= 0.0 ? box.lo.y : box.hi.y,
                             f.z >= 0.0 ? box.lo.z : box.hi.z};
    const double depth = glm::dot(f, nearest - camera.position);
    return std::max(depth, camera.nearPlane) / k;
}

namespace {

struct Selector {
    const LodTree& tree;
    const ChildrenResident& resident;
    const NodeHidden& hidden;
    const NodeHeld& held;
    QuadtreeExtent extent;
    Frustum frustum;
    glm::dvec3 eye;
    double c = 0.0;
    const Camera& camera;
    double k = 1.0;
    LodSelection& out;

    /// `d`: metres to the node's box; `ld`: its lodDistance.
    void select(const NodeId& id, double d, double ld, double dm, double dmParent, bool isRoot)
    {
        float morph = 1.0f;
        if (!isRoot && dmParent > dm) {
            morph = static_cast<float>(std::clamp(1.0 - (ld - dm) / (dmParent - dm), 0.0, 1.0));
        }
        double size = extent.nodeSize(id.level);
        glm::dvec3 origin{extent.originX + static_cast<double>(id.x) * size,
                          extent.originY + static_cast<double>(id.y) * size, 0.0};
        out.nodes.push_back({id, morph, d, ld, origin - eye, size});
    }

    /// `id` passed culling; `d` is its distance, `ld` its lodDistance, `info` its information.
    void visit(const NodeId& id, const NodeInfo& info, double d, double ld, double dmParent, bool isRoot)
    {
        ++out.visitedNodes;
        double dm = static_cast<double>(info.deltaC) * c;
        if (!(ld < dm) || !info.hasChildren) {
            select(id, d, ld, dm, dmParent, isRoot);
            return;
        }
        if (hidden && hidden(id)) {
            ++out.hiddenNodes;
            out.requestsSkippedHidden += resident && !resident(id) ? 1 : 0;
            select(id, d, ld, dm, dmParent, isRoot);
            out.nodes.back().hidden = true;
            return;
        }
        const bool isHeld = held && held(id);
        out.heldNodes += isHeld ? 1 : 0;
        if (resident && !resident(id)) {
            out.requests.push_back({id, d});
            select(id, d, ld, dm, dmParent, isRoot);
            return;
        }
        if (isHeld) {
            select(id, d, ld, dm, dmParent, isRoot);
            return;
        }
        struct Child {
            NodeId id;
            NodeInfo info;
            double d;
            double ld;
        };
        Child children[4];
        int count = 0;
        for (int q = 0; q < 4; ++q) {
            NodeId child = id.child(q);
            NodeInfo childInfo = tree.info(child);
            Aabb box = extent.box(child, childInfo.zMin, childInfo.zMax);
            if (!frustum.intersects(box)) {
                ++out.culledNodes;
                continue;
            }
            // Insertion sort by distance; strict < keeps quadrant order among equal distances.
            Child entry{child, childInfo, distanceToAabb(eye, box), lodDistance(camera, k, box)};
            int at = count;
            while (at > 0 && entry.d < children[at - 1].d) {
                children[at] = children[at - 1];
                --at;
            }
            children[at] = entry;
            ++count;
        }
        for (int i = 0; i < count; ++i) {
            visit(children[i].id, children[i].info, children[i].d, children[i].ld, dm, false);
        }
    }
};

}  // namespace

void selectNodes(const LodTree& tree, const Camera& camera, double tauPixels, const ChildrenResident& resident,
                 LodSelection& out)
{
    selectNodes(tree, camera, tauPixels, resident, NodeHidden{}, NodeHeld{}, out);
}

void selectNodes(const LodTree& tree, const Camera& camera, double tauPixels, const ChildrenResident& resident,
                 const NodeHidden& hidden, LodSelection& out)
{
    selectNodes(tree, camera, tauPixels, resident, hidden, NodeHeld{}, out);
}

void selectNodes(const LodTree& tree, const Camera& camera, double tauPixels, const ChildrenResident& resident,
                 const NodeHidden& hidden, const NodeHeld& held, LodSelection& out)
{
    out.nodes.clear();
    out.requests.clear();
    out.visitedNodes = 0;
    out.culledNodes = 0;
    out.hiddenNodes = 0;
    out.requestsSkippedHidden = 0;
    out.heldNodes = 0;
    Selector s{tree,
               resident,
               hidden,
               held,
               tree.extent(),
               Frustum::fromCamera(camera),
               camera.position,
               lodDistanceFactor(camera, tauPixels),
               camera,
               verticalErrorFactor(camera),
               out};
    TERRAIN_EXPECTS(s.extent.rootSize > 0.0, "the quadtree's root size must be > 0");
    NodeId root = NodeId::root();
    NodeInfo info = tree.info(root);
    Aabb box = s.extent.box(root, info.zMin, info.zMax);
    if (!s.frustum.intersects(box)) {
        ++out.culledNodes;
        return;
    }
    s.visit(root, info, distanceToAabb(camera.position, box), lodDistance(camera, s.k, box), 0.0, true);
}

}  // namespace terrain
