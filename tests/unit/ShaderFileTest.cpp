// Shader files with `#include "name"` (gpudata/ShaderFile.h, readShaderFile): the included text replaces the
// line, #line directives keep each file's own line numbers, and bad includes are errors naming the file and line.
// The shipped shaders that share the detail layers' code expand to one text each. No GL needed.
#include "gpudata/ShaderFile.h"

#include "TestSupport.h"

#include <gtest/gtest.h>

#include <fstream>

namespace terrain {
namespace {

void write(const std::filesystem::path& path, const std::string& text)
{
    std::ofstream out(path, std::ios::binary);
    out << text;
}

TEST(ShaderFileTest, IncludesAreReplacedByTheFileWithLineNumbersKept)
{
    test::ScratchDir dir;
    write(dir.path() / "common.glsl",
          "float twice(float x) { return 2.0 * x; }\nfloat half(float x) { return x / 2.0; }");
    write(dir.path() / "a.frag", "#version 330 core\n  #include \"common.glsl\"\nvoid main() {}\n");
    auto text = readShaderFile(dir.path() / "a.frag");
    ASSERT_TRUE(text.ok()) << text.error().message;
    EXPECT_EQ(*text,
              "#version 330 core\n"
              "#line 1\n"
              "float twice(float x) { return 2.0 * x; }\nfloat half(float x) { return x / 2.0; }\n"
              "#line 3\n"
              "void main() {}\n");
    // Without includes the text is the file's.
    write(dir.path() / "b.vert", "#version 330 core\nvoid main() {}\n");
    EXPECT_EQ(readShaderFile(dir.path() / "b.vert").value(), "#version 330 core\nvoid main() {}\n");
}

TEST(ShaderFileTest, BadIncludesNameTheFileAndLine)
{
    test::ScratchDir dir;
    const std::string file = (dir.path() / "a.frag").string();
    auto errorOf = [&](const std::string& text) {
        write(dir.path() / "a.frag", text);
        auto result = readShaderFile(dir.path() / "a.frag");
        EXPECT_FALSE(result.ok());
        return result.ok() ? std::string() : result.error().message;
    };
    std::string message = errorOf("#version 330 core\n\n#include \"missing.glsl\"\n");
    EXPECT_NE(message.find(file + ":3: "), std::string::npos) << message;
    EXPECT_NE(message.find("missing.glsl"), std::string::npos) << message;
    message = errorOf("#version 330 core\n#include common.glsl\n");
    EXPECT_NE(message.find(file + ":2: #include needs one quoted file name"), std::string::npos) << message;
    message = errorOf("#include \"\"\n");
    EXPECT_NE(message.find(file + ":1: "), std::string::npos) << message;
    message = errorOf("#include \"x.glsl\" trailing\n");
    EXPECT_NE(message.find(file + ":1: "), std::string::npos) << message;
    write(dir.path() / "outer.glsl", "#include \"inner.glsl\"\n");
    message = errorOf("#include \"outer.glsl\"\n");
    EXPECT_NE(message.find("outer.glsl: included from " + file + ":1, and includes another file"), std::string::npos)
        << message;
    EXPECT_FALSE(readShaderFile(dir.path() / "none.frag").ok());
}

TEST(ShaderFileTest, TheShippedProgramsShareTheDetailLayersCode)
{
    const std::filesystem::path shaders = TERRAIN_SHADER_DIR;
    auto detail = readShaderFile(shaders / "detail.glsl");
    ASSERT_TRUE(detail.ok()) << detail.error().message;
    for (const char* name : {"terrain.frag", "clipmap.frag"}) {
        auto text = readShaderFile(shaders / name);
        ASSERT_TRUE(text.ok()) << text.error().message;
        EXPECT_EQ(text->find("#include"), std::string::npos) << name;
        EXPECT_NE(text->find(*detail), std::string::npos) << name << " holds shaders/detail.glsl";
    }
}

}  // namespace
}  // namespace terrain
