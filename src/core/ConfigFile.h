// The `option = value` text format of configuration files (paper 4.3 and Appendix A) and material files.
// This is only the syntax; what the keys mean belongs to whoever reads them (apps/TengineOptions.h).
//
// Syntax, one entry per line:
//     # a comment: from '#' to the end of the line, on a line of its own or after an entry
//     key = value              whitespace around key and value is trimmed
//     key = "value # kept"     double quotes keep spaces and '#'; no escapes, so no '"' inside
//     key =                    an empty value
// Keys are letters, digits, '_', '-' and '.'. The value is everything after the first '='. A key may
// appear more than once; entries keep file order, so applying them in order lets the later one win.
// Lines may end in "\n" or "\r\n"; a UTF-8 byte order mark at the start is skipped.
#pragma once

#include "core/Expected.h"

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace terrain {

/// One `key = value` line and where it came from, for messages.
struct ConfigEntry {
    std::string key;
    std::string value;  ///< trimmed, quotes removed
    std::string file;   ///< the name given to parse() or the path given to load()
    int line = 0;       ///< 1-based; 0 when the entry did not come from a numbered line (`--set`)

    /// "file:line" (or "file" when line is 0): the prefix of every message about this entry.
    std::string location() const;
};

class ConfigFile {
public:
    /// Parses `text`; `name` (usually the path) names the source in entries and in errors, which read
    /// "name:line: what is wrong" (no '=', empty key, bad character in key, unterminated quote, text
    /// after a closing quote).
    static Expected<ConfigFile> parse(std::string_view text, std::string name);
    /// Reads and parses the file at `path`; directory() is then the file's directory.
    static Expected<ConfigFile> load(const std::filesystem::path& path);

    /// Parses one `key = value` line on its own; errors read "file:line: ..." ("file: ..." when `line`
    /// is 0). A blank or comment-only line is an error here ("expected key = value").
    static Expected<ConfigEntry> parseEntry(std::string_view line, std::string file, int lineNumber);

    /// The source's name as given to parse() or load().
    const std::string& name() const { return mName; }
    /// The directory of the file given to load(); empty for parse(). Relative paths inside the file can be
    /// resolved against it.
    const std::filesystem::path& directory() const { return mDirectory; }
    /// All entries in file order, duplicates included.
    const std::vector<ConfigEntry>& entries() const { return mEntries; }
    /// The last entry with `key`, or nullptr.
    const ConfigEntry* find(std::string_view key) const;

private:
    std::string mName;
    std::filesystem::path mDirectory;
    std::vector<ConfigEntry> mEntries;
};

}  // namespace terrain
