#include "lod/StaticNodeSource.h"

namespace terrain {

Expected<NodePtr> StaticNodeSource::load(const NodeId& id, const std::vector<std::uint16_t>& parentHeights) const
{
    auto node = mMap.loadNode(id, parentHeights);
    TERRAIN_TRY(node);
    const DirectoryEntry* entry = mMap.find(id);
    auto data = std::make_shared<NodeData>();
    data->id = id;
    data->isStatic = true;
    data->hasChildren = entry->hasChildren;
    data->deltaC = entry->deltaC;
    data->zMin = mMap.header().heightOf(entry->minCode);
    data->zMax = mMap.header().heightOf(entry->maxCode);
    data->heights = std::move(node->heights);
    data->texture = std::move(node->texture);
    return NodePtr(std::move(data));
}

Expected<NodePtr> StaticNodeSource::loadRoot() { return load(NodeId::root(), {}); }

Expected<ChildNodes> StaticNodeSource::loadChildren(const NodeData& parent)
{
    if (!parent.hasChildren) {
        return makeError(mMap.name(), ": node ", parent.id.toString(), " has no static children");
    }
    ChildNodes children;
    for (int q = 0; q < 4; ++q) {
        auto child = load(parent.id.child(q), parent.heights);
        TERRAIN_TRY(child);
        children[static_cast<std::size_t>(q)] = std::move(child.value());
    }
    return children;
}

}  // namespace terrain
