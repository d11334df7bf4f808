// Strict parsing of numbers from text (command lines, config files): the whole text must be the number.
#pragma once

#include "core/Expected.h"

#include <charconv>
#include <cmath>
#include <string>
#include <string_view>

namespace terrain {

/// Parses a finite decimal number; fails on empty text, trailing characters, NaN or infinity.
inline Expected<double> parseDouble(std::string_view text)
{
    double value = 0;
    auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || ec != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
        return makeError("'", text, "' is not a number");
    }
    return value;
}

/// Parses a decimal integer; fails on empty text, trailing characters or overflow.
inline Expected<long long> parseInteger(std::string_view text)
{
    long long value = 0;
    auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || ec != std::errc() || end != text.data() + text.size()) {
        return makeError("'", text, "' is not an integer");
    }
    return value;
}

}  // namespace terrain
