// Strict parsing of numbers from text (command lines, config files): the whole text must be the number;
// and the inverse, numbers as the shortest text that reads back exactly.
#pragma once

#include "core/Expected.h"

#include <charconv>
#include <cmath>
#include <cstdint>
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

/// `text` as a number in [lo, hi] for command-line option `option`; the error names both ("--tau: 'x' is not
/// a number in [0.01, 1000]"). NaN is out of every range.
inline Expected<double> parseNumberIn(std::string_view option, std::string_view text, double lo, double hi)
{
    auto v = parseDouble(text);
    if (!v.ok() || !(*v >= lo && *v <= hi)) {
        return makeError(option, ": '", text, "' is not a number in [", lo, ", ", hi, "]");
    }
    return v;
}

/// A byte count: a decimal number with an optional suffix K, M or G (powers of 1024, either case), e.g.
/// "256M", "1.5G", "4096". Fails on anything else, on 0 and on more than 2^62 bytes.
inline Expected<std::uint64_t> parseByteSize(std::string_view text)
{
    double unit = 1.0;
    std::string_view number = text;
    if (!text.empty()) {
        switch (text.back()) {
            case 'k':
            case 'K':
                unit = 1024.0;
                break;
            case 'm':
            case 'M':
                unit = 1024.0 * 1024.0;
                break;
            case 'g':
            case 'G':
                unit = 1024.0 * 1024.0 * 1024.0;
                break;
            default:
                break;
        }
        if (unit > 1.0) {
            number.remove_suffix(1);
        }
    }
    auto value = parseDouble(number);
    if (!value.ok() || !(*value * unit >= 1.0) || !(*value * unit <= std::ldexp(1.0, 62))) {
        return makeError("'", text, "' is not a size in bytes (a number with an optional K, M or G, e.g. 256M)");
    }
    return static_cast<std::uint64_t>(*value * unit);
}

/// The shortest text that parses back to exactly `value`; plain decimals ("200000", not "2e+05") for
/// everyday magnitudes (1e-4 <= |value| < 1e15), scientific notation otherwise.
inline std::string formatNumber(double value)
{
    char buffer[64];
    const double magnitude = std::fabs(value);
    const bool plain = magnitude == 0 || (magnitude >= 1e-4 && magnitude < 1e15);
    auto [end, ec] = plain ? std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::fixed)
                           : std::to_chars(buffer, buffer + sizeof buffer, value);
    return ec == std::errc() ? std::string(buffer, end) : std::string("nan");
}

/// The same for a float: the shortest text that parses back to exactly this float.
inline std::string formatNumber(float value)
{
    char buffer[64];
    auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
    return ec == std::errc() ? std::string(buffer, end) : std::string("nan");
}

}  // namespace terrain
