// Error values (core/Expected.h): an Expected holds a value or an Error, a Status success or an Error, and
// reading the wrong one is a checked precondition that stops the program in every build type (this suite
// is usually built with NDEBUG, where assert would do nothing).
#include "core/Expected.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>

namespace terrain {
namespace {

Expected<int> parsePositive(int v)
{
    if (v <= 0) {
        return makeError("value ", v, " is not positive");
    }
    return v;
}

Status twice(int v, int& out)
{
    auto parsed = parsePositive(v);
    TERRAIN_TRY(parsed);
    out = 2 * *parsed;
    return {};
}

TEST(Expected, HoldsAValueOrAnError)
{
    const Expected<int> good = parsePositive(3);
    ASSERT_TRUE(good.ok());
    EXPECT_EQ(good.value(), 3);
    EXPECT_EQ(*good, 3);
    const Expected<int> bad = parsePositive(-2);
    ASSERT_FALSE(bad.ok());
    EXPECT_FALSE(static_cast<bool>(bad));
    EXPECT_EQ(bad.error().message, "value -2 is not positive");
    Expected<std::unique_ptr<int>> owned(std::make_unique<int>(7));
    std::unique_ptr<int> taken = std::move(owned).value();
    EXPECT_EQ(*taken, 7);
}

TEST(Expected, TryPropagatesTheError)
{
    int out = 0;
    EXPECT_TRUE(twice(4, out).ok());
    EXPECT_EQ(out, 8);
    const Status failed = twice(0, out);
    ASSERT_FALSE(failed.ok());
    EXPECT_EQ(failed.error().message, "value 0 is not positive");
    EXPECT_EQ(out, 8);
}

TEST(ExpectedDeathTest, ValueOfAnErrorStops)
{
    const Expected<int> bad = parsePositive(-1);
    EXPECT_DEATH((void)bad.value(), "precondition failed.*value\\(\\) of an Expected that holds an error");
    EXPECT_DEATH((void)*bad, "value\\(\\) of an Expected that holds an error");
    Expected<std::string> badString = makeError("no");
    EXPECT_DEATH((void)badString->size(), "value\\(\\) of an Expected that holds an error");
    EXPECT_DEATH((void)std::move(badString).value(), "value\\(\\) of an Expected that holds an error");
}

TEST(ExpectedDeathTest, ErrorOfAValueStops)
{
    const Expected<int> good = parsePositive(1);
    EXPECT_DEATH((void)good.error(), "precondition failed.*error\\(\\) of an Expected that holds a value");
}

TEST(ExpectedDeathTest, ErrorOfASuccessfulStatusStops)
{
    const Status success;
    EXPECT_DEATH((void)success.error(), "precondition failed.*error\\(\\) of a Status that is success");
}

}  // namespace
}  // namespace terrain
