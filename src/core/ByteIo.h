// Little-endian encoding of fixed-size fields into byte buffers, independent of the host's byte order.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace terrain {

/// Appends little-endian fields to a byte vector.
class ByteWriter {
public:
    explicit ByteWriter(std::vector<std::uint8_t>& out) : mOut(out) {}

    template <class T>
    void put(T value)
    {
        static_assert(std::is_arithmetic_v<T>);
        using U =
            std::conditional_t<sizeof(T) == 1, std::uint8_t,
                               std::conditional_t<sizeof(T) == 2, std::uint16_t,
                                                  std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;
        U bits = std::bit_cast<U>(value);
        for (std::size_t i = 0; i < sizeof(T); ++i) {
            mOut.push_back(static_cast<std::uint8_t>(bits >> (8 * i)));
        }
    }
    void putBytes(const void* data, std::size_t size)
    {
        const auto* p = static_cast<const std::uint8_t*>(data);
        mOut.insert(mOut.end(), p, p + size);
    }
    /// A string in exactly `size` bytes: truncated or zero-padded.
    void putFixedString(const std::string& s, std::size_t size)
    {
        for (std::size_t i = 0; i < size; ++i) {
            mOut.push_back(i < s.size() ? static_cast<std::uint8_t>(s[i]) : 0);
        }
    }
    void padTo(std::size_t size)
    {
        if (mOut.size() < size) {
            mOut.resize(size, 0);
        }
    }

private:
    std::vector<std::uint8_t>& mOut;
};

/// Reads little-endian fields from a byte span; reading past the end sets failed() and returns zeros.
class ByteReader {
public:
    explicit ByteReader(std::span<const std::uint8_t> in) : mIn(in) {}

    template <class T>
    T get()
    {
        static_assert(std::is_arithmetic_v<T>);
        using U =
            std::conditional_t<sizeof(T) == 1, std::uint8_t,
                               std::conditional_t<sizeof(T) == 2, std::uint16_t,
                                                  std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;
        if (mPos + sizeof(T) > mIn.size()) {
            mFailed = true;
            mPos = mIn.size();
            return T{};
        }
        U bits = 0;
        for (std::size_t i = 0; i < sizeof(T); ++i) {
            bits = static_cast<U>(bits | (static_cast<U>(mIn[mPos + i]) << (8 * i)));
        }
        mPos += sizeof(T);
        return std::bit_cast<T>(bits);
    }
    std::string getFixedString(std::size_t size)
    {
        std::string s;
        for (std::size_t i = 0; i < size; ++i) {
            auto c = get<std::uint8_t>();
            if (c != 0) {
                s.push_back(static_cast<char>(c));
            }
        }
        return s;
    }
    void skip(std::size_t size) { mPos = std::min(mIn.size(), mPos + size); }
    std::size_t position() const { return mPos; }
    bool failed() const { return mFailed; }

private:
    std::span<const std::uint8_t> mIn;
    std::size_t mPos = 0;
    bool mFailed = false;
};

}  // namespace terrain
