// Static nodes: read and decoded from the .map (3.2.14).
#pragma once

#include "lod/NodeData.h"
#include "quadtree/MapFile.h"

namespace terrain {

class StaticNodeSource final : public NodeSource {
public:
    /// `map` must outlive the source.
    explicit StaticNodeSource(const MapFile& map) : mMap(map) {}

    Expected<NodePtr> loadRoot() override;
    /// Fails for a node without static children (a static leaf).
    Expected<ChildNodes> loadChildren(const NodeData& parent) override;

private:
    Expected<NodePtr> load(const NodeId& id, const std::vector<std::uint16_t>& parentHeights) const;

    const MapFile& mMap;
};

}  // namespace terrain
