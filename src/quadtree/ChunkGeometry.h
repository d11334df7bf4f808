// The size rules of chunks and their windows (paper 3.2.9, 3.4.3 "Borders"; docs/map-format.md): the one
// definition the map format, the builder, synthesis, the renderer and the apps share.
//
// A node holds N x N samples, N = 2^k + 1 (the chunk size), so a parent's samples are exactly its children's
// even samples. Its heights are kept as a window of W = N + 2 kBorder samples per side, the border being
// used only by subdivision.
#pragma once

#include <cstdint>

namespace terrain {

/// Samples of border kept on every side of a node's heights, used by subdivision (3.4.3 "Borders"):
/// the 4-point rule needs two parent samples beyond a child's edge to produce the child's own border.
/// Even, so a window index has the parity of the sample it holds.
inline constexpr int kBorder = 2;
static_assert(kBorder % 2 == 0, "window index parity must equal sample parity");

/// The largest chunk size N a map may have (and so the builder, synthesis and the template mesh accept).
inline constexpr int kMaxChunkSize = 1025;
/// The largest node texture size T a map may have.
inline constexpr int kMaxTextureSize = 4097;

/// True when `n` is 2^k with k >= 0.
constexpr bool isPowerOfTwo(std::int64_t n)
{
    return n > 0 && (n & (n - 1)) == 0;
}

/// True when `n` is 2^k + 1 with k >= 1 (3, 5, 9, 17, ...): the rule for chunk and texture sizes.
constexpr bool isPowerOfTwoPlusOne(std::int64_t n)
{
    return n >= 3 && ((n - 1) & (n - 2)) == 0;
}

/// True when `chunkSize` is a valid N: 2^k + 1 in [3, kMaxChunkSize].
constexpr bool isValidChunkSize(std::int64_t chunkSize)
{
    return isPowerOfTwoPlusOne(chunkSize) && chunkSize <= kMaxChunkSize;
}

/// W = N + 2 * kBorder: samples per side of the window of a node of chunk size N.
constexpr int windowSize(int chunkSize)
{
    return chunkSize + 2 * kBorder;
}

/// Triangles the renderer draws per node of chunk size N: the (N - 1)^2 quads as two triangles each and a
/// skirt of two triangles under each of the 4 (N - 1) edge segments (the template mesh, 3.2.6, 3.2.9).
constexpr std::int64_t trianglesPerChunk(int chunkSize)
{
    const std::int64_t cells = chunkSize - 1;
    return 2 * cells * cells + 8 * cells;
}

}  // namespace terrain
