// The screen-space error meter (lod/ErrorMeter.h) and `tengine-tool error` (apps/ErrorCommand.h), checked
// against brute-force references written from their documentation, not from the meter: every sample of the
// input grid (or of the deepest dynamic level) in view, the drawn surface from drawnHeightAt or from the
// decoded nodes interpolated here with explicit barycentric weights, the reference from the input data or
// surfaceHeightAt, and vertical segments projected with the camera's glm matrices.
#include "MapTestSupport.h"

#include "apps/ErrorCommand.h"
#include "lod/ErrorMeter.h"
#include "lod/HeightQuery.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "synthesis/DetailErrorModel.h"
#include "synthesis/LeafErrorEstimator.h"

#include <gtest/gtest.h>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace terrain {
namespace {

const std::filesystem::path kMaterials = TERRAIN_MATERIALS_DIR;

// ---- An independent projection ----

/// Vertical segments projected the textbook way: world -> clip with camera.viewProjection() (absolute
/// positions, not camera-relative), inside when |x|, |y|, |z| <= w, then NDC -> pixels; an upper end in
/// front of the near plane is moved along the segment to clip w = near (w is the eye depth).
class BruteProjector {
public:
    explicit BruteProjector(const Camera& camera)
        : mMatrix(camera.viewProjection()),
          mWidth(camera.viewportWidth),
          mHeight(camera.viewportHeight),
          mNear(camera.nearPlane)
    {
    }

    glm::dvec4 clip(const glm::dvec3& p) const { return mMatrix * glm::dvec4(p, 1.0); }

    bool inView(const glm::dvec3& p) const
    {
        const glm::dvec4 c = clip(p);
        return c.w > 0.0 && std::abs(c.x) <= c.w && std::abs(c.y) <= c.w && std::abs(c.z) <= c.w;
    }

    /// Pixel coordinates (origin at the bottom-left corner of the viewport).
    glm::dvec2 pixel(const glm::dvec3& p) const
    {
        const glm::dvec4 c = clip(p);
        return {(c.x / c.w + 1.0) * 0.5 * mWidth, (c.y / c.w + 1.0) * 0.5 * mHeight};
    }

    /// Pixels between (x, y, z) and (x, y, z + dz), -1 when (x, y, z) is outside the frustum.
    double pixels(double x, double y, double z, double dz) const
    {
        const glm::dvec3 a{x, y, z};
        if (!inView(a)) {
            return -1.0;
        }
        glm::dvec3 b{x, y, z + dz};
        const double wa = clip(a).w, wb = clip(b).w;
        if (wb < mNear) {
            b = a + (wa - mNear) / (wa - wb) * (b - a);
        }
        return glm::length(pixel(b) - pixel(a));
    }

private:
    glm::dmat4 mMatrix;
    double mWidth, mHeight, mNear;
};

/// The world point at normalized device coordinates (u, v) and eye depth `depth` metres.
glm::dvec3 unproject(const Camera& camera, double u, double v, double depth)
{
    const double tanV = std::tan(camera.verticalFov * 0.5);
    const double tanH = tanV * camera.aspect();
    return camera.position + depth * (camera.forward() + u * tanH * camera.right() + v * tanV * camera.up());
}

Camera makeCamera(glm::dvec3 position, double yawDegrees, double pitchDegrees)
{
    Camera camera;
    camera.position = position;
    camera.yaw = yawDegrees * kRadiansPerDegree;
    camera.pitch = pitchDegrees * kRadiansPerDegree;
    camera.farPlane = 100000.0;
    return camera;
}

TEST(ErrorMeterProjectorTest, MatchesTheCameraMatricesInsideTheFrustum)
{
    const std::vector<Camera> cameras = {
        makeCamera({512.0, 512.0, 2500.0}, 0.0, -90.0),   // straight down
        makeCamera({100.0, -40.0, 1030.0}, 37.0, -12.0),  // low and oblique
        makeCamera({-3.0e5, 2.0e5, 800.0}, 200.0, 25.0),  // far from the origin, looking up
    };
    int compared = 0;
    for (const Camera& camera : cameras) {
        const VerticalSegmentProjector projector(camera);
        const BruteProjector brute(camera);
        for (int k = 0; k < 200; ++k) {
            const double u = -0.95 + 1.9 * test::unitNoise(1, k, 0);
            const double v = -0.95 + 1.9 * test::unitNoise(2, k, 0);
            const double depth = 2.0 + 3000.0 * test::unitNoise(3, k, 0);
            // Short and long, up and down; the long ones may leave the view, which must not matter.
            const double dz = (test::unitNoise(4, k, 0) - 0.5) * (k % 2 ? 2.0 : 400.0);
            const glm::dvec3 p = unproject(camera, u, v, depth);
            ASSERT_TRUE(brute.inView(p));
            const double expected = brute.pixels(p.x, p.y, p.z, dz);
            const double got = projector.pixels(p.x, p.y, p.z, dz);
            ASSERT_GE(expected, 0.0);
            EXPECT_NEAR(got, expected, 1e-6 * expected + 1e-9)
                << "camera " << compared / 200 << " point " << k << " depth " << depth << " dz " << dz;
            ++compared;
        }
    }
    EXPECT_EQ(compared, 600);
}

TEST(ErrorMeterProjectorTest, AgreesWithTheClosedFormForAHorizontalCamera)
{
    // Looking north from the origin: a segment of dz metres starting on the view axis at distance d spans
    // dz / (d tan(fov / 2)) in NDC, half the viewport height per unit.
    const Camera camera = makeCamera({0.0, 0.0, 0.0}, 0.0, 0.0);
    const VerticalSegmentProjector projector(camera);
    for (double d : {1.0, 10.0, 1234.5}) {
        for (double dz : {0.01, 0.5, -3.0}) {
            const double expected =
                std::abs(dz) / (d * std::tan(camera.verticalFov * 0.5)) * 0.5 * camera.viewportHeight;
            EXPECT_NEAR(projector.pixels(0.0, d, 0.0, dz), expected, 1e-9 * expected) << d << " " << dz;
        }
    }
    EXPECT_EQ(projector.pixels(0.0, 10.0, 0.0, 0.0), 0.0);
}

TEST(ErrorMeterProjectorTest, ClipsSegmentsThatLeaveThroughTheNearPlane)
{
    // Looking straight down from 100 m, eye depth is height below the camera: a segment from just beyond the
    // near plane up past the camera is seen from its foot to the near plane, at z = 100 - near.
    const Camera camera = makeCamera({10.0, 20.0, 100.0}, 30.0, -90.0);
    const VerticalSegmentProjector projector(camera);
    const BruteProjector brute(camera);
    const double nearZ = camera.position.z - camera.nearPlane;
    for (const glm::dvec3& p : {unproject(camera, 0.5, 0.3, 0.75), unproject(camera, -0.9, 0.8, 3.0)}) {
        const double expected = brute.pixels(p.x, p.y, p.z, 200.0);
        ASSERT_GT(expected, 0.0);
        EXPECT_NEAR(projector.pixels(p.x, p.y, p.z, 200.0), expected, 1e-6 * expected);
        EXPECT_NEAR(projector.pixels(p.x, p.y, p.z, 200.0), projector.pixels(p.x, p.y, p.z, nearZ - p.z),
                    1e-6 * expected);
        EXPECT_GT(projector.pixels(p.x, p.y, p.z, 200.0), projector.pixels(p.x, p.y, p.z, 0.9 * (nearZ - p.z)));
    }
}

TEST(ErrorMeterProjectorTest, PointsOutsideTheFrustumGiveMinusOne)
{
    const Camera camera = makeCamera({100.0, 200.0, 50.0}, 45.0, -10.0);
    const VerticalSegmentProjector projector(camera);
    const BruteProjector brute(camera);
    const glm::dvec3 outside[] = {
        camera.position - 10.0 * camera.forward(),            // behind the camera
        camera.position,                                      // at the eye
        unproject(camera, 0.0, 0.0, 0.5 * camera.nearPlane),  // in front of the near plane
        unproject(camera, 0.0, 0.0, 1.5 * camera.farPlane),   // beyond the far plane
        unproject(camera, 1.2, 0.0, 100.0),                   // right of the view
        unproject(camera, -1.05, 0.0, 100.0),                 // left of it
        unproject(camera, 0.0, 1.1, 100.0),                   // above it
        unproject(camera, 0.3, -1.3, 100.0),                  // below it
    };
    for (const glm::dvec3& p : outside) {
        EXPECT_FALSE(brute.inView(p));
        EXPECT_EQ(projector.pixels(p.x, p.y, p.z, 1.0), -1.0) << p.x << " " << p.y << " " << p.z;
    }
    const glm::dvec3 inside = unproject(camera, 0.99, -0.99, 100.0);
    EXPECT_GT(projector.pixels(inside.x, inside.y, inside.z, 1.0), 0.0);
}

// ---- Small maps, streamers, brute-force errors ----

/// Runs frames (inline loads) until the selection wants nothing more.
void settle(TerrainStreamer& streamer, const Camera& camera, double tau)
{
    const FrameStats stats = streamer.settle(Settle::Complete, camera, tau);
    EXPECT_EQ(stats.requested, stats.deferred) << "the streamer did not settle";
}

std::unique_ptr<TerrainStreamer> makeStreamer(NodeSource& source, const MapHeader& header)
{
    StreamerOptions options;
    options.cacheSize = 4000;
    options.queueLimit = 64;
    options.workers = 0;
    auto streamer = TerrainStreamer::create(source, extentOf(header), options);
    EXPECT_TRUE(streamer.ok()) << streamer.error().message;
    return std::move(streamer).value();
}

Expected<FrameError> measure(ErrorMeter& meter, const TerrainStreamer& streamer, const LodSelection& selection,
                             const Camera& camera, double tau)
{
    return meter.measure(
        makeDrawList(selection, streamer, camera), [&streamer](const NodeId& id) { return streamer.node(id); }, tau);
}

/// The largest error over a set of points.
struct BruteError {
    double maxPixels = -1.0;
    double sumPixels = 0.0;
    std::size_t points = 0;  ///< points in view (addDrawnError: distinct; bruteForceDecoded: per node)
    double worstX = 0.0, worstY = 0.0;

    double mean() const { return points ? sumPixels / static_cast<double>(points) : 0.0; }

    void add(double px, double x, double y)
    {
        if (px > maxPixels) {
            maxPixels = px;
            worstX = x;
            worstY = y;
        }
    }
};

/// Offsets that put a query point just inside each node whose closed square holds it: a point on a node
/// edge is drawn by both neighbours (at T-junctions at different heights, hidden by skirts), and the meter
/// measures it under each, while drawnHeightAt answers for the first node that contains it. 1e-9 m moves a
/// drawn height by about slope x 1e-9 m: far below the tolerances (positions here are < 2^11 m, so the
/// offsets are exact to about 2e-13 m).
constexpr double kNudge = 1e-9;
constexpr std::array<std::array<double, 2>, 4> kNudges = {
    {{-kNudge, -kNudge}, {kNudge, -kNudge}, {-kNudge, kNudge}, {kNudge, kNudge}}};

/// The error at grid point (x, y) with reference height `ref`: the drawn surface under every selected node
/// holding the point, from drawnHeightAt. Adds to `out`; returns whether the point was in view.
bool addDrawnError(const TerrainStreamer& streamer, const MapHeader& header, const BruteProjector& projector, double x,
                   double y, const std::function<double()>& ref, BruteError& out)
{
    bool inView = false;
    double worst = -1.0;
    std::optional<double> reference;  // made once, and only for points in view
    for (const auto& [dx, dy] : kNudges) {
        const std::optional<double> z = drawnHeightAt(streamer, header, x + dx, y + dy);
        if (!z || !projector.inView({x, y, *z})) {
            continue;
        }
        if (!reference) {
            reference = ref();
        }
        worst = std::max(worst, projector.pixels(x, y, *z, *reference - *z));
        inView = true;
    }
    if (inView) {
        out.add(worst, x, y);
        out.sumPixels += worst;
        ++out.points;
    }
    return inView;
}

/// A static node's surface at world (x, y) (clamped into its square), metres: its codes on the template
/// triangulation (each grid quad split from south-west to north-east), by barycentric weights.
double staticSurface(const MapHeader& h, const StaticNode& node, double x, double y)
{
    const int n1 = static_cast<int>(h.chunkSize) - 1;
    const double spacing = h.spacingAt(node.id.level);
    const double lx = std::clamp((x - h.originX) / spacing - node.id.x * static_cast<double>(n1), 0.0, 1.0 * n1);
    const double ly = std::clamp((y - h.originY) / spacing - node.id.y * static_cast<double>(n1), 0.0, 1.0 * n1);
    const int i = std::min(static_cast<int>(std::floor(lx)), n1 - 1);
    const int j = std::min(static_cast<int>(std::floor(ly)), n1 - 1);
    const double fx = lx - i, fy = ly - j;
    auto c = [&](int di, int dj) -> double { return test::windowCode(h, node, i + di, j + dj); };
    // Triangle (SW, SE, NE) below the diagonal, (SW, NE, NW) above it.
    const double code = fx >= fy ? (1.0 - fx) * c(0, 0) + (fx - fy) * c(1, 0) + fy * c(1, 1)
                                 : (1.0 - fy) * c(0, 0) + (fy - fx) * c(0, 1) + fx * c(1, 1);
    return h.heightOffset + h.heightStep * code;
}

struct StaticMapData {
    test::ScratchDir dir;
    HeightField field;
    std::unique_ptr<MapFile> map;
    test::DecodedTree tree;
};

/// A static map of a 129 x 129 hilly field at 8 m (1024 m square, 4 levels of 17 x 17 chunks, no padding:
/// its finest grid is the input), without detail synthesis.
class ErrorMeterStaticTest : public ::testing::Test {
protected:
    static constexpr int kChunk = 17;
    static constexpr int kSamples = 129;

    static void SetUpTestSuite()
    {
        sData = new StaticMapData;
        sData->field = test::hillyField(kSamples, kSamples, 5);
        BuildOptions options = test::testOptions(kChunk);
        options.spacing = 8.0;
        auto report = buildMap(sData->field, options, sData->dir / "static.map");
        ASSERT_TRUE(report.ok()) << report.error().message;
        sData->map = test::openMap(sData->dir / "static.map");
        ASSERT_TRUE(sData->map);
        auto tree = test::decodeTree(*sData->map);
        ASSERT_TRUE(tree.ok()) << tree.error().message;
        sData->tree = std::move(tree).value();
    }
    static void TearDownTestSuite()
    {
        delete sData;
        sData = nullptr;
    }

    void SetUp() override
    {
        ASSERT_TRUE(sData && sData->map);
        const MapHeader& h = header();
        ASSERT_EQ(h.gridSize(), static_cast<std::uint64_t>(kSamples));
        ASSERT_EQ(h.validWidth, static_cast<std::uint32_t>(kSamples));
        ASSERT_EQ(h.maxErrorBound, 0.0);
        mSource = std::make_unique<TerrainNodeSource>(*sData->map, DetailPolicy{});
        mStreamer = makeStreamer(*mSource, h);
    }

    static const MapHeader& header() { return sData->map->header(); }
    static const MapFile& map() { return *sData->map; }
    static double worldX(int i) { return header().originX + i * header().sampleSpacing; }
    static double worldY(int j) { return header().originY + j * header().sampleSpacing; }
    /// The input sample (the map is lossless and unpadded, so this is the finest static grid).
    static double input(int i, int j) { return sData->field.at(i, j); }

    Camera groundCamera(double x, double y, double above, double yawDegrees, double pitchDegrees) const
    {
        auto ground = staticHeightAt(map(), x, y);
        EXPECT_TRUE(ground.ok());
        return makeCamera({x, y, ground->height + above}, yawDegrees, pitchDegrees);
    }

    /// Brute force over every sample of the finest static grid: drawn from drawnHeightAt, reference the input
    /// sample (which is staticHeightAt there: FinestStaticGridIsTheInput; staticHeightAt itself decodes a
    /// path of nodes per call, too slow to ask at every sample of every case).
    BruteError bruteForceDrawn(const Camera& camera) const
    {
        const BruteProjector projector(camera);
        BruteError out;
        for (int j = 0; j < kSamples; ++j) {
            for (int i = 0; i < kSamples; ++i) {
                addDrawnError(
                    *mStreamer, header(), projector, worldX(i), worldY(j), [&] { return input(i, j); }, out);
            }
        }
        return out;
    }

    /// The surface selected node `s` draws at (x, y), from the decoded map: its own surface blended with its
    /// parent's by its morph factor (eq. 3.4).
    static double decodedDrawn(const SelectedNode& s, double x, double y)
    {
        const StaticNode* own = sData->tree.find(s.id);
        EXPECT_TRUE(own) << s.id.toString();
        double z = staticSurface(header(), *own, x, y);
        if (!s.id.isRoot() && s.morph < 1.0f) {
            const double f = s.morph;
            z = f * z + (1.0 - f) * staticSurface(header(), *sData->tree.find(s.id.parent()), x, y);
        }
        return z;
    }

    /// Counts of the refinements that bought nothing, by brute force (see FrameError::refined).
    struct BruteRefinements {
        std::size_t refined = 0;
        std::size_t withinTau = 0;
    };

    /// Brute force over the selected nodes of `selection`, every finest-grid sample in each one's closed
    /// square: the drawn surface from the decoded map (own surface blended with the parent's by the morph
    /// factor, eq. 3.4) against the input. Also the worst error of each resident ancestor's own surface at
    /// those of the points that are in view, for the refinement counts at `tau`.
    BruteError bruteForceDecoded(const LodSelection& selection, const Camera& camera, double tau,
                                 BruteRefinements* refinements = nullptr) const
    {
        const MapHeader& h = header();
        const BruteProjector projector(camera);
        const int n1 = kChunk - 1;
        BruteError out;
        std::map<std::uint64_t, double> ancestorWorst;
        for (const SelectedNode& s : selection.nodes) {
            const int stride = 1 << (static_cast<int>(h.levels) - 1 - s.id.level);
            std::vector<const StaticNode*> ancestors;
            for (NodeId up = s.id; !up.isRoot();) {
                up = up.parent();
                if (mStreamer->node(up)) {
                    ancestors.push_back(sData->tree.find(up));
                }
            }
            for (int gj = static_cast<int>(s.id.y) * n1 * stride; gj <= (static_cast<int>(s.id.y) + 1) * n1 * stride;
                 ++gj) {
                for (int gi = static_cast<int>(s.id.x) * n1 * stride;
                     gi <= (static_cast<int>(s.id.x) + 1) * n1 * stride; ++gi) {
                    const double x = worldX(gi), y = worldY(gj), ref = input(gi, gj);
                    const double z = decodedDrawn(s, x, y);
                    const double px = projector.pixels(x, y, z, ref - z);
                    if (px < 0.0) {
                        continue;
                    }
                    out.add(px, x, y);
                    out.sumPixels += px;
                    ++out.points;
                    for (const StaticNode* a : ancestors) {
                        const double za = staticSurface(h, *a, x, y);
                        double& worst = ancestorWorst.try_emplace(a->id.key(), 0.0).first->second;
                        worst = std::max(worst, projector.pixels(x, y, za, ref - za));
                    }
                }
            }
        }
        if (refinements) {
            refinements->refined = ancestorWorst.size();
            refinements->withinTau = static_cast<std::size_t>(std::count_if(
                ancestorWorst.begin(), ancestorWorst.end(), [&](const auto& a) { return a.second <= tau; }));
        }
        return out;
    }

    std::unique_ptr<TerrainNodeSource> mSource;
    std::unique_ptr<TerrainStreamer> mStreamer;

    static StaticMapData* sData;
};

StaticMapData* ErrorMeterStaticTest::sData = nullptr;

/// Both are exact maxima over the same points (the reference leaves' vertices: the finest static grid, or the
/// deepest dynamic level's), each point under every selected node that holds it, computed through different
/// code and matrices: they agree to rounding (about 5e-9 px here, from the 1e-9 m nudges and the absolute
/// rather than camera-relative matrix).
void expectSameMaximum(double meter, double brute, const std::string& what)
{
    EXPECT_NEAR(meter, brute, 1e-6 * brute + 1e-6) << what;
}

TEST_F(ErrorMeterStaticTest, FinestStaticGridIsTheInput)
{
    // The reference of a static map without detail is its finest static level: here the input itself.
    int checked = 0;
    for (int j = 0; j < kSamples; j += 3) {
        for (int i = 0; i < kSamples; i += 3) {
            auto sample = staticHeightAt(map(), worldX(i), worldY(j));
            ASSERT_TRUE(sample.ok()) << sample.error().message;
            EXPECT_EQ(sample->height, input(i, j)) << i << ", " << j;
            EXPECT_EQ(sample->node.level, static_cast<int>(header().levels) - 1);
            ++checked;
        }
    }
    EXPECT_EQ(checked, 43 * 43);
}

TEST_F(ErrorMeterStaticTest, MaximumIsTheBruteForceMaximumOverTheInputGrid)
{
    struct Case {
        const char* name;
        Camera camera;
        double tau;
    };
    const double size = header().nodeSizeAt(0);
    const std::vector<Case> cases = {
        // With these settings: level 2 nodes, all morphing.
        {"high, looking down", groundCamera(0.5 * size, 0.45 * size, 1500.0, 0.0, -90.0), 8.0},
        // Static leaves, morphing towards level 2.
        {"low, oblique", groundCamera(0.2 * size, 0.15 * size, 25.0, 40.0, -15.0), 2.0},
        // Levels 2 and 3.
        {"low, oblique, coarse tau", groundCamera(0.1 * size, 0.1 * size, 100.0, 45.0, -15.0), 16.0},
    };
    for (const Case& c : cases) {
        settle(*mStreamer, c.camera, c.tau);
        ErrorMeter meter(header(), *mSource, {c.tau / 8.0, 1024, 16});
        auto measured = measure(meter, *mStreamer, mStreamer->selection(), c.camera, c.tau);
        ASSERT_TRUE(measured.ok()) << measured.error().message;
        const BruteError brute = bruteForceDrawn(c.camera);
        std::printf(
            "[ %s ] %zu nodes: meter max %.9f px at (%.1f, %.1f), brute force %.9f px at (%.1f, %.1f); "
            "mean %.6f vs %.6f; points %zu vs %zu distinct\n",
            c.name, measured->nodes, measured->maxPixels, measured->worstX, measured->worstY, brute.maxPixels,
            brute.worstX, brute.worstY, measured->meanPixels, brute.mean(), measured->points, brute.points);
        ASSERT_GT(brute.points, 0u) << c.name;
        ASSERT_GT(brute.maxPixels, 0.0) << c.name << ": the drawn surface is not the data anywhere in view";
        expectSameMaximum(measured->maxPixels, brute.maxPixels, c.name);
        // Every in-view grid point is a vertex of at least one reference leaf; edge vertices count once per leaf.
        EXPECT_GE(measured->points, brute.points) << c.name;
        EXPECT_LE(measured->points, 4 * brute.points) << c.name;
        if (&c == &cases.front()) {
            // The whole map in view: every vertex of the 8 x 8 static leaves is measured, once per leaf.
            EXPECT_EQ(brute.points, static_cast<std::size_t>(kSamples * kSamples));
            EXPECT_EQ(measured->referenceNodes, 64u);
            EXPECT_EQ(measured->points, 64u * kChunk * kChunk);
        }
        EXPECT_EQ(measured->pixels.size(), measured->points) << c.name;
        EXPECT_GT(measured->meanPixels, 0.0) << c.name;
        EXPECT_LE(measured->meanPixels, measured->maxPixels) << c.name;
        EXPECT_LE(measured->p99Pixels, measured->maxPixels) << c.name;
        EXPECT_EQ(measured->nodes, mStreamer->selection().nodes.size()) << c.name;
        EXPECT_EQ(measured->deepestReference, static_cast<int>(header().levels) - 1) << c.name;
        // The worst point: a grid sample in the worst node, where that node's error is the maximum.
        const auto worst = std::find_if(mStreamer->selection().nodes.begin(), mStreamer->selection().nodes.end(),
                                        [&](const SelectedNode& s) { return s.id == measured->worstNode; });
        ASSERT_NE(worst, mStreamer->selection().nodes.end()) << c.name;
        const double gi = (measured->worstX - header().originX) / header().sampleSpacing;
        const double gj = (measured->worstY - header().originY) / header().sampleSpacing;
        ASSERT_EQ(gi, std::round(gi));
        ASSERT_EQ(gj, std::round(gj));
        const double z = decodedDrawn(*worst, measured->worstX, measured->worstY);
        const double ref = input(static_cast<int>(gi), static_cast<int>(gj));
        EXPECT_NEAR(measured->maxMetres, std::abs(ref - z), 1e-6) << c.name;
        EXPECT_NEAR(BruteProjector(c.camera).pixels(measured->worstX, measured->worstY, z, ref - z),
                    measured->maxPixels, 1e-6 * measured->maxPixels)
            << c.name;
    }
}

/// measureSurface (issue 17: another method's surface, e.g. clipmaps): every in-view vertex of the reference (here
/// the input grid) against the drawn height there, the same maximum as brute force over the input.
TEST_F(ErrorMeterStaticTest, ASurfaceDrawnByAnotherMethodIsMeasuredAtEveryReferenceVertex)
{
    const double size = header().nodeSizeAt(0);
    const Camera camera = groundCamera(0.4 * size, 0.3 * size, 120.0, 30.0, -25.0);
    const double offset = header().heightOffset;
    auto plane = [](double x, double y) { return 1000.0 + 0.05 * x - 0.03 * y; };
    ErrorMeter meter(header(), *mSource, {0.25, 1024, 16});
    auto measured =
        meter.measureSurface([&](double x, double y) { return std::optional<double>(plane(x, y) - offset); }, camera);
    ASSERT_TRUE(measured.ok()) << measured.error().message;
    const BruteProjector projector(camera);
    BruteError brute;
    for (int j = 0; j < kSamples; ++j) {
        for (int i = 0; i < kSamples; ++i) {
            const double x = worldX(i), y = worldY(j), z = plane(x, y);
            const double px = projector.pixels(x, y, z, input(i, j) - z);
            if (px >= 0.0) {
                brute.add(px, x, y);
                ++brute.points;
            }
        }
    }
    ASSERT_GT(brute.points, 1000u);
    expectSameMaximum(measured->maxPixels, brute.maxPixels, "plane");
    EXPECT_GE(measured->points, brute.points);  // leaf edges count once per leaf
    EXPECT_LE(measured->points, 4 * brute.points);
    EXPECT_EQ(measured->deepestReference, static_cast<int>(header().levels) - 1);
    EXPECT_EQ(measured->nodes, 0u);
    // Where nothing is drawn, nothing is measured.
    auto nothing = meter.measureSurface([](double, double) { return std::optional<double>(); }, camera);
    ASSERT_TRUE(nothing.ok());
    EXPECT_EQ(nothing->points, 0u);
}

TEST_F(ErrorMeterStaticTest, MorphFactorsAreMeasured)
{
    // With these settings levels 2 and 3 are drawn, nearly all of them morphing.
    const double size = header().nodeSizeAt(0), tau = 16.0;
    const Camera camera = groundCamera(0.3 * size, 0.25 * size, 300.0, 20.0, -40.0);
    settle(*mStreamer, camera, tau);
    const LodSelection& selection = mStreamer->selection();
    int morphing = 0;
    for (const SelectedNode& s : selection.nodes) {
        morphing += !s.id.isRoot() && s.morph < 0.999f ? 1 : 0;
    }
    ASSERT_GT(morphing, 0) << "the camera must see a node between its own detail and its parent's";

    ErrorMeter meter(header(), *mSource, {tau / 8.0, 1024, 16});
    auto measured = measure(meter, *mStreamer, selection, camera, tau);
    ASSERT_TRUE(measured.ok()) << measured.error().message;
    // Two brute forces of the drawn surface: drawnHeightAt, and the decoded nodes blended here.
    const BruteError viaQuery = bruteForceDrawn(camera);
    const BruteError viaNodes = bruteForceDecoded(selection, camera, tau);
    expectSameMaximum(measured->maxPixels, viaQuery.maxPixels, "with morph, drawnHeightAt");
    expectSameMaximum(measured->maxPixels, viaNodes.maxPixels, "with morph, decoded nodes");

    // The same nodes drawn at their own detail.
    LodSelection unmorphed = selection;
    for (SelectedNode& s : unmorphed.nodes) {
        s.morph = 1.0f;
    }
    auto flat = measure(meter, *mStreamer, unmorphed, camera, tau);
    ASSERT_TRUE(flat.ok()) << flat.error().message;
    const BruteError unmorphedNodes = bruteForceDecoded(unmorphed, camera, tau);
    expectSameMaximum(flat->maxPixels, unmorphedNodes.maxPixels, "without morph, decoded nodes");
    std::printf(
        "%d of %zu nodes morphing: max %.6f px (brute force %.6f, %.6f), mean %.6f; at morph 1: max %.6f "
        "px (brute force %.6f), mean %.6f\n",
        morphing, selection.nodes.size(), measured->maxPixels, viaQuery.maxPixels, viaNodes.maxPixels,
        measured->meanPixels, flat->maxPixels, unmorphedNodes.maxPixels, flat->meanPixels);
    // Nodes part way to their parents' surfaces are further from the data than at their own detail: the
    // figures must change (a meter that ignored the morph would give the same ones).
    EXPECT_GT(std::abs(measured->meanPixels - flat->meanPixels), 1e-6 * flat->meanPixels);
    EXPECT_GT(measured->meanPixels, flat->meanPixels);
    EXPECT_NE(measured->maxPixels, flat->maxPixels);
}

TEST_F(ErrorMeterStaticTest, RefinementsThatBoughtNothing)
{
    const double size = header().nodeSizeAt(0);
    struct Case {
        Camera camera;
        double tau;
    };
    // Looking straight down, vertical errors shrink towards the middle of the view, and refinements that
    // eq. 3.3 asks for buy little there; obliquely they buy more.
    const Camera above = groundCamera(0.5 * size, 0.45 * size, 1500.0, 0.0, -90.0);
    const std::vector<Case> cases = {
        {above, 2.0},
        {above, 8.0},
        {groundCamera(0.3 * size, 0.25 * size, 300.0, 20.0, -40.0), 16.0},
        {groundCamera(0.2 * size, 0.15 * size, 25.0, 40.0, -15.0), 2.0},
    };
    int nontrivial = 0;
    for (const auto& [camera, tau] : cases) {
        settle(*mStreamer, camera, tau);
        ErrorMeter meter(header(), *mSource, {tau / 8.0, 1024, 16});
        auto measured = measure(meter, *mStreamer, mStreamer->selection(), camera, tau);
        ASSERT_TRUE(measured.ok()) << measured.error().message;
        BruteRefinements brute;
        const BruteError error = bruteForceDecoded(mStreamer->selection(), camera, tau, &brute);
        std::printf(
            "tau %.1f: %zu nodes, refined %zu (brute force %zu), within tau %zu (brute force %zu); max "
            "%.6f px (brute force %.6f)\n",
            tau, measured->nodes, measured->refined, brute.refined, measured->refinedWithinTau, brute.withinTau,
            measured->maxPixels, error.maxPixels);
        EXPECT_LE(measured->refinedWithinTau, measured->refined);
        EXPECT_EQ(measured->refined, brute.refined) << tau;
        EXPECT_EQ(measured->refinedWithinTau, brute.withinTau) << tau;
        expectSameMaximum(measured->maxPixels, error.maxPixels, "tau " + std::to_string(tau));
        nontrivial += measured->refinedWithinTau > 0 && measured->refinedWithinTau < measured->refined ? 1 : 0;
    }
    EXPECT_GE(nontrivial, 2) << "the cases must have refinements that bought something and some that did not";

    // A tau so large that the root alone is drawn (from above its box: inside it, d = 0 always refines):
    // nothing is refined, and the error is the root's.
    const double huge = 1e6;
    const Camera camera = above;
    settle(*mStreamer, camera, huge);
    ASSERT_EQ(mStreamer->selection().nodes.size(), 1u);
    ASSERT_TRUE(mStreamer->selection().nodes[0].id.isRoot());
    ErrorMeter meter(header(), *mSource, {0.25, 1024, 16});
    auto measured = measure(meter, *mStreamer, mStreamer->selection(), camera, huge);
    ASSERT_TRUE(measured.ok()) << measured.error().message;
    EXPECT_EQ(measured->refined, 0u);
    EXPECT_EQ(measured->refinedWithinTau, 0u);
    EXPECT_EQ(measured->nodes, 1u);
    const BruteError root = bruteForceDecoded(mStreamer->selection(), camera, huge);
    ASSERT_GT(root.maxPixels, 1.0);
    expectSameMaximum(measured->maxPixels, root.maxPixels, "the root alone");
}

/// The oracle (ErrorMeter::oracle) against brute force: every node it draws is within tau over every input
/// sample in view (the decoded map against the input, not the meter), every node it refined was over tau,
/// and the selection the bounds make has at least as many nodes.
TEST_F(ErrorMeterStaticTest, OracleDrawsTheFewestNodesWithinTau)
{
    const double size = header().nodeSizeAt(0);
    struct Case {
        Camera camera;
        double tau;
    };
    const std::vector<Case> cases = {
        {groundCamera(0.5 * size, 0.45 * size, 1500.0, 0.0, -90.0), 2.0},
        {groundCamera(0.3 * size, 0.25 * size, 300.0, 20.0, -40.0), 4.0},
        {groundCamera(0.2 * size, 0.15 * size, 25.0, 40.0, -15.0), 2.0},
        {groundCamera(0.2 * size, 0.15 * size, 25.0, 40.0, -15.0), 0.5},
    };
    int fewer = 0;
    for (const auto& [camera, tau] : cases) {
        ErrorMeter meter(header(), *mSource, {tau / 8.0, 1024, 16});
        auto oracle = meter.oracle(camera, tau);
        ASSERT_TRUE(oracle.ok()) << oracle.error().message;
        ASSERT_FALSE(oracle->nodes.empty());
        EXPECT_EQ(oracle->overTau, 0u) << "the input's own grid is within any tau";

        LodSelection selection;
        std::unordered_map<std::uint64_t, NodePtr> nodes;
        for (const NodePtr& node : oracle->nodes) {
            selection.nodes.push_back({node->id, 1.0f});
            nodes.emplace(node->id.key(), node);
        }
        for (const NodePtr& node : oracle->refined) {
            nodes.emplace(node->id.key(), node);
        }
        // The drawn nodes tile the view: disjoint, and no refined node among them.
        for (const NodePtr& node : oracle->nodes) {
            for (NodeId up = node->id; !up.isRoot();) {
                up = up.parent();
                ASSERT_TRUE(nodes.count(up.key()))
                    << "an oracle node's ancestor " << up.toString() << " is not refined";
                for (const NodePtr& other : oracle->nodes) {
                    ASSERT_FALSE(other->id == up) << other->id.toString() << " lies above another drawn node";
                }
            }
        }
        // Brute force: each drawn node over every input sample in its square, each refined node over those of
        // the drawn nodes below it; the meter agrees on what was refined.
        const BruteError brute = bruteForceDecoded(selection, camera, tau);
        EXPECT_LE(brute.maxPixels, tau);
        EXPECT_NEAR(oracle->maxPixels, brute.maxPixels, 1e-6 * brute.maxPixels + 1e-6);
        const ResidentNodeLookup oracleNodes = [&nodes](const NodeId& id) {
            auto it = nodes.find(id.key());
            return it == nodes.end() ? NodePtr{} : it->second;
        };
        auto measured =
            meter.measure(makeDrawList(selection, oracleNodes, extentOf(header()), camera), oracleNodes, tau);
        ASSERT_TRUE(measured.ok()) << measured.error().message;
        EXPECT_EQ(measured->refined, oracle->refined.size());
        EXPECT_EQ(measured->refinedWithinTau, 0u) << "the oracle refines only nodes over tau";
        EXPECT_LE(measured->maxPixels, tau);

        // The bound-driven selection, whose frame is within tau too, draws at least as many nodes.
        settle(*mStreamer, camera, tau);
        EXPECT_GE(mStreamer->selection().nodes.size(), oracle->nodes.size());
        fewer += mStreamer->selection().nodes.size() > oracle->nodes.size() ? 1 : 0;
        std::printf("tau %.1f: oracle %zu nodes (%zu refined, max %.4f px), bounds %zu nodes\n", tau,
                    oracle->nodes.size(), oracle->refined.size(), oracle->maxPixels,
                    mStreamer->selection().nodes.size());
    }
    EXPECT_GE(fewer, 2) << "the bounds are loose somewhere: the oracle must draw fewer nodes in some case";
}

// ---- With detail synthesis ----

TEST(ErrorMeterDetailTest, ReferenceReachesTheDeepestDynamicLevel)
{
    constexpr int kChunk = 17;
    test::ScratchDir dir;
    const auto synthesizer = test::grassAndRockSynthesizer(kChunk);
    BuildOptions options = test::testOptions(kChunk);
    options.spacing = 8.0;
    options.leafDetailError = leafDetailErrorFunction(*synthesizer);
    // Gentle slopes (at most about 25 degrees), so a low camera sees a wide patch.
    HeightField field = test::makeHeightField(65, 65, [](int i, int j) {
        return static_cast<float>(std::round(500.0 + 30.0 * std::sin(0.1 * i) * std::cos(0.08 * j) + 0.05 * i * j +
                                             3.0 * test::unitNoise(2, i, j)));
    });
    auto report = buildMap(std::move(field), options, dir / "detail.map");
    ASSERT_TRUE(report.ok()) << report.error().message;
    auto map = test::openMap(dir / "detail.map");
    ASSERT_TRUE(map);
    const MapHeader& h = map->header();
    ASSERT_TRUE(h.hasDetailErrors());
    ASSERT_EQ(h.gridSize(), 65u);
    const int leafLevel = static_cast<int>(h.levels) - 1;
    // lod_minimum_spacing 2 m: the 8 m leaves refine into 4 m and 2 m dynamic nodes, and no further.
    const int deepest = leafLevel + 2;
    ASSERT_EQ(h.spacingAt(deepest), 2.0);
    TerrainNodeSource source(*map, {synthesizer.get(), 2.0});
    auto streamer = makeStreamer(source, h);

    const double tau = 8.0;
    const double size = h.nodeSizeAt(0);
    auto ground = staticHeightAt(*map, 0.4 * size, 0.3 * size);
    ASSERT_TRUE(ground.ok());
    Camera camera = makeCamera({0.4 * size, 0.3 * size, ground->height + 160.0}, 15.0, -35.0);
    camera.verticalFov = 50.0 * kRadiansPerDegree;
    camera.viewportWidth = 640;
    camera.viewportHeight = 480;
    settle(*streamer, camera, tau);
    int dynamicSelected = 0, coarser = 0;
    for (const SelectedNode& s : streamer->selection().nodes) {
        dynamicSelected += s.id.level > leafLevel ? 1 : 0;
        coarser += s.id.level < deepest ? 1 : 0;
    }
    EXPECT_GT(dynamicSelected, 0) << "the camera must draw synthesized detail too";
    EXPECT_GT(coarser, 0) << "some drawn nodes must be coarser than the reference";

    ErrorMeter meter(h, source, {1e-9, 1024, 16});
    auto measured = measure(meter, *streamer, streamer->selection(), camera, tau);
    ASSERT_TRUE(measured.ok()) << measured.error().message;
    EXPECT_EQ(measured->deepestReference, deepest);

    // The reference: every sample of the deepest level's grid in view. Nodes are made by descending from the
    // root through `source` as surfaceHeightAt does, but kept, so each is made once; the sample value is read
    // straight from the node (a grid point is a sample). Spot checks below compare with surfaceHeightAt.
    const int n1 = kChunk - 1;
    const int cells = 1 << deepest;
    const int samples = n1 * cells + 1;
    const double spacing = h.spacingAt(deepest);
    std::unordered_map<std::uint64_t, NodePtr> made;
    NodePtr root = source.loadRoot().value();
    auto reference = [&](int gi, int gj) {
        const int nx = std::min(gi / n1, cells - 1), ny = std::min(gj / n1, cells - 1);
        NodePtr node = root;
        for (int level = 1; level <= deepest; ++level) {
            const int shift = deepest - level;
            const NodeId id{level, static_cast<std::uint32_t>(nx >> shift), static_cast<std::uint32_t>(ny >> shift)};
            auto it = made.find(id.key());
            if (it == made.end()) {
                auto children = source.loadChildren(*node);
                EXPECT_TRUE(children.ok());
                for (const NodePtr& child : *children) {
                    made.emplace(child->id.key(), child);
                }
                it = made.find(id.key());
            }
            node = it->second;
        }
        const int i = gi - nx * n1, j = gj - ny * n1, w = node->heights.size;
        return h.heightOffset + node->heights.height(static_cast<std::size_t>(j + kBorder) * w + i + kBorder);
    };
    const BruteProjector projector(camera);
    BruteError brute;
    std::vector<std::pair<int, int>> inView;
    for (int gj = 0; gj < samples; ++gj) {
        for (int gi = 0; gi < samples; ++gi) {
            if (addDrawnError(
                    *streamer, h, projector, h.originX + gi * spacing, h.originY + gj * spacing,
                    [&] { return reference(gi, gj); }, brute)) {
                inView.emplace_back(gi, gj);
            }
        }
    }
    ASSERT_GT(inView.size(), 1000u);
    // The reference is what the viewer draws at the deepest level (surfaceHeightAt), at a spread of points.
    for (std::size_t k = 0; k < inView.size(); k += inView.size() / 23) {
        const auto [gi, gj] = inView[k];
        auto query = surfaceHeightAt(*map, source, h.originX + gi * spacing, h.originY + gj * spacing, deepest);
        ASSERT_TRUE(query.ok()) << query.error().message;
        EXPECT_EQ(query->node.level, deepest);
        EXPECT_NEAR(query->height, reference(gi, gj), 1e-9) << gi << ", " << gj;
    }
    std::printf(
        "detail: %zu nodes (%d dynamic), deepest reference %d: meter max %.9f px at (%.2f, %.2f), brute force "
        "%.9f px at (%.2f, %.2f) over %zu points (meter %zu), mean %.6f vs %.6f, %zu reference leaves\n",
        measured->nodes, dynamicSelected, measured->deepestReference, measured->maxPixels, measured->worstX,
        measured->worstY, brute.maxPixels, brute.worstX, brute.worstY, brute.points, measured->points,
        measured->meanPixels, brute.mean(), measured->referenceNodes);
    ASSERT_GT(brute.maxPixels, 0.0);
    expectSameMaximum(measured->maxPixels, brute.maxPixels, "detail");
    EXPECT_GE(measured->points, brute.points);
}

// ---- tengine-tool error ----

class ErrorMeterCommandTest : public ::testing::Test {
protected:
    std::filesystem::path writeConfig(const std::string& name, const std::string& text) const
    {
        const auto path = mDir / name;
        std::ofstream(path) << text;
        return path;
    }

    static std::string readAll(std::FILE* file)
    {
        std::rewind(file);
        std::string text;
        char buffer[4096];
        for (std::size_t got; (got = std::fread(buffer, 1, sizeof buffer, file)) > 0;) {
            text.append(buffer, got);
        }
        return text;
    }

    test::ScratchDir mDir;
    const std::filesystem::path mMapPath = mDir / "terrain.map";
};

TEST_F(ErrorMeterCommandTest, BadArgumentsAreNamed)
{
    const std::string cfg = writeConfig("a.cfg", "lod_error = 3\n").string();
    struct Case {
        std::vector<std::string> args;
        std::string mentions;
    };
    const std::vector<Case> cases = {
        {{}, "--camera"},
        {{cfg}, "exactly one of --camera"},
        {{"--camera", "1,2,3,0,0", "--path", "a.path"}, "exactly one of"},
        {{"--camera", "1,2,3"}, "'1,2,3' is not X,Y,Z,YAW,PITCH"},
        {{"--camera", "1,2,3,4,95"}, "pitch in [-90, 90]"},
        {{"--camera", "1,2,,4,5"}, "--camera: '1,2,,4,5'"},
        {{"--camera", "1,2,3,4,nan"}, "--camera"},
        {{"--camera", "1,2,3,0,0", "--bogus", "1"}, "unknown option '--bogus'"},
        {{"--camera", "1,2,3,0,0", "--tau", "-1"}, "--tau: '-1'"},
        {{"--camera", "1,2,3,0,0", "--tau", "0"}, "--tau: '0'"},
        {{"--camera", "1,2,3,0,0", "--tau", "abc"}, "--tau: 'abc'"},
        {{"--camera", "1,2,3,0,0", "--size", "10x10"}, "--size: '10x10'"},
        {{"--camera", "1,2,3,0,0", "--size", "640x480x2"}, "--size: '640x480x2'"},
        {{"--camera", "1,2,3,0,0", "--size", "640"}, "--size: '640'"},
        {{"--camera", "1,2,3,0,0", "--fov", "180"}, "--fov: '180'"},
        {{"--camera", "1,2,3,0,0", "--fps", "0"}, "--fps: '0'"},
        {{"--camera", "1,2,3,0,0", "notes.txt"}, "'notes.txt' is neither a CONFIG.cfg"},
        {{"--camera", "1,2,3,0,0", "--tau"}, "--tau needs a value"},
        {{"--camera", "1,2,3,0,0", "--set", "lod_error=-2"}, "lod_error"},
        {{"--camera", "1,2,3,0,0", (mDir / "missing.cfg").string()}, "missing.cfg"},
    };
    for (const Case& c : cases) {
        auto parsed = parseErrorCommand(mMapPath, c.args);
        std::string joined;
        for (const auto& a : c.args) {
            joined += a + " ";
        }
        ASSERT_FALSE(parsed.ok()) << "accepted: " << joined;
        EXPECT_NE(parsed.error().message.find(c.mentions), std::string::npos)
            << joined << "-> " << parsed.error().message;
    }
    Camera camera;
    EXPECT_FALSE(parseCameraArgument("1,2,3,4,-90.5", camera).ok());
    EXPECT_FALSE(parseCameraArgument("1,2,3,4,5,6", camera).ok());
    EXPECT_FALSE(parseCameraArgument("", camera).ok());
}

TEST_F(ErrorMeterCommandTest, OptionsApplyInOrderAndTauWins)
{
    const std::string seven = writeConfig("seven.cfg", "lod_error = 7\nwindow_width = 800\n").string();
    auto lodError = [&](const std::vector<std::string>& tail) {
        std::vector<std::string> args = {"--camera", "10,20,30,90,-45"};
        args.insert(args.end(), tail.begin(), tail.end());
        auto parsed = parseErrorCommand(mMapPath, args);
        EXPECT_TRUE(parsed.ok()) << parsed.error().message;
        return parsed.ok() ? parsed->options.lodError : -1.0;
    };
    EXPECT_EQ(lodError({}), TengineOptions{}.lodError);
    EXPECT_EQ(lodError({"--set", "lod_error=3", "--tau", "1"}), 1.0);
    EXPECT_EQ(lodError({"--tau", "1", "--set", "lod_error=3"}), 1.0) << "--tau is lod_error, whatever the order";
    EXPECT_EQ(lodError({"--set", "lod_error=3", "--set", "lod_error=5"}), 5.0);
    EXPECT_EQ(lodError({seven, "--set", "lod_error=4"}), 4.0);
    EXPECT_EQ(lodError({"--set", "lod_error=4", seven}), 7.0);

    auto parsed = parseErrorCommand(mMapPath, {seven, "--camera", "10,20,30,90,-45", "--size", "320x200", "--fov", "45",
                                               "--set", "camera_z_near=2", "--fps", "12"});
    ASSERT_TRUE(parsed.ok()) << parsed.error().message;
    EXPECT_EQ(parsed->options.mapFile, mMapPath);
    EXPECT_EQ(parsed->lens.viewportWidth, 320);
    EXPECT_EQ(parsed->lens.viewportHeight, 200);
    EXPECT_EQ(parsed->options.windowWidth, 320) << "--size overrides the config's window_width";
    EXPECT_NEAR(parsed->lens.verticalFov, 45.0 * kRadiansPerDegree, 1e-12);
    EXPECT_EQ(parsed->lens.nearPlane, 2.0);
    EXPECT_EQ(parsed->lens.farPlane, TengineOptions{}.cameraZFar);
    EXPECT_EQ(parsed->fps, 12.0);
    ASSERT_TRUE(parsed->camera.has_value());
    EXPECT_EQ(parsed->camera->position, glm::dvec3(10.0, 20.0, 30.0));
    EXPECT_NEAR(parsed->camera->yaw, 0.5 * std::numbers::pi, 1e-12);
    EXPECT_NEAR(parsed->camera->pitch, -0.25 * std::numbers::pi, 1e-12);
    EXPECT_TRUE(parsed->path.empty());

    auto withPath = parseErrorCommand(mMapPath, {"--path", "fly.path"});
    ASSERT_TRUE(withPath.ok()) << withPath.error().message;
    EXPECT_EQ(withPath->path, std::filesystem::path("fly.path"));
    EXPECT_FALSE(withPath->camera.has_value());
    EXPECT_EQ(withPath->fps, static_cast<double>(TengineOptions{}.framesPerSecond));
    EXPECT_EQ(withPath->lens.viewportWidth, TengineOptions{}.windowWidth);
}

TEST_F(ErrorMeterCommandTest, RunsOnAMapAndRefusesCamerasOffIt)
{
    BuildOptions options = test::testOptions(17);
    options.spacing = 8.0;
    auto report = buildMap(test::hillyField(65, 65, 4), options, mMapPath);
    ASSERT_TRUE(report.ok()) << report.error().message;
    auto map = test::openMap(mMapPath);
    ASSERT_TRUE(map);
    auto run = [&](const std::string& camera, std::string& out, std::string& err) {
        auto parsed = parseErrorCommand(mMapPath, {"--camera", camera, "--size", "320x240", "--tau", "2"});
        EXPECT_TRUE(parsed.ok()) << parsed.error().message;
        std::FILE* outFile = std::tmpfile();
        std::FILE* errFile = std::tmpfile();
        EXPECT_TRUE(outFile && errFile);
        const int status = runErrorCommand(*map, *parsed, kMaterials, outFile, errFile);
        out = readAll(outFile);
        err = readAll(errFile);
        std::fclose(outFile);
        std::fclose(errFile);
        return status;
    };
    std::string out, err;
    EXPECT_EQ(run("-500,-500,2000,0,-30", out, err), 1);
    EXPECT_NE(err.find("--camera: the camera is not over the terrain"), std::string::npos) << err;
    EXPECT_EQ(out.find("error: max"), std::string::npos) << out;

    EXPECT_EQ(run("256,100,1800,0,-60", out, err), 0) << err;
    ASSERT_FALSE(out.empty());
    std::string last = out.substr(0, out.size() - 1);
    last = last.substr(last.rfind('\n') + 1);
    EXPECT_EQ(last.rfind("error: max ", 0), 0u) << out;
    EXPECT_NE(last.find("over 1 frames"), std::string::npos) << last;
    double max = -1.0;
    EXPECT_EQ(std::sscanf(last.c_str(), "error: max %lf px", &max), 1) << last;
    EXPECT_GT(max, 0.0);
    EXPECT_NE(out.find("# tau 2 px, 320x240"), std::string::npos) << out;
    EXPECT_EQ(out.find("below the terrain"), std::string::npos) << out;
    EXPECT_EQ(err.find("below the terrain"), std::string::npos) << err;

    // Under the terrain: measured, and said (it printed normal-looking figures without a word).
    const double ground = test::openMap(mMapPath)->header().heightOffset - 1000.0;
    EXPECT_EQ(run("256,100," + std::to_string(ground) + ",0,30", out, err), 0) << err;
    EXPECT_NE(err.find("frame 0 (t = 0.00 s): the camera is"), std::string::npos) << err;
    EXPECT_NE(err.find("m below the terrain"), std::string::npos) << err;
    EXPECT_NE(out.find("# camera below the terrain in 1 of 1 frames"), std::string::npos) << out;
}

}  // namespace
}  // namespace terrain
