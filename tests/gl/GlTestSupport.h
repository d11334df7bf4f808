// Helpers shared by the GL tests (tests/gl/*GLTest.cpp): the hole check of the viewer's frames and the
// video mode's frames.csv.
#pragma once

#include "TestSupport.h"
#include "core/Camera.h"
#include "core/Expected.h"
#include "heightfield/HeightField.h"
#include "quadtree/MapFile.h"
#include "quadtree/MapFormat.h"
#include "render/GlWindow.h"

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace terrain::test {

/// The clear colour the hole checks set (clear_color=1,0,1): a colour the scene never produces.
inline constexpr std::uint8_t kHole[3] = {255, 0, 255};

/// Whether an RGB pixel is the clear colour kHole.
inline bool isHole(const std::uint8_t* p)
{
    return p[0] == kHole[0] && p[1] == kHole[1] && p[2] == kHole[2];
}

/// Whether the view ray through pixel (px, py) must hit the terrain: it goes down and reaches `zMin`, the
/// lowest terrain height, inside the input's area (2 samples in from its edges) and before the far plane
/// (with a margin for the rasteriser's edges). The terrain lies at or above zMin everywhere there, so such
/// a ray crosses the surface first, and a clear-colour pixel there is a hole.
bool mustHitTerrain(const Camera& camera, const MapHeader& header, double zMin, int px, int py);

/// Builds the bundled terrain (demos/data, 90 m spacing, 2 threads) into a map at `path`, as prep does:
/// with `materials` (.mat files, the first the ground), the leaves' detail errors for them and the recipe
/// saying so; without, no detail errors and no recipe. The shared fixture of the GL tests.
Status buildDemoMap(const std::filesystem::path& path, const std::vector<std::filesystem::path>& materials = {});
/// The same for any height field `field` with `spacing` metres between its samples, coloured by `texture` (an
/// image prep's --texture takes) or, without, by height.
Status buildDetailMap(HeightField field, double spacing, const std::filesystem::path& path,
                      const std::vector<std::filesystem::path>& materials, const std::filesystem::path& texture = {});

/// An invisible window of `width` x `height` whose GL context is current.
Expected<std::unique_ptr<GlWindow>> openHiddenWindow(int width, int height);

/// The GL tests' usual start: the bundled terrain built into a scratch map (buildDemoMap), an invisible
/// window of `width` x `height` whose GL context is current, and the map opened for streaming.
struct DemoScene {
    ScratchDir dir;
    std::unique_ptr<GlWindow> window;
    std::unique_ptr<MapFile> map;
};
Expected<std::unique_ptr<DemoScene>> openDemoScene(int width, int height);

/// Rows of a video's frames.csv as maps from column name to value; empty fields (not measured) are left out.
std::vector<std::map<std::string, double>> readCsv(const std::filesystem::path& file);

}  // namespace terrain::test
