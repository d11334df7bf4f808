// Per-node textures (paper 3.2.7): every node has its own T x T RGB texture of its square; corner texels
// are centred on the node's corners, so neighbouring nodes of one level share their edge texels and
// bilinear filtering shows no seam. Leaves sample a TextureSource; inner nodes are filtered from their
// children (a texture pyramid like the geometry's), which keeps shared edges shared at every level.
#pragma once

#include "heightfield/Image.h"
#include "quadtree/MapFormat.h"
#include "quadtree/QuantizedGrid.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace terrain {

/// Colour of the terrain at a position of the finest static grid (x east, y north, in samples).
class TextureSource {
public:
    virtual ~TextureSource() = default;
    /// Writes the RGB colour averaged over a square of `footprint` samples centred on (gx, gy).
    virtual void colour(double gx, double gy, double footprint, std::uint8_t* rgb) const = 0;
};

/// Unlit colours generated from height and slope (grass low, dry ground higher, rock on steep slopes and
/// high up, snow on the highest gentle ground), so a map without `-t` looks like terrain. Lighting happens
/// at render time.
class HeightColouring final : public TextureSource {
public:
    /// `heightMin`/`heightMax`: metres spanned by the valid input, which sets the height bands.
    HeightColouring(const QuantizedGrid& grid, const MapHeader& header, double heightMin, double heightMax);
    void colour(double gx, double gy, double footprint, std::uint8_t* rgb) const override;

private:
    /// Palette resolution: height fraction and slope steps of the lookup table.
    static constexpr int kTableSteps = 256;
    /// Slope (rise over run) at the table's last column; steeper ground is coloured as this.
    static constexpr double kTableMaxSlope = 2.0;

    const std::uint8_t* colourAt(std::int64_t x, std::int64_t y) const;

    const QuantizedGrid& mGrid;
    double mCodeMin;                   ///< code of the lowest valid height
    double mHeightStepsPerCode;        ///< table rows per code
    double mSlopeStepsPerCode;         ///< table columns per code of height difference over 2 samples
    std::vector<std::uint8_t> mTable;  ///< kTableSteps^2 RGB colours, [height step][slope step]
};

/// A user texture (`prep -t`) stretched over the input's valid region: image pixel centres sit on the
/// samples, row 0 of the image is north.
class ImageTexture final : public TextureSource {
public:
    ImageTexture(const Image& rgb, const MapHeader& header);
    void colour(double gx, double gy, double footprint, std::uint8_t* rgb) const override;

private:
    const Image& mImage;
    double mScaleX, mScaleY;  ///< image pixels per grid sample
    double mX0, mY0;          ///< the grid position of the image's south-west pixel centre
};

/// Georeferenced imagery (`prep -t` of a GDAL raster with a CRS), already resampled by GDAL onto the
/// finest level's texel lattice (readGeoImagery): an RGBA image whose pixel (c, r), r = 0 the north row, is
/// at grid position (x0 + c / pixelsPerSample, y0 + (height - 1 - r) / pixelsPerSample). Where its alpha is
/// below 255 (the imagery does not cover) the fallback's colour shows through in proportion.
class CoveredImageTexture final : public TextureSource {
public:
    CoveredImageTexture(Image rgba, double pixelsPerSample, double x0, double y0, const TextureSource& fallback);
    void colour(double gx, double gy, double footprint, std::uint8_t* rgb) const override;
    /// Share of the image's pixels with full coverage (alpha 255), for prep's summary.
    double coverage() const;

private:
    Image mImage;
    double mPixelsPerSample;
    double mX0, mY0;
    const TextureSource& mFallback;
};

/// Fills node `id`'s texture (size*size*3, rows south to north) directly from `source`.
void sampleNodeTexture(const TextureSource& source, const MapHeader& header, const NodeId& id,
                       std::span<std::uint8_t> rgb);

/// Filters the four children's textures (quadrant order of NodeId::child) into their parent's: a [1 2 1]
/// tent at every parent texel; along the node's edges only along the edge, so both nodes sharing an edge
/// compute the same texels from the same children's edge texels.
void downsampleChildTextures(const std::array<std::span<const std::uint8_t>, 4>& children, int size,
                             std::span<std::uint8_t> parent);

}  // namespace terrain
