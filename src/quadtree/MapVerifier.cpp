#include "quadtree/MapVerifier.h"

#include "quadtree/SimplificationError.h"
#include "quadtree/TemplateTriangulation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

namespace terrain {

namespace {

struct Checked {
    std::uint16_t minCode = 65535;
    std::uint16_t maxCode = 0;
    float deltaC = 0.0f;
    float detailDeltaC = 0.0f;
};

class Verifier {
public:
    Verifier(const MapFile& map, const std::function<void(double)>& progress) : mMap(map), mProgress(progress) {}

    std::vector<std::string> run()
    {
        auto root = mMap.loadNode(NodeId::root(), {});
        if (!root.ok()) {
            mProblems.push_back(root.error().message);
            return mProblems;
        }
        std::vector<StaticNode> leaves;
        visit(*root, leaves);
        return mProblems;
    }

private:
    void problem(const NodeId& id, const std::string& what)
    {
        mProblems.push_back(mMap.name() + ": node " + id.toString() + ": " + what);
    }

    /// The largest vertical distance in codes from `node`'s surface to the samples of `leaves` (all below it).
    double directError(const StaticNode& node, const std::vector<StaticNode>& leaves) const
    {
        const int n = static_cast<int>(mMap.header().chunkSize);
        const int w = mMap.window().size();
        auto code = [&](const StaticNode& at, int i, int j) -> double {
            return at.heights[static_cast<std::size_t>(j + kBorder) * w + i + kBorder];
        };
        double worst = 0.0;
        for (const StaticNode& leaf : leaves) {
            const int k = leaf.id.level - node.id.level;
            const std::int64_t dx = (std::int64_t{leaf.id.x} - (std::int64_t{node.id.x} << k)) * (n - 1);
            const std::int64_t dy = (std::int64_t{leaf.id.y} - (std::int64_t{node.id.y} << k)) * (n - 1);
            const double scale = std::ldexp(1.0, -k);
            for (int j = 0; j < n; ++j) {
                const std::int64_t v = dy + j;
                const int iy = static_cast<int>(std::min<std::int64_t>(v >> k, n - 2));
                const double fy = static_cast<double>(v - (std::int64_t{iy} << k)) * scale;
                for (int i = 0; i < n; ++i) {
                    const std::int64_t u = dx + i;
                    const int ix = static_cast<int>(std::min<std::int64_t>(u >> k, n - 2));
                    const double fx = static_cast<double>(u - (std::int64_t{ix} << k)) * scale;
                    const double surface = interpolateQuad(code(node, ix, iy), code(node, ix + 1, iy),
                                                           code(node, ix, iy + 1), code(node, ix + 1, iy + 1), fx, fy);
                    worst = std::max(worst, std::abs(code(leaf, i, j) - surface));
                }
            }
        }
        return worst;
    }

    // Returns the subtree's nested bounds and error, or nothing if the node could not be decoded; appends the
    // subtree's leaves to `leaves`.
    std::optional<Checked> visit(const StaticNode& node, std::vector<StaticNode>& leaves)
    {
        const DirectoryEntry& entry = *mMap.find(node.id);
        const bool detail = mMap.header().hasDetailErrors();  // version 1 maps carry no detail errors
        const NodeWindow& window = mMap.window();
        const WindowRect inside = window.insideRect(node.id);
        Checked checked;
        for (int y = inside.y0; y <= inside.y1; ++y) {
            for (int x = inside.x0; x <= inside.x1; ++x) {
                auto code = node.heights[static_cast<std::size_t>(y) * window.size() + x];
                checked.minCode = std::min(checked.minCode, code);
                checked.maxCode = std::max(checked.maxCode, code);
            }
        }
        ++mDone;
        if (mProgress) {
            mProgress(static_cast<double>(mDone) / static_cast<double>(mMap.directory().size()));
        }
        const bool measured = mMap.header().version >= 4;  // errors measured directly
        if (entry.hasChildren) {
            std::array<StaticNode, 4> children;
            std::vector<StaticNode> below;
            float worst = 0.0f;
            float worstDetail = 0.0f;
            for (int q = 0; q < 4; ++q) {
                auto child = mMap.loadNode(node.id.child(q), node.heights);
                if (!child.ok()) {
                    mProblems.push_back(child.error().message);
                    return std::nullopt;
                }
                children[q] = std::move(child.value());
                auto sub = visit(children[q], below);
                if (!sub) {
                    return std::nullopt;
                }
                checked.minCode = std::min(checked.minCode, sub->minCode);
                checked.maxCode = std::max(checked.maxCode, sub->maxCode);
                worst = std::max(worst, sub->deltaC);
                worstDetail = std::max(worstDetail, sub->detailDeltaC);
            }
            const int n = static_cast<int>(mMap.header().chunkSize);
            const int w = window.size();
            double deltaM = mMap.header().heightStep * simplificationErrorCodes(n, [&](int a, int b) -> std::int32_t {
                                int q = (a >= n - 1 ? 1 : 0) | (b >= n - 1 ? 2 : 0);
                                int u = a - (q & 1) * (n - 1), v = b - (q >> 1) * (n - 1);
                                return children[q].heights[static_cast<std::size_t>(v + kBorder) * w + u + kBorder];
                            });
            if (std::abs(deltaM - entry.deltaM) > 1e-4 * std::max(1.0, deltaM)) {
                problem(node.id, "delta_m is " + std::to_string(entry.deltaM) + " m but the decoded heights give " +
                                     std::to_string(deltaM) + " m");
            }
            if (measured) {
                // delta_c = max(children's, the measured distance to the leaves' samples).
                const float direct = static_cast<float>(mMap.header().heightStep * directError(node, below));
                const float nested = std::max(kErrorNesting * worst, direct);
                if (mMap.header().heightCoding == kHeightCodingPifs) {
                    // Fractal coding stores a bound: the input's distance plus the node's and leaves' coding
                    // errors (QuadtreeBuilder), which must hold for what the map decodes to.
                    if (entry.deltaC < nested * (1.0f - 1e-5f)) {
                        problem(node.id, "delta_c is " + std::to_string(entry.deltaC) +
                                             " m, below the larger of its children's (x kErrorNesting) and the "
                                             "measured distance of its decoded heights to the leaves' below, " +
                                             std::to_string(nested) + " m");
                    }
                } else if (std::abs(nested - entry.deltaC) > 1e-4f * std::max(1.0f, nested)) {
                    problem(node.id, "delta_c is " + std::to_string(entry.deltaC) +
                                         " m but the larger of its children's (x kErrorNesting) and the measured "
                                         "distance to the leaves below is " +
                                         std::to_string(nested) + " m");
                }
                float leafDetail = 0.0f;
                for (const StaticNode& leaf : below) {
                    leafDetail = std::max(leafDetail, mMap.find(leaf.id)->detailDeltaC);
                }
                const float least = std::max(kErrorNesting * worstDetail, direct + leafDetail);
                if (detail && entry.detailDeltaC < least * (1.0f - 1e-5f)) {
                    problem(node.id, "detail_delta_c is " + std::to_string(entry.detailDeltaC) +
                                         " m, below its children's or its measured error plus the leaves' detail "
                                         "errors below (" +
                                         std::to_string(least) + " m)");
                }
            } else {
                float nested = worst + entry.deltaM;
                if (std::abs(nested - entry.deltaC) > 1e-4f * std::max(1.0f, nested)) {
                    problem(node.id, "delta_c is " + std::to_string(entry.deltaC) + " m but its children's nest to " +
                                         std::to_string(nested) + " m (eq. 3.1)");
                }
                float nestedDetail = worstDetail + entry.deltaM;
                if (detail && std::abs(nestedDetail - entry.detailDeltaC) > 1e-4f * std::max(1.0f, nestedDetail)) {
                    problem(node.id, "detail_delta_c is " + std::to_string(entry.detailDeltaC) +
                                         " m but its children's nest to " + std::to_string(nestedDetail) +
                                         " m (eq. 3.1 over the estimated leaf detail errors, 3.4.1)");
                }
            }
            for (StaticNode& leaf : below) {
                leaves.push_back(std::move(leaf));
            }
        } else if (entry.deltaM != 0.0f || entry.deltaC != 0.0f) {
            problem(node.id, "a leaf has a non-zero error");
        }
        if (detail && !(std::isfinite(entry.detailDeltaC) && entry.detailDeltaC >= 0.0f)) {
            problem(node.id, "detail_delta_c " + std::to_string(entry.detailDeltaC) + " m is not a finite number >= 0");
        } else if (detail && entry.detailDeltaC < entry.deltaC) {
            problem(node.id, "detail_delta_c " + std::to_string(entry.detailDeltaC) + " m is below delta_c " +
                                 std::to_string(entry.deltaC) + " m");
        }
        if (checked.minCode != entry.minCode || checked.maxCode != entry.maxCode) {
            problem(node.id, "bounding box codes " + std::to_string(entry.minCode) + ".." +
                                 std::to_string(entry.maxCode) + " differ from the decoded subtree's " +
                                 std::to_string(checked.minCode) + ".." + std::to_string(checked.maxCode));
        }
        if (!entry.hasChildren) {
            leaves.push_back(node);
        }
        checked.deltaC = entry.deltaC;
        checked.detailDeltaC = entry.detailDeltaC;
        return checked;
    }

    const MapFile& mMap;
    const std::function<void(double)>& mProgress;
    std::vector<std::string> mProblems;
    std::size_t mDone = 0;
};

}  // namespace

std::vector<std::string> verifyMap(const MapFile& map, const std::function<void(double)>& progress)
{
    return Verifier(map, progress).run();
}

}  // namespace terrain
