// Error values for "the world is wrong" failures (docs/design.md, "Errors", kind 3): a missing file, a corrupt
// map, a bad PNG, an out-of-range config value. They carry a message a user can act on. Reading the value
// of an error, or the error of a value, is a caller's bug: a checked precondition (core/Check.h), on in
// every build type.
#pragma once

#include "core/Check.h"

#include <sstream>
#include <string>
#include <utility>
#include <variant>

namespace terrain {

/// A user-facing error: what went wrong, where (file, line or node) and what was expected.
struct Error {
    std::string message;
};

/// Builds an Error from pieces streamed in order: `makeError(path, ": node ", id, ": bad checksum")`.
template <class... Args>
Error makeError(Args&&... args)
{
    std::ostringstream s;
    (s << ... << std::forward<Args>(args));
    return Error{s.str()};
}

/// Either a value or an Error. A small stand-in for C++23 std::expected. value() (and *, ->) requires
/// ok(); error() requires !ok().
template <class T>
class [[nodiscard]] Expected {
public:
    Expected(T value) : mData(std::in_place_index<0>, std::move(value)) {}
    Expected(Error error) : mData(std::in_place_index<1>, std::move(error)) {}

    bool ok() const { return mData.index() == 0; }
    explicit operator bool() const { return ok(); }

    T& value() &
    {
        TERRAIN_EXPECTS(ok(), "value() of an Expected that holds an error");
        return std::get<0>(mData);
    }
    const T& value() const&
    {
        TERRAIN_EXPECTS(ok(), "value() of an Expected that holds an error");
        return std::get<0>(mData);
    }
    T&& value() &&
    {
        TERRAIN_EXPECTS(ok(), "value() of an Expected that holds an error");
        return std::get<0>(std::move(mData));
    }
    T& operator*() & { return value(); }
    const T& operator*() const& { return value(); }
    T* operator->() { return &value(); }
    const T* operator->() const { return &value(); }

    const Error& error() const
    {
        TERRAIN_EXPECTS(!ok(), "error() of an Expected that holds a value");
        return std::get<1>(mData);
    }

private:
    std::variant<T, Error> mData;
};

/// Success or an Error, for operations without a result value. error() requires !ok().
class [[nodiscard]] Status {
public:
    Status() = default;
    Status(Error error) : mError(std::move(error)), mOk(false) {}

    bool ok() const { return mOk; }
    explicit operator bool() const { return mOk; }
    const Error& error() const
    {
        TERRAIN_EXPECTS(!mOk, "error() of a Status that is success");
        return mError;
    }

private:
    Error mError;
    bool mOk = true;
};

}  // namespace terrain

/// Propagates an Error from an Expected or Status expression out of the enclosing function.
#define TERRAIN_TRY(expr)                     \
    do {                                      \
        auto&& terrainTryResult_ = (expr);    \
        if (!terrainTryResult_.ok()) {        \
            return terrainTryResult_.error(); \
        }                                     \
    } while (false)
