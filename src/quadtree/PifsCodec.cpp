// Seed 003's fractal (PIFS) height coding (Erra, Scarano & Guida, section 7: range blocks, shrunk domains,
// least-squares scale and offset, iterated decoding), adapted to the quadtree's shared samples
// (PifsCodec.h, docs/map-format.md "Fractal height coding").
#include "quadtree/PifsCodec.h"

#include "core/ByteIo.h"
#include "core/Check.h"
#include "core/ParallelFor.h"
#include "core/Zlib.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace terrain {

namespace {

constexpr int kDomain = 2 * kPifsRange;
constexpr int kRangeSamples = kPifsRange * kPifsRange;

int rangesPerSide(int chunkSize)
{
    return (chunkSize - 1) / kPifsRange;
}

/// Domain positions per side: 8-sample blocks inside the square's first N - 1 samples.
int domainsPerSide(int chunkSize)
{
    return (chunkSize - 1 - kDomain) / kPifsDomainStep + 1;
}

/// Where a shrunk domain's sample (u, v) comes from under `isometry` (bit 2 swaps, bits 0 and 1 mirror).
int isometrySource(int isometry, int u, int v)
{
    int a = u, b = v;
    if (isometry & 4) {
        std::swap(a, b);
    }
    if (isometry & 1) {
        a = kPifsRange - 1 - a;
    }
    if (isometry & 2) {
        b = kPifsRange - 1 - b;
    }
    return b * kPifsRange + a;
}

/// Parent domains per side: origins within kPifsParentReach of the collocated one.
constexpr int kParentDomainsPerSide = 2 * kPifsParentReach + 1;

int ownDomains(int chunkSize)
{
    return domainsPerSide(chunkSize) * domainsPerSide(chunkSize);
}

int domainCount(const NodeId& id, int chunkSize)
{
    return ownDomains(chunkSize) + (id.isRoot() ? 0 : kParentDomainsPerSide * kParentDomainsPerSide);
}

int rangeCount(const NodeId& id, int chunkSize)
{
    return id.isRoot() ? 0 : rangesPerSide(chunkSize) * rangesPerSide(chunkSize);
}

/// The domain at `index`, shrunk: each value the sum of a 2 x 2 block of the window (4x the average).
std::array<std::int32_t, kRangeSamples> shrunkDomain(std::span<const std::uint16_t> window, int size, int chunkSize,
                                                     int index)
{
    const int perSide = domainsPerSide(chunkSize);
    const int x0 = kBorder + (index % perSide) * kPifsDomainStep;
    const int y0 = kBorder + (index / perSide) * kPifsDomainStep;
    std::array<std::int32_t, kRangeSamples> d{};
    for (int v = 0; v < kPifsRange; ++v) {
        for (int u = 0; u < kPifsRange; ++u) {
            const std::size_t i = static_cast<std::size_t>(y0 + 2 * v) * size + x0 + 2 * u;
            d[static_cast<std::size_t>(v * kPifsRange + u)] =
                window[i] + window[i + 1] + window[i + size] + window[i + size + 1];
        }
    }
    return d;
}

/// Domain `index` for range `block` as sums of 4 (the scale of shrunkDomain): an own domain of `window`, or
/// a 4 x 4 block of the parent's samples (twice the range's extent at half its spacing: no averaging)
/// around the one collocated with the range, each sample times 4.
std::array<std::int32_t, kRangeSamples> domainSums(const NodeId& id, int chunkSize,
                                                   std::span<const std::uint16_t> window,
                                                   std::span<const std::uint16_t> parent, int index, int block)
{
    const int size = windowSize(chunkSize);
    const int own = ownDomains(chunkSize);
    if (index < own) {
        return shrunkDomain(window, size, chunkSize, index);
    }
    const int j = index - own;
    const int perSide = rangesPerSide(chunkSize);
    const int half = (chunkSize - 1) / 2;
    // The range's child samples 4b .. 4b + 3 lie at parent samples q h + 2b .. + 1.5; the 4-sample block
    // centred there starts at q h + 2b - 1 (rounded from - 0.75).
    const int cx = kBorder + (id.quadrant() & 1) * half + kPifsRange / 2 * (block % perSide) - 1;
    const int cy = kBorder + (id.quadrant() >> 1) * half + kPifsRange / 2 * (block / perSide) - 1;
    const int x0 = std::clamp(cx + j % kParentDomainsPerSide - kPifsParentReach, 0, size - kPifsRange);
    const int y0 = std::clamp(cy + j / kParentDomainsPerSide - kPifsParentReach, 0, size - kPifsRange);
    std::array<std::int32_t, kRangeSamples> d{};
    for (int v = 0; v < kPifsRange; ++v) {
        for (int u = 0; u < kPifsRange; ++u) {
            d[static_cast<std::size_t>(v * kPifsRange + u)] =
                4 * parent[static_cast<std::size_t>(y0 + v) * size + x0 + u];
        }
    }
    return d;
}

/// The coded samples of range block `block`: local index v * 4 + u.
struct RangeMask {
    std::array<std::uint8_t, kRangeSamples> local{};
    int count = 0;
};

RangeMask rangeMask(const NodeId& id, int chunkSize, int block)
{
    const int perSide = rangesPerSide(chunkSize);
    const int x0 = kBorder + (block % perSide) * kPifsRange;
    const int y0 = kBorder + (block / perSide) * kPifsRange;
    RangeMask mask;
    for (int v = 0; v < kPifsRange; ++v) {
        for (int u = 0; u < kPifsRange; ++u) {
            if (pifsCodes(id, chunkSize, x0 + u, y0 + v)) {
                mask.local[static_cast<std::size_t>(mask.count++)] = static_cast<std::uint8_t>(v * kPifsRange + u);
            }
        }
    }
    return mask;
}

/// round(num / den) for den > 0, halves up, in integers.
std::int64_t roundDiv(std::int64_t num, std::int64_t den)
{
    const std::int64_t t = 2 * num + den;
    std::int64_t q = t / (2 * den);
    if (t % (2 * den) != 0 && t < 0) {
        --q;
    }
    return q;
}

std::uint16_t clampCode(std::int64_t v)
{
    return static_cast<std::uint16_t>(std::clamp<std::int64_t>(v, 0, 65535));
}

bool parentSample(const NodeId& id, int x, int y)
{
    // Window index parity is sample parity (kBorder is even).
    return !id.isRoot() && (x & 1) == 0 && (y & 1) == 0;
}

}  // namespace

bool pifsCodes(const NodeId& id, int chunkSize, int x, int y)
{
    const int last = kBorder + chunkSize - 1;
    return !id.isRoot() && x > kBorder && x < last && y > kBorder && y < last && !parentSample(id, x, y);
}

std::vector<PifsTransform> fitPifs(const NodeId& id, int chunkSize, std::span<const std::uint16_t> window,
                                   std::span<const std::uint16_t> parent)
{
    TERRAIN_EXPECTS(chunkSize >= 9, "fractal coding needs chunks of at least 9 samples");
    const int size = windowSize(chunkSize);
    TERRAIN_EXPECTS(window.size() == static_cast<std::size_t>(size) * size, "window must have W x W samples");
    TERRAIN_EXPECTS(id.isRoot() || parent.size() == window.size(), "a child needs its parent's window");
    const int own = ownDomains(chunkSize);
    const int domains = domainCount(id, chunkSize);
    // Every domain under every isometry, as averages (sum / 4), centred on the domain's mean: the sums over
    // a range's samples below then stay small and exact enough in double. Own domains are the same for every
    // range; parent domains depend on the range (collocated), so they fill the slots after `own` per range.
    std::vector<std::array<double, kRangeSamples>> candidates(static_cast<std::size_t>(domains) * 8);
    auto setCandidates = [&](int d, const std::array<std::int32_t, kRangeSamples>& sums) {
        double mean = 0.0;
        for (auto v : sums) {
            mean += v / 4.0;
        }
        mean /= kRangeSamples;
        for (int t = 0; t < 8; ++t) {
            auto& c = candidates[static_cast<std::size_t>(d) * 8 + t];
            for (int k = 0; k < kRangeSamples; ++k) {
                c[static_cast<std::size_t>(k)] =
                    sums[static_cast<std::size_t>(isometrySource(t, k % kPifsRange, k / kPifsRange))] / 4.0 - mean;
            }
        }
    };
    for (int d = 0; d < own && !id.isRoot(); ++d) {
        setCandidates(d, shrunkDomain(window, size, chunkSize, d));
    }
    const int perSide = rangesPerSide(chunkSize);
    std::vector<PifsTransform> transforms(static_cast<std::size_t>(rangeCount(id, chunkSize)));
    for (int block = 0; block < static_cast<int>(transforms.size()); ++block) {
        const RangeMask mask = rangeMask(id, chunkSize, block);
        if (mask.count == 0) {
            continue;
        }
        for (int d = own; d < domains; ++d) {
            setCandidates(d, domainSums(id, chunkSize, window, parent, d, block));
        }
        const int x0 = kBorder + (block % perSide) * kPifsRange;
        const int y0 = kBorder + (block / perSide) * kPifsRange;
        std::array<double, kRangeSamples> r{};
        double sumR = 0.0;
        for (int k = 0; k < mask.count; ++k) {
            const int local = mask.local[static_cast<std::size_t>(k)];
            r[static_cast<std::size_t>(k)] =
                window[static_cast<std::size_t>(y0 + local / kPifsRange) * size + x0 + local % kPifsRange];
            sumR += r[static_cast<std::size_t>(k)];
        }
        const double n = mask.count;
        const auto mean = static_cast<std::uint16_t>(std::clamp(std::lround(sumR / n), 0L, 65535L));
        double sumB2 = 0.0;  // b = r - m
        for (int k = 0; k < mask.count; ++k) {
            const double b = r[static_cast<std::size_t>(k)] - mean;
            sumB2 += b * b;
        }
        PifsTransform best;
        best.mean = mean;
        double bestError = sumB2;  // s = 0: the mean alone
        for (std::size_t c = 0; c < candidates.size(); ++c) {
            const auto& d = candidates[c];
            double sd = 0.0, sdd = 0.0, sdr = 0.0;
            for (int k = 0; k < mask.count; ++k) {
                const double v = d[mask.local[static_cast<std::size_t>(k)]];
                sd += v;
                sdd += v * v;
                sdr += v * r[static_cast<std::size_t>(k)];
            }
            const double aa = sdd - sd * sd / n;    // sum (d - mean d)^2
            const double ab = sdr - sd * sumR / n;  // sum (d - mean d)(r - m)
            if (aa < 1e-9) {
                continue;
            }
            const double q =
                std::clamp(std::round(kPifsScaleSteps * ab / aa), double{-kPifsMaxScale}, double{kPifsMaxScale});
            const double s = q / kPifsScaleSteps;
            const double error = s * s * aa - 2.0 * s * ab + sumB2;
            if (error < bestError - 1e-9) {
                bestError = error;
                best.domain = static_cast<std::uint16_t>(c / 8);
                best.isometry = static_cast<std::uint8_t>(c % 8);
                best.scale = static_cast<std::int8_t>(q);
            }
        }
        transforms[static_cast<std::size_t>(block)] = best;
    }
    return transforms;
}

void iteratePifs(const NodeId& id, int chunkSize, std::span<const PifsTransform> transforms, int iterations,
                 std::span<const std::uint16_t> parent, std::span<std::uint16_t> window)
{
    const int size = windowSize(chunkSize);
    const int perSide = rangesPerSide(chunkSize);
    TERRAIN_EXPECTS(window.size() == static_cast<std::size_t>(size) * size, "window must have W x W samples");
    TERRAIN_EXPECTS(transforms.size() == static_cast<std::size_t>(rangeCount(id, chunkSize)),
                    "one transform per range");
    TERRAIN_EXPECTS(transforms.empty() || parent.size() == window.size(), "a child needs its parent's window");
    const int ranges = static_cast<int>(transforms.size());
    std::vector<RangeMask> masks(transforms.size());
    for (int block = 0; block < ranges; ++block) {
        masks[static_cast<std::size_t>(block)] = rangeMask(id, chunkSize, block);
    }
    auto forEachCoded = [&](int block, auto&& fn) {
        const int x0 = kBorder + (block % perSide) * kPifsRange;
        const int y0 = kBorder + (block / perSide) * kPifsRange;
        const RangeMask& mask = masks[static_cast<std::size_t>(block)];
        for (int k = 0; k < mask.count; ++k) {
            const int local = mask.local[static_cast<std::size_t>(k)];
            fn(local, static_cast<std::size_t>(y0 + local / kPifsRange) * size + x0 + local % kPifsRange);
        }
    };
    for (int block = 0; block < ranges; ++block) {
        forEachCoded(block, [&](int, std::size_t i) { window[i] = transforms[static_cast<std::size_t>(block)].mean; });
    }
    std::vector<std::uint16_t> previous(window.begin(), window.end());
    for (int pass = 0; pass < iterations; ++pass) {
        for (int block = 0; block < ranges; ++block) {
            const PifsTransform& t = transforms[static_cast<std::size_t>(block)];
            const RangeMask& mask = masks[static_cast<std::size_t>(block)];
            if (mask.count == 0) {
                continue;
            }
            const auto d = domainSums(id, chunkSize, previous, parent, t.domain, block);
            std::int64_t sumD = 0;
            for (int k = 0; k < mask.count; ++k) {
                sumD += d[static_cast<std::size_t>(
                    isometrySource(t.isometry, mask.local[static_cast<std::size_t>(k)] % kPifsRange,
                                   mask.local[static_cast<std::size_t>(k)] / kPifsRange))];
            }
            const std::int64_t n = mask.count;
            // s (d - mean d) with d = D / 4, s = q / 16: q (n D - sum D) / (64 n).
            forEachCoded(block, [&](int local, std::size_t i) {
                const std::int64_t dk =
                    d[static_cast<std::size_t>(isometrySource(t.isometry, local % kPifsRange, local / kPifsRange))];
                window[i] = clampCode(t.mean + roundDiv(t.scale * (n * dk - sumD), 4 * kPifsScaleSteps * n));
            });
        }
        std::copy(window.begin(), window.end(), previous.begin());
    }
}

std::vector<std::uint8_t> encodePifsHeights(const NodeWindow& geometry, const NodeId& id,
                                            std::span<const std::uint16_t> stored,
                                            std::span<const std::uint16_t> parent,
                                            std::span<const PifsTransform> transforms, int iterations, int zlibLevel)
{
    TERRAIN_EXPECTS(iterations >= 1 && iterations <= kPifsMaxIterations, "iterations must be in [1, 64]");
    const int size = geometry.size();
    const int chunk = geometry.chunkSize();
    const WindowRect inside = geometry.insideRect(id);
    std::vector<std::uint8_t> raw;
    ByteWriter out(raw);
    out.put(static_cast<std::uint8_t>(iterations));
    std::int32_t previousMean = 0;
    for (const PifsTransform& t : transforms) {
        out.putVarint(std::uint32_t{t.domain} * 8 + t.isometry);
        out.put(static_cast<std::uint8_t>(t.scale + kPifsMaxScale));
        out.putVarint(zigzagEncode(std::int32_t{t.mean} - previousMean));
        previousMean = t.mean;
    }
    std::vector<std::int32_t> prediction(geometry.sampleCount());
    if (!id.isRoot()) {
        predictChildWindow(parent, size, chunk, id.quadrant(), prediction);
    }
    for (int y = inside.y0; y <= inside.y1; ++y) {
        for (int x = inside.x0; x <= inside.x1; ++x) {
            if (pifsCodes(id, chunk, x, y) || parentSample(id, x, y)) {
                continue;
            }
            const auto i = static_cast<std::size_t>(y) * size + x;
            const std::int32_t predicted = id.isRoot() ? rootPrediction(stored, size, inside, x, y) : prediction[i];
            out.putVarint(zigzagEncode(std::int32_t{stored[i]} - predicted));
        }
    }
    std::vector<std::uint8_t> stream;
    ByteWriter(stream).put(static_cast<std::uint32_t>(raw.size()));
    auto packed = zlibCompress(raw, zlibLevel);
    stream.insert(stream.end(), packed.begin(), packed.end());
    return stream;
}

Status decodePifsHeights(const NodeWindow& geometry, const NodeId& id, std::span<const std::uint8_t> stream,
                         std::span<const std::uint16_t> parent, std::span<std::uint16_t> window)
{
    TERRAIN_EXPECTS(window.size() == geometry.sampleCount(), "window must have size*size samples");
    TERRAIN_EXPECTS(id.isRoot() || parent.size() == geometry.sampleCount(), "a child needs its parent's window");
    const int size = geometry.size();
    const int chunk = geometry.chunkSize();
    if (chunk < 9) {
        return makeError("fractal height stream for chunks of ", chunk, " samples (at least 9 are needed)");
    }
    const WindowRect inside = geometry.insideRect(id);
    ByteReader header(stream);
    const auto rawSize = header.get<std::uint32_t>();
    const auto ranges = static_cast<std::size_t>(rangeCount(id, chunk));
    // Per range at most 3 + 1 + 3 bytes, per corrected sample at most 3 (a 17-bit zigzag), plus the count.
    if (header.failed() || rawSize > 1 + 7 * ranges + 3 * geometry.sampleCount()) {
        return makeError("fractal height stream header is invalid");
    }
    auto raw = zlibDecompress(stream.subspan(4), rawSize);
    if (!raw.ok()) {
        return makeError("fractal height stream: ", raw.error().message);
    }
    ByteReader in(raw.value());
    const int iterations = in.get<std::uint8_t>();
    if (in.failed() || iterations < 1 || iterations > kPifsMaxIterations) {
        return makeError("fractal height stream asks for ", iterations, " iterations (1 to ", kPifsMaxIterations, ")");
    }
    const auto domains = static_cast<std::uint32_t>(domainCount(id, chunk));
    std::vector<PifsTransform> transforms(ranges);
    std::int64_t mean = 0;
    for (std::size_t block = 0; block < ranges; ++block) {
        std::uint32_t code = 0, delta = 0;
        if (!in.getVarint(code)) {
            return makeError("fractal height stream ends early or holds a malformed number (range ", block, ")");
        }
        const auto scale = in.get<std::uint8_t>();
        if (!in.getVarint(delta)) {
            return makeError("fractal height stream ends early or holds a malformed number (range ", block, ")");
        }
        mean += zigzagDecode(delta);
        if (code / 8 >= domains || scale > 2 * kPifsMaxScale || mean < 0 || mean > 65535) {
            return makeError("fractal height stream: range ", block, " has domain ", code / 8, " of ", domains,
                             ", scale code ", int{scale}, " (at most ", 2 * kPifsMaxScale, "), mean ", mean);
        }
        transforms[block] = {static_cast<std::uint16_t>(code / 8), static_cast<std::uint8_t>(code % 8),
                             static_cast<std::int8_t>(scale - kPifsMaxScale), static_cast<std::uint16_t>(mean)};
    }
    std::vector<std::int32_t> prediction(geometry.sampleCount());
    if (!id.isRoot()) {
        predictChildWindow(parent, size, chunk, id.quadrant(), prediction);
    }
    for (int y = inside.y0; y <= inside.y1; ++y) {
        for (int x = inside.x0; x <= inside.x1; ++x) {
            const auto i = static_cast<std::size_t>(y) * size + x;
            if (pifsCodes(id, chunk, x, y)) {
                continue;
            }
            if (parentSample(id, x, y)) {
                window[i] = static_cast<std::uint16_t>(prediction[i]);  // exact copy of the parent's sample
                continue;
            }
            std::uint32_t v = 0;
            if (!in.getVarint(v)) {
                return makeError("fractal height stream ends early or holds a malformed number (edge samples)");
            }
            const std::int64_t predicted =
                id.isRoot() ? rootPrediction(window, size, inside, x, y) : std::int64_t{prediction[i]};
            const std::int64_t value = predicted + zigzagDecode(v);
            if (value < 0 || value > 65535) {
                return makeError("fractal height stream decodes to ", value, ", outside the 16-bit range");
            }
            window[i] = static_cast<std::uint16_t>(value);
        }
    }
    if (in.position() != raw.value().size()) {
        return makeError("fractal height stream has ", raw.value().size() - in.position(), " bytes left over");
    }
    iteratePifs(id, chunk, transforms, iterations, parent, window);
    fillOutside(window, size, inside);
    return {};
}

PifsPyramid::PifsPyramid(const MapHeader& header) : mHeader(header)
{
    mLevels.resize(header.levels);
    for (std::uint32_t level = 0; level < header.levels; ++level) {
        mLevelSize.push_back(header.levelGridSize(static_cast<int>(level)));
    }
}

void PifsPyramid::extractWindow(const NodeId& id, std::span<std::uint16_t> window) const
{
    const NodeWindow geometry(mHeader);
    const int size = geometry.size();
    TERRAIN_EXPECTS(window.size() == geometry.sampleCount(), "window must have size*size samples");
    const WindowRect inside = geometry.insideRect(id);
    const std::int64_t x0 = std::int64_t{id.x} * (geometry.chunkSize() - 1) - kBorder;
    const std::int64_t y0 = std::int64_t{id.y} * (geometry.chunkSize() - 1) - kBorder;
    for (int y = inside.y0; y <= inside.y1; ++y) {
        for (int x = inside.x0; x <= inside.x1; ++x) {
            window[static_cast<std::size_t>(y) * size + x] =
                at(id.level, static_cast<std::uint64_t>(x0 + x), static_cast<std::uint64_t>(y0 + y));
        }
    }
    fillOutside(window, size, inside);
}

void PifsPyramid::buildLevel(int level, const QuantizedGrid& grid, const std::vector<NodeId>& nodes, int threads,
                             int zlibLevel)
{
    const NodeWindow geometry(mHeader);
    const int size = geometry.size();
    const int chunk = geometry.chunkSize();
    const auto k = static_cast<std::size_t>(level);
    const std::uint64_t side = mLevelSize[k];
    const int stride = 1 << (static_cast<int>(mHeader.levels) - 1 - level);
    // The level's grid before the interiors: even-even samples the level above's, the rest the input's.
    auto rule = [&](std::uint64_t x, std::uint64_t y) -> std::uint16_t {
        if (level > 0 && (x & 1) == 0 && (y & 1) == 0) {
            return at(level - 1, x / 2, y / 2);
        }
        return grid.at(x * static_cast<std::uint64_t>(stride), y * static_cast<std::uint64_t>(stride));
    };
    auto& samples = mLevels[k];
    samples.resize(side * side);
    parallelFor(side, threads, [&](std::size_t y) {
        for (std::uint64_t x = 0; x < side; ++x) {
            samples[y * side + x] = rule(x, y);
        }
    });
    std::vector<std::vector<PifsTransform>> transforms(nodes.size());
    for (const NodeId& id : nodes) {
        mNodes[id.key()];  // every slot before the workers write them
    }
    // Interiors: each node reads only its own square's rule values and writes only its interior.
    parallelFor(nodes.size(), threads, [&](std::size_t n) {
        const NodeId& id = nodes[n];
        const std::uint64_t x0 = std::uint64_t{id.x} * (chunk - 1) - kBorder;
        const std::uint64_t y0 = std::uint64_t{id.y} * (chunk - 1) - kBorder;
        std::vector<std::uint16_t> window(geometry.sampleCount(), 0);
        for (int y = kBorder; y < kBorder + chunk; ++y) {
            for (int x = kBorder; x < kBorder + chunk; ++x) {
                window[static_cast<std::size_t>(y) * size + x] = rule(x0 + x, y0 + y);
            }
        }
        std::vector<std::uint16_t> parent;
        if (!id.isRoot()) {
            parent.resize(geometry.sampleCount());
            extractWindow(id.parent(), parent);
        }
        transforms[n] = fitPifs(id, chunk, window, parent);
        iteratePifs(id, chunk, transforms[n], kPifsIterations, parent, window);
        for (int y = kBorder; y < kBorder + chunk; ++y) {
            for (int x = kBorder; x < kBorder + chunk; ++x) {
                if (pifsCodes(id, chunk, x, y)) {
                    samples[(y0 + y) * side + x0 + x] = window[static_cast<std::size_t>(y) * size + x];
                }
            }
        }
    });
    // Streams and errors, from the finished level.
    parallelFor(nodes.size(), threads, [&](std::size_t n) {
        const NodeId& id = nodes[n];
        std::vector<std::uint16_t> stored(geometry.sampleCount()), input(geometry.sampleCount()), parent;
        extractWindow(id, stored);
        grid.extractWindow(mHeader, id, input);
        if (!id.isRoot()) {
            parent.resize(geometry.sampleCount());
            extractWindow(id.parent(), parent);
        }
        const WindowRect inside = geometry.insideRect(id);
        std::uint32_t worst = 0;
        for (int y = inside.y0; y <= inside.y1; ++y) {
            for (int x = inside.x0; x <= inside.x1; ++x) {
                const auto i = static_cast<std::size_t>(y) * size + x;
                worst = std::max<std::uint32_t>(worst, static_cast<std::uint32_t>(std::abs(stored[i] - input[i])));
            }
        }
        Node& node = mNodes.at(id.key());
        node.errorCodes = worst;
        node.stream = encodePifsHeights(geometry, id, stored, parent, transforms[n], kPifsIterations, zlibLevel);
    });
    for (const NodeId& id : nodes) {
        mMaxError = std::max(mMaxError, mNodes.at(id.key()).errorCodes);
    }
}

}  // namespace terrain
