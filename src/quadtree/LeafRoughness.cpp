#include "quadtree/LeafRoughness.h"

#include "core/Check.h"
#include "core/ParallelFor.h"

#include <algorithm>

namespace terrain {

LeafRoughnessMeter::LeafRoughnessMeter(int width, int height, double metresPerUnit, const MapHeader& header)
    : mWidth(width),
      mHeight(height),
      mCells(static_cast<int>(header.chunkSize) - 1),
      mSide(1 << (header.levels - 1)),
      mMetresPerUnit(metresPerUnit)
{
    TERRAIN_EXPECTS(header.levels >= 1 && header.levels <= 15, "roughness grids are for maps of 1 to 15 levels");
    mSums.resize(static_cast<std::size_t>(mSide) * mSide);
}

int LeafRoughnessMeter::leafRowBegin(int ly) const
{
    return ly >= mSide ? mHeight : std::min(ly * mCells, mHeight);
}

void LeafRoughnessMeter::addLeafRows(int ly0, int ly1, std::span<const float> window, int windowRow0, int windowRows,
                                     int threads)
{
    TERRAIN_EXPECTS(0 <= ly0 && ly0 <= ly1 && ly1 <= mSide, "leaf rows inside the map");
    const int y0 = leafRowBegin(ly0), y1 = leafRowBegin(ly1);
    TERRAIN_EXPECTS(windowRow0 <= std::max(0, y0 - kRoughnessMargin) &&
                        windowRow0 + windowRows >= std::min(mHeight, y1 + kRoughnessMargin),
                    "the window must hold the leaf rows and their margin");
    TERRAIN_EXPECTS(window.size() >= static_cast<std::size_t>(windowRows) * mWidth, "width samples per window row");
    const std::size_t count = static_cast<std::size_t>(ly1 - ly0) * mSide;
    parallelFor(count, std::max(threads, 1), [&](std::size_t k) {
        const int lx = static_cast<int>(k % mSide), ly = ly0 + static_cast<int>(k / mSide);
        const int x0 = std::min(lx * mCells, mWidth);
        const int x1 = lx == mSide - 1 ? mWidth : std::min((lx + 1) * mCells, mWidth);
        const int r0 = leafRowBegin(ly), r1 = leafRowBegin(ly + 1);
        auto& sums = mSums[static_cast<std::size_t>(ly) * mSide + lx];
        for (std::size_t l = 0; l < kRoughnessLags.size(); ++l) {
            sums[l] = midpointDeviation(window.first(static_cast<std::size_t>(windowRows) * mWidth), mWidth, windowRows,
                                        kRoughnessLags[l], x0, r0 - windowRow0, x1, r1 - windowRow0, mMetresPerUnit);
        }
    });
}

RoughnessGrid LeafRoughnessMeter::finish() const
{
    RoughnessGrid grid;
    grid.leavesPerSide = mSide;
    grid.laws.assign(mSums.size(), RoughnessLaw{});
    auto fit = [](const std::array<MidpointSums, kRoughnessLags.size()>& sums, bool& enough) {
        std::array<double, kRoughnessLags.size()> rms{};
        enough = true;
        for (std::size_t l = 0; l < sums.size(); ++l) {
            enough = enough && sums[l].count >= kMinRoughnessSamples;
            rms[l] = sums[l].rms();
        }
        return fitRoughnessLaw(rms);
    };
    std::vector<int> sources;  // the measured leaves
    for (std::size_t k = 0; k < mSums.size(); ++k) {
        bool enough = false;
        grid.laws[k] = fit(mSums[k], enough);
        if (enough) {
            sources.push_back(static_cast<int>(k));
        }
    }
    if (sources.empty()) {
        std::array<MidpointSums, kRoughnessLags.size()> whole{};
        for (const auto& sums : mSums) {
            for (std::size_t l = 0; l < sums.size(); ++l) {
                whole[l] += sums[l];
            }
        }
        bool enough = false;
        std::fill(grid.laws.begin(), grid.laws.end(), fit(whole, enough));
        return grid;
    }
    // The others: the nearest measured leaf (squared leaf distance; ties to the lowest index).
    std::size_t next = 0;
    for (std::size_t k = 0; k < mSums.size(); ++k) {
        if (next < sources.size() && sources[next] == static_cast<int>(k)) {
            ++next;
            continue;
        }
        const int lx = static_cast<int>(k % mSide), ly = static_cast<int>(k / mSide);
        long best = -1;
        int from = sources.front();
        for (int source : sources) {
            const long dx = source % mSide - lx, dy = source / mSide - ly;
            if (best < 0 || dx * dx + dy * dy < best) {
                best = dx * dx + dy * dy;
                from = source;
            }
        }
        grid.laws[k] = grid.laws[static_cast<std::size_t>(from)];
    }
    return grid;
}

RoughnessGrid measureLeafRoughness(const HeightField& field, double metresPerUnit, const MapHeader& header, int threads)
{
    TERRAIN_EXPECTS(field.samples.size() == static_cast<std::size_t>(field.width) * field.height,
                    "the field must hold width x height samples");
    LeafRoughnessMeter meter(field.width, field.height, metresPerUnit, header);
    meter.addLeafRows(0, meter.leafRows(), field.samples, 0, field.height, threads);
    return meter.finish();
}

}  // namespace terrain
