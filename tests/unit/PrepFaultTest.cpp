// prep under faults, run as a user runs it, over a previous map at its output path: stopped by a signal
// at random moments (before, while and after it writes), and out of disk (a file size limit, a full
// tmpfs). Afterwards the previous map is there byte for byte, or, where prep got to the end first, the
// new map is there whole and verifies; nothing else is ever left in the directory; a full disk is an
// error that names the output and says what is wrong.
#include "MapTestSupport.h"

#include <dirent.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <random>
#include <sstream>

namespace terrain {
namespace {

const std::string kPrep = TERRAIN_PREP_EXE;
const std::string kTool = TERRAIN_TENGINE_TOOL_EXE;

bool mentions(const std::string& text, const std::string& what)
{
    return text.find(what) != std::string::npos;
}

/// prep on `input` with one thread (so a run takes a few tenths of a second) into `output`.
std::vector<std::string> prepArgs(const std::filesystem::path& input, const std::filesystem::path& output,
                                  const std::vector<std::string>& extra = {})
{
    std::vector<std::string> args = {input.string(), "-h", "90", "--threads", "1", "-o", output.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
}

std::filesystem::path trinidad()
{
    return test::demoDataPath("trinidad_co_srtm3_crop_1025.png");
}
std::filesystem::path jacksboro()
{
    return test::testDataPath("jacksboro_fault_dem_403x344.png");
}

/// Whether process `pid` has a file in `dir` open (its output: an O_TMPFILE shows as "dir/#inode (deleted)").
bool hasFileOpenIn(pid_t pid, const std::filesystem::path& dir)
{
    std::error_code ec;
    for (std::filesystem::directory_iterator it("/proc/" + std::to_string(pid) + "/fd", ec), end; !ec && it != end;
         it.increment(ec)) {
        std::error_code linkError;
        const auto target = std::filesystem::read_symlink(it->path(), linkError).string();
        if (!linkError && target.rfind(dir.string() + "/", 0) == 0) {
            return true;
        }
    }
    return false;
}

/// A uniform double in [0, 1) from the generator's standardised output (not from a <random> distribution,
/// whose results differ between standard libraries): the same seed gives the same delays everywhere.
double unitInterval(std::mt19937_64& rng)
{
    return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

std::uint64_t faultSeed()
{
    if (const char* text = std::getenv("TERRAIN_FAULT_SEED")) {
        return std::strtoull(text, nullptr, 10);
    }
    return 20240611;
}

TEST(PrepFaultTest, StoppedAtRandomMomentsKeepsThePreviousMapWhole)
{
    // Two maps of the same terrain that differ (lossless, and within 1 m): each round makes the one that is
    // not at the output now, so a prep that finished can be told from one that left the previous map alone.
    test::ScratchDir refs, work;
    struct Variant {
        const char* name;
        std::vector<std::string> extra;
        test::Bytes bytes;
        double seconds = 0.0;
    };
    Variant variants[] = {{"lossless", {}, {}}, {"max-error 1", {"--max-error", "1"}, {}}};
    for (int i = 0; i < 2; ++i) {
        Variant& v = variants[i];
        const auto path = refs / ("variant-" + std::to_string(i) + ".map");
        const auto start = std::chrono::steady_clock::now();
        auto built = test::runProgram(kPrep, prepArgs(trinidad(), path, v.extra));
        v.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        ASSERT_EQ(built.exitCode, 0) << built.output;
        auto verify = test::runProgram(kTool, {"verify", path.string()});
        ASSERT_EQ(verify.exitCode, 0) << verify.output;
        v.bytes = test::readFileBytes(path);
    }
    ASSERT_FALSE(variants[0].bytes == variants[1].bytes);
    const double runSeconds = std::max(variants[0].seconds, variants[1].seconds);
    const auto output = work / "terrain.map";
    test::writeFileBytes(output, variants[0].bytes);

    // Delays spread over [0, 1.3 x a whole run): round r draws from its own slice, so every stage (reading
    // the PNG, building and writing, after the rename) is hit whatever the seed; the order is shuffled.
    const std::uint64_t seed = faultSeed();
    std::mt19937_64 rng(seed);
    constexpr int kRounds = 12;
    std::vector<double> delays(kRounds);
    for (int r = 0; r < kRounds; ++r) {
        delays[static_cast<std::size_t>(r)] = 1.3 * runSeconds * (r + unitInterval(rng)) / kRounds;
    }
    for (int r = kRounds - 1; r > 0; --r) {
        std::swap(delays[static_cast<std::size_t>(r)],
                  delays[static_cast<std::size_t>(rng() % static_cast<std::uint64_t>(r + 1))]);
    }
    const int signals[] = {SIGINT, SIGTERM, SIGKILL};
    std::ostringstream log;
    log << "seed " << seed << " (set TERRAIN_FAULT_SEED to repeat), a whole run takes " << runSeconds << " s;";
    int killedWhileWriting = 0, killedNotWriting = 0, killedAfterRename = 0, finished = 0;
    const test::Bytes* current = &variants[0].bytes;
    for (int r = 0; r < kRounds; ++r) {
        const Variant& variant = current == &variants[0].bytes ? variants[1] : variants[0];
        const int signal = signals[r % 3];
        const double delay = delays[static_cast<std::size_t>(r)];
        std::ostringstream round;
        round << " round " << r << ": " << variant.name << ", " << strsignal(signal) << " after "
              << static_cast<int>(delay * 1000) << " ms";
        SCOPED_TRACE(log.str() + round.str());

        const auto start = std::chrono::steady_clock::now();
        const pid_t child = test::spawnProgram(kPrep, prepArgs(trinidad(), output, variant.extra), refs / "prep.txt");
        ASSERT_GT(child, 0);
        int status = 0;
        bool exited = false;
        while (!(exited = ::waitpid(child, &status, WNOHANG) == child) &&
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < delay) {
            ::usleep(100);
        }
        bool writing = false;
        if (!exited) {
            writing = hasFileOpenIn(child, work.path());
            ::kill(child, signal);
            ASSERT_EQ(::waitpid(child, &status, 0), child);
        }
        const bool killed = WIFSIGNALED(status) && WTERMSIG(status) == signal;
        ASSERT_TRUE(killed || (WIFEXITED(status) && WEXITSTATUS(status) == 0))
            << "prep neither finished nor died of the signal: " << test::describeWaitStatus(status) << "\n"
            << test::readTextFile(refs / "prep.txt");

        EXPECT_EQ(work.list(), std::vector<std::string>{"terrain.map"}) << "something besides the map was left";
        const test::Bytes now = test::readFileBytes(output);
        if (now == *current) {
            EXPECT_TRUE(killed) << "prep finished but the previous map is still there";
            round << ": killed " << (writing ? "while writing" : "with no output open") << ", previous map intact";
            (writing ? killedWhileWriting : killedNotWriting) += 1;
        } else {
            ASSERT_TRUE(now == variant.bytes)
                << "the map is neither the previous one nor the complete new one (" << now.size() << " bytes)";
            auto verify = test::runProgram(kTool, {"verify", output.string()});
            EXPECT_EQ(verify.exitCode, 0) << verify.output;
            round << (killed ? ": killed after the rename" : ": finished") << ", new map complete and verified";
            (killed ? killedAfterRename : finished) += 1;
            current = &variant.bytes;
        }
        log << round.str() << ";";
    }
    ::testing::Test::RecordProperty("rounds", log.str());
    std::printf("%s\n", log.str().c_str());
    EXPECT_GT(killedWhileWriting, 0) << log.str() << "\nno round stopped prep while it was writing its output";
    EXPECT_GE(killedWhileWriting + killedNotWriting, kRounds / 4) << log.str() << "\nprep was hardly ever stopped";
}

/// Ignores SIGXFSZ and limits files written to `bytes` (RLIMIT_FSIZE), in a child before exec.
struct FileSizeLimit {
    rlim_t bytes;
    bool ignoreSignal;
    void operator()() const
    {
        if (ignoreSignal) {
            ::signal(SIGXFSZ, SIG_IGN);
        }
        const rlimit limit{bytes, bytes};
        ::setrlimit(RLIMIT_FSIZE, &limit);
    }
};

TEST(PrepFaultTest, FileSizeLimitIsAClearErrorAndKeepsThePreviousMap)
{
    // `ulimit -f 256` (in 1 KiB blocks): the 1 MB map cannot be written. With SIGXFSZ ignored by the caller,
    // and with its default disposition (prep must not die of it with a core dump).
    test::ScratchDir logs, work;
    const auto output = work / "terrain.map";
    auto built = test::runProgram(kPrep, prepArgs(jacksboro(), output));
    ASSERT_EQ(built.exitCode, 0) << built.output;
    const test::Bytes previous = test::readFileBytes(output);
    for (bool ignoreSignal : {true, false}) {
        SCOPED_TRACE(ignoreSignal ? "SIGXFSZ ignored by the caller" : "SIGXFSZ at its default");
        const pid_t child = test::spawnProgram(kPrep, prepArgs(trinidad(), output), logs / "prep.txt",
                                               FileSizeLimit{256 * 1024, ignoreSignal});
        ASSERT_GT(child, 0);
        const auto status = test::waitForProgram(child, 60);
        ASSERT_TRUE(status) << "prep did not finish within 60 s";
        const std::string printed = test::readTextFile(logs / "prep.txt");
        EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 1)
            << test::describeWaitStatus(*status) << ", expected exit code 1\n"
            << printed;
        EXPECT_TRUE(mentions(printed, output.string() + ": write failed: File too large")) << printed;
        EXPECT_TRUE(mentions(printed, "ulimit -f")) << printed;
        EXPECT_EQ(work.list(), std::vector<std::string>{"terrain.map"});
        EXPECT_TRUE(test::readFileBytes(output) == previous) << "the previous map was changed";
    }
    ::testing::Test::RecordProperty("checked",
                                    "prep over a 256 KiB file size limit exits 1 naming the output, "
                                    "'File too large', previous map intact, no other file");
}

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kSanitized = true;  // the sanitizers reserve terabytes of address space at startup
#else
constexpr bool kSanitized = false;
#endif

TEST(PrepFaultTest, OversizedRawSizeIsRefusedBeforeAllocating)
{
    // `ulimit -v` 2 GiB: --raw-size claims far more than the 12-byte file (and than memory) holds; prep
    // must say so, naming the file and the size, rather than die allocating.
    if (kSanitized) {
        GTEST_SKIP() << "a sanitized prep cannot start under a 2 GiB address space limit";
    }
    test::ScratchDir dir;
    test::writeFileBytes(dir / "tiny.raw", test::Bytes(12, 0));
    for (const char* size : {"1073741824x1073741824", "40000x40000"}) {
        SCOPED_TRACE(size);
        const pid_t child = test::spawnProgram(
            kPrep, {(dir / "tiny.raw").string(), "--raw-size", size, "-o", (dir / "out.map").string()},
            dir / "prep.txt", [] {
                const rlimit limit{rlim_t{2} << 30, rlim_t{2} << 30};
                ::setrlimit(RLIMIT_AS, &limit);
            });
        ASSERT_GT(child, 0);
        const auto status = test::waitForProgram(child, 60);
        ASSERT_TRUE(status);
        const std::string printed = test::readTextFile(dir / "prep.txt");
        EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 1) << test::describeWaitStatus(*status) << "\n"
                                                                     << printed;
        EXPECT_TRUE(mentions(printed, (dir / "tiny.raw").string() + ": a " + size + " raw 16-bit file has exactly"))
            << printed;
        EXPECT_FALSE(std::filesystem::exists(dir / "out.map"));
    }
}

/// Writes all of `bytes` to `path` with system calls only (for the forked child below).
bool writeAll(const std::string& path, const test::Bytes& bytes)
{
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::size_t done = 0;
    while (fd >= 0 && done < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n <= 0) {
            break;
        }
        done += static_cast<std::size_t>(n);
    }
    return fd >= 0 && ::close(fd) == 0 && done == bytes.size();
}

/// In a new mount namespace (as root, or as root of a new user namespace), mounts a tmpfs of `bytes` on
/// `dir`. Only for a forked child: the mount dies with it. False when not permitted.
bool mountPrivateTmpfs(const std::filesystem::path& dir, std::uint64_t bytes)
{
    const uid_t uid = ::geteuid();
    const gid_t gid = ::getegid();
    if (::unshare(CLONE_NEWNS) != 0) {
        if (::unshare(CLONE_NEWUSER | CLONE_NEWNS) != 0) {
            return false;
        }
        const std::string uidMap = "0 " + std::to_string(uid) + " 1\n";
        const std::string gidMap = "0 " + std::to_string(gid) + " 1\n";
        if (!writeAll("/proc/self/setgroups", test::Bytes{'d', 'e', 'n', 'y'}) ||
            !writeAll("/proc/self/uid_map", test::Bytes(uidMap.begin(), uidMap.end())) ||
            !writeAll("/proc/self/gid_map", test::Bytes(gidMap.begin(), gidMap.end()))) {
            return false;
        }
    }
    ::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr);  // keep the tmpfs out of the parent's view
    const std::string options = "size=" + std::to_string(bytes);
    return ::mount("tmpfs", dir.c_str(), "tmpfs", MS_NOSUID | MS_NODEV, options.c_str()) == 0;
}

/// What prep did writing into a tmpfs that holds the previous map and half a megabyte more, mounted in a
/// private mount namespace of a forked child (so nothing outlives the test): "skip" where mounting is not
/// allowed, else the exit status, the files left and whether the previous map is intact; `printed` gets
/// prep's output.
std::string prepIntoAFullDisk(const std::vector<std::string>& extra, std::string& printed,
                              std::filesystem::path& output, std::uint64_t& tmpfsBytes)
{
    test::ScratchDir logs, work;
    auto built = test::runProgram(kPrep, prepArgs(jacksboro(), logs / "previous.map"));
    EXPECT_EQ(built.exitCode, 0) << built.output;
    const test::Bytes previous = test::readFileBytes(logs / "previous.map");
    tmpfsBytes = (previous.size() + 512 * 1024 + 4095) / 4096 * 4096;
    output = work / "terrain.map";

    int report[2];
    EXPECT_EQ(::pipe(report), 0);
    const pid_t child = ::fork();
    EXPECT_GE(child, 0);
    if (child == 0) {
        ::close(report[0]);
        if (!mountPrivateTmpfs(work.path(), tmpfsBytes)) {
            ::_exit(77);
        }
        std::string result;
        if (!writeAll(output.string(), previous)) {
            result = "cannot write the previous map into the tmpfs";
        } else {
            const pid_t prep = test::spawnProgram(kPrep, prepArgs(trinidad(), output, extra), logs / "prep.txt");
            const auto status = test::waitForProgram(prep, 60);
            std::string names;
            if (DIR* d = ::opendir(work.path().c_str())) {
                while (dirent* e = ::readdir(d)) {
                    if (std::string(e->d_name) != "." && std::string(e->d_name) != "..") {
                        names += std::string(names.empty() ? "" : ",") + e->d_name;
                    }
                }
                ::closedir(d);
            }
            const bool intact = test::readFileBytes(output) == previous;
            result = "status " + (status ? test::describeWaitStatus(*status) : std::string("timed out")) + "; files " +
                     names + "; previous map " + (intact ? "intact" : "changed");
        }
        [[maybe_unused]] const auto written = ::write(report[1], result.data(), result.size());
        ::_exit(0);
    }
    ::close(report[1]);
    std::string result;
    char buffer[512];
    for (ssize_t n; (n = ::read(report[0], buffer, sizeof buffer)) > 0;) {
        result.append(buffer, static_cast<std::size_t>(n));
    }
    ::close(report[0]);
    int status = 0;
    EXPECT_EQ(::waitpid(child, &status, 0), child);
    if (WIFEXITED(status) && WEXITSTATUS(status) == 77) {
        return "skip";
    }
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << test::describeWaitStatus(status);
    printed = test::readTextFile(logs / "prep.txt");
    return result;
}

TEST(PrepFaultTest, FullDiskIsAClearErrorAndKeepsThePreviousMap)
{
    std::string printed;
    std::filesystem::path output;
    std::uint64_t tmpfsBytes = 0;
    const std::string result = prepIntoAFullDisk({}, printed, output, tmpfsBytes);
    if (result == "skip") {
        GTEST_SKIP() << "cannot mount a tmpfs here (needs CAP_SYS_ADMIN or unprivileged user namespaces); "
                        "the file size limit test covers the same error path";
    }
    EXPECT_EQ(result, "status exit code 1; files terrain.map; previous map intact") << printed;
    EXPECT_TRUE(mentions(printed, output.string() + ": write failed: No space left on device (the disk is full"))
        << printed;
    ::testing::Test::RecordProperty("checked", "prep into a full " + std::to_string(tmpfsBytes / 1024) +
                                                   " KiB tmpfs exits 1 naming the output and 'the disk is full', "
                                                   "previous map intact, no other file");
}

TEST(PrepFaultTest, FullDiskUnderTheOutOfCoreScratchFileIsAClearErrorNotASigbus)
{
    // The scratch grid is reserved when it is made: a sparse one died of SIGBUS at the first page the disk
    // had no room for.
    std::string printed;
    std::filesystem::path output;
    std::uint64_t tmpfsBytes = 0;
    const std::string result = prepIntoAFullDisk({"--out-of-core"}, printed, output, tmpfsBytes);
    if (result == "skip") {
        GTEST_SKIP() << "cannot mount a tmpfs here (needs CAP_SYS_ADMIN or unprivileged user namespaces)";
    }
    EXPECT_EQ(result, "status exit code 1; files terrain.map; previous map intact") << printed;
    EXPECT_TRUE(mentions(printed, "No space left on device")) << printed;
    EXPECT_TRUE(mentions(printed, "scratch")) << printed;
}

}  // namespace
}  // namespace terrain
