// A table-driven command-line parser (CommandLine.h).
#include "apps/CommandLine.h"

#include "core/Parse.h"

#include <algorithm>

namespace terrain {

namespace {

/// The column the help of every flag starts at.
constexpr std::size_t kHelpColumn = 23;

/// A negative number ("-500", "-1e3") is a value, not an option.
bool isNegativeNumber(const std::string& argument)
{
    return argument.size() > 1 && argument[0] == '-' && parseDouble(argument).ok();
}

std::string unitSuffix(std::string_view unit)
{
    return unit.empty() ? std::string() : " " + std::string(unit);
}

}  // namespace

Status CommandLine::parse(std::span<const std::string> arguments) const
{
    for (std::size_t i = 0; i < arguments.size(); ++i) {
        const std::string& argument = arguments[i];
        auto takePositional = [&]() -> Status {
            if (!positional) {
                return makeError("unexpected argument '", argument, "'");
            }
            return positional(argument);
        };
        if (argument.size() < 2 || argument[0] != '-' || isNegativeNumber(argument)) {
            TERRAIN_TRY(takePositional());
            continue;
        }
        const std::size_t equals = argument.starts_with("--") ? argument.find('=') : std::string::npos;
        const std::string name = argument.substr(0, equals);
        auto flag = std::find_if(flags.begin(), flags.end(), [&](const Flag& f) { return f.name == name; });
        if (flag == flags.end()) {
            if (passUnknown) {
                TERRAIN_TRY(takePositional());
                continue;
            }
            return makeError("unknown option '", argument, "'", unknownHint);
        }
        std::string value;
        if (equals != std::string::npos) {
            if (flag->value.empty() && !flag->optionalAttachedValue) {
                return makeError(name, " takes no value");
            }
            value = argument.substr(equals + 1);
            if (value.empty() && flag->optionalAttachedValue) {
                return makeError(name, "= needs a value after '='");
            }
        } else if (!flag->value.empty()) {
            if (i + 1 >= arguments.size()) {
                return makeError(name, " needs a value");
            }
            value = arguments[++i];
        }
        if (Status applied = flag->apply(value); !applied.ok()) {
            const std::string& message = applied.error().message;
            return message.starts_with(name + ": ") ? applied.error() : makeError(name, ": ", message);
        }
    }
    return {};
}

std::string CommandLine::help() const
{
    std::string text;
    for (const Flag& flag : flags) {
        std::string head = "  " + flag.name + (flag.value.empty() ? "" : " " + flag.value);
        head += head.size() + 2 <= kHelpColumn ? std::string(kHelpColumn - head.size(), ' ') : "  ";
        std::size_t at = 0;
        bool first = true;
        while (at <= flag.help.size()) {
            const std::size_t end = std::min(flag.help.find('\n', at), flag.help.size());
            text += (first ? head : std::string(kHelpColumn, ' ')) + flag.help.substr(at, end - at) + "\n";
            first = false;
            at = end + 1;
        }
    }
    return text;
}

Expected<double> numberIn(std::string_view text, double lo, double hi, std::string_view unit)
{
    auto value = parseDouble(text);
    if (!value.ok() || !(*value >= lo && *value <= hi)) {
        return makeError("'", text, "' is not a number in [", lo, ", ", hi, "]", unitSuffix(unit));
    }
    return value;
}

Expected<long long> wholeNumberIn(std::string_view text, long long lo, long long hi, std::string_view unit)
{
    auto value = parseInteger(text);
    if (!value.ok() || *value < lo || *value > hi) {
        return makeError("'", text, "' is not a whole number in [", lo, ", ", hi, "]", unitSuffix(unit));
    }
    return value;
}

Expected<std::pair<int, int>> sizeIn(std::string_view text, int lo, int hi)
{
    const std::size_t x = text.find('x');
    auto width = parseInteger(text.substr(0, x == std::string_view::npos ? 0 : x));
    auto height = parseInteger(x == std::string_view::npos ? std::string_view() : text.substr(x + 1));
    if (!width.ok() || !height.ok() || *width < lo || *width > hi || *height < lo || *height > hi) {
        return makeError("'", text, "' is not WIDTHxHEIGHT (", lo, " to ", hi, " pixels each)");
    }
    return std::pair{static_cast<int>(*width), static_cast<int>(*height)};
}

}  // namespace terrain
