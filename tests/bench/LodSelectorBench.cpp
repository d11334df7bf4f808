// LOD selection time per frame (listing 3.7 + culling + morph) on a synthetic tree the size of a
// 16385 x 16385 height field with 65-sample chunks (9 levels), tau = 2 px, 1280 x 720, 60 degree fov,
// camera 2 m above the ground. Target: median <= 100 microseconds per frame. Measures, never gates.
#include "lod/LodSelector.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace terrain {
namespace {

/// Dense in-memory tree: every node down to `levels - 1`, nested errors and boxes from a smooth
/// synthetic height function (about 300 m of relief) plus noise.
class BenchTree final : public LodTree {
public:
    BenchTree(int levels, double rootSize) : mLevels(levels), mExtent{0.0, 0.0, rootSize}
    {
        std::mt19937_64 rng(1);
        std::uniform_real_distribution<double> uni(0.0, 1.0);
        mNodes.resize(static_cast<std::size_t>(NodeId{levels, 0, 0}.key()));
        for (int level = levels - 1; level >= 0; --level) {
            double size = mExtent.nodeSize(level);
            std::uint32_t n = 1u << level;
            for (std::uint32_t y = 0; y < n; ++y) {
                for (std::uint32_t x = 0; x < n; ++x) {
                    NodeId id{level, x, y};
                    NodeInfo& info = mNodes[id.key()];
                    if (level == levels - 1) {
                        double h = height((x + 0.5) * size, (y + 0.5) * size);
                        info = {false, static_cast<float>(0.1 + 0.2 * uni(rng)), h - 0.02 * size, h + 0.02 * size};
                        continue;
                    }
                    info.hasChildren = true;
                    info.zMin = 1e300;
                    info.zMax = -1e300;
                    float childError = 0.0f;
                    for (int q = 0; q < 4; ++q) {
                        const NodeInfo& c = mNodes[id.child(q).key()];
                        info.zMin = std::min(info.zMin, c.zMin);
                        info.zMax = std::max(info.zMax, c.zMax);
                        childError = std::max(childError, c.deltaC);
                    }
                    info.deltaC = childError + static_cast<float>(size / 256.0 * (0.2 + uni(rng)));
                }
            }
        }
    }

    static double height(double x, double y)
    {
        return 150.0 * std::sin(x * 0.0007) * std::cos(y * 0.0005) + 30.0 * std::sin(x * 0.01 + y * 0.013);
    }
    QuadtreeExtent extent() const override { return mExtent; }
    NodeInfo info(const NodeId& id) const override { return mNodes[id.key()]; }

private:
    int mLevels;
    QuadtreeExtent mExtent;
    std::vector<NodeInfo> mNodes;
};

void BM_SelectNodes(benchmark::State& state)
{
    const int levels = 9;                          // 65-sample chunks: (65 - 1) * 2^8 + 1 = 16385 samples
    static const BenchTree tree(levels, 16384.0);  // 1 m spacing
    std::vector<Camera> cameras;
    for (int i = 0; i < 16; ++i) {
        Camera c;
        double x = 3000.0 + 700.0 * i, y = 4000.0 + 500.0 * i;
        c.position = {x, y, BenchTree::height(x, y) + 2.0};
        c.yaw = i * 0.4;
        c.pitch = -0.05;
        c.verticalFov = std::numbers::pi / 3.0;
        c.viewportWidth = 1280;
        c.viewportHeight = 720;
        c.nearPlane = 0.5;
        c.farPlane = 30000.0;
        cameras.push_back(c);
    }
    LodSelection out;
    out.nodes.reserve(4096);
    out.requests.reserve(1024);
    std::size_t frame = 0, selected = 0;
    for (auto _ : state) {
        selectNodes(tree, cameras[frame % cameras.size()], 2.0, {}, out);
        benchmark::DoNotOptimize(out.nodes.data());
        selected += out.nodes.size();
        ++frame;
    }
    state.counters["nodes/frame"] = static_cast<double>(selected) / static_cast<double>(frame);
}
BENCHMARK(BM_SelectNodes)->Unit(benchmark::kMicrosecond)->Repetitions(9)->ReportAggregatesOnly(true);

}  // namespace
}  // namespace terrain

BENCHMARK_MAIN();
