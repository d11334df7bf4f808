// The size rules of chunks and windows (quadtree/ChunkGeometry.h) that the map format, the builder,
// synthesis, the template mesh and the viewer's options all use.
#include "quadtree/ChunkGeometry.h"

#include <gtest/gtest.h>

namespace terrain {
namespace {

TEST(ChunkGeometry, PowerOfTwoPlusOne)
{
    struct Case {
        std::int64_t n;
        bool expected;
    };
    const Case cases[] = {{-1, false},
                          {0, false},
                          {1, false},
                          {2, false},
                          {3, true},
                          {4, false},
                          {5, true},
                          {6, false},
                          {9, true},
                          {65, true},
                          {66, false},
                          {1024, false},
                          {1025, true},
                          {2049, true},
                          {4097, true},
                          {4096, false},
                          {std::int64_t{1} << 40, false},
                          {(std::int64_t{1} << 40) + 1, true}};
    for (const Case& c : cases) {
        EXPECT_EQ(isPowerOfTwoPlusOne(c.n), c.expected) << c.n;
    }
}

TEST(ChunkGeometry, ValidChunkSizesAre2kPlus1UpTo1025)
{
    struct Case {
        int chunkSize;
        bool valid;
    };
    const Case cases[] = {{-1, false}, {0, false}, {1, false}, {2, false},    {3, true},    {4, false},   {5, true},
                          {6, false},  {9, true},  {65, true}, {1024, false}, {1025, true}, {2049, false}};
    for (const Case& c : cases) {
        EXPECT_EQ(isValidChunkSize(c.chunkSize), c.valid) << c.chunkSize;
    }
    EXPECT_EQ(kMaxChunkSize, 1025);
    EXPECT_TRUE(isPowerOfTwoPlusOne(kMaxTextureSize));
}

TEST(ChunkGeometry, WindowsHaveATwoSampleBorder)
{
    // 3.4.3 "Borders": the 4-point rule reaches two parent samples past a child's edge. Stored maps depend
    // on this value (the header records it), so changing it is a format change.
    EXPECT_EQ(kBorder, 2);
    EXPECT_EQ(windowSize(3), 7);
    EXPECT_EQ(windowSize(65), 69);
}

}  // namespace
}  // namespace terrain
