// The `option = value` reader (paper 4.3): entries with their file and line, comments, quoting, and a
// "file:line: what is wrong" error for every kind of bad line.
#include "TestSupport.h"
#include "core/ConfigFile.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

namespace terrain {
namespace {

ConfigFile parseOk(std::string_view text, const std::string& name = "test.cfg")
{
    auto config = ConfigFile::parse(text, name);
    EXPECT_TRUE(config.ok()) << (config.ok() ? "" : config.error().message);
    return config.ok() ? std::move(config).value() : ConfigFile::parse("", name).value();
}

TEST(ConfigFile, EntriesKeepKeyValueFileAndLine)
{
    ConfigFile config = parseOk(
        "# a comment\n"
        "\n"
        "lod_error = 2.5\n"
        "   camera_fov=45   \n"
        "\tmap_file\t=\tdata/terrain.map\t# trailing comment\n"
        "log_file =\n"
        "    # indented comment\n"
        "image_path = \"my frames # 1\"   # comment after a quote\n"
        "title = a = b\n");
    ASSERT_EQ(config.entries().size(), 6u);
    struct Want {
        const char* key;
        const char* value;
        int line;
    };
    const Want want[] = {{"lod_error", "2.5", 3},
                         {"camera_fov", "45", 4},
                         {"map_file", "data/terrain.map", 5},
                         {"log_file", "", 6},
                         {"image_path", "my frames # 1", 8},
                         {"title", "a = b", 9}};
    for (std::size_t i = 0; i < std::size(want); ++i) {
        SCOPED_TRACE(want[i].key);
        const ConfigEntry& e = config.entries()[i];
        EXPECT_EQ(e.key, want[i].key);
        EXPECT_EQ(e.value, want[i].value);
        EXPECT_EQ(e.line, want[i].line);
        EXPECT_EQ(e.file, "test.cfg");
        EXPECT_EQ(e.location(), "test.cfg:" + std::to_string(want[i].line));
    }
    EXPECT_EQ(config.name(), "test.cfg");
    EXPECT_TRUE(config.directory().empty());
}

TEST(ConfigFile, EmptyAndCommentOnlyTextsHaveNoEntries)
{
    for (const char* text : {"", "\n", "   \n\t\n", "# only\n  # comments\n", "#no newline at end"}) {
        SCOPED_TRACE(text);
        EXPECT_TRUE(parseOk(text).entries().empty());
    }
}

TEST(ConfigFile, QuotesKeepSpacesAndHashesAndMayBeEmpty)
{
    ConfigFile config = parseOk("a = \"  padded  \"\nb = \"\"\nc = \"x#y\"#z\nd = say \"hi\" # unquoted\n");
    ASSERT_EQ(config.entries().size(), 4u);
    EXPECT_EQ(config.entries()[0].value, "  padded  ");
    EXPECT_EQ(config.entries()[1].value, "");
    EXPECT_EQ(config.entries()[2].value, "x#y");
    // A quote that does not open the value is an ordinary character.
    EXPECT_EQ(config.entries()[3].value, "say \"hi\"");
}

TEST(ConfigFile, WindowsLineEndingsAndByteOrderMark)
{
    ConfigFile config = parseOk("\xEF\xBB\xBFkey = value\r\n# c\r\nother = 2\r\n");
    ASSERT_EQ(config.entries().size(), 2u);
    EXPECT_EQ(config.entries()[0].key, "key");
    EXPECT_EQ(config.entries()[0].value, "value");
    EXPECT_EQ(config.entries()[1].value, "2");
    EXPECT_EQ(config.entries()[1].line, 3);
}

TEST(ConfigFile, DuplicateKeysAreKeptInOrderAndFindReturnsTheLast)
{
    ConfigFile config = parseOk("lod_error = 1\nother = x\nlod_error = 3\n");
    ASSERT_EQ(config.entries().size(), 3u);
    const ConfigEntry* e = config.find("lod_error");
    ASSERT_NE(e, nullptr);
    EXPECT_EQ(e->value, "3");
    EXPECT_EQ(e->line, 3);
    EXPECT_EQ(config.find("missing"), nullptr);
}

TEST(ConfigFile, SyntaxErrorsNameFileLineAndProblem)
{
    struct Case {
        const char* text;
        const char* message;
    };
    const Case cases[] = {
        {"lod_error 2\n", "bad.cfg:1: expected 'key = value', found 'lod_error 2' (no '=')"},
        {"a = 1\n\n  just words  # comment\n", "bad.cfg:3: expected 'key = value', found 'just words' (no '=')"},
        {"a # = 1\n", "bad.cfg:1: expected 'key = value', found 'a' (no '=')"},
        {"= 5\n", "bad.cfg:1: empty key before '='"},
        {"a = 1\n   = \n", "bad.cfg:2: empty key before '='"},
        {"lod error = 2\n", "bad.cfg:1: key 'lod error' contains ' '; keys are letters, digits, '_', '-' and '.'"},
        {"k\"ey = 2\n", "bad.cfg:1: key 'k\"ey' contains '\"'; keys are letters, digits, '_', '-' and '.'"},
        {"x = 1\ny = \"open\n", "bad.cfg:2: unterminated quote in the value of 'y'"},
        {"path = \"a b\" c\n", "bad.cfg:1: unexpected text 'c' after the closing quote of 'path'"},
        {"a = 1\r\nb\r\n", "bad.cfg:2: expected 'key = value', found 'b' (no '=')"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.text);
        auto config = ConfigFile::parse(c.text, "bad.cfg");
        ASSERT_FALSE(config.ok());
        EXPECT_EQ(config.error().message, c.message);
    }
}

TEST(ConfigFile, ParseEntryWithoutLineNumberNamesOnlyTheSource)
{
    auto entry = ConfigFile::parseEntry("lod_error=3", "--set", 0);
    ASSERT_TRUE(entry.ok()) << entry.error().message;
    EXPECT_EQ(entry->key, "lod_error");
    EXPECT_EQ(entry->value, "3");
    EXPECT_EQ(entry->location(), "--set");

    auto bad = ConfigFile::parseEntry("lod_error", "--set", 0);
    ASSERT_FALSE(bad.ok());
    EXPECT_EQ(bad.error().message, "--set: expected 'key = value', found 'lod_error' (no '=')");
    auto empty = ConfigFile::parseEntry("  # nothing", "--set", 0);
    ASSERT_FALSE(empty.ok());
    EXPECT_EQ(empty.error().message, "--set: expected 'key = value', found nothing");
}

TEST(ConfigFile, LoadReadsAFileAndRemembersItsDirectory)
{
    test::ScratchDir dir;
    std::filesystem::path path = dir / "view.cfg";
    std::ofstream(path) << "camera_fov = 50\n# c\nbroken\n";
    auto bad = ConfigFile::load(path);
    ASSERT_FALSE(bad.ok());
    EXPECT_EQ(bad.error().message, path.string() + ":3: expected 'key = value', found 'broken' (no '=')");

    std::ofstream(path) << "camera_fov = 50\n";
    auto config = ConfigFile::load(path);
    ASSERT_TRUE(config.ok()) << config.error().message;
    EXPECT_EQ(config->name(), path.string());
    EXPECT_EQ(config->directory(), dir.path());
    ASSERT_EQ(config->entries().size(), 1u);
    EXPECT_EQ(config->entries()[0].location(), path.string() + ":1");
}

TEST(ConfigFile, LoadOfAMissingFileIsAnError)
{
    test::ScratchDir dir;
    auto config = ConfigFile::load(dir / "missing.cfg");
    ASSERT_FALSE(config.ok());
    EXPECT_EQ(config.error().message, (dir / "missing.cfg").string() + ": cannot open configuration file");
}

}  // namespace
}  // namespace terrain
