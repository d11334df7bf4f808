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

}  // namespace
}  // namespace terrain
