#include "TestSupport.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <complex>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <new>
#include <numbers>
#include <thread>

namespace terrain::test {

ScratchDir::ScratchDir()
{
    static std::atomic<int> counter{0};
    mPath = std::filesystem::temp_directory_path() /
            ("tengine-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    std::filesystem::remove_all(mPath);
    std::filesystem::create_directories(mPath);
}

ScratchDir::~ScratchDir()
{
    std::error_code ignored;
    std::filesystem::remove_all(mPath, ignored);
}

std::vector<std::string> ScratchDir::list() const
{
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(mPath)) {
        names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
}

namespace {
std::string shellQuote(const std::string& s)
{
    std::string quoted = "'";
    for (char c : s) {
        if (c == '\'') {
            quoted += "'\\''";
        } else {
            quoted += c;
        }
    }
    return quoted + "'";
}
}  // namespace

RunResult runProgram(const std::string& program, const std::vector<std::string>& args)
{
    std::string command = shellQuote(program);
    for (const auto& arg : args) {
        command += " " + shellQuote(arg);
    }
    command += " 2>&1 </dev/null";
    RunResult result;
    std::FILE* pipe = ::popen(command.c_str(), "r");
    if (!pipe) {
        return result;
    }
    std::array<char, 4096> buffer{};
    std::size_t n = 0;
    while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) {
        result.output.append(buffer.data(), n);
    }
    int status = ::pclose(pipe);
    result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return result;
}

pid_t spawnProgram(const std::string& program, const std::vector<std::string>& args,
                   const std::filesystem::path& outputFile, const std::function<void()>& beforeExec)
{
    // Everything the child needs is made before fork: after it, only async-signal-safe calls.
    std::vector<std::string> strings = {program};
    strings.insert(strings.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& s : strings) {
        argv.push_back(s.data());
    }
    argv.push_back(nullptr);
    const std::string output = outputFile.string();
    const pid_t child = ::fork();
    if (child != 0) {
        return child;
    }
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    const int in = ::open("/dev/null", O_RDONLY);
    const int out = ::open(output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (in < 0 || out < 0) {
        ::_exit(127);
    }
    ::dup2(in, STDIN_FILENO);
    ::dup2(out, STDOUT_FILENO);
    ::dup2(out, STDERR_FILENO);
    if (beforeExec) {
        beforeExec();
    }
    ::execv(argv[0], argv.data());
    ::_exit(127);
}

std::optional<int> waitForProgram(pid_t pid, double timeoutSeconds)
{
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeoutSeconds);
    int status = 0;
    while (::waitpid(pid, &status, WNOHANG) == 0) {
        if (std::chrono::steady_clock::now() > deadline) {
            ::kill(pid, SIGKILL);
            ::waitpid(pid, &status, 0);
            return std::nullopt;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return status;
}

std::string describeWaitStatus(int status)
{
    if (WIFEXITED(status)) {
        return "exit code " + std::to_string(WEXITSTATUS(status));
    }
    if (WIFSIGNALED(status)) {
        return "killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
    }
    return "wait status " + std::to_string(status);
}

LimitedRun runWithMemoryLimit(const std::function<std::string()>& body, std::uint64_t headroomBytes)
{
    LimitedRun run;
    int channel[2];
    if (::pipe(channel) != 0) {
        return run;
    }
    const pid_t child = ::fork();
    if (child == 0) {
        ::close(channel[0]);
        std::uint64_t pages = 0;
        std::ifstream("/proc/self/statm") >> pages;
        const auto used = static_cast<rlim_t>(pages * static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE)));
        const rlimit limit{used + headroomBytes, used + headroomBytes};
        std::string message;
        if (pages == 0 || ::setrlimit(RLIMIT_AS, &limit) != 0) {
            message = "Ecannot set RLIMIT_AS";
        } else {
            try {
                message = "R" + body();
            } catch (const std::bad_alloc&) {
                message = "B";
            }
        }
        std::size_t done = 0;
        while (done < message.size()) {
            const ssize_t n = ::write(channel[1], message.data() + done, message.size() - done);
            if (n <= 0) {
                break;
            }
            done += static_cast<std::size_t>(n);
        }
        ::_exit(0);
    }
    ::close(channel[1]);
    std::string message;
    char buffer[4096];
    for (ssize_t n; (n = ::read(channel[0], buffer, sizeof buffer)) > 0;) {
        message.append(buffer, static_cast<std::size_t>(n));
    }
    ::close(channel[0]);
    if (child < 0 || ::waitpid(child, &run.status, 0) != child) {
        return run;
    }
    if (WIFEXITED(run.status) && WEXITSTATUS(run.status) == 0 && !message.empty()) {
        run.outcome = message[0] == 'R'   ? LimitedRun::Outcome::Returned
                      : message[0] == 'B' ? LimitedRun::Outcome::OutOfMemory
                                          : LimitedRun::Outcome::Died;
        run.text = message.substr(1);
    }
    return run;
}

std::string describe(const LimitedRun& run)
{
    switch (run.outcome) {
        case LimitedRun::Outcome::Returned:
            return "returned '" + run.text + "'";
        case LimitedRun::Outcome::OutOfMemory:
            return "ran out of memory (std::bad_alloc): it allocated before refusing";
        case LimitedRun::Outcome::Died:
            break;
    }
    return "the child died: " + describeWaitStatus(run.status) + (run.text.empty() ? "" : ", " + run.text);
}

std::string readTextFile(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

bool flipBits(const std::filesystem::path& path, std::uint64_t offset, std::uint8_t mask)
{
    std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
    char byte = 0;
    file.seekg(static_cast<std::streamoff>(offset));
    file.read(&byte, 1);
    byte = static_cast<char>(byte ^ static_cast<char>(mask));
    file.seekp(static_cast<std::streamoff>(offset));
    file.write(&byte, 1);
    return file.good();
}

void fft(std::vector<std::complex<double>>& a, bool inverse)
{
    const std::size_t n = a.size();
    for (std::size_t i = 1, j = 0; i < n; ++i) {
        std::size_t bit = n >> 1;
        for (; j & bit; bit >>= 1) {
            j ^= bit;
        }
        j ^= bit;
        if (i < j) {
            std::swap(a[i], a[j]);
        }
    }
    for (std::size_t len = 2; len <= n; len <<= 1) {
        const double angle = 2.0 * std::numbers::pi / static_cast<double>(len) * (inverse ? 1.0 : -1.0);
        const std::complex<double> step(std::cos(angle), std::sin(angle));
        for (std::size_t i = 0; i < n; i += len) {
            std::complex<double> w(1.0);
            for (std::size_t k = 0; k < len / 2; ++k) {
                const std::complex<double> u = a[i + k], v = a[i + k + len / 2] * w;
                a[i + k] = u + v;
                a[i + k + len / 2] = u - v;
                w *= step;
            }
        }
    }
}

glm::dvec3 direction(double azimuthDegrees, double elevationDegrees)
{
    const double a = azimuthDegrees * std::numbers::pi / 180.0, e = elevationDegrees * std::numbers::pi / 180.0;
    return {std::sin(a) * std::cos(e), std::cos(a) * std::cos(e), std::sin(e)};
}

namespace {

/// The 2D FFT of a w x h row-major grid (both powers of 2).
void fft2(std::vector<std::complex<double>>& grid, std::size_t w, std::size_t h, bool inverse)
{
    std::vector<std::complex<double>> line;
    for (std::size_t y = 0; y < h; ++y) {
        line.assign(grid.begin() + static_cast<std::ptrdiff_t>(y * w),
                    grid.begin() + static_cast<std::ptrdiff_t>((y + 1) * w));
        fft(line, inverse);
        std::copy(line.begin(), line.end(), grid.begin() + static_cast<std::ptrdiff_t>(y * w));
    }
    line.resize(h);
    for (std::size_t x = 0; x < w; ++x) {
        for (std::size_t y = 0; y < h; ++y) {
            line[y] = grid[y * w + x];
        }
        fft(line, inverse);
        for (std::size_t y = 0; y < h; ++y) {
            grid[y * w + x] = line[y];
        }
    }
}

/// |X|^2's inverse transform: the circular autocorrelation of the padded grid (unnormalised).
std::vector<double> paddedAutocorrelation(std::vector<std::complex<double>> grid, std::size_t w, std::size_t h)
{
    fft2(grid, w, h, false);
    for (auto& c : grid) {
        c = std::norm(c);
    }
    fft2(grid, w, h, true);
    std::vector<double> out(grid.size());
    for (std::size_t i = 0; i < grid.size(); ++i) {
        out[i] = grid[i].real() / static_cast<double>(grid.size());
    }
    return out;
}

}  // namespace

AutocorrelationPeak autocorrelationPeak(const std::vector<double>& values, int width, int height, int minLag,
                                        int maxLag)
{
    auto pow2 = [](int n) {
        std::size_t p = 1;
        while (p < static_cast<std::size_t>(n)) {
            p <<= 1;
        }
        return p;
    };
    const std::size_t w = pow2(2 * width), h = pow2(2 * height);
    double mean = 0.0;
    for (double v : values) {
        mean += v / static_cast<double>(values.size());
    }
    std::vector<std::complex<double>> grid(w * h), ones(w * h);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            grid[static_cast<std::size_t>(y) * w + static_cast<std::size_t>(x)] =
                values[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)] -
                mean;
            ones[static_cast<std::size_t>(y) * w + static_cast<std::size_t>(x)] = 1.0;
        }
    }
    const std::vector<double> products = paddedAutocorrelation(std::move(grid), w, h);
    const std::vector<double> overlaps = paddedAutocorrelation(std::move(ones), w, h);
    const double variance = products[0] / overlaps[0];
    AutocorrelationPeak peak{-1.0, 0, 0};
    for (int dy = -maxLag; dy <= maxLag; ++dy) {
        for (int dx = -maxLag; dx <= maxLag; ++dx) {
            const int length2 = dx * dx + dy * dy;
            if (length2 < minLag * minLag || length2 > maxLag * maxLag) {
                continue;
            }
            const std::size_t i = static_cast<std::size_t>((dy + static_cast<int>(h)) % static_cast<int>(h)) * w +
                                  static_cast<std::size_t>((dx + static_cast<int>(w)) % static_cast<int>(w));
            const double r = products[i] / std::max(overlaps[i], 1.0) / variance;
            if (r > peak.value) {
                peak = {r, dx, dy};
            }
        }
    }
    return peak;
}

std::filesystem::path testDataPath(const std::string& name)
{
    return std::filesystem::path(TERRAIN_TEST_DATA_DIR) / name;
}
std::filesystem::path demoDataPath(const std::string& name)
{
    return std::filesystem::path(TERRAIN_DEMO_DATA_DIR) / name;
}

}  // namespace terrain::test
