// How much a visibility-driven LOD (issue 16) could save at most along a camera path, from the height field
// alone: the share of the view that terrain hides. Screen-space-error LOD spends triangles in proportion to
// 1/d^2 per unit of ground at distance d (nodes refined until their error projects below tau), so within a
// thin wedge of the view every octave of distance costs the same; the share of that weight lying behind
// nearer terrain bounds what hiding hidden terrain can save: at most 1 / (1 - hidden) fewer triangles, even if
// every hidden triangle were dropped and nothing visible changed. Rays through the view frustum (60 degrees
// vertical, 16:9) march the bilinear height field from 30 m to 40 km; what lies above or below the frustum is
// left out. The near share (within --near metres, default 3 km) is where the dynamic nodes are made (synthesis
// below the 90 m data), so it bounds how much fewer of them a visibility LOD can make.
//
//   build/tests/ViewshedSurvey [--routes] [--near METRES] [PATH...]
//
// PATH: camera paths (default: demos/trinidad-valley.path and demos/trinidad.path), poses every 0.5 s.
// --routes: also every valley route of the terrain, flown up-valley: from each sample 2 km apart that lies above
// 3300 m, the steepest-descent line down to 12 km long, smoothed, flown up again 35 m above the ground looking
// along it; the ten most enclosed are printed. Prints figures; exits 1 only on bad input.
#include "core/Parse.h"
#include "heightfield/HeightFieldIo.h"
#include "lod/CameraPath.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

namespace {

using namespace terrain;

constexpr double kSpacing = 90.0;  // metres between the bundled terrain's samples (prep -h 90)

struct Terrain {
    HeightField field;

    /// Metres at world (x, y) (origin at the south-west sample), bilinear; NaN outside.
    double at(double x, double y) const
    {
        const double u = x / kSpacing, v = y / kSpacing;
        if (!(u >= 0.0 && v >= 0.0 && u < field.width - 1.0 && v < field.height - 1.0)) {
            return std::nan("");
        }
        const int i = static_cast<int>(u), j = static_cast<int>(v);
        const double fu = u - i, fv = v - j;
        auto h = [&](int a, int b) {
            return double{field.samples[static_cast<std::size_t>(b) * static_cast<std::size_t>(field.width) + a]};
        };
        return (1 - fv) * ((1 - fu) * h(i, j) + fu * h(i + 1, j)) +
               fv * ((1 - fu) * h(i, j + 1) + fu * h(i + 1, j + 1));
    }
};

struct Share {
    double hidden = 0.0;      ///< of the view's weight, hidden behind nearer terrain
    double hiddenNear = 0.0;  ///< the same within the near distance
};

/// The hidden shares of the view from (x, y, z) looking along `yaw` with `pitch` (radians, Camera.h), the near
/// one within `near` metres.
Share hiddenShare(const Terrain& terrain, double x, double y, double z, double yaw, double pitch, double near)
{
    const double halfV = 30.0 * std::numbers::pi / 180.0;
    const double halfH = std::atan(std::tan(halfV) * 16.0 / 9.0);
    constexpr int kRays = 184;
    double total = 0.0, hidden = 0.0, totalNear = 0.0, hiddenNear = 0.0;
    for (int k = 0; k < kRays; ++k) {
        const double a = yaw - halfH + 2.0 * halfH * (k + 0.5) / kRays;
        const double dx = std::sin(a), dy = std::cos(a);
        double horizon = -1e9;  // the steepest slope to the terrain so far along the ray
        for (double d = 30.0; d < 40000.0;) {
            const double step = std::max(15.0, 0.02 * d);
            const double ground = terrain.at(x + dx * d, y + dy * d);
            if (std::isnan(ground)) {
                break;
            }
            const double slope = (ground - z) / d;
            const double angle = std::atan(slope);
            const bool inFrustum = angle > pitch - halfV && angle < pitch + halfV;
            const bool behind = slope < horizon;
            if (inFrustum) {
                const double weight = step / d;
                total += weight;
                hidden += behind ? weight : 0.0;
                if (d < near) {
                    totalNear += weight;
                    hiddenNear += behind ? weight : 0.0;
                }
            }
            horizon = std::max(horizon, slope);
            d += step;
        }
    }
    return {total > 0.0 ? hidden / total : 0.0, totalNear > 0.0 ? hiddenNear / totalNear : 0.0};
}

void printRow(const std::string& name, double hidden, double hiddenNear, double heightAbove)
{
    std::printf("%-44s %7.3f %9.2fx %7.3f %9.2fx %9.0f\n", name.c_str(), hidden, 1.0 / (1.0 - hidden), hiddenNear,
                1.0 / (1.0 - hiddenNear), heightAbove);
}

/// The mean shares over a path's poses every 0.5 s, and the mean height above the ground.
void surveyPath(const Terrain& terrain, const CameraPath& path, const std::string& name, double near)
{
    double hidden = 0.0, hiddenNear = 0.0, above = 0.0;
    int poses = 0;
    for (double t = path.startTime(); t <= path.endTime(); t += 0.5) {
        const CameraPose pose = path.evaluate(t);
        const Share s =
            hiddenShare(terrain, pose.position.x, pose.position.y, pose.position.z, pose.yaw, pose.pitch, near);
        hidden += s.hidden;
        hiddenNear += s.hiddenNear;
        above += pose.position.z - terrain.at(pose.position.x, pose.position.y);
        ++poses;
    }
    printRow(name, hidden / poses, hiddenNear / poses, above / poses);
}

/// Up-valley routes: see the file comment.
void surveyRoutes(const Terrain& terrain, double near)
{
    struct Route {
        double hidden, hiddenNear;
        double x, y;
    };
    std::vector<Route> routes;
    const int w = terrain.field.width, h = terrain.field.height;
    auto sample = [&](int i, int j) {
        return double{terrain.field.samples[static_cast<std::size_t>(j) * static_cast<std::size_t>(w) + i]};
    };
    const int every = static_cast<int>(2000.0 / kSpacing);
    for (int j0 = every; j0 < h - 1; j0 += every) {
        for (int i0 = every; i0 < w - 1; i0 += every) {
            if (sample(i0, j0) < 3300.0) {
                continue;
            }
            // Steepest descent over the 8 neighbours not visited yet (across flats too), at most 12 km.
            std::vector<std::pair<double, double>> line;
            std::vector<std::pair<int, int>> visited;
            int i = i0, j = j0;
            for (double length = 0.0; length < 12000.0;) {
                line.emplace_back(i * kSpacing, j * kSpacing);
                visited.emplace_back(i, j);
                int bi = i, bj = j;
                double best = -1.0;  // metres per sample: a flat or a small rise still flows on
                for (int dj = -1; dj <= 1; ++dj) {
                    for (int di = -1; di <= 1; ++di) {
                        const int ni = i + di, nj = j + dj;
                        if ((di != 0 || dj != 0) && ni > 0 && nj > 0 && ni < w - 1 && nj < h - 1 &&
                            std::find(visited.begin(), visited.end(), std::pair{ni, nj}) == visited.end()) {
                            const double drop = (sample(i, j) - sample(ni, nj)) / std::hypot(di, dj);
                            if (drop > best) {
                                best = drop, bi = ni, bj = nj;
                            }
                        }
                    }
                }
                if (bi == i && bj == j) {
                    break;  // a pit or the edge
                }
                length += kSpacing * std::hypot(bi - i, bj - j);
                i = bi, j = bj;
            }
            // Keys every 12 samples (about 1 km), each the mean of the line around it, flown up-valley.
            std::vector<std::pair<double, double>> keys;
            for (std::size_t k = 0; k < line.size(); k += 12) {
                double sx = 0.0, sy = 0.0;
                const std::size_t a = k >= 12 ? k - 12 : 0, b = std::min(line.size(), k + 13);
                for (std::size_t m = a; m < b; ++m) {
                    sx += line[m].first, sy += line[m].second;
                }
                keys.emplace_back(sx / static_cast<double>(b - a), sy / static_cast<double>(b - a));
            }
            if (keys.size() < 8) {
                continue;
            }
            std::reverse(keys.begin(), keys.end());
            double hidden = 0.0, hiddenNear = 0.0;
            for (std::size_t k = 0; k + 1 < keys.size(); ++k) {
                const auto [x, y] = keys[k];
                const double yaw = std::atan2(keys[k + 1].first - x, keys[k + 1].second - y);
                const Share s =
                    hiddenShare(terrain, x, y, terrain.at(x, y) + 35.0, yaw, -2.0 * std::numbers::pi / 180, near);
                hidden += s.hidden;
                hiddenNear += s.hiddenNear;
            }
            const auto n = static_cast<double>(keys.size() - 1);
            routes.push_back({hidden / n, hiddenNear / n, keys.front().first, keys.front().second});
        }
    }
    std::sort(routes.begin(), routes.end(), [](const Route& a, const Route& b) { return a.hidden > b.hidden; });
    std::printf("%zu up-valley routes; the most enclosed:\n", routes.size());
    for (std::size_t k = 0; k < std::min<std::size_t>(10, routes.size()); ++k) {
        char name[64];
        std::snprintf(name, sizeof name, "  route from (%.0f, %.0f)", routes[k].x, routes[k].y);
        printRow(name, routes[k].hidden, routes[k].hiddenNear, 35.0);
    }
}

}  // namespace

int main(int argc, char** argv)
{
    bool routes = false;
    double near = 3000.0;
    std::vector<std::string> paths;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--routes") {
            routes = true;
        } else if (arg == "--near" && i + 1 < argc) {
            const auto value = parseDouble(argv[++i]);
            if (!value.ok() || *value <= 30.0) {
                std::fprintf(stderr, "ViewshedSurvey: --near %s: expected metres > 30\n", argv[i]);
                return 1;
            }
            near = *value;
        } else if (!arg.empty() && arg[0] == '-') {
            std::fprintf(
                stderr,
                "ViewshedSurvey: unknown option %s\nusage: ViewshedSurvey [--routes] [--near METRES] [PATH...]\n",
                arg.c_str());
            return 1;
        } else {
            paths.push_back(arg);
        }
    }
    if (paths.empty()) {
        paths = {TERRAIN_DEMOS_DIR "/trinidad-valley.path", TERRAIN_DEMOS_DIR "/trinidad.path"};
    }
    auto field = readHeightField(TERRAIN_DEMOS_DIR "/data/trinidad_co_srtm3_crop_1025.png");
    if (!field.ok()) {
        std::fprintf(stderr, "ViewshedSurvey: %s\n", field.error().message.c_str());
        return 1;
    }
    const Terrain terrain{std::move(field).value()};
    const std::string nearColumn = "<" + std::to_string(static_cast<int>(near)) + " m";
    std::printf("%-44s %7s %10s %7s %10s %9s\n", "view", "hidden", "bound", nearColumn.c_str(), "bound", "above (m)");
    for (const std::string& file : paths) {
        auto path = CameraPath::load(file);
        if (!path.ok()) {
            std::fprintf(stderr, "ViewshedSurvey: %s\n", path.error().message.c_str());
            return 1;
        }
        surveyPath(terrain, *path, std::filesystem::path(file).filename().string(), near);
    }
    if (routes) {
        surveyRoutes(terrain, near);
    }
    std::printf(
        "(hidden: share of the view's weight behind nearer terrain; bound: 1 / (1 - hidden), the most a "
        "visibility LOD can divide triangles by)\n");
    return 0;
}
