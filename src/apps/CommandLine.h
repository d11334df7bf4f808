// The command lines of prep and tengine-tool's subcommands, declared as tables: each flag with its name, the
// name of its value (none for a switch), its help text and what applies its value; positional arguments go
// to a function of their own. The parser names the flag in every error ("--memory: '0' is not a size in
// bytes ...", "-h needs a value", "unknown option '--bogus'"), and --help's list of flags is generated from
// the same table. tengine's own command line is config-style (TengineOptions.cpp's option table).
#pragma once

#include "core/Expected.h"

#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace terrain {

/// One flag of a command line.
struct Flag {
    std::string name;   ///< as typed: "--memory", "-h"
    std::string value;  ///< the value's name in the help ("SIZE"); empty: a switch, which takes no value
    std::string help;   ///< lines of help, '\n' between them
    /// Applies the flag with its value ("" for a switch). An error says what was expected and what was found;
    /// the parser puts "NAME: " before it unless it starts so already.
    std::function<Status(const std::string& value)> apply;
    /// A switch that also takes a value spelled --name=VALUE (tengine-tool error's --oracle and --oracle=B).
    bool optionalAttachedValue = false;
};

/// A command line: its flags and what takes the other arguments.
struct CommandLine {
    std::vector<Flag> flags;
    /// Takes each positional argument in order: one not starting with '-', "-" alone, or a negative number.
    /// Null: a positional argument is an error.
    std::function<Status(const std::string& argument)> positional;
    /// Added to the error for an unknown option, e.g. " (see prep --help)".
    std::string unknownHint;
    /// Unknown options go to `positional` too (a first pass that takes the flags common to subcommands).
    bool passUnknown = false;

    /// Applies `arguments` in order: "NAME VALUE" or "NAME=VALUE" for a flag with a value (a value may start
    /// with '-'), "NAME" for a switch (or "NAME=VALUE", VALUE not empty, with optionalAttachedValue). Stops at
    /// the first error: "NAME needs a value", "NAME takes no value", "NAME= needs a value after '='",
    /// "unknown option 'ARG'" + unknownHint, "unexpected argument 'ARG'" without `positional`, a flag's own
    /// error after "NAME: ", and what `positional` returns.
    Status parse(std::span<const std::string> arguments) const;

    /// The flags' help in table order: "  NAME VALUE" padded to 23 columns (longer ones get two spaces), then
    /// the help's first line; its further lines indented 23 columns. Ends with a newline.
    std::string help() const;
};

/// `text` as a number in [lo, hi]; the error (for Flag::apply) is "'TEXT' is not a number in [LO, HI]",
/// then " UNIT" where a unit is given. NaN, infinities, empty text and trailing characters are refused.
Expected<double> numberIn(std::string_view text, double lo, double hi, std::string_view unit = {});

/// `text` as a whole number in [lo, hi]: "'TEXT' is not a whole number in [LO, HI]", then " UNIT".
Expected<long long> wholeNumberIn(std::string_view text, long long lo, long long hi, std::string_view unit = {});

/// `text` as WIDTHxHEIGHT pixels, each a whole number in [lo, hi]: "'TEXT' is not WIDTHxHEIGHT (LO to HI pixels
/// each)".
Expected<std::pair<int, int>> sizeIn(std::string_view text, int lo, int hi);

}  // namespace terrain
