#include "heightfield/NoDataFill.h"

#include "core/Check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace terrain {

namespace {

/// Fills the NaN samples of a w x h grid ring by ring from the valid ones, up to `maxRings` rings: each ring
/// takes the mean of its valid or earlier-ring 8-neighbours (computed first, assigned after, so the result
/// does not depend on the scan order). Marks filled samples in `queued` (w x h, zero on entry). Returns the
/// count filled.
std::uint64_t fillRings(std::span<float> samples, int w, int h, int maxRings, std::vector<std::uint8_t>& queued)
{
    auto index = [w](int x, int y) { return static_cast<std::size_t>(y) * w + x; };
    auto isHole = [&](int x, int y) { return std::isnan(samples[index(x, y)]); };
    std::vector<std::size_t> frontier;
    // The first ring: holes next to a valid sample.
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            if (!isHole(x, y)) {
                continue;
            }
            bool rim = false;
            for (int dy = -1; dy <= 1 && !rim; ++dy) {
                for (int dx = -1; dx <= 1 && !rim; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    rim = nx >= 0 && ny >= 0 && nx < w && ny < h && !isHole(nx, ny);
                }
            }
            if (rim) {
                queued[index(x, y)] = 1;
                frontier.push_back(index(x, y));
            }
        }
    }
    std::uint64_t filledCount = 0;
    std::vector<float> values;
    std::vector<std::size_t> next;
    for (int ring = 1; ring <= maxRings && !frontier.empty(); ++ring) {
        values.clear();
        for (std::size_t i : frontier) {
            const int x = static_cast<int>(i % w), y = static_cast<int>(i / w);
            double sum = 0;
            int count = 0;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if (nx >= 0 && ny >= 0 && nx < w && ny < h && !isHole(nx, ny)) {
                        sum += samples[index(nx, ny)];
                        ++count;
                    }
                }
            }
            values.push_back(static_cast<float>(sum / count));
        }
        for (std::size_t k = 0; k < frontier.size(); ++k) {
            samples[frontier[k]] = values[k];
        }
        filledCount += frontier.size();
        if (ring == maxRings) {
            break;
        }
        next.clear();
        for (std::size_t i : frontier) {
            const int x = static_cast<int>(i % w), y = static_cast<int>(i / w);
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if (nx >= 0 && ny >= 0 && nx < w && ny < h && isHole(nx, ny) && !queued[index(nx, ny)]) {
                        queued[index(nx, ny)] = 1;
                        next.push_back(index(nx, ny));
                    }
                }
            }
        }
        frontier.swap(next);
    }
    return filledCount;
}

}  // namespace

float FarFillGrid::at(int x, int y) const
{
    auto axis = [](int sample, int blocks, int& i0, double& f) {
        const double u = std::clamp((sample + 0.5) / kFillBlock - 0.5, 0.0, blocks - 1.0);
        i0 = std::min(static_cast<int>(u), std::max(blocks - 2, 0));
        f = u - i0;
    };
    int i0 = 0, j0 = 0;
    double fx = 0, fy = 0;
    axis(x, blocksX, i0, fx);
    axis(y, blocksY, j0, fy);
    const int i1 = std::min(i0 + 1, blocksX - 1), j1 = std::min(j0 + 1, blocksY - 1);
    auto m = [&](int i, int j) -> double { return means[static_cast<std::size_t>(j) * blocksX + i]; };
    return static_cast<float>((m(i0, j0) * (1 - fx) + m(i1, j0) * fx) * (1 - fy) +
                              (m(i0, j1) * (1 - fx) + m(i1, j1) * fx) * fy);
}

FarFillBuilder::FarFillBuilder(int width, int height)
    : mWidth(width),
      mHeight(height),
      mBlocksX((width + kFillBlock - 1) / kFillBlock),
      mBlocksY((height + kFillBlock - 1) / kFillBlock),
      mSums(static_cast<std::size_t>(mBlocksX) * mBlocksY, 0.0),
      mCounts(mSums.size(), 0)
{
}

void FarFillBuilder::addRows(int j0, int rows, std::span<const float> samples)
{
    TERRAIN_EXPECTS(j0 >= 0 && rows >= 0 && j0 + rows <= mHeight, "rows inside the field");
    TERRAIN_EXPECTS(samples.size() >= static_cast<std::size_t>(rows) * mWidth, "width samples per row");
    for (int r = 0; r < rows; ++r) {
        const std::size_t block = static_cast<std::size_t>((j0 + r) / kFillBlock) * mBlocksX;
        const float* row = samples.data() + static_cast<std::size_t>(r) * mWidth;
        for (int x = 0; x < mWidth; ++x) {
            if (!std::isnan(row[x])) {
                mSums[block + x / kFillBlock] += row[x];
                ++mCounts[block + x / kFillBlock];
            }
        }
    }
}

FarFillGrid FarFillBuilder::finish() const
{
    FarFillGrid grid;
    grid.blocksX = mBlocksX;
    grid.blocksY = mBlocksY;
    grid.means.resize(mSums.size());
    for (std::size_t k = 0; k < mSums.size(); ++k) {
        grid.means[k] =
            mCounts[k] ? static_cast<float>(mSums[k] / mCounts[k]) : std::numeric_limits<float>::quiet_NaN();
    }
    std::vector<std::uint8_t> queued(grid.means.size(), 0);
    fillRings(grid.means, mBlocksX, mBlocksY, std::numeric_limits<int>::max(), queued);
    return grid;
}

std::uint64_t fillNoDataRows(std::span<float> samples, int width, int rows, int firstRow, const FarFillGrid& far,
                             std::vector<std::uint8_t>* filled)
{
    TERRAIN_EXPECTS(samples.size() >= static_cast<std::size_t>(width) * rows, "width x rows samples");
    const std::size_t count = static_cast<std::size_t>(width) * rows;
    std::size_t holes = 0;
    for (std::size_t k = 0; k < count; ++k) {
        holes += std::isnan(samples[k]) ? 1 : 0;
    }
    if (filled) {
        filled->clear();
    }
    if (holes == 0) {
        return 0;
    }
    std::vector<std::uint8_t> queued(count, 0);
    std::uint64_t done = holes == count ? 0 : fillRings(samples.first(count), width, rows, kFillRings, queued);
    if (done < holes) {
        // Farther than kFillRings from any valid sample: the block means.
        for (int y = 0; y < rows; ++y) {
            for (int x = 0; x < width; ++x) {
                float& v = samples[static_cast<std::size_t>(y) * width + x];
                if (std::isnan(v)) {
                    v = far.at(x, firstRow + y);
                    queued[static_cast<std::size_t>(y) * width + x] = 1;
                    ++done;
                }
            }
        }
    }
    if (filled) {
        filled->swap(queued);
    }
    return done;
}

std::uint64_t fillNoData(HeightField& field, std::vector<std::uint8_t>* filled)
{
    const std::uint64_t valid = countValid(field);
    if (valid == field.samples.size() || valid == 0) {
        if (filled) {
            filled->clear();
        }
        return 0;
    }
    FarFillBuilder far(field.width, field.height);
    far.addRows(0, field.height, field.samples);
    return fillNoDataRows(field.samples, field.width, field.height, 0, far.finish(), filled);
}

std::uint64_t countValid(const HeightField& field)
{
    std::uint64_t valid = 0;
    for (float v : field.samples) {
        valid += std::isnan(v) ? 0 : 1;
    }
    return valid;
}

}  // namespace terrain
