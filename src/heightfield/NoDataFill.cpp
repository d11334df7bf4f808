#include "heightfield/NoDataFill.h"

#include <cmath>
#include <vector>

namespace terrain {

std::uint64_t countValid(const HeightField& field)
{
    std::uint64_t valid = 0;
    for (float v : field.samples) {
        valid += std::isnan(v) ? 0 : 1;
    }
    return valid;
}

std::uint64_t fillNoData(HeightField& field, std::vector<std::uint8_t>* filled)
{
    const int w = field.width;
    const int h = field.height;
    auto index = [w](int x, int y) { return static_cast<std::size_t>(y) * w + x; };
    auto isHole = [&](int x, int y) { return std::isnan(field.samples[index(x, y)]); };

    // Frontier: holes with at least one valid neighbour. Each ring is filled from values of earlier rings
    // only (computed first, assigned after), so the result does not depend on the scan order.
    if (countValid(field) == field.samples.size()) {
        return 0;
    }
    std::vector<std::size_t> frontier;
    std::vector<std::uint8_t> queued(field.samples.size(), 0);
    auto pushNeighbours = [&](int x, int y, std::vector<std::size_t>& into) {
        for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
                int nx = x + dx, ny = y + dy;
                if (nx >= 0 && ny >= 0 && nx < w && ny < h && isHole(nx, ny) && !queued[index(nx, ny)]) {
                    queued[index(nx, ny)] = 1;
                    into.push_back(index(nx, ny));
                }
            }
        }
    };
    // The first ring: holes next to a valid sample.
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            if (!isHole(x, y)) {
                continue;
            }
            bool rim = false;
            for (int dy = -1; dy <= 1 && !rim; ++dy) {
                for (int dx = -1; dx <= 1 && !rim; ++dx) {
                    int nx = x + dx, ny = y + dy;
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
    while (!frontier.empty()) {
        values.clear();
        for (std::size_t i : frontier) {
            int x = static_cast<int>(i % w), y = static_cast<int>(i / w);
            double sum = 0;
            int count = 0;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    int nx = x + dx, ny = y + dy;
                    if (nx >= 0 && ny >= 0 && nx < w && ny < h && !isHole(nx, ny)) {
                        sum += field.samples[index(nx, ny)];
                        ++count;
                    }
                }
            }
            values.push_back(static_cast<float>(sum / count));
        }
        for (std::size_t k = 0; k < frontier.size(); ++k) {
            field.samples[frontier[k]] = values[k];
        }
        filledCount += frontier.size();
        next.clear();
        for (std::size_t i : frontier) {
            pushNeighbours(static_cast<int>(i % w), static_cast<int>(i / w), next);
        }
        frontier.swap(next);
    }
    if (filled) {
        filled->swap(queued);  // every queued sample was a hole, and every hole gets queued
    }
    return filledCount;
}

}  // namespace terrain
