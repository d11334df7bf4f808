// A damaged .map under the reader and the runtime core, on a real terrain (tests/data, Jacksboro fault):
// flipped bits in one node's payload, and a file truncated while it is open (with the memory-mapped
// reader a truncated file would otherwise kill the viewer with SIGBUS). Each is an error naming the file
// and the node, for both readers; nothing else is affected; the streamer reports a failed group once,
// never makes it resident, and keeps drawing its parent, so the selection still covers the terrain.
#include "MapTestSupport.h"

#include "core/MappedCopy.h"
#include "heightfield/HeightFieldIo.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "quadtree/MapVerifier.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <thread>

namespace terrain {
namespace {

using test::Bytes;

constexpr ReaderKind kReaders[] = {ReaderKind::Stream, ReaderKind::MemoryMapped};
const char* readerName(ReaderKind kind)
{
    return kind == ReaderKind::Stream ? "stream" : "memory_mapped";
}

bool mentions(const std::string& text, const std::string& what)
{
    return text.find(what) != std::string::npos;
}

/// The Jacksboro DEM (403 x 344 samples, 30 m) as a map of 17-sample chunks: 6 levels, grid 513^2.
class MapFaultTest : public ::testing::Test {
protected:
    static void SetUpTestSuite()
    {
        sDir = new test::ScratchDir;
        auto field = readHeightField(test::testDataPath("jacksboro_fault_dem_403x344.png"));
        ASSERT_TRUE(field.ok()) << field.error().message;
        BuildOptions options = test::testOptions(17);
        options.spacing = 30.0;
        auto built = buildMap(std::move(field.value()), options, *sDir / "jacksboro.map");
        ASSERT_TRUE(built.ok()) << built.error().message;
        sBytes = new Bytes(test::readFileBytes(*sDir / "jacksboro.map"));
        auto map = MapFile::open(*sDir / "jacksboro.map", ReaderKind::Stream);
        ASSERT_TRUE(map.ok()) << map.error().message;
        auto tree = test::decodeTree(**map);
        ASSERT_TRUE(tree.ok()) << tree.error().message;
        sTree = new test::DecodedTree(std::move(tree.value()));
        sMap = map->release();
    }
    static void TearDownTestSuite()
    {
        delete sMap;
        delete sTree;
        delete sBytes;
        delete sDir;
    }

    static const MapFile& pristine() { return *sMap; }
    static const DirectoryEntry& entryOf(const NodeId& id)
    {
        const DirectoryEntry* entry = sMap->find(id);
        EXPECT_NE(entry, nullptr) << id.toString();
        return *entry;
    }
    /// The decoded heights the node's children are predicted from (from the undamaged map).
    static std::span<const std::uint16_t> heightsOf(const NodeId& id) { return sTree->find(id)->heights; }
    static std::span<const std::uint16_t> parentHeightsOf(const NodeId& id)
    {
        return id.isRoot() ? std::span<const std::uint16_t>() : heightsOf(id.parent());
    }

    /// A copy of the map in `dir` with bits `bits` (offsets from the start of `id`'s payload) flipped.
    static std::filesystem::path damagedCopy(const test::ScratchDir& dir, const NodeId& id,
                                             const std::vector<std::uint64_t>& bits)
    {
        Bytes bytes = *sBytes;
        const DirectoryEntry& entry = entryOf(id);
        for (std::uint64_t bit : bits) {
            bytes[entry.offset + bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
        }
        const auto path = dir / "damaged.map";
        test::writeFileBytes(path, bytes);
        return path;
    }

    /// Straight down over the middle of the map, high enough to see all of it (nothing culled).
    static Camera overhead()
    {
        const MapHeader& h = sMap->header();
        const double size = h.nodeSizeAt(0);
        Camera camera;
        camera.position = {h.originX + size / 2, h.originY + size / 2, 14500.0};
        camera.pitch = -std::numbers::pi / 2 + 1e-3;
        camera.farPlane = 1e6;
        return camera;
    }
    /// Low over node `id`, looking down at it.
    static Camera above(const NodeId& id)
    {
        const MapHeader& h = sMap->header();
        const double size = h.nodeSizeAt(id.level);
        Camera camera;
        camera.position = {h.originX + (id.x + 0.5) * size, h.originY + (id.y + 0.5) * size,
                           h.heightOf(entryOf(id).maxCode) + 1.5 * size};
        camera.pitch = -std::numbers::pi / 2 + 1e-3;
        return camera;
    }

    static test::ScratchDir* sDir;
    static Bytes* sBytes;
    static test::DecodedTree* sTree;
    static MapFile* sMap;
};

test::ScratchDir* MapFaultTest::sDir = nullptr;
Bytes* MapFaultTest::sBytes = nullptr;
test::DecodedTree* MapFaultTest::sTree = nullptr;
MapFile* MapFaultTest::sMap = nullptr;

/// Whether `id` is `ancestor` or lies below it.
bool isWithin(NodeId id, const NodeId& ancestor)
{
    while (id.level > ancestor.level) {
        id = id.parent();
    }
    return id == ancestor;
}

/// Sum of the selected nodes' areas as fractions of the root's: 1 when they partition the terrain.
double coveredFraction(const LodSelection& selection)
{
    double sum = 0.0;
    for (const auto& node : selection.nodes) {
        sum += std::ldexp(1.0, -2 * node.id.level);
    }
    return sum;
}

/// The node ids named in `message` as "node L/X/Y".
std::vector<NodeId> namedNodes(const std::string& message)
{
    std::vector<NodeId> ids;
    for (std::size_t at = message.find("node "); at != std::string::npos; at = message.find("node ", at + 1)) {
        int level = 0;
        unsigned x = 0, y = 0;
        if (std::sscanf(message.c_str() + at, "node %d/%u/%u", &level, &x, &y) == 3) {
            ids.push_back({level, x, y});
        }
    }
    return ids;
}

// ---- Flipped bits ----

TEST_F(MapFaultTest, FlippedBitsInANodeAreAChecksumErrorNamingIt)
{
    // CRC-32 catches every 1- and 2-bit error and every burst of up to 32 bits at these payload sizes; the
    // victims and bit positions come from a seeded generator (printed), over every level.
    const std::uint64_t seed = 7;
    std::mt19937_64 rng(seed);
    const auto directory = pristine().directory();
    std::vector<NodeId> victims;
    for (int level = 0; level < static_cast<int>(pristine().header().levels); ++level) {
        std::vector<NodeId> atLevel;
        for (const auto& e : directory) {
            if (e.id.level == level) {
                atLevel.push_back(e.id);
            }
        }
        victims.push_back(atLevel[rng() % atLevel.size()]);
    }
    test::ScratchDir dir;
    std::ostringstream checked;
    checked << "seed " << seed << ":";
    for (const NodeId& victim : victims) {
        const DirectoryEntry& entry = entryOf(victim);
        const std::uint64_t payloadBits = entry.payloadBytes() * 8;
        const std::uint64_t a = rng() % payloadBits;
        const std::uint64_t b = (a + 1 + rng() % (payloadBits - 1)) % payloadBits;  // another bit
        const std::uint64_t burst = rng() % (payloadBits - 32);
        const std::vector<std::pair<std::string, std::vector<std::uint64_t>>> damages = {
            {"1 bit", {a}},
            {"2 bits", {a, b}},
            {"32-bit burst", {burst, burst + 5, burst + 17, burst + 31}},
        };
        for (const auto& [what, bits] : damages) {
            std::ostringstream trace;
            trace << "node " << victim.toString() << ", " << what << " at payload bit";
            for (auto bit : bits) {
                trace << " " << bit;
            }
            SCOPED_TRACE(trace.str());
            checked << " " << trace.str() << ";";
            const auto path = damagedCopy(dir, victim, bits);
            for (ReaderKind kind : kReaders) {
                SCOPED_TRACE(readerName(kind));
                auto map = test::openMap(path, kind);
                ASSERT_TRUE(map) << "damage to a payload must not stop the map from opening";
                auto node = map->loadNode(victim, parentHeightsOf(victim));
                ASSERT_FALSE(node.ok()) << "the damaged node decoded";
                EXPECT_TRUE(mentions(node.error().message,
                                     path.string() + ": node " + victim.toString() + ": checksum mismatch"))
                    << node.error().message;
                // Its parent, siblings and children (decoded from the undamaged heights) are untouched.
                std::vector<NodeId> neighbours;
                if (!victim.isRoot()) {
                    neighbours.push_back(victim.parent());
                    for (int q = 0; q < 4; ++q) {
                        neighbours.push_back(victim.parent().child(q));
                    }
                }
                if (entry.hasChildren) {
                    for (int q = 0; q < 4; ++q) {
                        neighbours.push_back(victim.child(q));
                    }
                }
                for (const NodeId& other : neighbours) {
                    if (other == victim) {
                        continue;
                    }
                    auto loaded = map->loadNode(other, parentHeightsOf(other));
                    ASSERT_TRUE(loaded.ok())
                        << "damage spread to " << other.toString() << ": " << loaded.error().message;
                    EXPECT_EQ(loaded->heights, sTree->find(other)->heights) << other.toString();
                }
            }
        }
    }
    // verify lists exactly the damaged node (one case, both readers: it decodes the whole map).
    const auto path = damagedCopy(dir, victims[3], {12345 % (entryOf(victims[3]).payloadBytes() * 8)});
    for (ReaderKind kind : kReaders) {
        auto map = test::openMap(path, kind);
        ASSERT_TRUE(map);
        const auto problems = verifyMap(*map);
        ASSERT_FALSE(problems.empty());
        for (const auto& problem : problems) {
            EXPECT_TRUE(mentions(problem, victims[3].toString())) << problem;
        }
    }
    RecordProperty("checked", checked.str());
}

/// Runs `frames` frames of `streamer` at `camera`, waiting for every load after each.
void fly(TerrainStreamer& streamer, const Camera& camera, double tau, int frames)
{
    for (int frame = 0; frame < frames; ++frame) {
        streamer.update(camera, tau);
        streamer.drain();
    }
}

TEST_F(MapFaultTest, StreamerReportsACorruptNodeOnceAndKeepsDrawingItsParent)
{
    const NodeId victim{3, 2, 3};
    const NodeId parent = victim.parent();
    const Camera camera = above(victim);
    constexpr double kTau = 1.0;
    // Over the sound map this camera draws the victim or nodes below it: the node is wanted.
    {
        TerrainNodeSource source(pristine(), {});
        auto streamer = TerrainStreamer::create(source, extentOf(pristine().header()), {});
        ASSERT_TRUE(streamer.ok());
        fly(**streamer, camera, kTau, 12);
        const auto& nodes = (*streamer)->selection().nodes;
        ASSERT_TRUE(
            std::any_of(nodes.begin(), nodes.end(), [&](const SelectedNode& n) { return isWithin(n.id, victim); }))
            << "the camera should want node " << victim.toString();
    }
    test::ScratchDir dir;
    const auto path = damagedCopy(dir, victim, {entryOf(victim).payloadBytes() * 4 + 3});
    for (ReaderKind kind : kReaders) {
        for (int workers : {0, 2}) {
            SCOPED_TRACE(std::string(readerName(kind)) + ", " + std::to_string(workers) + " workers");
            auto map = test::openMap(path, kind);
            ASSERT_TRUE(map);
            TerrainNodeSource source(*map, {});
            StreamerOptions options;
            options.workers = workers;
            auto streamer = TerrainStreamer::create(source, extentOf(map->header()), options);
            ASSERT_TRUE(streamer.ok()) << streamer.error().message;
            std::vector<std::string> reports;
            (*streamer)->onLoadError([&](const std::string& message) { reports.push_back(message); });
            bool parentDrawn = false;
            for (int frame = 0; frame < 30; ++frame) {
                (*streamer)->update(camera, kTau);
                if (frame % 3 == 0) {
                    (*streamer)->drain();  // also frames where loads are still in flight
                }
                for (int q = 0; q < 4; ++q) {
                    ASSERT_EQ((*streamer)->node(parent.child(q)), nullptr)
                        << "frame " << frame << ": " << parent.child(q).toString()
                        << " of the failed group is resident";
                }
                for (const auto& selected : (*streamer)->selection().nodes) {
                    ASSERT_FALSE(isWithin(selected.id, victim))
                        << "frame " << frame << " drew " << selected.id.toString();
                    parentDrawn = parentDrawn || selected.id == parent;
                }
            }
            (*streamer)->drain();
            ASSERT_EQ(reports.size(), 1u) << "reported " << reports.size() << " times";
            EXPECT_TRUE(mentions(reports[0], path.string() + ": node " + victim.toString() + ": checksum mismatch"))
                << reports[0];
            EXPECT_EQ((*streamer)->serverStats().failed, 1u);
            const auto& nodes = (*streamer)->selection().nodes;
            EXPECT_TRUE(std::any_of(nodes.begin(), nodes.end(), [&](const SelectedNode& n) { return n.id == parent; }))
                << "the parent " << parent.toString() << " is not drawn in the last frame";
            EXPECT_TRUE(parentDrawn);
        }
    }
    RecordProperty("checked",
                   "node 3/2/3 with a flipped bit: both readers, inline and 2 workers, 30 frames: one "
                   "report naming the file and node, its group never resident, parent 2/1/1 drawn");
}

// ---- Truncated while open ----

TEST_F(MapFaultTest, FileTruncatedWhileOpenIsAnErrorNamingTheNode)
{
    // Opened whole, then cut to half (the directory at the end goes too; the reader has it in memory).
    const std::uint64_t cut = sBytes->size() / 2;
    for (ReaderKind kind : kReaders) {
        SCOPED_TRACE(readerName(kind));
        test::ScratchDir dir;
        const auto path = dir / "truncated.map";
        test::writeFileBytes(path, *sBytes);
        auto map = test::openMap(path, kind);
        ASSERT_TRUE(map);
        std::filesystem::resize_file(path, cut);
        int whole = 0, lost = 0;
        for (const DirectoryEntry& entry : map->directory()) {
            auto node = map->loadNode(entry.id, parentHeightsOf(entry.id));
            if (entry.offset + entry.payloadBytes() <= cut) {
                ASSERT_TRUE(node.ok()) << entry.id.toString() << " lies before the cut: " << node.error().message;
                EXPECT_EQ(node->heights, sTree->find(entry.id)->heights) << entry.id.toString();
                ++whole;
            } else {
                ASSERT_FALSE(node.ok()) << entry.id.toString() << " lies past the cut but loaded";
                EXPECT_TRUE(mentions(node.error().message,
                                     path.string() + ": node " + entry.id.toString() + ": file is truncated"))
                    << node.error().message;
                ++lost;
            }
        }
        EXPECT_GT(whole, 100);
        EXPECT_GT(lost, 100);
        RecordProperty(std::string("checked_") + readerName(kind),
                       std::to_string(whole) + " nodes before the cut load unchanged, " + std::to_string(lost) +
                           " past it are errors naming the file and node");
    }
}

TEST_F(MapFaultTest, StreamerKeepsTheParentsOfNodesLostToATruncation)
{
    // The file is cut to half once the streamer has the coarse levels (they are written last, at the end
    // of the node area); then the camera wants every level. The groups past the cut fail, once each, and
    // the selection still covers the whole terrain with the nodes it has.
    const std::uint64_t cut = sBytes->size() / 2;
    const Camera camera = overhead();
    for (ReaderKind kind : kReaders) {
        SCOPED_TRACE(readerName(kind));
        test::ScratchDir dir;
        const auto path = dir / "truncated.map";
        test::writeFileBytes(path, *sBytes);
        auto map = test::openMap(path, kind);
        ASSERT_TRUE(map);
        TerrainNodeSource source(*map, {});
        StreamerOptions options;
        options.workers = 2;
        options.cacheSize = map->directory().size();
        auto streamer = TerrainStreamer::create(source, extentOf(map->header()), options);
        ASSERT_TRUE(streamer.ok()) << streamer.error().message;
        std::vector<std::string> reports;
        (*streamer)->onLoadError([&](const std::string& message) { reports.push_back(message); });
        fly(**streamer, camera, 8.0, 10);
        ASSERT_TRUE(reports.empty()) << reports.front();
        for (std::uint32_t y = 0; y < 4; ++y) {
            for (std::uint32_t x = 0; x < 4; ++x) {
                ASSERT_NE((*streamer)->node({2, x, y}), nullptr) << "level 2 should be resident before the cut";
            }
        }

        std::filesystem::resize_file(path, cut);
        fly(**streamer, camera, 0.25, 40);
        const LodSelection& selection = (*streamer)->selection();
        EXPECT_EQ(selection.culledNodes, 0u) << "the camera should see the whole terrain";
        EXPECT_DOUBLE_EQ(coveredFraction(selection), 1.0) << "the selection has a hole";
        std::set<std::uint64_t> failed;
        for (const auto& report : reports) {
            EXPECT_TRUE(mentions(report, path.string() + ": node ")) << report;
            EXPECT_TRUE(mentions(report, "file is truncated")) << report;
            const auto ids = namedNodes(report);
            ASSERT_EQ(ids.size(), 1u) << report;
            const NodeId lost = ids.front();
            EXPECT_TRUE(failed.insert(lost.parent().key()).second)
                << "group of " << lost.toString() << " reported twice";
            EXPECT_GT(entryOf(lost).offset + entryOf(lost).payloadBytes(), cut)
                << lost.toString() << " lies before the cut";
            EXPECT_EQ((*streamer)->node(lost), nullptr) << lost.toString() << " is resident";
            EXPECT_NE((*streamer)->node(lost.parent()), nullptr)
                << "parent of " << lost.toString() << " is not resident";
            for (const auto& selected : selection.nodes) {
                EXPECT_FALSE(isWithin(selected.id, lost.parent()) && selected.id != lost.parent())
                    << selected.id.toString() << " is drawn below the failed group of " << lost.toString();
            }
        }
        EXPECT_GT(failed.size(), 4u) << "the cut should cost some groups";
        int deep = 0;
        for (const auto& selected : selection.nodes) {
            ASSERT_NE((*streamer)->node(selected.id), nullptr) << selected.id.toString() << " drawn but not resident";
            deep += selected.id.level == static_cast<int>(map->header().levels) - 1 ? 1 : 0;
        }
        EXPECT_GT(deep, 10) << "nodes before the cut should still load down to the leaves";
        RecordProperty(std::string("checked_") + readerName(kind),
                       std::to_string(failed.size()) + " groups lost to the cut, each reported once; " +
                           std::to_string(selection.nodes.size()) + " nodes drawn cover the terrain, " +
                           std::to_string(deep) + " of them leaves");
    }
}

TEST_F(MapFaultTest, TruncationDuringConcurrentReadsNeverCrashes)
{
    // Two threads load nodes past the cut point over and over while the file is cut and restored: every
    // load either succeeds with the right heights or fails naming the node (checksum or truncation), and
    // the memory-mapped reader never dies of SIGBUS, even when the cut lands between its size check and
    // its copy.
    for (ReaderKind kind : kReaders) {
        SCOPED_TRACE(readerName(kind));
        test::ScratchDir dir;
        const auto path = dir / "flapping.map";
        test::writeFileBytes(path, *sBytes);
        auto map = test::openMap(path, kind);
        ASSERT_TRUE(map);
        std::vector<NodeId> late;
        for (const auto& e : map->directory()) {
            if (e.offset > sBytes->size() / 2) {
                late.push_back(e.id);
            }
        }
        ASSERT_FALSE(late.empty());
        std::atomic<bool> stop{false};
        std::atomic<int> loaded{0}, refused{0}, wrong{0};
        auto reader = [&](std::size_t start) {
            for (std::size_t i = start; !stop; i += 7) {
                const NodeId id = late[i % late.size()];
                auto node = map->loadNode(id, parentHeightsOf(id));
                if (node.ok()) {
                    (node->heights == sTree->find(id)->heights ? loaded : wrong)++;
                } else {
                    (mentions(node.error().message, "node " + id.toString() + ": ") ? refused : wrong)++;
                }
            }
        };
        std::thread a(reader, 0), b(reader, 3);
        for (int round = 0; round < 40; ++round) {
            std::filesystem::resize_file(path, sBytes->size() / 2);
            std::this_thread::sleep_for(std::chrono::microseconds(500));
            test::writeFileBytes(path, *sBytes);  // whole again, in place (same inode)
            std::this_thread::sleep_for(std::chrono::microseconds(500));
        }
        stop = true;
        a.join();
        b.join();
        EXPECT_EQ(wrong.load(), 0);
        EXPECT_GT(refused.load(), 0) << "no load noticed the cut";
        EXPECT_GT(loaded.load(), 0);
    }
}

// ---- The guarded copy under the memory-mapped reader ----

/// A file of `pages` pages mapped read-only; unmapped on destruction.
struct MappedFile {
    std::filesystem::path path;
    std::size_t size = 0;
    void* data = MAP_FAILED;
    MappedFile(const std::filesystem::path& p, std::size_t pages) : path(p)
    {
        size = pages * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
        Bytes bytes(size);
        for (std::size_t i = 0; i < size; ++i) {
            bytes[i] = static_cast<std::uint8_t>(i * 7 + 1);
        }
        test::writeFileBytes(path, bytes);
        const int fd = ::open(path.c_str(), O_RDONLY);
        data = ::mmap(nullptr, size, PROT_READ, MAP_SHARED, fd, 0);
        ::close(fd);
    }
    ~MappedFile()
    {
        if (data != MAP_FAILED) {
            ::munmap(data, size);
        }
    }
    const std::uint8_t* at(std::size_t offset) const { return static_cast<const std::uint8_t*>(data) + offset; }
};

TEST(MappedCopyTest, APagePastTheEndOfATruncatedFileIsAnErrorNotSigbus)
{
    test::ScratchDir dir;
    MappedFile file(dir / "three-pages.bin", 3);
    ASSERT_NE(file.data, MAP_FAILED);
    const std::size_t page = file.size / 3;
    Bytes out(page * 2);
    ASSERT_TRUE(copyFromMapping(out.data(), file.at(0), out.size()).ok());
    EXPECT_EQ(out[page + 5], static_cast<std::uint8_t>((page + 5) * 7 + 1));

    std::filesystem::resize_file(file.path, page + 100);                 // the third page is gone, the second partly
    auto past = copyFromMapping(out.data(), file.at(page), out.size());  // second and third pages
    ASSERT_FALSE(past.ok()) << "a copy over a page past the end succeeded";
    EXPECT_TRUE(mentions(past.error().message, "at byte " + std::to_string(page) + " of this")) << past.error().message;
    EXPECT_TRUE(mentions(past.error().message, "truncated")) << past.error().message;
    auto inside = copyFromMapping(out.data(), file.at(page), 100);
    ASSERT_TRUE(inside.ok()) << inside.error().message;
    EXPECT_EQ(out[99], static_cast<std::uint8_t>((page + 99) * 7 + 1));
    // Again, and from another thread: the guard is per thread and stays installed.
    std::thread other([&] { EXPECT_FALSE(copyFromMapping(out.data(), file.at(2 * page), 1).ok()); });
    other.join();
    EXPECT_FALSE(copyFromMapping(out.data(), file.at(2 * page), 1).ok());
}

TEST(MappedCopyTest, ASigbusOutsideAGuardedCopyStillKillsTheProcess)
{
    // The handler must not swallow faults it does not own: a plain read past the end after a guarded copy
    // has installed it dies of SIGBUS as before.
    test::ScratchDir dir;
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        MappedFile file(dir / "two-pages.bin", 2);
        std::uint8_t byte = 0;
        if (file.data == MAP_FAILED || !copyFromMapping(&byte, file.at(0), 1).ok()) {
            ::_exit(2);
        }
        std::filesystem::resize_file(file.path, 10);
        const int devNull = ::open("/dev/null", O_WRONLY);
        ::dup2(devNull, STDERR_FILENO);  // a sanitizer's report of the fault is expected, not news
        const volatile std::uint8_t* p = file.at(file.size / 2);
        byte = *p;  // SIGBUS
        ::_exit(byte == 0 ? 3 : 4);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    // The sanitizer's own SIGBUS handler (the one ours hands over to) reports the fault and exits with the
    // sanitizer's exit code or aborts; 0, 2, 3 and 4 are this child's own exits (it survived).
    EXPECT_TRUE(WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) != 0 && WEXITSTATUS(status) != 2 &&
                                        WEXITSTATUS(status) != 3 && WEXITSTATUS(status) != 4))
        << test::describeWaitStatus(status);
#else
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGBUS) << test::describeWaitStatus(status);
#endif
}

}  // namespace
}  // namespace terrain
