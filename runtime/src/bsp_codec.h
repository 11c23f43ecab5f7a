// The level file's packed form of a cell grid's BSP nodes (CGR4, docs/level_format.md). Internal to the
// runtime (level_io.cpp).
//
// buildCellGrid lays each cell's tree out in preorder (a node, its under subtree, its over subtree) and the
// trees one after another, and cuts every split plane from a tet face. So a node needs no index and no plane:
// it is the face it was cut from and what its two children are. The stream holds, per node in array order,
// one LEB128 varint
//   zigzag(faceTet - previous node's faceTet) << 6 | face << 4 | code(child[0]) << 2 | code(child[1])
// (the first node's previous faceTet is 0), where a child's code is
//   0  a node: the next node in preorder,
//   1  the leaf naming faceTet itself,
//   2  the leaf naming the tet across that face (the neighbour linkTetNeighbours derives on load),
//   3  a leaf given by a second varint: 0 for kEmptyLeaf, else zigzag(leafTet - faceTet) + 1.
// On the shared levels a node takes about 3 bytes (24 as BspNode, 12 as CGR3 did). The planes are recomputed
// with cellGridFacePlane, the same floats the build stored.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "tetraprobe/runtime/cell_grid.h"
#include "tetraprobe/runtime/level.h"

namespace tetraprobe::runtime_detail {

// Appends the stream of `nodes` to `out`. faces[n] = tet << 2 | face: the face whose cellGridFacePlane is
// node n's plane (level_io's nodeFaces); `tets` carry the neighbours a loader derives (linkTetNeighbours), or
// -1 where unknown (code 2 is then not used). False, with `out` unchanged, when the nodes are not preorder
// trees laid one after another (a node's child[0] node is not the next node, or its child[1] node is not the
// node after child[0]'s subtree): such a grid is written with its float planes (CGR2).
bool encodeBspNodes(const std::vector<BspNode>& nodes, const std::vector<uint32_t>& faces,
                    const std::vector<Tet>& tets, std::string& out);

// Decodes `nodeCount` nodes from the `size` bytes at `p`, which must be exactly their stream, against the
// loaded tets (neighbours linked) and probes. Returns "" on success, else what is wrong (a face of a missing
// tet or a flat face, a leaf naming a missing tet, a neighbour code on a hull face, a truncated or overlong
// varint, a tree left open at the end, bytes left over), naming the node. Never reads outside [p, p + size)
// and allocates nothing before checking nodeCount <= size (a node takes at least one byte).
std::string decodeBspNodes(const uint8_t* p, size_t size, size_t nodeCount, const std::vector<Tet>& tets,
                           const std::vector<glm::vec3>& probes, std::vector<BspNode>& nodes);

}  // namespace tetraprobe::runtime_detail
