// The `option = value` reader (paper 4.3, Appendix A). Syntax rules are in ConfigFile.h.
#include "core/ConfigFile.h"

#include <fstream>
#include <sstream>

namespace terrain {
namespace {

constexpr std::string_view kWhitespace = " \t\r\f\v";

std::string_view trim(std::string_view s)
{
    std::size_t first = s.find_first_not_of(kWhitespace);
    if (first == std::string_view::npos) {
        return {};
    }
    std::size_t last = s.find_last_not_of(kWhitespace);
    return s.substr(first, last - first + 1);
}

bool isKeyCharacter(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
           c == '.';
}

std::string location(const std::string& file, int line)
{
    return line > 0 ? file + ":" + std::to_string(line) : file;
}

}  // namespace

std::string ConfigEntry::location() const
{
    return terrain::location(file, line);
}

Expected<ConfigEntry> ConfigFile::parseEntry(std::string_view text, std::string file, int lineNumber)
{
    const std::string where = location(file, lineNumber);
    std::string_view line = trim(text);
    std::size_t equals = line.find('=');
    std::size_t hash = line.find('#');
    if (equals == std::string_view::npos || (hash != std::string_view::npos && hash < equals)) {
        std::string_view content = trim(line.substr(0, hash));
        if (content.empty()) {
            return makeError(where, ": expected 'key = value', found nothing");
        }
        return makeError(where, ": expected 'key = value', found '", content, "' (no '=')");
    }

    std::string_view key = trim(line.substr(0, equals));
    if (key.empty()) {
        return makeError(where, ": empty key before '='");
    }
    for (char c : key) {
        if (!isKeyCharacter(c)) {
            return makeError(where, ": key '", key, "' contains '", c, "'; keys are letters, digits, '_', '-' and '.'");
        }
    }

    std::string_view rest = trim(line.substr(equals + 1));
    std::string_view value;
    if (!rest.empty() && rest.front() == '"') {
        std::size_t close = rest.find('"', 1);
        if (close == std::string_view::npos) {
            return makeError(where, ": unterminated quote in the value of '", key, "'");
        }
        value = rest.substr(1, close - 1);
        std::string_view after = trim(rest.substr(close + 1));
        if (!after.empty() && after.front() != '#') {
            return makeError(where, ": unexpected text '", after, "' after the closing quote of '", key, "'");
        }
    } else {
        value = trim(rest.substr(0, rest.find('#')));
    }
    return ConfigEntry{std::string(key), std::string(value), std::move(file), lineNumber};
}

Expected<ConfigFile> ConfigFile::parse(std::string_view text, std::string name)
{
    constexpr std::string_view kByteOrderMark = "\xEF\xBB\xBF";
    if (text.starts_with(kByteOrderMark)) {
        text.remove_prefix(kByteOrderMark.size());
    }
    ConfigFile config;
    int lineNumber = 0;
    while (!text.empty()) {
        std::size_t end = text.find('\n');
        std::string_view line = text.substr(0, end);
        text.remove_prefix(end == std::string_view::npos ? text.size() : end + 1);
        ++lineNumber;
        std::string_view content = trim(line);
        if (content.empty() || content.front() == '#') {
            continue;
        }
        auto entry = parseEntry(content, name, lineNumber);
        TERRAIN_TRY(entry);
        config.mEntries.push_back(std::move(entry).value());
    }
    config.mName = std::move(name);
    return config;
}

Expected<ConfigFile> ConfigFile::load(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        return makeError(path.string(), ": cannot open configuration file");
    }
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) {
        return makeError(path.string(), ": read error");
    }
    auto config = parse(text.str(), path.string());
    TERRAIN_TRY(config);
    config->mDirectory = path.parent_path();
    return config;
}

const ConfigEntry* ConfigFile::find(std::string_view key) const
{
    for (auto it = mEntries.rbegin(); it != mEntries.rend(); ++it) {
        if (it->key == key) {
            return &*it;
        }
    }
    return nullptr;
}

}  // namespace terrain
