#include "lod/LodSelector.h"

#include "core/Frustum.h"
#include "lod/ErrorMeter.h"

#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <random>

namespace terrain {
namespace {

constexpr double kPi = std::numbers::pi;

/// An in-memory quadtree with random, properly nested errors and boxes; some branches pruned early.
class SyntheticTree final : public LodTree {
public:
    SyntheticTree(int levels, std::uint64_t seed, QuadtreeExtent extent) : mLevels(levels), mExtent(extent)
    {
        std::mt19937_64 rng(seed);
        std::uniform_real_distribution<double> uni(0.0, 1.0);
        mNodes.resize(static_cast<std::size_t>(NodeId{levels, 0, 0}.key()));
        mExists.assign(mNodes.size(), false);
        mExists[0] = true;
        // Top-down: which nodes exist and which have children (pruning below level 2 with 15%).
        for (std::size_t k = 0; k < mNodes.size(); ++k) {
            if (!mExists[k]) {
                continue;
            }
            NodeId id = idOf(k);
            bool children = id.level + 1 < levels && (id.level < 2 || uni(rng) > 0.15);
            mNodes[k].hasChildren = children;
            for (int q = 0; children && q < 4; ++q) {
                mExists[id.child(q).key()] = true;
            }
        }
        // Bottom-up: nested errors (eq. 3.1 with random deltaM > 0) and nested boxes.
        for (std::size_t k = mNodes.size(); k-- > 0;) {
            if (!mExists[k]) {
                continue;
            }
            NodeId id = idOf(k);
            NodeInfo& n = mNodes[k];
            double size = mExtent.nodeSize(id.level);
            if (!n.hasChildren) {
                double cx = mExtent.originX + (id.x + 0.5) * size, cy = mExtent.originY + (id.y + 0.5) * size;
                double base = 80.0 * std::sin(cx * 0.003) * std::cos(cy * 0.002) + 20.0 * uni(rng);
                n.zMin = base;
                n.zMax = base + size * 0.2 * uni(rng);
                n.deltaC = uni(rng) < 0.3 ? 0.0f : static_cast<float>(0.3 * uni(rng));  // estimated detail error
            } else {
                double zMin = 1e300, zMax = -1e300;
                float childError = 0.0f;
                for (int q = 0; q < 4; ++q) {
                    const NodeInfo& c = mNodes[id.child(q).key()];
                    zMin = std::min(zMin, c.zMin);
                    zMax = std::max(zMax, c.zMax);
                    childError = std::max(childError, c.deltaC);
                }
                n.zMin = zMin - 2.0 * uni(rng);
                n.zMax = zMax + 2.0 * uni(rng);
                n.deltaC = childError + static_cast<float>(size / 256.0 * (0.2 + uni(rng)));
            }
        }
    }

    QuadtreeExtent extent() const override { return mExtent; }
    NodeInfo info(const NodeId& id) const override
    {
        EXPECT_TRUE(exists(id)) << id.toString();
        return mNodes[id.key()];
    }
    bool exists(const NodeId& id) const { return id.level < mLevels && mExists[id.key()]; }
    Aabb box(const NodeId& id) const { return mExtent.box(id, mNodes[id.key()].zMin, mNodes[id.key()].zMax); }
    int levels() const { return mLevels; }
    /// The deepest node containing (x, y).
    NodeId leafAt(double x, double y) const
    {
        NodeId id = NodeId::root();
        while (mNodes[id.key()].hasChildren) {
            double half = mExtent.nodeSize(id.level + 1);
            double x0 = mExtent.originX + id.x * 2 * half, y0 = mExtent.originY + id.y * 2 * half;
            id = id.child((x >= x0 + half ? 1 : 0) | (y >= y0 + half ? 2 : 0));
        }
        return id;
    }

    /// Inverse of NodeId::key().
    static NodeId idOf(std::size_t key)
    {
        int level = 0;
        std::size_t before = 0;
        while (key >= before + (std::size_t{1} << (2 * level))) {
            before += std::size_t{1} << (2 * level);
            ++level;
        }
        std::size_t within = key - before;
        return {level, static_cast<std::uint32_t>(within & ((std::size_t{1} << level) - 1)),
                static_cast<std::uint32_t>(within >> level)};
    }

private:
    int mLevels;
    QuadtreeExtent mExtent;
    std::vector<NodeInfo> mNodes;
    std::vector<bool> mExists;
};

const QuadtreeExtent kExtent{1000.0, -500.0, 4096.0};

/// Some nodes' children are not resident: a fixed pseudo-random subset.
bool sometimesResident(const NodeId& id)
{
    return (id.key() * 2654435761u) % 7 != 3;
}

Camera randomCamera(std::mt19937_64& rng, const SyntheticTree& tree)
{
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    const QuadtreeExtent e = tree.extent();
    Camera c;
    c.position = {e.originX - 300.0 + uni(rng) * (e.rootSize + 600.0),
                  e.originY - 300.0 + uni(rng) * (e.rootSize + 600.0), -100.0 + uni(rng) * 600.0};
    c.yaw = uni(rng) * 2.0 * kPi;
    c.pitch = (uni(rng) * 100.0 - 70.0) * kPi / 180.0;
    c.verticalFov = (30.0 + uni(rng) * 60.0) * kPi / 180.0;
    c.viewportWidth = 320 + static_cast<int>(uni(rng) * 1600);
    c.viewportHeight = 240 + static_cast<int>(uni(rng) * 1000);
    c.nearPlane = 0.5;
    c.farPlane = 1500.0 + uni(rng) * 8000.0;
    return c;
}

/// The brute-force reference: the same refinement rule over the whole tree, no culling, children in
/// quadrant order. Its selection is a partition of the terrain square.
struct Reference {
    std::map<std::uint64_t, double> selected;   ///< key -> the error test's distance
    std::map<std::uint64_t, double> requested;  ///< key -> metres to the box (the request's priority)
};

/// The error test's distance, written out independently of lodDistance(): the smallest eye depth over the
/// box's eight corners (at least the near plane) over K, the largest |(-x' sin p, cos p - y' sin p)| at the
/// image's four corners.
double referenceLodDistance(const Camera& cam, const Aabb& box)
{
    const glm::dmat4 view = cam.view();
    double depth = std::numeric_limits<double>::infinity();
    for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 p{corner & 1 ? box.hi.x : box.lo.x, corner & 2 ? box.hi.y : box.lo.y,
                           corner & 4 ? box.hi.z : box.lo.z};
        depth = std::min(depth, -(view * glm::dvec4(p, 1.0)).z);  // eye space looks down -z
    }
    const double tv = std::tan(cam.verticalFov / 2), th = tv * cam.aspect();
    double k = 0.0;
    for (double x : {-th, th}) {
        for (double y : {-tv, tv}) {
            k = std::max(k, std::hypot(x * std::sin(cam.pitch), std::cos(cam.pitch) - y * std::sin(cam.pitch)));
        }
    }
    return std::max(depth, cam.nearPlane) / k;
}

void referenceSelect(const SyntheticTree& tree, const NodeId& id, const Camera& cam, double c,
                     const ChildrenResident& resident, Reference& out)
{
    NodeInfo info = tree.info(id);
    double d = referenceLodDistance(cam, tree.box(id));
    if (d < info.deltaC * c && info.hasChildren) {
        if (resident && !resident(id)) {
            out.requested[id.key()] = distanceToAabb(cam.position, tree.box(id));
            out.selected[id.key()] = d;
            return;
        }
        for (int q = 0; q < 4; ++q) {
            referenceSelect(tree, id.child(q), cam, c, resident, out);
        }
        return;
    }
    out.selected[id.key()] = d;
}

double expectedMorph(const SyntheticTree& tree, const NodeId& id, double d, double c)
{
    if (id.isRoot()) {
        return 1.0;
    }
    double dm = tree.info(id).deltaC * c, dmp = tree.info(id.parent()).deltaC * c;
    return dmp > dm ? std::clamp(1.0 - (d - dm) / (dmp - dm), 0.0, 1.0) : 1.0;
}

/// The child of `ancestor` on the way down to `id` (id.level > ancestor.level).
NodeId childTowards(const NodeId& ancestor, NodeId id)
{
    while (id.level > ancestor.level + 1) {
        id = id.parent();
    }
    return id;
}

bool isAncestor(const NodeId& a, NodeId b)
{
    while (b.level > a.level) {
        b = b.parent();
    }
    return a == b;
}

/// Checks one frame's output against the brute-force reference and the documented guarantees.
void checkFrame(const SyntheticTree& tree, const Camera& cam, double tau, const ChildrenResident& resident,
                const LodSelection& out, std::mt19937_64& rng)
{
    double c = lodDistanceFactor(cam, tau);
    Frustum frustum = Frustum::fromCamera(cam);
    Reference ref;
    referenceSelect(tree, NodeId::root(), cam, c, resident, ref);

    // Exactly the reference nodes whose box passes the frustum test (nested boxes make the test
    // monotone, so culled ancestors imply a culled node), with the reference's distance and eq. 3.5.
    std::map<std::uint64_t, const SelectedNode*> got;
    for (const SelectedNode& n : out.nodes) {
        ASSERT_TRUE(got.emplace(n.id.key(), &n).second) << "selected twice: " << n.id.toString();
        auto it = ref.selected.find(n.id.key());
        ASSERT_NE(it, ref.selected.end()) << n.id.toString() << " is not in the reference selection";
        EXPECT_NEAR(n.lodDistance, it->second, 1e-9 * std::max(1.0, it->second)) << n.id.toString();
        EXPECT_EQ(n.distance, distanceToAabb(cam.position, tree.box(n.id)));
        EXPECT_NEAR(n.morph, expectedMorph(tree, n.id, n.lodDistance, c), 1e-6) << n.id.toString();
        EXPECT_GE(n.morph, 0.0f);
        EXPECT_LE(n.morph, 1.0f);
        EXPECT_EQ(n.size, kExtent.nodeSize(n.id.level));
        glm::dvec3 corner = tree.box(n.id).lo;
        EXPECT_NEAR(glm::length(n.cameraRelativeOrigin + cam.position - glm::dvec3(corner.x, corner.y, 0.0)), 0.0,
                    1e-9);
        // Error rule: acceptable, or a leaf, or waiting for its children.
        NodeInfo info = tree.info(n.id);
        bool acceptable = n.lodDistance >= info.deltaC * c;
        EXPECT_TRUE(acceptable || !info.hasChildren || ref.requested.count(n.id.key()))
            << n.id.toString() << " is too coarse but neither a leaf nor waiting for its children";
    }
    for (const auto& [key, d] : ref.selected) {
        (void)d;
        NodeId id = SyntheticTree::idOf(key);
        EXPECT_EQ(got.count(key) > 0, frustum.intersects(tree.box(id))) << id.toString();
    }
    std::size_t requestsSeen = 0;
    for (const ChildRequest& r : out.requests) {
        auto it = ref.requested.find(r.parent.key());
        ASSERT_NE(it, ref.requested.end()) << r.parent.toString();
        EXPECT_EQ(r.distance, it->second);
        EXPECT_TRUE(got.count(r.parent.key())) << "a requesting node is drawn meanwhile";
        ++requestsSeen;
    }
    EXPECT_EQ(requestsSeen, std::count_if(out.nodes.begin(), out.nodes.end(),
                                          [&](const SelectedNode& n) { return ref.requested.count(n.id.key()) > 0; }));

    // Order: depth-first, siblings by non-decreasing distance (ties by quadrant).
    for (std::size_t a = 0; a < out.nodes.size(); ++a) {
        for (std::size_t b = a + 1; b < out.nodes.size(); ++b) {
            NodeId p = out.nodes[a].id, q = out.nodes[b].id;
            ASSERT_FALSE(isAncestor(p, q) || isAncestor(q, p)) << "overlap: " << p.toString() << " " << q.toString();
            NodeId lca = p;
            while (!isAncestor(lca, q)) {
                lca = lca.parent();
            }
            NodeId cp = childTowards(lca, p), cq = childTowards(lca, q);
            double dp = distanceToAabb(cam.position, tree.box(cp)), dq = distanceToAabb(cam.position, tree.box(cq));
            EXPECT_TRUE(dp < dq || (dp == dq && cp.quadrant() < cq.quadrant()))
                << p.toString() << " comes before " << q.toString() << " but its sibling subtree is farther";
        }
    }

    // Coverage: a point inside the frustum and inside the box of the finest node at its (x, y) (where the
    // terrain can be) lies in exactly one selected node's square.
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    for (int s = 0; s < 300; ++s) {
        double x = kExtent.originX + uni(rng) * kExtent.rootSize, y = kExtent.originY + uni(rng) * kExtent.rootSize;
        Aabb leaf = tree.box(tree.leafAt(x, y));
        glm::dvec3 p{x, y, leaf.lo.z + uni(rng) * (leaf.hi.z - leaf.lo.z)};
        int containing = 0;
        for (const SelectedNode& n : out.nodes) {
            Aabb b = tree.box(n.id);
            containing += x >= b.lo.x && x < b.hi.x && y >= b.lo.y && y < b.hi.y ? 1 : 0;
        }
        EXPECT_LE(containing, 1);
        if (frustum.contains(p)) {
            EXPECT_EQ(containing, 1) << "visible terrain point (" << x << ", " << y << ", " << p.z << ") not covered";
        }
    }
}

/// Culling is conservative: every node of the unculled reference selection with a sampled point inside
/// the frustum is selected.
void checkNothingVisibleIsCulled(const SyntheticTree& tree, const Camera& cam, double tau,
                                 const ChildrenResident& resident, const LodSelection& out)
{
    Frustum frustum = Frustum::fromCamera(cam);
    Reference ref;
    referenceSelect(tree, NodeId::root(), cam, lodDistanceFactor(cam, tau), resident, ref);
    std::map<std::uint64_t, bool> got;
    for (const SelectedNode& n : out.nodes) {
        got[n.id.key()] = true;
    }
    const int k = 6;
    for (const auto& [key, d] : ref.selected) {
        (void)d;
        if (got.count(key)) {
            continue;
        }
        NodeId id = SyntheticTree::idOf(key);
        Aabb b = tree.box(id);
        for (int i = 0; i <= k; ++i) {
            for (int j = 0; j <= k; ++j) {
                for (int l = 0; l <= k; ++l) {
                    glm::dvec3 p = b.lo + (b.hi - b.lo) * glm::dvec3(i, j, l) / double(k);
                    ASSERT_FALSE(frustum.contains(p))
                        << id.toString() << " was culled but has a point inside the frustum";
                }
            }
        }
    }
}

struct Scenario {
    const char* name;
    bool allResident;
    double tau;
};

class LodSelectorRandomCameras : public ::testing::TestWithParam<Scenario> {};

TEST_P(LodSelectorRandomCameras, MatchesBruteForceReferenceAndGuarantees)
{
    SyntheticTree tree(6, 42, kExtent);
    std::mt19937_64 rng(7);
    ChildrenResident resident = GetParam().allResident ? ChildrenResident{} : ChildrenResident{sometimesResident};
    LodSelection out;
    int nonEmpty = 0, withRequests = 0, refinedDeep = 0;
    for (int i = 0; i < 300; ++i) {
        SCOPED_TRACE("camera " + std::to_string(i));
        Camera cam = randomCamera(rng, tree);
        selectNodes(tree, cam, GetParam().tau, resident, out);
        checkFrame(tree, cam, GetParam().tau, resident, out, rng);
        checkNothingVisibleIsCulled(tree, cam, GetParam().tau, resident, out);
        if (::testing::Test::HasFatalFailure()) {
            return;
        }
        nonEmpty += out.nodes.empty() ? 0 : 1;
        withRequests += out.requests.empty() ? 0 : 1;
        refinedDeep += std::any_of(out.nodes.begin(), out.nodes.end(),
                                   [&](const SelectedNode& n) { return n.id.level == tree.levels() - 1; });
    }
    // The scenarios must exercise what they claim to (a test that cannot fail is a defect).
    EXPECT_GT(nonEmpty, 150) << "the random cameras should mostly see the terrain";
    EXPECT_GT(refinedDeep, 10) << "the random cameras should often reach the finest level";
    if (!GetParam().allResident) {
        EXPECT_GT(withRequests, 20);
    }
}

INSTANTIATE_TEST_SUITE_P(LodSelector, LodSelectorRandomCameras,
                         ::testing::Values(Scenario{"AllResidentTau2", true, 2.0},
                                           Scenario{"SomeMissingTau2", false, 2.0},
                                           Scenario{"AllResidentTau0_5", true, 0.5},
                                           Scenario{"SomeMissingTau8", false, 8.0}),
                         [](const auto& testInfo) { return std::string(testInfo.param.name); });

TEST(LodSelectorTest, MorphIsContinuousAlongACameraPath)
{
    // |df| <= |dd| / (d_mp - d_m), and the error test's distance (a depth over K, K fixed by the pitch) moves
    // by at most (|camera step| + |turn| x the farthest box corner) / K: eq. 3.5 is Lipschitz in the camera.
    SyntheticTree tree(6, 3, kExtent);
    Camera cam;
    cam.position = {kExtent.originX + 200.0, kExtent.originY + 300.0, 60.0};
    cam.yaw = 0.7;
    cam.pitch = -0.2;
    const double tau = 1.0, step = 0.05;
    double c = lodDistanceFactor(cam, tau);
    LodSelection previous, current;
    selectNodes(tree, cam, tau, {}, previous);
    int compared = 0, morphing = 0;
    for (int i = 0; i < 4000; ++i) {
        cam.position += glm::dvec3(std::sin(cam.yaw), std::cos(cam.yaw), 0.0) * step;
        cam.yaw += 0.0002;
        selectNodes(tree, cam, tau, {}, current);
        std::map<std::uint64_t, const SelectedNode*> before;
        for (const SelectedNode& n : previous.nodes) {
            before[n.id.key()] = &n;
        }
        for (const SelectedNode& n : current.nodes) {
            auto it = before.find(n.id.key());
            if (it == before.end() || n.id.isRoot()) {
                continue;
            }
            double dm = tree.info(n.id).deltaC * c, dmp = tree.info(n.id.parent()).deltaC * c;
            ASSERT_GT(dmp, dm);
            const Aabb box = tree.box(n.id);
            double farthest = 0.0;
            for (int corner = 0; corner < 8; ++corner) {
                const glm::dvec3 p{corner & 1 ? box.hi.x : box.lo.x, corner & 2 ? box.hi.y : box.lo.y,
                                   corner & 4 ? box.hi.z : box.lo.z};
                farthest = std::max(farthest, glm::length(p - cam.position));
            }
            const double move = (step + 0.0002 * (farthest + step)) / verticalErrorFactor(cam);
            ASSERT_LE(std::abs(n.morph - it->second->morph), move / (dmp - dm) + 1e-6) << n.id.toString();
            ++compared;
            morphing += n.morph > 0.0f && n.morph < 1.0f ? 1 : 0;
        }
        std::swap(previous, current);
    }
    EXPECT_GT(compared, 10000);
    EXPECT_GT(morphing, 1000) << "the path should cross morph zones";
}

TEST(LodSelectorTest, SingleLeafRootIsSelectedWithFullMorph)
{
    struct OneNode final : LodTree {
        QuadtreeExtent extent() const override { return {0.0, 0.0, 100.0}; }
        NodeInfo info(const NodeId&) const override { return {false, 5.0f, 0.0, 10.0}; }
    } tree;
    Camera cam;
    cam.position = {50.0, -20.0, 5.0};  // south of the square, looking north at it
    LodSelection out;
    selectNodes(tree, cam, 2.0, {}, out);
    ASSERT_EQ(out.nodes.size(), 1u);
    EXPECT_EQ(out.nodes[0].id, NodeId::root());
    EXPECT_EQ(out.nodes[0].morph, 1.0f);
    EXPECT_DOUBLE_EQ(out.nodes[0].distance, 20.0);
    EXPECT_EQ(out.nodes[0].cameraRelativeOrigin, glm::dvec3(-50.0, 20.0, -5.0));
    EXPECT_TRUE(out.requests.empty());

    cam.yaw = kPi;  // looking south, away from it
    selectNodes(tree, cam, 2.0, {}, out);
    EXPECT_TRUE(out.nodes.empty());
    EXPECT_EQ(out.culledNodes, 1u);
}

TEST(LodSelectorTest, SteadyStateReusesTheOutputBuffers)
{
    SyntheticTree tree(6, 42, kExtent);
    Camera cam;
    cam.position = {kExtent.originX + 2000.0, kExtent.originY + 1000.0, 50.0};
    LodSelection out;
    selectNodes(tree, cam, 2.0, sometimesResident, out);
    ASSERT_FALSE(out.nodes.empty());
    const SelectedNode* nodes = out.nodes.data();
    std::size_t capacity = out.nodes.capacity();
    selectNodes(tree, cam, 2.0, sometimesResident, out);
    EXPECT_EQ(out.nodes.data(), nodes);
    EXPECT_EQ(out.nodes.capacity(), capacity);
}

TEST(LodSelectorFrustum, AgreesWithTheViewProjectionMatrix)
{
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    SyntheticTree tree(2, 1, kExtent);
    int inside = 0;
    for (int i = 0; i < 50; ++i) {
        Camera cam = randomCamera(rng, tree);
        cam.position += glm::dvec3(3e6, -2e6, 0.0);  // far from the origin: planes must stay exact
        Frustum frustum = Frustum::fromCamera(cam);
        glm::dmat4 vp = cam.projection() * cam.viewRotation();
        for (int j = 0; j < 400; ++j) {
            glm::dvec3 rel = glm::dvec3(uni(rng), uni(rng), uni(rng)) * (cam.farPlane * 1.2);
            glm::dvec4 clip = vp * glm::dvec4(rel, 1.0);
            double margin = 1e-9 * std::abs(clip.w);
            bool clipInside = std::abs(clip.x) <= clip.w - margin && std::abs(clip.y) <= clip.w - margin &&
                              std::abs(clip.z) <= clip.w - margin;
            bool clipOutside = std::abs(clip.x) > clip.w + std::abs(margin) ||
                               std::abs(clip.y) > clip.w + std::abs(margin) ||
                               std::abs(clip.z) > clip.w + std::abs(margin);
            if (clipInside) {
                EXPECT_TRUE(frustum.contains(cam.position + rel));
                ++inside;
            } else if (clipOutside) {
                EXPECT_FALSE(frustum.contains(cam.position + rel));
            }
        }
    }
    EXPECT_GT(inside, 50);
}

TEST(LodSelectorFrustum, CameraLooksNorthAtYawZeroAndEastAtNinety)
{
    Camera cam;
    EXPECT_NEAR(glm::length(cam.forward() - glm::dvec3(0, 1, 0)), 0.0, 1e-15);
    cam.yaw = kPi / 2;
    EXPECT_NEAR(glm::length(cam.forward() - glm::dvec3(1, 0, 0)), 0.0, 1e-15);
    cam.pitch = kPi / 2;
    EXPECT_NEAR(glm::length(cam.forward() - glm::dvec3(0, 0, 1)), 0.0, 1e-15);
    EXPECT_NEAR(glm::length(cam.right() - glm::dvec3(0, -1, 0)), 0.0, 1e-15);
}

TEST(LodSelectorTest, LodDistanceBoundsTheScreenLengthOfVerticalErrorsEverywhereInTheImage)
{
    // lodDistance() is what makes eq. 3.3 a pixel bound (issue 12): a vertical error of delta metres at any
    // point of the box that is in view covers at most delta * S / (2 tan(fov / 2)) / lodDistance pixels.
    // Checked against the projection of the segment's two ends (VerticalSegmentProjector, the camera's
    // matrices) at points all over random boxes and cameras, looking level, up and steeply down.
    std::mt19937_64 rng(12);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    int inView = 0;
    double tightest = 0.0;  // the largest screen length over the bound seen: how tight the bound is
    for (int trial = 0; trial < 300; ++trial) {
        Camera cam;
        cam.position = {uni(rng) * 1000.0, uni(rng) * 1000.0, 50.0 + uni(rng) * 500.0};
        cam.yaw = uni(rng) * 6.28;
        cam.pitch = (uni(rng) - 0.7) * 2.4;
        cam.verticalFov = 0.5 + uni(rng) * 1.5;
        cam.viewportWidth = 320 + static_cast<int>(uni(rng) * 1600);
        cam.viewportHeight = 240 + static_cast<int>(uni(rng) * 900);
        const double k = verticalErrorFactor(cam);
        const double pixelsPerRadian = cam.viewportHeight / (2.0 * std::tan(cam.verticalFov / 2));
        const VerticalSegmentProjector projector(cam);
        const glm::dvec3 lo{uni(rng) * 1500.0 - 250.0, uni(rng) * 1500.0 - 250.0, uni(rng) * 300.0};
        const Aabb box{lo, lo + glm::dvec3(10.0 + uni(rng) * 400.0, 10.0 + uni(rng) * 400.0, uni(rng) * 200.0)};
        const double d = lodDistance(cam, k, box);
        ASSERT_GT(d, 0.0);
        for (int s = 0; s < 200; ++s) {
            const glm::dvec3 p = box.lo + (box.hi - box.lo) * glm::dvec3(uni(rng), uni(rng), uni(rng));
            const double delta = 1e-4 * glm::length(p - cam.position);
            const double px = projector.pixels(p.x, p.y, p.z, delta);
            if (px < 0.0) {
                continue;
            }
            ++inView;
            const double bound = delta * pixelsPerRadian / d;
            ASSERT_LE(px, bound * (1.0 + 1e-3)) << "trial " << trial;
            tightest = std::max(tightest, px / bound);
        }
    }
    EXPECT_GT(inView, 2000);
    EXPECT_GT(tightest, 0.9) << "the bound should be nearly reached somewhere";
}

}  // namespace
}  // namespace terrain

namespace terrain {
namespace {

// ---- Visibility (issue 16): hidden nodes are selected as they are and request nothing ----

TEST(LodSelectorVisibility, HiddenNodesAreNotRefinedAndTheRestIsUnchanged)
{
    SyntheticTree tree(7, 77, kExtent);
    Camera cam;
    cam.position = {kExtent.originX + 2048.0, kExtent.originY - 300.0, 60.0};  // south of the middle, looking north
    cam.pitch = -0.2;
    const double mid = kExtent.originX + kExtent.rootSize / 2;
    // Hidden: nodes of level >= 2 wholly in the west half.
    auto westHidden = [&](const NodeId& id) {
        const double size = kExtent.nodeSize(id.level);
        return id.level >= 2 && kExtent.originX + (id.x + 1) * size <= mid;
    };
    LodSelection plain, hiddenOut;
    selectNodes(tree, cam, 2.0, sometimesResident, plain);
    selectNodes(tree, cam, 2.0, sometimesResident, westHidden, hiddenOut);
    ASSERT_GT(plain.nodes.size(), 20u);
    EXPECT_LT(hiddenOut.nodes.size(), plain.nodes.size()) << "the west half must be drawn coarser";
    EXPECT_EQ(plain.hiddenNodes, 0u);

    auto inWest = [&](const NodeId& id) { return kExtent.originX + (id.x + 1) * kExtent.nodeSize(id.level) <= mid; };
    std::size_t hiddenSelected = 0;
    for (const SelectedNode& n : hiddenOut.nodes) {
        if (!inWest(n.id) || n.id.level < 2) {
            // Where nothing is hidden the selection is the plain one.
            EXPECT_TRUE(std::any_of(plain.nodes.begin(), plain.nodes.end(), [&](const SelectedNode& p) {
                return p.id == n.id;
            })) << n.id.toString();
            continue;
        }
        // In the west half refinement stops at the first hidden level: a level-2 node, or a shallower one
        // the plain selection also stops at.
        const bool stopsHere =
            std::any_of(plain.nodes.begin(), plain.nodes.end(), [&](const SelectedNode& p) { return p.id == n.id; });
        EXPECT_TRUE(n.id.level == 2 || stopsHere) << n.id.toString();
        // Counted as hidden where the plain selection refined it, or wanted to and requested its children.
        const bool requested = std::any_of(plain.requests.begin(), plain.requests.end(),
                                           [&](const ChildRequest& r) { return r.parent == n.id; });
        hiddenSelected += !stopsHere || requested ? 1 : 0;
    }
    EXPECT_EQ(hiddenOut.hiddenNodes, hiddenSelected);
    EXPECT_GT(hiddenOut.hiddenNodes, 0u);
    // Every plain node is covered by exactly one node of the hidden selection (a partition, coarser in
    // the west), and no request comes from below a hidden node.
    for (const SelectedNode& p : plain.nodes) {
        const auto covering = std::count_if(hiddenOut.nodes.begin(), hiddenOut.nodes.end(),
                                            [&](const SelectedNode& n) { return isAncestor(n.id, p.id); });
        EXPECT_EQ(covering, 1) << p.id.toString();
    }
    for (const ChildRequest& r : hiddenOut.requests) {
        EXPECT_FALSE(inWest(r.parent) && r.parent.level >= 2) << r.parent.toString();
    }
    std::size_t westRequests = 0;
    for (const ChildRequest& r : plain.requests) {
        westRequests += inWest(r.parent) && r.parent.level >= 2 ? 1 : 0;
    }
    EXPECT_EQ(hiddenOut.requests.size(), plain.requests.size() - westRequests) << "the other requests are the same";
    // A hidden node whose children are not resident requested them in the plain selection.
    EXPECT_LE(hiddenOut.requestsSkippedHidden, westRequests);
}

}  // namespace
}  // namespace terrain
