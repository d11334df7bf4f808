#include "TestSupport.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdio>
#include <sys/wait.h>
#include <unistd.h>

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

std::filesystem::path testDataPath(const std::string& name) { return std::filesystem::path(TERRAIN_TEST_DATA_DIR) / name; }
std::filesystem::path demoDataPath(const std::string& name) { return std::filesystem::path(TERRAIN_DEMO_DATA_DIR) / name; }

}  // namespace terrain::test
