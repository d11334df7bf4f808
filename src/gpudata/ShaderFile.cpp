// Shader files with their includes (ShaderFile.h).
#include "gpudata/ShaderFile.h"

#include <fstream>
#include <sstream>

namespace terrain {

namespace {

Expected<std::string> readText(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        return makeError(path.string(), ": cannot read shader");
    }
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

}  // namespace

Expected<std::string> readShaderFile(const std::filesystem::path& file)
{
    auto text = readText(file);
    TERRAIN_TRY(text);
    std::istringstream lines(*text);
    std::string out, line;
    int number = 0;
    while (std::getline(lines, line)) {
        ++number;
        const auto first = line.find_first_not_of(" \t");
        if (first == std::string::npos || line.compare(first, 8, "#include") != 0) {
            out += line + "\n";
            continue;
        }
        const auto open = line.find('"', first + 8);
        const auto close = open == std::string::npos ? open : line.find('"', open + 1);
        if (close == std::string::npos || close == open + 1 ||
            line.find_first_not_of(" \t", close + 1) != std::string::npos) {
            return makeError(file.string(), ":", number, ": #include needs one quoted file name, as #include \"name\"");
        }
        const std::filesystem::path included = file.parent_path() / line.substr(open + 1, close - open - 1);
        auto inner = readText(included);
        if (!inner.ok()) {
            return makeError(file.string(), ":", number, ": ", inner.error().message);
        }
        if (inner->find("#include") != std::string::npos) {
            return makeError(included.string(), ": included from ", file.string(), ":", number,
                             ", and includes another file (one level only)");
        }
        // The included lines count from 1; after them the file's own numbering resumes.
        out += "#line 1\n" + *inner + (inner->empty() || inner->back() == '\n' ? "" : "\n") + "#line " +
               std::to_string(number + 1) + "\n";
    }
    return out;
}

}  // namespace terrain
