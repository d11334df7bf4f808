// `tengine-tool verify`: every check a map can be put through without its source.
#pragma once

#include "quadtree/MapFile.h"

#include <functional>
#include <string>
#include <vector>

namespace terrain {

/// Reads and decodes every node (parents before children) and checks: payload checksums and streams;
/// bounding boxes equal the decoded heights nested over the subtree (3.2.12); delta_m equals the error
/// recomputed from the decoded parent and children; delta_c nests (eq. 3.1) and leaves have none; from
/// version 2, detail_delta_c nests the same way over the leaves' estimated detail errors (3.4.1), which are
/// finite and >= 0, and detail_delta_c >= delta_c everywhere. Returns one line per problem, each naming the
/// node; empty when the map is sound. `progress` gets the fraction of nodes done.
std::vector<std::string> verifyMap(const MapFile& map, const std::function<void(double)>& progress = {});

}  // namespace terrain
