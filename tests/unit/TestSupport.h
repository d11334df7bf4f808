// Shared helpers for unit tests: scratch directories, running the apps, test data paths.
#pragma once

#include <sys/types.h>
#include <complex>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <glm/vec3.hpp>
#include <optional>
#include <string>
#include <vector>

namespace terrain::test {

/// A fresh, empty directory under the system temp dir, removed (with contents) on destruction.
class ScratchDir {
public:
    ScratchDir();
    ~ScratchDir();
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;

    const std::filesystem::path& path() const { return mPath; }
    std::filesystem::path operator/(const std::string& name) const { return mPath / name; }
    /// Names of the files now in the directory, sorted.
    std::vector<std::string> list() const;

private:
    std::filesystem::path mPath;
};

/// Result of running a program: exit code and everything it printed (stdout and stderr interleaved).
struct RunResult {
    int exitCode = -1;
    std::string output;
};

/// Runs `program` with `args` (no shell quoting issues: each arg is quoted), capturing its output.
RunResult runProgram(const std::string& program, const std::vector<std::string>& args);

/// Starts `program` with `args` in the background (fork + exec) and returns its pid (-1 if fork failed):
/// stdout and stderr go to `outputFile` (created or truncated), stdin is /dev/null, SIGINT and SIGTERM
/// have their default dispositions (a shell that started the tests in the background may ignore them, and
/// ignored signals survive exec). `beforeExec` runs in the child just before exec (setrlimit, signal
/// dispositions); it must not allocate or take locks. A child that cannot exec exits with 127.
pid_t spawnProgram(const std::string& program, const std::vector<std::string>& args,
                   const std::filesystem::path& outputFile, const std::function<void()>& beforeExec = {});

/// Waits for a spawned program and returns its wait status (see waitpid). After `timeoutSeconds` it is
/// killed (SIGKILL) and reaped, and the result is empty.
std::optional<int> waitForProgram(pid_t pid, double timeoutSeconds);

/// "exit code 3", "killed by signal 9 (Killed)": a wait status for messages.
std::string describeWaitStatus(int status);

/// What a function run by runWithMemoryLimit did.
struct LimitedRun {
    enum class Outcome {
        Returned,     ///< it returned `text`
        OutOfMemory,  ///< it threw std::bad_alloc: it tried to allocate past the limit
        Died,         ///< the child was killed by a signal or exited on its own (see `status`)
    };
    Outcome outcome = Outcome::Died;
    std::string text;
    int status = 0;  ///< the child's wait status
};

/// Runs `body` in a forked child whose address space may grow by at most `headroomBytes` over its size
/// at the fork (RLIMIT_AS), so an allocation the code under test should have refused to make fails there
/// with std::bad_alloc rather than succeeding. Call from a single-threaded test.
LimitedRun runWithMemoryLimit(const std::function<std::string()>& body, std::uint64_t headroomBytes = 1ull << 30);

/// "returned '...'", "ran out of memory (std::bad_alloc)", "exit code 3": for messages.
std::string describe(const LimitedRun& run);

/// The whole of a text file; empty if it cannot be read.
std::string readTextFile(const std::filesystem::path& path);

/// Flips the bits `mask` of the byte at `offset` of `file` in place (a damaged file for fault tests); false when
/// the byte could not be read and written.
[[nodiscard]] bool flipBits(const std::filesystem::path& file, std::uint64_t offset, std::uint8_t mask);

/// In-place radix-2 FFT of `a` (its size a power of 2): X_k = sum x_j e^(-2 pi i jk/n), or with `inverse` the
/// same with e^(+...) and without the 1/n.
void fft(std::vector<std::complex<double>>& a, bool inverse = false);

/// The unit vector at `azimuthDegrees` (0 north, 90 east) and `elevationDegrees` above the horizon (world x east,
/// y north, z up).
glm::dvec3 direction(double azimuthDegrees, double elevationDegrees);

/// The largest normalised autocorrelation of `values` (width x height, row-major, its mean removed) at a lag of
/// at least `minLag` and at most `maxLag` pixels (Euclidean length): each lag's sum of products over the pixels
/// that overlap, divided by their count, over the variance. 1 for a pattern that repeats at such a lag, about 0
/// for noise. By FFT (zero-padded, so no wrap-around).
struct AutocorrelationPeak {
    double value = 0.0;
    int dx = 0;
    int dy = 0;
};
AutocorrelationPeak autocorrelationPeak(const std::vector<double>& values, int width, int height, int minLag,
                                        int maxLag);

std::filesystem::path testDataPath(const std::string& name);  ///< tests/data/<name>
std::filesystem::path demoDataPath(const std::string& name);  ///< demos/data/<name>

}  // namespace terrain::test

/// In a gtest body: `result` (an Expected or Status) is an error whose message names `path`'s file name and
/// contains `text`.
#define EXPECT_ERROR_MENTIONS(result, path, text)                                                      \
    do {                                                                                               \
        ASSERT_FALSE((result).ok()) << "expected an error mentioning: " << (text);                     \
        EXPECT_NE((result).error().message.find((path).filename().string()), std::string::npos)        \
            << (result).error().message;                                                               \
        EXPECT_NE((result).error().message.find(text), std::string::npos) << (result).error().message; \
    } while (false)
