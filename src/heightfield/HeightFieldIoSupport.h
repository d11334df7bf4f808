// Internal helpers shared by the height field readers and writers (not part of the layer's API):
// byte-order loads and stores, a positioned binary input file, and the checks every format makes.
#pragma once

#include "core/ByteIo.h"
#include "core/Expected.h"
#include "heightfield/HeightField.h"
#include "heightfield/HeightFieldIo.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace terrain::detail {

// ---- Byte order. Every format here fixes its byte order, so none of this depends on the host's. ----

/// A little-endian field at `p` (core/ByteIo.h's reader, for decoding at fixed offsets).
template <class T>
T loadLe(const std::uint8_t* p)
{
    return ByteReader(std::span<const std::uint8_t>(p, sizeof(T))).get<T>();
}

/// Big-endian 16-bit, as in PNG samples and big-endian raw files (ByteIo.h is little-endian only).
inline std::uint16_t loadU16Be(const std::uint8_t* p)
{
    return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}
inline void storeU16Be(std::uint8_t* p, std::uint16_t v)
{
    p[0] = static_cast<std::uint8_t>(v >> 8);
    p[1] = static_cast<std::uint8_t>(v);
}

// ---- Input. ----

/// A binary file opened for positioned reads. Errors name the path.
class InputFile {
public:
    /// Fails with "<path>: cannot open: <reason>" (missing, unreadable, a directory).
    static Expected<InputFile> open(const std::filesystem::path& path);

    const std::filesystem::path& path() const { return mPath; }
    std::uint64_t size() const { return mSize; }
    /// Reads exactly `size` bytes at `offset`; false on a short read or an I/O error.
    bool readAt(std::uint64_t offset, void* data, std::size_t size);

private:
    struct Closer {
        void operator()(std::FILE* file) const { std::fclose(file); }
    };
    std::unique_ptr<std::FILE, Closer> mFile;
    std::filesystem::path mPath;
    std::uint64_t mSize = 0;
};

/// Samples read per block by the streaming readers: bounds the temporary buffer whatever the grid size.
inline constexpr std::size_t kSamplesPerBlock = 1 << 16;

/// Streams `count` consecutive samples of `bytesPerSample` bytes starting at `offset`, calling
/// `decode(index, bytes)` for each in file order. False on a short read.
template <class Decode>
bool forEachSample(InputFile& file, std::uint64_t offset, std::uint64_t count, std::size_t bytesPerSample,
                   Decode&& decode)
{
    std::vector<std::uint8_t> block(std::min<std::uint64_t>(count, kSamplesPerBlock) * bytesPerSample);
    for (std::uint64_t first = 0; first < count; first += kSamplesPerBlock) {
        const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(kSamplesPerBlock, count - first));
        if (!file.readAt(offset + first * bytesPerSample, block.data(), n * bytesPerSample)) {
            return false;
        }
        for (std::size_t k = 0; k < n; ++k) {
            decode(first + k, block.data() + k * bytesPerSample);
        }
    }
    return true;
}

// ---- Checks shared by the formats. ----

/// Refuses (naming the file and size) a width x height grid whose float samples plus `extraBytes` of
/// temporary buffers cannot fit in the memory available now. Call before allocating the samples.
Status checkSampleMemory(const std::filesystem::path& path, std::uint64_t width, std::uint64_t height,
                         std::uint64_t extraBytes = 0);

/// Allocates field.samples for field.width x field.height (call checkSampleMemory first).
void allocateSamples(HeightField& field);

/// Turns samples equal to options.noData into NaN.
void applyNoData(HeightField& field, const HeightFieldReadOptions& options);

/// A writer's input check: width and height >= 1 and width * height samples.
Status checkFieldShape(const std::filesystem::path& path, const HeightField& field);

/// Fails when a sample is NaN and the format has no no-data marker; names the first such sample.
Status checkNoNaN(const std::filesystem::path& path, const HeightField& field, std::string_view format);

/// Rounds to nearest and clamps to [lo, hi]; the value must not be NaN.
inline double roundClamp(double value, double lo, double hi)
{
    return std::clamp(std::nearbyint(value), lo, hi);
}

/// A number for descriptions and messages: up to 6 significant digits, no trailing zeros ("30", "92.6").
std::string formatNumber(double value);

/// Printable text for a file's magic bytes or chunk marker: non-printable bytes as \xNN.
std::string printableBytes(const std::uint8_t* bytes, std::size_t size);

}  // namespace terrain::detail
