// Time to subdivide one child window (65 x 65 plus a border of 2: 69 x 69 samples) from its parent, one
// thread, for each `detail_subdivision_scheme`: kobbelt (our separable 4-point rule), bilinear and
// catmull-clark (OpenSubdiv Far, refiner built once, interpolation per child). One iteration is one child
// window, so the Time and CPU columns are microseconds per child. Measures, never gates.
#include "synthesis/Subdivider.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace terrain {
namespace {

constexpr int kChunkSize = 65;

std::vector<float> parentWindow()
{
    const int w = windowSize(kChunkSize);
    std::vector<float> window(static_cast<std::size_t>(w) * w);
    for (int y = 0; y < w; ++y) {
        for (int x = 0; x < w; ++x) {
            window[static_cast<std::size_t>(y) * w + x] = static_cast<float>(
                500.0 + 80.0 * std::sin(0.21 * x) * std::cos(0.13 * y) + 0.37 * ((x * 7 + y * 13) % 11));
        }
    }
    return window;
}

void subdivideChild(benchmark::State& state, const std::string& scheme)
{
    auto subdivider = makeSubdivider(scheme, kChunkSize, 1.0);
    if (!subdivider.ok()) {
        state.SkipWithError(subdivider.error().message.c_str());
        return;
    }
    auto parent = parentWindow();
    std::vector<float> child(parent.size());
    int quadrant = 0;
    for (auto _ : state) {
        (*subdivider)->subdivide(parent, quadrant, child);
        benchmark::DoNotOptimize(child.data());
        benchmark::ClobberMemory();
        quadrant = (quadrant + 1) & 3;
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(child.size()));
}

BENCHMARK_CAPTURE(subdivideChild, kobbelt, std::string("kobbelt"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(subdivideChild, bilinear_osd, std::string("bilinear"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(subdivideChild, catmull_clark_osd, std::string("catmull-clark"))->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace terrain

BENCHMARK_MAIN();
