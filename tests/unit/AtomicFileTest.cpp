#include "core/AtomicFile.h"

#include "TestSupport.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cstdlib>
#include <fstream>

namespace terrain {
namespace {

std::string readAll(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(AtomicFileTest, CommitMakesTheFileAppearWhole)
{
    test::ScratchDir dir;
    auto file = AtomicFile::create(dir / "out.bin");
    ASSERT_TRUE(file.ok()) << file.error().message;
    file->write("hello", 5);
    EXPECT_FALSE(std::filesystem::exists(dir / "out.bin")) << "the final name must not exist before commit";
    file->writeAt(0, "J", 1);
    ASSERT_TRUE(file->commit().ok());
    EXPECT_EQ(readAll(dir / "out.bin"), "Jello");
    EXPECT_EQ(dir.list(), std::vector<std::string>{"out.bin"});
}

TEST(AtomicFileTest, AbandonedWriteLeavesNothing)
{
    test::ScratchDir dir;
    {
        auto file = AtomicFile::create(dir / "out.bin");
        ASSERT_TRUE(file.ok());
        file->write("partial", 7);
        // Destroyed without commit, as when a build fails half way.
    }
    EXPECT_TRUE(dir.list().empty());
}

TEST(AtomicFileTest, AbandonedWriteKeepsThePreviousFile)
{
    test::ScratchDir dir;
    ASSERT_TRUE(writeFileAtomically(dir / "out.bin", std::vector<std::uint8_t>{'o', 'l', 'd'}).ok());
    {
        auto file = AtomicFile::create(dir / "out.bin");
        ASSERT_TRUE(file.ok());
        file->write("new", 3);
    }
    EXPECT_EQ(readAll(dir / "out.bin"), "old");
}

TEST(AtomicFileTest, KilledWriterLeavesNothing)
{
    // A process that dies mid-write (no destructors, no commit), as prep does under SIGKILL.
    test::ScratchDir dir;
    pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        auto file = AtomicFile::create(dir / "out.map");
        if (file.ok()) {
            file->write("partial", 7);
        }
        std::_Exit(0);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    EXPECT_TRUE(dir.list().empty()) << "left behind: " << (dir.list().empty() ? "" : dir.list().front());
}

TEST(AtomicFileTest, UnwritableDirectoryIsAClearError)
{
    auto file = AtomicFile::create("/nonexistent-dir/x/out.map");
    ASSERT_FALSE(file.ok());
    EXPECT_NE(file.error().message.find("/nonexistent-dir/x/out.map"), std::string::npos);
}

TEST(AtomicFileTest, OutputsThatCannotBeCreatedAreRefusedBeforeAnyWork)
{
    test::ScratchDir dir;
    std::filesystem::create_directory(dir / "sub");
    struct Case {
        std::filesystem::path path;
        std::string says;
    };
    const Case cases[] = {
        {dir / "sub", "it is a directory"},
        {dir.path() / "", "no file name"},
        {dir / std::string(256, 'n'), "its name is 256 bytes long, more than the 255"},
        {dir / "missing" / "out.map", "the directory " + (dir / "missing").string() + " does not exist"},
    };
    for (const Case& c : cases) {
        const Status checked = checkOutputPath(c.path);
        ASSERT_FALSE(checked.ok()) << c.path;
        EXPECT_NE(checked.error().message.find(c.says), std::string::npos) << checked.error().message;
        auto file = AtomicFile::create(c.path);
        ASSERT_FALSE(file.ok()) << c.path;
        EXPECT_NE(file.error().message.find(c.says), std::string::npos) << file.error().message;
    }
    EXPECT_TRUE(checkOutputPath(dir / std::string(255, 'n')).ok());
    EXPECT_EQ(dir.list(), std::vector<std::string>{"sub"}) << "nothing is created by the checks";
}

TEST(AtomicFileTest, TheLongestNamesAreWrittenTheirTemporariesStayWithinTheLimit)
{
    test::ScratchDir dir;
    const std::string longest(255, 'x');
    EXPECT_LE(temporaryOutputName(dir / longest).filename().string().size(), kMaxFileNameBytes);
    EXPECT_LE(temporaryOutputName(dir / longest, ".tif").filename().string().size(), kMaxFileNameBytes);
    EXPECT_TRUE(temporaryOutputName(dir / longest, ".tif").string().ends_with(".tif"));
    EXPECT_NE(temporaryOutputName(dir / "a"), temporaryOutputName(dir / "a")) << "unique per call";
    ASSERT_TRUE(writeFileAtomically(dir / longest, std::vector<std::uint8_t>{1, 2, 3}).ok());
    EXPECT_EQ(readAll(dir / longest), std::string("\x01\x02\x03"));
}

TEST(AtomicFileTest, AFailedRenameSaysWhy)
{
    // The target becomes a non-empty directory between create and commit: the rename fails, and the message
    // keeps its reason (it said "Success": the temporary's removal overwrote the error).
    test::ScratchDir dir;
    auto file = AtomicFile::create(dir / "out");
    ASSERT_TRUE(file.ok()) << file.error().message;
    file->write("data", 4);
    std::filesystem::create_directories(dir / "out" / "inside");
    const Status committed = file->commit();
    ASSERT_FALSE(committed.ok());
    EXPECT_EQ(committed.error().message.find("Success"), std::string::npos) << committed.error().message;
    EXPECT_NE(committed.error().message.find("directory"), std::string::npos) << committed.error().message;
    EXPECT_EQ(dir.list(), std::vector<std::string>{"out"}) << "no temporary is left";
}

}  // namespace
}  // namespace terrain
