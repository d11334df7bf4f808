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

/// Maps signed to unsigned so that small magnitudes get small codes: 0, -1, 1, -2, ... -> 0, 1, 2, 3, ...
inline std::uint32_t zigzagEncode(std::int32_t v)
{
    return (static_cast<std::uint32_t>(v) << 1) ^ static_cast<std::uint32_t>(v >> 31);
}
inline std::int32_t zigzagDecode(std::uint32_t v)
{
    return static_cast<std::int32_t>(v >> 1) ^ -static_cast<std::int32_t>(v & 1);
}

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
    /// An unsigned LEB128 varint: 7 bits per byte, low bits first, high bit set on all but the last.
    void putVarint(std::uint32_t value)
    {
        while (value >= 0x80) {
            mOut.push_back(static_cast<std::uint8_t>(value | 0x80));
            value >>= 7;
        }
        mOut.push_back(static_cast<std::uint8_t>(value));
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
    /// Reads a varint of ByteWriter::putVarint into `value`; false (and failed()) when the bytes end first
    /// or the number does not fit 32 bits.
    bool getVarint(std::uint32_t& value)
    {
        value = 0;
        for (int shift = 0; shift <= 28; shift += 7) {
            if (mPos >= mIn.size()) {
                break;
            }
            const std::uint8_t byte = mIn[mPos++];
            value |= static_cast<std::uint32_t>(byte & 0x7f) << shift;
            if ((byte & 0x80) == 0) {
                return true;
            }
        }
        mFailed = true;
        return false;
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
