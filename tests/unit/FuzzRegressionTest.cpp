// Every input stored under tests/data/fuzz/<target>/ (seeds and each finding of tests/fuzz/run, named
// after what it broke) replayed through its fuzz target (tests/fuzz/FuzzTargets.h): in the ASan + UBSan
// CI build a regression is a sanitizer report, in every build a crash, an abort on a non-finite result
// or a hang (ctest's timeout).
#include "FuzzTargets.h"
#include "TestSupport.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <set>

namespace terrain {
namespace {

std::vector<std::uint8_t> readBytes(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class FuzzRegression : public ::testing::TestWithParam<fuzz::Target> {};

TEST_P(FuzzRegression, StoredInputsRunCleanly)
{
    const fuzz::Target& target = GetParam();
    const auto dir = test::testDataPath("fuzz") / std::string(target.name);
    ASSERT_TRUE(std::filesystem::is_directory(dir)) << dir << ": every target keeps at least a seed here";
    int inputs = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        SCOPED_TRACE(entry.path().string());
        const auto bytes = readBytes(entry.path());
        ASSERT_EQ(bytes.size(), std::filesystem::file_size(entry.path()));
        target.run(bytes);
        ++inputs;
    }
    EXPECT_GE(inputs, 1) << dir;
    RecordProperty("inputs", inputs);
}

TEST(FuzzRegression, EveryTargetHasItsFolderAndNoFolderIsOrphaned)
{
    std::set<std::string> names, folders;
    for (const auto& target : fuzz::targets()) {
        names.insert(std::string(target.name));
    }
    for (const auto& entry : std::filesystem::directory_iterator(test::testDataPath("fuzz"))) {
        folders.insert(entry.path().filename().string());
    }
    EXPECT_EQ(names, folders);
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzRegression, ::testing::ValuesIn(fuzz::targets().begin(), fuzz::targets().end()),
                         [](const auto& testInfo) { return std::string(testInfo.param.name); });

}  // namespace
}  // namespace terrain
