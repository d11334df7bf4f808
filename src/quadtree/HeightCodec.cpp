// Residual coding of static node heights from the Kobbelt 4-point prediction of the parent
// (quadtree/FourPointSubdivision.h with omega = 1; docs/design.md "Static heights on disk").
#include "quadtree/HeightCodec.h"

#include "core/ByteIo.h"
#include "core/Check.h"
#include "core/Zlib.h"
#include "quadtree/FourPointSubdivision.h"

#include <algorithm>

namespace terrain {

namespace {

bool isCoded(const NodeId& id, int x, int y)
{
    // Window index parity equals sample parity (kBorder is even); even-even samples are the parent's.
    return id.isRoot() || (x & 1) != 0 || (y & 1) != 0;
}

std::uint16_t clampCode(std::int32_t v)
{
    return static_cast<std::uint16_t>(std::clamp(v, 0, 65535));
}

}  // namespace

NodeWindow::NodeWindow(const MapHeader& header)
    : mHeader(&header), mChunk(static_cast<int>(header.chunkSize)), mSize(header.windowSize())
{
}

WindowRect NodeWindow::insideRect(const NodeId& id) const
{
    auto gridLast = static_cast<std::int64_t>(mHeader->levelGridSize(id.level)) - 1;
    auto clampAxis = [&](std::uint32_t cell, int& lo, int& hi) {
        std::int64_t first = std::int64_t{cell} * (mChunk - 1) - kBorder;  // grid index of window index 0
        lo = static_cast<int>(std::max<std::int64_t>(0, -first));
        hi = static_cast<int>(std::min<std::int64_t>(mSize - 1, gridLast - first));
    };
    WindowRect r;
    clampAxis(id.x, r.x0, r.x1);
    clampAxis(id.y, r.y0, r.y1);
    return r;
}

void fillOutside(std::span<std::uint16_t> window, int size, const WindowRect& inside)
{
    auto at = [&](int x, int y) -> std::uint16_t& { return window[static_cast<std::size_t>(y) * size + x]; };
    for (int y = inside.y0; y <= inside.y1; ++y) {
        for (int x = 0; x < inside.x0; ++x) {
            at(x, y) = clampCode(2 * at(inside.x0, y) - at(2 * inside.x0 - x, y));
        }
        for (int x = inside.x1 + 1; x < size; ++x) {
            at(x, y) = clampCode(2 * at(inside.x1, y) - at(2 * inside.x1 - x, y));
        }
    }
    for (int x = 0; x < size; ++x) {
        for (int y = 0; y < inside.y0; ++y) {
            at(x, y) = clampCode(2 * at(x, inside.y0) - at(x, 2 * inside.y0 - y));
        }
        for (int y = inside.y1 + 1; y < size; ++y) {
            at(x, y) = clampCode(2 * at(x, inside.y1) - at(x, 2 * inside.y1 - y));
        }
    }
}

void predictChildWindow(std::span<const std::uint16_t> parent, int size, int chunkSize, int quadrant,
                        std::span<std::int32_t> out)
{
    TERRAIN_EXPECTS(size == windowSize(chunkSize), "the window size must be the chunk size's");
    // Weights scaled by 16 in each pass, so a sum carries 256: round half up, exact for copies.
    subdivideFourPoint(parent, chunkSize, quadrant, kKobbeltWeightsTimes16, out,
                       [](std::int32_t sum) { return (sum + 128) >> 8; });
}

std::vector<std::uint8_t> encodeNodeHeights(const NodeWindow& geometry, const NodeId& id,
                                            std::span<const std::uint16_t> window,
                                            std::span<const std::uint16_t> parent, std::uint32_t bin, int zlibLevel)
{
    const int size = geometry.size();
    const WindowRect inside = geometry.insideRect(id);
    std::vector<std::int32_t> prediction(geometry.sampleCount());
    if (!id.isRoot()) {
        predictChildWindow(parent, size, geometry.chunkSize(), id.quadrant(), prediction);
    }
    std::vector<std::uint8_t> raw;
    raw.reserve(geometry.sampleCount());
    ByteWriter rawWriter(raw);
    for (int y = inside.y0; y <= inside.y1; ++y) {
        for (int x = inside.x0; x <= inside.x1; ++x) {
            if (!isCoded(id, x, y)) {
                continue;
            }
            auto i = static_cast<std::size_t>(y) * size + x;
            std::int32_t predicted = id.isRoot() ? rootPrediction(window, size, inside, x, y) : prediction[i];
            std::int32_t residual = window[i] - predicted;
            TERRAIN_ASSERT(residual % static_cast<std::int32_t>(bin) == 0);
            rawWriter.putVarint(zigzagEncode(residual / static_cast<std::int32_t>(bin)));
        }
    }
    std::vector<std::uint8_t> stream;
    ByteWriter(stream).put(static_cast<std::uint32_t>(raw.size()));
    auto packed = zlibCompress(raw, zlibLevel);
    stream.insert(stream.end(), packed.begin(), packed.end());
    return stream;
}

Status decodeNodeHeights(const NodeWindow& geometry, const NodeId& id, std::span<const std::uint8_t> stream,
                         std::span<const std::uint16_t> parent, std::uint32_t bin, std::span<std::uint16_t> window)
{
    TERRAIN_EXPECTS(window.size() == geometry.sampleCount(), "window must have size*size samples");
    TERRAIN_EXPECTS(id.isRoot() || parent.size() == geometry.sampleCount(), "a child needs its parent's window");
    const int size = geometry.size();
    const WindowRect inside = geometry.insideRect(id);
    ByteReader header(stream);
    auto rawSize = header.get<std::uint32_t>();
    // A varint of a 16-bit-range residual takes at most 3 bytes.
    if (header.failed() || rawSize > 3 * geometry.sampleCount()) {
        return makeError("height stream header is invalid");
    }
    auto raw = zlibDecompress(stream.subspan(4), rawSize);
    if (!raw.ok()) {
        return makeError("height stream: ", raw.error().message);
    }
    std::vector<std::int32_t> prediction(geometry.sampleCount());
    if (!id.isRoot()) {
        predictChildWindow(parent, size, geometry.chunkSize(), id.quadrant(), prediction);
    }
    const auto& bytes = raw.value();
    ByteReader reader(bytes);
    const auto b = static_cast<std::int32_t>(bin);
    for (int y = inside.y0; y <= inside.y1; ++y) {
        for (int x = inside.x0; x <= inside.x1; ++x) {
            auto i = static_cast<std::size_t>(y) * size + x;
            if (!isCoded(id, x, y)) {
                window[i] = static_cast<std::uint16_t>(prediction[i]);  // exact copy of the parent's sample
                continue;
            }
            std::uint32_t v = 0;
            if (!reader.getVarint(v)) {
                return makeError("height stream ends early or holds a malformed number");
            }
            std::int32_t predicted = id.isRoot() ? rootPrediction(window, size, inside, x, y) : prediction[i];
            std::int64_t value = std::int64_t{predicted} + std::int64_t{zigzagDecode(v)} * b;
            if (value < 0 || value > 65535) {
                return makeError("height stream decodes to ", value, ", outside the 16-bit range");
            }
            window[i] = static_cast<std::uint16_t>(value);
        }
    }
    if (reader.position() != bytes.size()) {
        return makeError("height stream has ", bytes.size() - reader.position(), " bytes left over");
    }
    fillOutside(window, size, inside);
    return {};
}

}  // namespace terrain
