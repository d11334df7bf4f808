// Resident quadtree nodes as the runtime holds them (paper 3.2.14-3.2.15, 3.4.1): immutable once built,
// shared between the cache (render thread) and the workers that decode children from them.
#pragma once

#include "core/Expected.h"
#include "quadtree/NodeId.h"

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace terrain {

struct NodeData {
    NodeId id;
    bool isStatic = true;     ///< read from the map (false: synthesized, issue 5)
    bool hasChildren = false; ///< children can be loaded or synthesized
    float deltaC = 0.0f;      ///< nested error, metres (eq. 3.1)
    double zMin = 0.0;        ///< nested bounding box, metres (3.2.12)
    double zMax = 0.0;
    std::vector<std::uint16_t> heights;  ///< window of codes, (N + 4)^2, rows south to north
    std::vector<std::uint8_t> texture;   ///< T x T RGB, rows south to north
};

using NodePtr = std::shared_ptr<const NodeData>;
using ChildNodes = std::array<NodePtr, 4>;

/// Where nodes come from: the map (static) and, later, synthesis (dynamic).
class NodeSource {
public:
    virtual ~NodeSource() = default;
    virtual Expected<NodePtr> loadRoot() = 0;
    /// The four children of `parent` in NodeId::child() order. Called on worker threads, concurrently:
    /// implementations must be thread-safe. Errors name the file and node.
    virtual Expected<ChildNodes> loadChildren(const NodeData& parent) = 0;
};

}  // namespace terrain
