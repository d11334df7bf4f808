// Shared helpers for unit tests: scratch directories, running the apps, test data paths.
#pragma once

#include <filesystem>
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

std::filesystem::path testDataPath(const std::string& name);  ///< tests/data/<name>
std::filesystem::path demoDataPath(const std::string& name);  ///< demos/data/<name>

}  // namespace terrain::test
