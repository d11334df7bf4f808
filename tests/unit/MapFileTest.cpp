// The .map reader and verifier: both reader kinds agree, the file is laid out as docs/map-format.md says
// (checked from the raw bytes with zlib's own crc32 and an independent height-stream decoder), and every
// kind of damage (a flipped payload byte, truncation, bad header fields, a bad directory) is an error that
// names the file and, where there is one, the node.
#include "quadtree/MapFile.h"

#include "MapTestSupport.h"
#include "heightfield/Image.h"
#include "quadtree/MapVerifier.h"

#include <gtest/gtest.h>
#include <zlib.h>
#include <bit>
#include <limits>
#include <map>
#include <thread>

namespace terrain {
namespace {

using test::Bytes;

constexpr ReaderKind kReaders[] = {ReaderKind::Stream, ReaderKind::MemoryMapped};

const char* readerName(ReaderKind kind)
{
    return kind == ReaderKind::Stream ? "stream" : "memory_mapped";
}

std::filesystem::path buildSmallMap(const test::ScratchDir& dir, const std::string& name = "small.map",
                                    double maxError = 0.0, bool detail = false, bool roughness = true)
{
    // 65 x 65 samples, chunk 17: three levels, 21 nodes. With `detail`, leaves get fake detail errors.
    BuildOptions options = test::testOptions(17);
    options.maxError = maxError;
    options.measureRoughness = roughness;
    if (detail) {
        options.leafDetailError = test::fakeLeafDetailError;
    }
    auto report = buildMap(test::hillyField(65, 65, 41), options, dir / name);
    EXPECT_TRUE(report.ok()) << report.error().message;
    return dir / name;
}

bool mentions(const std::string& message, const std::string& what)
{
    return message.find(what) != std::string::npos;
}

/// zlib's crc32, called directly rather than through the code under test.
std::uint32_t zlibCrc(std::span<const std::uint8_t> bytes)
{
    return static_cast<std::uint32_t>(::crc32(0, bytes.data(), static_cast<uInt>(bytes.size())));
}

// ---- Readers ----

TEST(MapFileTest, ParseReaderKind)
{
    EXPECT_EQ(parseReaderKind("stream").value(), ReaderKind::Stream);
    EXPECT_EQ(parseReaderKind("memory_mapped").value(), ReaderKind::MemoryMapped);
    for (const char* bad : {"", "mmap", "Stream", "memory-mapped"}) {
        auto kind = parseReaderKind(bad);
        ASSERT_FALSE(kind.ok()) << "'" << bad << "'";
        EXPECT_TRUE(mentions(kind.error().message, "stream")) << kind.error().message;
    }
}

TEST(MapFileTest, StreamAndMemoryMappedReadersDecodeIdenticalNodes)
{
    test::ScratchDir dir;
    // Lossy and pruned, so the payloads are not all alike.
    Image weights{5, 5, 1, Bytes(25, 170)};
    ASSERT_TRUE(writePngImage(dir / "w.png", weights).ok());
    BuildOptions options = test::testOptions(9);
    options.maxError = 2.0;
    options.weights = dir / "w.png";
    ASSERT_TRUE(buildMap(test::roughField(100, 80, 42, 0, 4000), options, dir / "m.map").ok());
    auto stream = test::openMap(dir / "m.map", ReaderKind::Stream);
    auto mapped = test::openMap(dir / "m.map", ReaderKind::MemoryMapped);
    ASSERT_TRUE(stream && mapped);
    ASSERT_EQ(stream->directory().size(), mapped->directory().size());
    auto a = test::decodeTree(*stream);
    auto b = test::decodeTree(*mapped);
    ASSERT_TRUE(a.ok() && b.ok());
    ASSERT_EQ(a->nodes.size(), stream->directory().size());
    for (const auto& [key, node] : a->nodes) {
        const StaticNode* other = b->find(node.id);
        ASSERT_NE(other, nullptr) << node.id.toString();
        EXPECT_EQ(node.heights, other->heights) << node.id.toString();
        EXPECT_EQ(node.texture, other->texture) << node.id.toString();
    }
}

TEST(MapFileTest, ConcurrentLoadsGiveTheSameNodes)
{
    test::ScratchDir dir;
    const auto path = buildSmallMap(dir);
    for (ReaderKind kind : kReaders) {
        auto map = test::openMap(path, kind);
        ASSERT_TRUE(map);
        auto reference = test::decodeTree(*map);
        ASSERT_TRUE(reference.ok());
        std::vector<int> differences(4, 0);
        std::vector<std::thread> threads;
        for (int t = 0; t < 4; ++t) {
            threads.emplace_back([&, t] {
                for (int round = 0; round < 5; ++round) {
                    for (const auto& [key, node] : reference->nodes) {
                        std::span<const std::uint16_t> parent;
                        if (!node.id.isRoot()) {
                            parent = reference->find(node.id.parent())->heights;
                        }
                        auto loaded = map->loadNode(node.id, parent);
                        differences[static_cast<std::size_t>(t)] +=
                            !loaded.ok() || loaded->heights != node.heights || loaded->texture != node.texture;
                    }
                }
            });
        }
        for (auto& thread : threads) {
            thread.join();
        }
        EXPECT_EQ(differences, std::vector<int>(4, 0)) << readerName(kind);
    }
}

TEST(MapFileTest, LoadPathDecodesTheChainFromTheRoot)
{
    test::ScratchDir dir;
    auto map = test::openMap(buildSmallMap(dir));
    ASSERT_TRUE(map);
    auto tree = test::decodeTree(*map);
    ASSERT_TRUE(tree.ok());
    for (const NodeId id : {NodeId{0, 0, 0}, NodeId{1, 1, 0}, NodeId{2, 3, 1}, NodeId{2, 0, 3}}) {
        auto node = map->loadPath(id);
        ASSERT_TRUE(node.ok()) << node.error().message;
        EXPECT_EQ(node->id, id);
        EXPECT_EQ(node->heights, tree->find(id)->heights) << id.toString();
    }
    for (const NodeId id : {NodeId{3, 0, 0}, NodeId{2, 4, 0}}) {
        auto node = map->loadNode(id, tree->find(NodeId::root())->heights);
        ASSERT_FALSE(node.ok()) << id.toString();
        EXPECT_TRUE(mentions(node.error().message, id.toString())) << node.error().message;
        EXPECT_TRUE(mentions(node.error().message, map->name())) << node.error().message;
    }
}

TEST(MapFileTest, VerifyFindsNothingWrongWithSoundMaps)
{
    test::ScratchDir dir;
    for (double maxError : {0.0, 4.0}) {
        const auto path = buildSmallMap(dir, "m" + std::to_string(maxError) + ".map", maxError, maxError > 0);
        for (ReaderKind kind : kReaders) {
            auto map = test::openMap(path, kind);
            ASSERT_TRUE(map);
            std::vector<double> fractions;
            auto problems = verifyMap(*map, [&](double f) { fractions.push_back(f); });
            EXPECT_TRUE(problems.empty()) << problems.front();
            ASSERT_EQ(fractions.size(), map->directory().size());
            EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
        }
    }
}

// ---- Layout from the raw bytes ----

TEST(MapFileTest, RawBytesFollowTheFormatDescription)
{
    test::ScratchDir dir;
    const auto path = buildSmallMap(dir, "small.map", 0.0, true);
    const Bytes bytes = test::readFileBytes(path);
    auto map = test::openMap(path);
    ASSERT_TRUE(map);
    const MapHeader& h = map->header();
    auto u32 = [&](std::size_t offset) { return static_cast<std::uint32_t>(test::readLe(bytes, offset, 4)); };
    auto u64 = [&](std::size_t offset) { return test::readLe(bytes, offset, 8); };
    auto f64 = [&](std::size_t offset) { return std::bit_cast<double>(u64(offset)); };
    auto f32 = [&](std::size_t offset) { return std::bit_cast<float>(u32(offset)); };
    const Bytes magic = {0x89, 'T', 'M', 'A', 'P', 0x0d, 0x0a, 0x1a};
    EXPECT_TRUE(std::equal(magic.begin(), magic.end(), bytes.begin()));
    EXPECT_EQ(u32(8), 6u);
    EXPECT_EQ(u32(12), 256u);
    EXPECT_EQ(u32(16), 17u);
    EXPECT_EQ(u32(20), 2u);
    EXPECT_EQ(u32(24), 3u);
    EXPECT_EQ(u32(28), 17u);
    EXPECT_EQ(u32(32), 1u);
    EXPECT_EQ(u32(36), 1u);
    EXPECT_EQ(u32(40), 1u);
    EXPECT_EQ(f64(44), 2.0);
    EXPECT_EQ(f64(52), h.heightOffset);
    EXPECT_EQ(f64(60), 1.0);
    EXPECT_EQ(f64(68), 0.0);
    EXPECT_EQ(u32(100), 65u);
    EXPECT_EQ(u32(104), 65u);
    EXPECT_EQ(u32(116), 21u);
    const std::uint64_t directoryOffset = u64(120);
    EXPECT_EQ(u64(128), 21u * 48);
    EXPECT_EQ(directoryOffset + u64(128), bytes.size());
    EXPECT_EQ(u32(136), zlibCrc(std::span(bytes).subspan(directoryOffset)));
    EXPECT_EQ(std::string(reinterpret_cast<const char*>(&bytes[140])), "generated 65x65");
    EXPECT_EQ(u32(228), 0u) << "version 6: no CRS, no georeference block";
    EXPECT_EQ(u32(232), 0u);
    EXPECT_EQ(u32(236), 0u) << "built without a detail recipe: no block";
    EXPECT_EQ(u32(240), 0u);
    // The roughness block right after the header (no recipe): 4 x 4 leaves, amplitude and exponent each.
    const std::size_t roughnessBytes = 4 + 16 * 8;
    EXPECT_EQ(u32(244), roughnessBytes);
    EXPECT_EQ(u32(248), zlibCrc(std::span(bytes).subspan(256, roughnessBytes)));
    EXPECT_EQ(u32(252), zlibCrc(std::span(bytes).first(252)));
    ASSERT_TRUE(h.roughness.has_value());
    EXPECT_EQ(u32(256), 4u);
    for (std::size_t k = 0; k < 16; ++k) {
        EXPECT_EQ(f32(260 + 8 * k), h.roughness->laws[k].amplitude) << k;
        EXPECT_EQ(f32(264 + 8 * k), h.roughness->laws[k].exponent) << k;
        EXPECT_GT(h.roughness->laws[k].amplitude, 0.0) << k;
    }

    // Directory: sorted by key, each CRC over its payload; the payloads tile the node area, siblings
    // together in quadrant order, the root last.
    struct Raw {
        NodeId id;
        bool children;
        std::uint64_t offset, size;
        float deltaM, deltaC, detailDeltaC;
    };
    std::vector<Raw> raw;
    for (std::size_t k = 0; k < 21; ++k) {
        const std::size_t e = directoryOffset + 48 * k;
        const Raw r{{bytes[e], u32(e + 4), u32(e + 8)},
                    (bytes[e + 1] & 1) != 0,
                    u64(e + 12),
                    std::uint64_t{u32(e + 20)} + u32(e + 24),
                    f32(e + 32),
                    f32(e + 36),
                    f32(e + 44)};
        EXPECT_EQ(u32(e + 28), zlibCrc(std::span(bytes).subspan(r.offset, r.size))) << r.id.toString();
        EXPECT_EQ(test::readLe(bytes, e + 2, 2), 0u);
        EXPECT_EQ(r.detailDeltaC, map->directory()[k].detailDeltaC) << r.id.toString();
        if (!raw.empty()) {
            EXPECT_LT(raw.back().id.key(), r.id.key()) << "directory not sorted by key at entry " << k;
        }
        EXPECT_EQ(r.id, map->directory()[k].id);
        raw.push_back(r);
    }
    std::vector<Raw> byOffset = raw;
    std::sort(byOffset.begin(), byOffset.end(), [](const Raw& a, const Raw& b) { return a.offset < b.offset; });
    EXPECT_EQ(byOffset.front().offset, 256u + roughnessBytes);
    for (std::size_t k = 1; k < byOffset.size(); ++k) {
        EXPECT_EQ(byOffset[k].offset, byOffset[k - 1].offset + byOffset[k - 1].size) << byOffset[k].id.toString();
    }
    EXPECT_EQ(byOffset.back().offset + byOffset.back().size, directoryOffset);
    EXPECT_EQ(byOffset.back().id, NodeId::root());
    // detail_delta_c: the leaves' estimates (here the fake one), nested like delta_c (eq. 3.1).
    for (const Raw& r : raw) {
        if (!r.children) {
            EXPECT_EQ(r.detailDeltaC, test::fakeLeafDetailError(h, r.id, {})) << r.id.toString();
            EXPECT_EQ(r.deltaC, 0.0f) << r.id.toString();
            continue;
        }
        float worst = 0.0f;
        for (int q = 0; q < 4; ++q) {
            auto child = std::find_if(raw.begin(), raw.end(), [&](const Raw& o) { return o.id == r.id.child(q); });
            ASSERT_NE(child, raw.end());
            worst = std::max(worst, child->detailDeltaC);
        }
        // Version 4: at least the children's and the node's own (measured) error; here no displacement range.
        EXPECT_GE(r.detailDeltaC, worst) << r.id.toString();
        EXPECT_GE(r.detailDeltaC, r.deltaC) << r.id.toString();
    }
    for (const Raw& r : raw) {
        if (r.children) {
            auto at = [&](int q) {
                return std::find_if(byOffset.begin(), byOffset.end(),
                                    [&](const Raw& o) { return o.id == r.id.child(q); });
            };
            for (int q = 1; q < 4; ++q) {
                ASSERT_NE(at(q), byOffset.end());
                EXPECT_EQ(at(q) - at(q - 1), 1)
                    << "children of " << r.id.toString() << " are not stored together in order";
            }
        }
    }
}

/// Decodes every node's height stream from the raw file bytes by docs/map-format.md alone.
std::map<std::uint64_t, std::vector<std::uint16_t>> decodeHeightsIndependently(const Bytes& bytes)
{
    const auto n = static_cast<int>(test::readLe(bytes, 16, 4));
    const auto bin = static_cast<std::int64_t>(test::readLe(bytes, 40, 4));
    const auto count = test::readLe(bytes, 116, 4);
    const auto directoryOffset = test::readLe(bytes, 120, 8);
    const int w = n + 4;
    std::map<std::uint64_t, std::vector<std::uint16_t>> windows;
    for (std::uint64_t k = 0; k < count; ++k) {  // sorted by key: parents first
        const std::size_t e = directoryOffset + 48 * k;
        const NodeId id{bytes[e], static_cast<std::uint32_t>(test::readLe(bytes, e + 4, 4)),
                        static_cast<std::uint32_t>(test::readLe(bytes, e + 8, 4))};
        const auto offset = test::readLe(bytes, e + 12, 8);
        const auto heightBytes = test::readLe(bytes, e + 20, 4);
        uLongf rawSize = static_cast<uLongf>(test::readLe(bytes, offset, 4));
        Bytes raw(rawSize);
        if (::uncompress(raw.data(), &rawSize, &bytes[offset + 4], static_cast<uLong>(heightBytes - 4)) != Z_OK ||
            rawSize != raw.size()) {
            ADD_FAILURE() << id.toString() << ": zlib stream does not inflate to its stated size";
            return {};
        }
        const std::int64_t last = (std::int64_t{n} - 1) << id.level;  // the level grid's last index
        const std::int64_t firstX = std::int64_t{id.x} * (n - 1) - 2, firstY = std::int64_t{id.y} * (n - 1) - 2;
        auto inGrid = [&](int c, std::int64_t first) { return first + c >= 0 && first + c <= last; };
        std::vector<std::uint16_t> window(static_cast<std::size_t>(w) * w);
        const std::vector<std::uint16_t>* parent = id.isRoot() ? nullptr : &windows.at(id.parent().key());
        std::size_t pos = 0;
        std::int64_t previous = 0;
        bool rowStart = true;
        for (int y = 0; y < w; ++y) {
            if (!inGrid(y, firstY)) {
                continue;
            }
            rowStart = true;
            for (int x = 0; x < w; ++x) {
                if (!inGrid(x, firstX)) {
                    continue;
                }
                const std::size_t i = static_cast<std::size_t>(y) * w + x;
                std::int64_t prediction = 0;
                if (parent) {
                    prediction = test::referencePrediction(*parent, w, n, id.quadrant(), x, y);
                    if (x % 2 == 0 && y % 2 == 0) {
                        window[i] = static_cast<std::uint16_t>(prediction);  // the parent's sample, not coded
                        continue;
                    }
                } else if (rowStart) {
                    // First column: the sample below; the very first: 0.
                    prediction = inGrid(y - 1, firstY) ? window[i - static_cast<std::size_t>(w)] : 0;
                } else {
                    prediction = previous;
                }
                std::uint32_t v = 0;
                for (int shift = 0;; shift += 7) {
                    const std::uint8_t b = raw.at(pos++);
                    v |= std::uint32_t{b & 0x7fu} << shift;
                    if (!(b & 0x80)) {
                        break;
                    }
                }
                const std::int64_t residual = (v & 1) ? -std::int64_t{(v + 1) / 2} : std::int64_t{v / 2};
                window[i] = static_cast<std::uint16_t>(prediction + residual * bin);
                previous = window[i];
                rowStart = false;
            }
        }
        if (pos != raw.size()) {
            ADD_FAILURE() << id.toString() << ": " << raw.size() - pos << " residual bytes left over";
        }
        // Outside samples: the reflection of the inside ones.
        const std::vector<std::uint16_t> inside = window;
        for (int y = 0; y < w; ++y) {
            for (int x = 0; x < w; ++x) {
                window[static_cast<std::size_t>(y) * w + x] = test::reflectedCode(
                    [&](std::int64_t gx, std::int64_t gy) {
                        return inside[static_cast<std::size_t>(gy - firstY) * w +
                                      static_cast<std::size_t>(gx - firstX)];
                    },
                    last, firstX + x, firstY + y);
            }
        }
        windows[id.key()] = std::move(window);
    }
    return windows;
}

TEST(MapFileTest, HeightStreamsDecodeIndependentlyToTheInput)
{
    test::ScratchDir dir;
    for (double maxError : {0.0, 3.0}) {
        const HeightField field = test::roughField(70, 41, 43, 0, 3000);
        BuildOptions options = test::testOptions(9);
        options.maxError = maxError;
        const auto path = dir / ("m" + std::to_string(maxError) + ".map");
        ASSERT_TRUE(buildMap(field, options, path).ok());
        auto map = test::openMap(path);
        ASSERT_TRUE(map);
        const MapHeader& h = map->header();
        auto windows = decodeHeightsIndependently(test::readFileBytes(path));
        ASSERT_EQ(windows.size(), map->directory().size());
        auto tree = test::decodeTree(*map);
        ASSERT_TRUE(tree.ok());
        const std::int64_t leafSide = std::int64_t{h.chunkSize - 1} << (h.levels - 1);
        for (const auto& [key, window] : windows) {
            const StaticNode* node = tree->find(tree->nodes.at(key).id);
            EXPECT_EQ(window, node->heights) << node->id.toString();
        }
        // The leaves hold the input: exactly, or within the bound.
        for (int j = 0; j < field.height; ++j) {
            for (int i = 0; i < field.width; ++i) {
                const int n1 = static_cast<int>(h.chunkSize) - 1;
                const NodeId leaf{static_cast<int>(h.levels) - 1,
                                  static_cast<std::uint32_t>(std::min<std::int64_t>(i / n1, leafSide / n1 - 1)),
                                  static_cast<std::uint32_t>(std::min<std::int64_t>(j / n1, leafSide / n1 - 1))};
                const auto& window = windows.at(leaf.key());
                const int u = i - static_cast<int>(leaf.x) * n1 + 2, v = j - static_cast<int>(leaf.y) * n1 + 2;
                const double stored = h.heightOf(window[static_cast<std::size_t>(v) * (n1 + 5) + u]);
                EXPECT_LE(std::abs(stored - field.at(i, j)), maxError) << "(" << i << ", " << j << ")";
            }
        }
    }
}

// ---- Damage ----

/// Header and directory of a map, with the payload area, so tests can change entries and reassemble.
struct MapParts {
    MapHeader header;
    std::vector<DirectoryEntry> entries;
    Bytes body;  ///< bytes [0, directoryOffset): header and payloads
};

MapParts readParts(const std::filesystem::path& path)
{
    MapParts parts;
    auto map = test::openMap(path);
    if (!map) {
        return parts;
    }
    parts.header = map->header();
    parts.entries.assign(map->directory().begin(), map->directory().end());
    Bytes bytes = test::readFileBytes(path);
    parts.body.assign(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(parts.header.directoryOffset));
    return parts;
}

/// A consistent file from the parts: directory re-encoded, its size and CRC and the header CRC updated.
Bytes assemble(MapParts parts)
{
    auto directory = encodeDirectory(parts.entries, parts.header.version);
    parts.header.nodeCount = static_cast<std::uint32_t>(parts.entries.size());
    parts.header.directoryOffset = parts.body.size();
    parts.header.directoryBytes = directory.size();
    parts.header.directoryCrc = crc32Of(directory);
    auto header = encodeHeader(parts.header);
    Bytes bytes = parts.body;
    std::copy(header.begin(), header.end(), bytes.begin());
    bytes.insert(bytes.end(), directory.begin(), directory.end());
    return bytes;
}

TEST(MapFileTest, ReassemblingUnchangedPartsGivesTheSameFile)
{
    // Guards the mutation tests below: their only change is the one they make.
    test::ScratchDir dir;
    const auto path = buildSmallMap(dir);
    EXPECT_TRUE(assemble(readParts(path)) == test::readFileBytes(path));
}

TEST(MapFileTest, CorruptPayloadByteIsReportedForItsNode)
{
    test::ScratchDir dir;
    const auto path = buildSmallMap(dir);
    const MapParts parts = readParts(path);
    const NodeId victim{2, 1, 2};
    const auto entry =
        std::find_if(parts.entries.begin(), parts.entries.end(), [&](const auto& e) { return e.id == victim; });
    ASSERT_NE(entry, parts.entries.end());
    struct Case {
        const char* what;
        std::uint64_t offset;
        bool fixCrc;  ///< also store the damaged payload's CRC, so the stream decoders must notice
    };
    const Case cases[] = {
        {"first height byte", entry->offset, false},
        {"middle of the height stream", entry->offset + entry->heightBytes / 2, false},
        {"middle of the texture stream", entry->offset + entry->heightBytes + entry->textureBytes / 2, false},
        {"last payload byte", entry->offset + entry->payloadBytes() - 1, false},
        {"raw size of the height stream, CRC fixed", entry->offset + 1, true},
        {"middle of the height stream, CRC fixed", entry->offset + entry->heightBytes / 2, true},
        {"middle of the texture stream, CRC fixed", entry->offset + entry->heightBytes + entry->textureBytes / 2, true},
    };
    for (const Case& c : cases) {
        MapParts damaged = parts;
        damaged.body[c.offset] ^= 0x5a;
        if (c.fixCrc) {
            for (auto& e : damaged.entries) {
                if (e.id == victim) {
                    e.crc = crc32Of(std::span(damaged.body).subspan(e.offset, e.payloadBytes()));
                }
            }
        }
        const auto bad = dir / "damaged.map";
        test::writeFileBytes(bad, assemble(damaged));
        for (ReaderKind kind : kReaders) {
            SCOPED_TRACE(std::string(c.what) + ", " + readerName(kind));
            auto map = test::openMap(bad, kind);
            ASSERT_TRUE(map) << "a payload byte must not stop the map from opening";
            auto parent = map->loadPath(victim.parent());
            ASSERT_TRUE(parent.ok()) << parent.error().message;
            auto node = map->loadNode(victim, parent->heights);
            ASSERT_FALSE(node.ok());
            EXPECT_TRUE(mentions(node.error().message, bad.string())) << node.error().message;
            EXPECT_TRUE(mentions(node.error().message, "2/1/2")) << node.error().message;
            auto sibling = map->loadNode({2, 0, 2}, parent->heights);
            EXPECT_TRUE(sibling.ok()) << "damage spread to a sibling: " << sibling.error().message;
            auto problems = verifyMap(*map);
            ASSERT_FALSE(problems.empty());
            EXPECT_TRUE(std::any_of(problems.begin(), problems.end(), [](const std::string& p) {
                return mentions(p, "2/1/2");
            })) << problems.front();
        }
    }
}

TEST(MapFileTest, TruncatedOrExtendedFilesAreErrorsNamingTheFile)
{
    test::ScratchDir dir;
    const auto path = buildSmallMap(dir);
    const Bytes bytes = test::readFileBytes(path);
    const std::uint64_t directoryOffset = test::readLe(bytes, 120, 8);
    const std::size_t lengths[] = {0, 1, 8, 100, 255, 256, 1000, directoryOffset, bytes.size() - 48, bytes.size() - 1};
    for (std::size_t length : lengths) {
        const auto bad = dir / "truncated.map";
        test::writeFileBytes(bad, std::span(bytes).first(length));
        for (ReaderKind kind : kReaders) {
            auto map = MapFile::open(bad, kind);
            ASSERT_FALSE(map.ok()) << length << " bytes, " << readerName(kind);
            EXPECT_TRUE(mentions(map.error().message, bad.string())) << map.error().message;
        }
    }
    for (std::size_t extra : {1u, 48u}) {
        Bytes longer = bytes;
        longer.resize(bytes.size() + extra, 0);
        const auto bad = dir / "extended.map";
        test::writeFileBytes(bad, longer);
        auto map = MapFile::open(bad, ReaderKind::Stream);
        ASSERT_FALSE(map.ok()) << extra << " extra bytes";
        EXPECT_TRUE(mentions(map.error().message, bad.string())) << map.error().message;
    }
}

TEST(MapFileTest, EmptyMissingAndNonRegularFilesAreErrors)
{
    test::ScratchDir dir;
    test::writeFileBytes(dir / "empty.map", {});
    std::filesystem::create_directory(dir / "folder.map");
    struct Case {
        std::filesystem::path path;
        const char* mentions;
    };
    const Case cases[] = {
        {dir / "empty.map", "0 bytes"},
        {dir / "missing.map", "cannot open"},
        {dir / "folder.map", "not a regular file"},
    };
    for (const Case& c : cases) {
        for (ReaderKind kind : kReaders) {
            auto map = MapFile::open(c.path, kind);
            ASSERT_FALSE(map.ok()) << c.path;
            EXPECT_TRUE(mentions(map.error().message, c.path.string())) << map.error().message;
            EXPECT_TRUE(mentions(map.error().message, c.mentions)) << map.error().message;
        }
    }
}

TEST(MapFileTest, BadHeaderFieldsAreErrors)
{
    test::ScratchDir dir;
    const auto path = buildSmallMap(dir);
    const Bytes good = test::readFileBytes(path);
    struct Case {
        const char* what;
        std::size_t offset;
        int size;
        std::uint64_t value;
        bool fixCrc;
        const char* mentions;
    };
    const auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
    const Case cases[] = {
        {"magic", 1, 1, 'X', false, "not a terrain map"},
        {"version 7", 8, 4, 7, true, "version 7"},
        {"georeference block too short", 228, 4, 5, true, "georeference block"},
        {"roughness block of the wrong size", 244, 4, 140, true, "roughness block of 140 bytes"},
        {"roughness block checksum", 248, 4, 0x12345678, true, "roughness block checksum"},
        {"detail recipe over 64 KiB", 236, 4, 70000, true, "detail recipe of 70000 bytes"},
        {"detail recipe that is not there", 236, 4, 40, true, "detail recipe"},
        {"version 0", 8, 4, 0, true, "version 0"},
        {"header checksum", 150, 1, 'x', false, "checksum"},
        {"header size", 12, 4, 255, true, "header size 255"},
        {"chunk size 64", 16, 4, 64, true, "chunk size 64"},
        {"chunk size 2049", 16, 4, 2049, true, "chunk size 2049"},
        {"border 3", 20, 4, 3, true, "border 3"},
        {"no levels", 24, 4, 0, true, "level count 0"},
        {"25 levels", 24, 4, 25, true, "level count 25"},
        {"texture size 100", 28, 4, 100, true, "texture size 100"},
        {"height coding 3", 32, 4, 3, true, "height coding 3"},
        {"texture coding 7", 36, 4, 7, true, "texture coding 7"},
        {"even quantizer bin", 40, 4, 4, true, "quantizer bin 4"},
        {"zero quantizer bin", 40, 4, 0, true, "quantizer bin 0"},
        {"zero spacing", 44, 8, bits(0.0), true, "spacing"},
        {"NaN spacing", 44, 8, bits(std::nan("")), true, "spacing"},
        {"negative height step", 60, 8, bits(-1.0), true, "height step"},
        {"infinite origin", 76, 8, bits(std::numeric_limits<double>::infinity()), true, "origin"},
        {"empty valid region", 100, 4, 0, true, "valid region"},
        {"valid region wider than the grid", 100, 4, 66, true, "valid region"},
        {"valid region shifted out", 92, 4, 1, true, "valid region"},
        {"no nodes", 116, 4, 0, true, "directory"},
        {"directory inside the header", 120, 8, 8, true, "directory"},
        {"directory size not 48 per node", 128, 8, 21 * 48 - 1, true, "directory"},
        {"directory past the end", 120, 8, 1u << 30, true, "directory"},
        {"directory checksum", 136, 4, 0x12345678, true, "directory checksum"},
    };
    for (const Case& c : cases) {
        Bytes bad = good;
        test::writeLe(bad, c.offset, c.value, c.size);
        if (c.fixCrc) {
            test::writeLe(bad, 252, zlibCrc(std::span(bad).first(252)), 4);
        }
        const auto badPath = dir / "bad-header.map";
        test::writeFileBytes(badPath, bad);
        for (ReaderKind kind : kReaders) {
            auto map = MapFile::open(badPath, kind);
            ASSERT_FALSE(map.ok()) << c.what << " was accepted (" << readerName(kind) << ")";
            EXPECT_TRUE(mentions(map.error().message, badPath.string())) << map.error().message;
            EXPECT_TRUE(mentions(map.error().message, c.mentions))
                << c.what << ": '" << map.error().message << "' does not mention '" << c.mentions << "'";
        }
    }
}

TEST(MapFileTest, OversizedHeaderFieldsAreRefusedBeforeAllocating)
{
    // The largest values the header's fields can hold, with a valid header checksum, each opened (and its
    // root loaded) in a child that may allocate at most 1 GiB more (RLIMIT_AS): refused with the file and
    // the value named, or, for the largest sizes the format allows, a clean error from the node's data.
    test::ScratchDir dir;
    const Bytes good = test::readFileBytes(buildSmallMap(dir));
    const std::uint64_t fileSize = good.size();
    const std::uint64_t allNodes = 0xffffffffull;
    struct Field {
        std::size_t offset;
        int size;
        std::uint64_t value;
    };
    struct Case {
        const char* what;
        std::vector<Field> fields;
        const char* mentions;
    };
    const Case cases[] = {
        {"chunk size 2^31 + 1", {{16, 4, (1ull << 31) + 1}}, "chunk size 2147483649"},
        {"2^32 - 1 levels", {{24, 4, 0xffffffff}}, "level count 4294967295"},
        {"texture size 2^31 + 1", {{28, 4, (1ull << 31) + 1}}, "texture size 2147483649"},
        {"2^32 - 1 nodes, directory past the end", {{116, 4, allNodes}, {128, 8, allNodes * 48}}, "4294967295 nodes"},
        // offset + size wraps around 2^64 to the file's size: would read a 192 GiB directory.
        {"2^32 - 1 nodes, directory offset wrapping to the file's end",
         {{116, 4, allNodes}, {128, 8, allNodes * 48}, {120, 8, fileSize - allNodes * 48}},
         "4294967295 nodes"},
        {"directory of 2^63 bytes", {{128, 8, 1ull << 63}}, "9223372036854775808 bytes"},
        // Accepted by the header: the largest chunks, levels and textures the format allows.
        {"roughness block of 2^32 - 1 bytes", {{244, 4, 0xffffffff}}, "roughness block of 4294967295 bytes"},
        // Accepted by the header: the largest chunks, levels and textures the format allows (a map of 24
        // levels has no roughness block).
        {"chunk 1025, 24 levels, texture 4097",
         {{16, 4, 1025}, {24, 4, 24}, {28, 4, 4097}, {244, 4, 0}, {248, 4, 0}},
         "node 0/0/0"},
    };
    std::string checked;
    for (const Case& c : cases) {
        Bytes bad = good;
        for (const Field& f : c.fields) {
            test::writeLe(bad, f.offset, f.value, f.size);
        }
        test::writeLe(bad, 252, zlibCrc(std::span(bad).first(252)), 4);
        const auto path = dir / "oversized.map";
        test::writeFileBytes(path, bad);
        for (ReaderKind kind : kReaders) {
            SCOPED_TRACE(std::string(c.what) + ", " + readerName(kind));
            const auto run = test::runWithMemoryLimit([&] {
                auto map = MapFile::open(path, kind);
                if (!map.ok()) {
                    return "refused: " + map.error().message;
                }
                auto root = (*map)->loadNode(NodeId::root(), {});
                return root.ok() ? std::string("accepted") : "refused: " + root.error().message;
            });
            ASSERT_EQ(run.outcome, test::LimitedRun::Outcome::Returned) << test::describe(run);
            EXPECT_EQ(run.text.rfind("refused: " + path.string() + ": ", 0), 0u) << test::describe(run);
            EXPECT_TRUE(mentions(run.text, c.mentions)) << run.text << "\ndoes not mention " << c.mentions;
            if (kind == ReaderKind::Stream) {
                checked += std::string(c.what) + ": " + run.text.substr(run.text.find(": ", 9) + 2) + "; ";
            }
        }
    }
    ::testing::Test::RecordProperty("checked", checked);
}

TEST(MapFileTest, ADirectoryOfMoreNodesThanTheTreeOrMemoryHoldsIsRefusedBeforeAllocating)
{
    // 2^31 nodes in a (sparse) file large enough to hold their directory: with the map's own levels more than
    // the tree has; with 24 levels and 2 GiB of node area, more than memory holds. Both ended in bad_alloc.
    test::ScratchDir dir;
    const Bytes good = test::readFileBytes(buildSmallMap(dir));
    const std::uint64_t nodes = 1ull << 31;
    const std::uint64_t nodeArea = test::readLe(good, 120, 8);  // the directory offset the map has
    struct Case {
        const char* what;
        std::uint32_t levels;  ///< 0: the map's own
        std::uint64_t directoryOffset;
        const char* mentions;
    };
    const Case cases[] = {
        {"2^31 nodes in the map's levels", 0, nodeArea, "header claims 2147483648 nodes"},
        {"2^31 nodes in 24 levels", 24, nodeArea + nodes, "the directory of 2147483648 nodes"},
    };
    for (const Case& c : cases) {
        Bytes bad = good;
        test::writeLe(bad, 116, nodes, 4);
        test::writeLe(bad, 128, nodes * 48, 8);
        test::writeLe(bad, 120, c.directoryOffset, 8);
        if (c.levels > 0) {
            test::writeLe(bad, 24, c.levels, 4);
            test::writeLe(bad, 244, 0, 4);  // a map of 24 levels has no roughness block
            test::writeLe(bad, 248, 0, 4);
        }
        test::writeLe(bad, 252, zlibCrc(std::span(bad).first(252)), 4);
        const auto path = dir / "claims.map";
        test::writeFileBytes(path, bad);
        std::filesystem::resize_file(path, c.directoryOffset + nodes * 48);  // sparse: no disk used
        for (ReaderKind kind : kReaders) {
            SCOPED_TRACE(std::string(c.what) + ", " + readerName(kind));
            const auto run = test::runWithMemoryLimit([&] {
                auto map = MapFile::open(path, kind);
                return map.ok() ? std::string("accepted") : "refused: " + map.error().message;
            });
            ASSERT_EQ(run.outcome, test::LimitedRun::Outcome::Returned) << test::describe(run);
            EXPECT_EQ(run.text.rfind("refused: " + path.string() + ": ", 0), 0u) << test::describe(run);
            EXPECT_TRUE(mentions(run.text, c.mentions)) << run.text << "\ndoes not mention " << c.mentions;
        }
        std::filesystem::remove(path);
    }
}

TEST(MapFileTest, DamagedDirectoryBytesAreAChecksumError)
{
    test::ScratchDir dir;
    const auto path = buildSmallMap(dir);
    Bytes bytes = test::readFileBytes(path);
    const std::uint64_t directoryOffset = test::readLe(bytes, 120, 8);
    for (std::uint64_t at : {directoryOffset, directoryOffset + 12, directoryOffset + 48 * 7 + 33, bytes.size() - 1}) {
        Bytes bad = bytes;
        bad[at] ^= 0x10;
        test::writeFileBytes(dir / "bad.map", bad);
        auto map = MapFile::open(dir / "bad.map", ReaderKind::Stream);
        ASSERT_FALSE(map.ok()) << "byte " << at;
        EXPECT_TRUE(mentions(map.error().message, (dir / "bad.map").string())) << map.error().message;
        EXPECT_TRUE(mentions(map.error().message, "directory checksum")) << map.error().message;
    }
}

TEST(MapFileTest, InconsistentDirectoriesAreErrorsNamingTheNode)
{
    test::ScratchDir dir;
    const auto path = buildSmallMap(dir);
    const MapParts parts = readParts(path);
    ASSERT_EQ(parts.entries.size(), 21u);
    const auto inner = std::find_if(parts.entries.begin(), parts.entries.end(), [](const auto& e) {
        return e.id == NodeId{1, 0, 1};
    });
    ASSERT_GT(inner->deltaC, 0.0f) << "the detail_delta_c below delta_c case needs delta_c > 0";
    auto at = [](std::vector<DirectoryEntry>& entries, NodeId id) -> DirectoryEntry& {
        return *std::find_if(entries.begin(), entries.end(), [&](const auto& e) { return e.id == id; });
    };
    struct Case {
        const char* what;
        std::function<void(std::vector<DirectoryEntry>&)> change;
        const char* mentions;
    };
    const std::uint64_t nodeAreaEnd = parts.header.directoryOffset;
    const Case cases[] = {
        {"payload starting at the directory",
         [&](auto& e) {
             at(e, {2, 1, 1}).offset = nodeAreaEnd;
         },
         "2/1/1"},
        {"payload inside the header",
         [&](auto& e) {
             at(e, {2, 1, 1}).offset = 10;
         },
         "2/1/1"},
        {"payload running into the directory",
         [&](auto& e) {
             at(e, {2, 1, 1}).textureBytes = 1u << 20;
         },
         "2/1/1"},
        {"payload offset that wraps around 2^64",
         [&](auto& e) {
             at(e, {2, 1, 1}).offset = std::numeric_limits<std::uint64_t>::max() - 100;
         },
         "2/1/1"},
        {"payload far beyond the file",
         [&](auto& e) {
             at(e, {2, 1, 1}).offset = std::uint64_t{1} << 40;
         },
         "2/1/1"},
        {"empty height stream",
         [&](auto& e) {
             at(e, {2, 1, 1}).heightBytes = 0;
         },
         "2/1/1"},
        {"level beyond the map",
         [&](auto& e) {
             at(e, {2, 1, 1}).id = {3, 1, 1};
         },
         "3/1/1"},
        {"position outside its level",
         [&](auto& e) {
             at(e, {2, 1, 1}).id = {2, 4, 1};
         },
         "2/4/1"},
        {"min code above max code",
         [&](auto& e) {
             std::swap(at(e, {1, 0, 1}).minCode, at(e, {1, 0, 1}).maxCode);
         },
         "1/0/1"},
        {"delta_c below delta_m",
         [&](auto& e) {
             at(e, {1, 0, 1}).deltaC = at(e, {1, 0, 1}).deltaM - 1.0f;
         },
         "1/0/1"},
        {"NaN delta_m",
         [&](auto& e) {
             at(e, {1, 0, 1}).deltaM = std::nanf("");
         },
         "1/0/1"},
        {"negative delta_m",
         [&](auto& e) {
             at(e, {1, 0, 1}).deltaM = -1.0f;
         },
         "1/0/1"},
        {"deepest-level node with children",
         [&](auto& e) {
             at(e, {2, 3, 3}).hasChildren = true;
         },
         "2/3/3"},
        {"negative detail_delta_c",
         [&](auto& e) {
             at(e, {2, 1, 1}).detailDeltaC = -0.5f;
         },
         "2/1/1"},
        {"NaN detail_delta_c",
         [&](auto& e) {
             at(e, {1, 0, 1}).detailDeltaC = std::nanf("");
         },
         "1/0/1"},
        {"infinite detail_delta_c",
         [&](auto& e) {
             at(e, {1, 0, 1}).detailDeltaC = std::numeric_limits<float>::infinity();
         },
         "1/0/1"},
        {"detail_delta_c below delta_c",
         [&](auto& e) {
             at(e, {1, 0, 1}).detailDeltaC = at(e, {1, 0, 1}).deltaC * 0.5f;
         },
         "1/0/1"},
        {"root without children flag", [&](auto& e) { at(e, NodeId::root()).hasChildren = false; }, "has no parent"},
        {"missing child",
         [&](auto& e) {
             e.erase(std::find_if(e.begin(), e.end(), [](const auto& x) { return x.id == NodeId{2, 1, 1}; }));
         },
         "2/1/1"},
        {"missing root", [&](auto& e) { e.erase(e.begin()); }, "root"},
        {"node listed twice",
         [&](auto& e) {
             at(e, {2, 1, 1}).id = {2, 0, 1};
         },
         "2/"},
    };
    for (const Case& c : cases) {
        MapParts damaged = parts;
        c.change(damaged.entries);
        const auto bad = dir / "bad-directory.map";
        test::writeFileBytes(bad, assemble(damaged));
        for (ReaderKind kind : kReaders) {
            auto map = MapFile::open(bad, kind);
            ASSERT_FALSE(map.ok()) << c.what << " was accepted (" << readerName(kind) << ")";
            EXPECT_TRUE(mentions(map.error().message, bad.string())) << map.error().message;
            EXPECT_TRUE(mentions(map.error().message, c.mentions))
                << c.what << ": '" << map.error().message << "' does not mention '" << c.mentions << "'";
        }
    }
}

// ---- Detail errors (version 2) and version 1 files ----

TEST(MapFileTest, DetailDeltaCRoundTripsThroughTheDirectory)
{
    test::ScratchDir dir;
    const MapParts parts = readParts(buildSmallMap(dir));
    struct Case {
        const char* what;
        float above;  ///< detailDeltaC = deltaC + above
    };
    const Case cases[] = {
        {"no detail (equal to delta_c)", 0.0f},
        {"the smallest step above", std::numeric_limits<float>::denorm_min()},
        {"centimetres", 0.01f},
        {"a fraction", 1.0f / 3.0f},
        {"kilometres", 1234.5f},
        {"the largest float", std::numeric_limits<float>::max()},
    };
    for (const Case& c : cases) {
        MapParts changed = parts;
        for (std::size_t k = 0; k < changed.entries.size(); ++k) {
            // Vary by node as well, so entries cannot be swapped unnoticed.
            auto& e = changed.entries[k];
            const bool largest = c.above == std::numeric_limits<float>::max();
            e.detailDeltaC = largest ? c.above : e.deltaC + c.above * static_cast<float>(k + 1);
        }
        test::writeFileBytes(dir / "detail.map", assemble(changed));
        for (ReaderKind kind : kReaders) {
            auto map = test::openMap(dir / "detail.map", kind);
            ASSERT_TRUE(map) << c.what;
            EXPECT_TRUE(map->header().hasDetailErrors());
            ASSERT_EQ(map->directory().size(), changed.entries.size());
            for (std::size_t k = 0; k < changed.entries.size(); ++k) {
                const DirectoryEntry& read = map->directory()[k];
                EXPECT_EQ(std::bit_cast<std::uint32_t>(read.detailDeltaC),
                          std::bit_cast<std::uint32_t>(changed.entries[k].detailDeltaC))
                    << c.what << ", " << read.id.toString() << ", " << readerName(kind);
                EXPECT_EQ(read.deltaC, changed.entries[k].deltaC) << c.what;
                EXPECT_EQ(read.minCode, changed.entries[k].minCode) << c.what;
            }
        }
    }
}

TEST(MapFileTest, Version1MapsStillOpenDecodeAndVerify)
{
    // A version 1 file written by hand from the format description: version 1 in the header, the last 4
    // bytes of every directory entry zero, both checksums recomputed (from a map without a roughness block,
    // which version 1 does not have).
    test::ScratchDir dir;
    const auto path = buildSmallMap(dir, "v2.map", 0.0, true, false);
    Bytes bytes = test::readFileBytes(path);
    const std::uint64_t directoryOffset = test::readLe(bytes, 120, 8);
    const std::uint64_t count = test::readLe(bytes, 116, 4);
    test::writeLe(bytes, 8, 1, 4);
    // Version 1 errors follow eq. 3.1 (max of the children's plus delta_m), not version 4's measured ones.
    const MapParts parts = readParts(path);
    std::map<std::uint64_t, float> summed;
    std::vector<DirectoryEntry> byLevel = parts.entries;
    std::sort(byLevel.begin(), byLevel.end(), [](const auto& a, const auto& b) { return a.id.level > b.id.level; });
    for (const DirectoryEntry& e : byLevel) {
        float worst = 0.0f;
        if (e.hasChildren) {
            for (int q = 0; q < 4; ++q) {
                worst = std::max(worst, summed.at(e.id.child(q).key()));
            }
        }
        summed[e.id.key()] = e.hasChildren ? worst + e.deltaM : 0.0f;
    }
    ASSERT_EQ(parts.entries.size(), count);
    for (std::uint64_t k = 0; k < count; ++k) {
        test::writeLe(bytes, directoryOffset + 48 * k + 36,
                      std::bit_cast<std::uint32_t>(summed.at(parts.entries[k].id.key())), 4);
        test::writeLe(bytes, directoryOffset + 48 * k + 44, 0, 4);
    }
    test::writeLe(bytes, 136, zlibCrc(std::span(bytes).subspan(directoryOffset)), 4);
    test::writeLe(bytes, 252, zlibCrc(std::span(bytes).first(252)), 4);
    test::writeFileBytes(dir / "v1.map", bytes);

    // The encoder writes the same bytes for a version 1 header.
    MapParts v1 = readParts(path);
    v1.header.version = 1;
    for (DirectoryEntry& e : v1.entries) {
        e.deltaC = summed.at(e.id.key());
    }
    EXPECT_TRUE(assemble(v1) == bytes);

    auto current = test::openMap(path);
    ASSERT_TRUE(current);
    for (ReaderKind kind : kReaders) {
        SCOPED_TRACE(readerName(kind));
        auto map = test::openMap(dir / "v1.map", kind);
        ASSERT_TRUE(map);
        EXPECT_EQ(map->header().version, 1u);
        EXPECT_FALSE(map->header().hasDetailErrors());
        ASSERT_EQ(map->directory().size(), current->directory().size());
        for (std::size_t k = 0; k < map->directory().size(); ++k) {
            const DirectoryEntry& old = map->directory()[k];
            const DirectoryEntry& now = current->directory()[k];
            EXPECT_EQ(old.detailDeltaC, 0.0f) << old.id.toString();
            EXPECT_EQ(old.id, now.id);
            EXPECT_EQ(old.deltaM, now.deltaM);
            EXPECT_EQ(old.deltaC, summed.at(now.id.key()));
            EXPECT_GE(old.deltaC, now.deltaC) << "eq. 3.1 bounds the measured error from above";
            EXPECT_EQ(old.minCode, now.minCode);
            EXPECT_EQ(old.maxCode, now.maxCode);
            EXPECT_EQ(old.crc, now.crc);
        }
        auto tree = test::decodeTree(*map);
        EXPECT_TRUE(tree.ok()) << tree.error().message;
        auto problems = verifyMap(*map);
        EXPECT_TRUE(problems.empty()) << problems.front();
    }
}

TEST(MapFileTest, VerifyCatchesWrongDetailErrors)
{
    // Each change decodes (every detail_delta_c stays finite and >= delta_c) but breaks the nesting: version 4
    // requires at least the children's and the node's own error plus the largest leaf detail error below.
    test::ScratchDir dir;
    const MapParts parts = readParts(buildSmallMap(dir, "small.map", 0.0, true));
    auto at = [](std::vector<DirectoryEntry>& entries, NodeId id) -> DirectoryEntry& {
        return *std::find_if(entries.begin(), entries.end(), [&](const auto& e) { return e.id == id; });
    };
    struct Case {
        const char* what;
        std::function<void(std::vector<DirectoryEntry>&)> change;
        const char* mentions;  ///< the node whose nesting no longer holds
    };
    const Case cases[] = {
        {"inner node's below its measured error plus the leaves' below",
         [&](auto& e) {
             at(e, {1, 0, 1}).detailDeltaC -= 0.5f;
         },
         "1/0/1"},
        {"inner node's only delta_c",
         [&](auto& e) {
             at(e, {1, 1, 0}).detailDeltaC = at(e, {1, 1, 0}).deltaC;
         },
         "1/1/0"},
        {"leaf's raised above its siblings",
         [&](auto& e) {
             at(e, {2, 1, 1}).detailDeltaC += 5.0f;
         },
         "1/0/0"},
        {"root's too small", [&](auto& e) { at(e, NodeId::root()).detailDeltaC -= 0.125f; }, "0/0/0"},
    };
    for (const Case& c : cases) {
        MapParts damaged = parts;
        c.change(damaged.entries);
        test::writeFileBytes(dir / "wrong.map", assemble(damaged));
        auto map = test::openMap(dir / "wrong.map");
        ASSERT_TRUE(map) << c.what;
        auto problems = verifyMap(*map);
        ASSERT_FALSE(problems.empty()) << c.what << " was not noticed";
        EXPECT_TRUE(std::any_of(problems.begin(), problems.end(),
                                [&](const std::string& p) {
                                    return mentions(p, c.mentions) && mentions(p, "detail_delta_c") &&
                                           mentions(p, (dir / "wrong.map").string());
                                }))
            << c.what << ": " << problems.front();
    }
    // The untouched map verifies.
    test::writeFileBytes(dir / "right.map", assemble(parts));
    auto map = test::openMap(dir / "right.map");
    ASSERT_TRUE(map);
    auto problems = verifyMap(*map);
    EXPECT_TRUE(problems.empty()) << problems.front();
}

}  // namespace
}  // namespace terrain

namespace terrain {
namespace {

// ---- The detail recipe (version 3) ----

TEST(MapFileTest, DetailRecipeRoundTripsAndIsChecked)
{
    test::ScratchDir dir;
    DetailRecipe recipe;
    recipe.scheme = "catmull-clark";
    recipe.omega = 0.75;
    recipe.materials = {{"grass", 0x0123456789abcdefull}, {"rock", 0xfedcba9876543210ull}, {"", 7}};
    recipe.roughness = true;
    BuildOptions options = test::testOptions(17);
    options.leafDetailError = test::fakeLeafDetailError;
    options.detailRecipe = recipe;
    ASSERT_TRUE(buildMap(test::hillyField(65, 65, 41), options, dir / "recipe.map").ok());
    for (ReaderKind kind : kReaders) {
        auto map = test::openMap(dir / "recipe.map", kind);
        ASSERT_TRUE(map) << readerName(kind);
        EXPECT_EQ(map->header().version, kMapVersion);
        ASSERT_TRUE(map->header().detailRecipe.has_value());
        EXPECT_EQ(*map->header().detailRecipe, recipe) << readerName(kind);
        EXPECT_TRUE(verifyMap(*map).empty());
        EXPECT_TRUE(test::decodeTree(*map).ok()) << "payloads start after the recipe block";
    }
    // Written from the format description: the block's size and CRC at 236 and 240, the block at 256.
    Bytes bytes = test::readFileBytes(dir / "recipe.map");
    const std::uint64_t size = test::readLe(bytes, 236, 4);
    ASSERT_EQ(size, 1 + 13 + 8 + 4 + (1 + 5 + 8) + (1 + 4 + 8) + (1 + 0 + 8) + 1);
    EXPECT_EQ(bytes[256 + size - 1], 1) << "version 5: the roughness flag ends the block";
    EXPECT_EQ(test::readLe(bytes, 240, 4), zlibCrc(std::span(bytes).subspan(256, size)));
    EXPECT_EQ(std::string(bytes.begin() + 257, bytes.begin() + 270), "catmull-clark");

    // A flipped bit in the block, or a size that does not fit the fields, is refused naming the file.
    Bytes flipped = bytes;
    flipped[256 + 20] ^= 1;
    test::writeFileBytes(dir / "flipped.map", flipped);
    Bytes resized = bytes;
    test::writeLe(resized, 236, size - 1, 4);
    test::writeLe(resized, 240, zlibCrc(std::span(resized).subspan(256, size - 1)), 4);
    test::writeLe(resized, 252, zlibCrc(std::span(resized).first(252)), 4);
    test::writeFileBytes(dir / "resized.map", resized);
    for (const char* name : {"flipped.map", "resized.map"}) {
        auto map = MapFile::open(dir / name, ReaderKind::Stream);
        ASSERT_FALSE(map.ok()) << name;
        EXPECT_TRUE(mentions(map.error().message, name)) << map.error().message;
        EXPECT_TRUE(mentions(map.error().message, "detail recipe")) << map.error().message;
    }

    // Version 2 (no recipe fields: bytes 236..243 zero) still opens, without a recipe.
    const auto plain = buildSmallMap(dir, "plain.map", 0.0, true, false);
    Bytes v2 = test::readFileBytes(plain);
    ASSERT_EQ(test::readLe(v2, 236, 4), 0u) << "a map built without a recipe has no block";
    test::writeLe(v2, 8, 2, 4);
    test::writeLe(v2, 252, zlibCrc(std::span(v2).first(252)), 4);
    test::writeFileBytes(dir / "v2.map", v2);
    auto old = test::openMap(dir / "v2.map");
    ASSERT_TRUE(old);
    EXPECT_EQ(old->header().version, 2u);
    EXPECT_TRUE(old->header().hasDetailErrors());
    EXPECT_FALSE(old->header().detailRecipe.has_value());
}

TEST(MapFileTest, DetailRecipesCompareBySynthesis)
{
    DetailRecipe a{"kobbelt", 1.0, {{"grass", 1}}};
    EXPECT_TRUE(a.sameSynthesis(a));
    EXPECT_FALSE(a.sameSynthesis({"kobbelt", 0.5, {{"grass", 1}}})) << "omega matters for kobbelt";
    EXPECT_FALSE(a.sameSynthesis({"kobbelt", 1.0, {{"grass", 2}}})) << "an edited material file";
    EXPECT_FALSE(a.sameSynthesis({"kobbelt", 1.0, {}}));
    EXPECT_FALSE(a.sameSynthesis({"kobbelt", 1.0, {{"grass", 1}}, true})) << "roughness continued or not";
    EXPECT_FALSE(a.sameSynthesis({"bilinear", 1.0, {{"grass", 1}}}));
    DetailRecipe b{"bilinear", 1.0, {{"rock", 3}, {"grass", 1}}};
    EXPECT_TRUE(b.sameSynthesis({"bilinear", 0.25, {{"rock", 3}, {"grass", 1}}})) << "omega is not bilinear's";
    EXPECT_FALSE(b.sameSynthesis({"bilinear", 1.0, {{"grass", 1}, {"rock", 3}}})) << "order: the first is the ground";
    EXPECT_EQ(a.describe(), "kobbelt omega 1, materials grass (hash 0000000000000001)");
}

}  // namespace
}  // namespace terrain
