// Quadtree node addresses (paper 3.2.1): a node at `level` covers cell (x, y) of a 2^level x 2^level
// partition of the terrain square; x grows east, y grows north; level 0 is the root.
#pragma once

#include <cstdint>
#include <string>

namespace terrain {

struct NodeId {
    /// Deepest level a NodeId can address: keys must fit 64 bits (static and dynamic nodes together).
    static constexpr int kMaxLevel = 30;

    int level = 0;
    std::uint32_t x = 0;
    std::uint32_t y = 0;

    static NodeId root() { return {}; }

    NodeId parent() const { return {level - 1, x >> 1, y >> 1}; }
    /// Child `quadrant` 0..3: bit 0 = east half, bit 1 = north half.
    NodeId child(int quadrant) const
    {
        return {level + 1, (x << 1) | static_cast<std::uint32_t>(quadrant & 1),
                (y << 1) | static_cast<std::uint32_t>(quadrant >> 1)};
    }
    /// Which quadrant of its parent this node is (see child()).
    int quadrant() const { return static_cast<int>((x & 1) | ((y & 1) << 1)); }
    bool isRoot() const { return level == 0; }

    /// Level-order index: all nodes of level k come after those of levels < k, row-major (y, then x)
    /// within a level. Sorting by key sorts by level, then y, then x.
    std::uint64_t key() const
    {
        std::uint64_t before = ((std::uint64_t{1} << (2 * level)) - 1) / 3;
        return before + (static_cast<std::uint64_t>(y) << level) + x;
    }

    /// "level/x/y", the form used in every message that names a node.
    std::string toString() const { return std::to_string(level) + "/" + std::to_string(x) + "/" + std::to_string(y); }

    friend bool operator==(const NodeId&, const NodeId&) = default;
};

}  // namespace terrain
