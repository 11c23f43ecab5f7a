// The packed BSP node stream of the level file (CGR4): the contract and the layout are in bsp_codec.h.
#include "bsp_codec.h"

#include <utility>

#include "varint.h"

namespace tetraprobe::runtime_detail {
namespace {

enum ChildCode : uint32_t { kChildNode = 0, kLeafFaceTet = 1, kLeafAcross = 2, kLeafExplicit = 3 };

}  // namespace

bool encodeBspNodes(const std::vector<BspNode>& nodes, const std::vector<uint32_t>& faces,
                    const std::vector<Tet>& tets, std::string& out) {
  if (faces.size() != nodes.size()) return false;
  std::string s;
  s.reserve(3 * nodes.size());
  std::vector<std::pair<size_t, int>> pending;  // (node, child) whose node child comes next in preorder
  int64_t previous = 0;
  std::string leaves;  // the node's explicit leaves, written after its head varint
  for (size_t n = 0; n < nodes.size(); ++n) {
    if (!pending.empty()) {
      const auto [parent, c] = pending.back();
      pending.pop_back();
      if (nodes[parent].child[c] != int32_t(n)) return false;  // not preorder
    }
    const int64_t t = int64_t(faces[n] >> 2);
    const int f = int(faces[n] & 3u);
    if (size_t(t) >= tets.size()) return false;
    uint32_t codes[2];
    leaves.clear();
    for (int c = 0; c < 2; ++c) {
      const int32_t child = nodes[n].child[c];
      if (child >= 0) {
        codes[c] = kChildNode;
      } else if (child != kEmptyLeaf && ~child == t) {
        codes[c] = kLeafFaceTet;
      } else if (child != kEmptyLeaf && ~child == tets[size_t(t)].n[f]) {
        codes[c] = kLeafAcross;
      } else {
        codes[c] = kLeafExplicit;
        putVarint(leaves, child == kEmptyLeaf ? 0 : zigzag(int64_t(~child) - t) + 1);
      }
    }
    putVarint(s, zigzag(t - previous) << 6 | uint64_t(f) << 4 | codes[0] << 2 | codes[1]);
    s += leaves;
    previous = t;
    for (int c = 1; c >= 0; --c)  // child[0] is popped first: it comes next
      if (codes[c] == kChildNode) pending.emplace_back(n, c);
  }
  if (!pending.empty()) return false;  // a child index past the last node, or not preorder
  out += s;
  return true;
}

std::string decodeBspNodes(const uint8_t* p, size_t size, size_t nodeCount, const std::vector<Tet>& tets,
                           const std::vector<glm::vec3>& probes, std::vector<BspNode>& nodes) {
  if (nodeCount > size)
    return std::to_string(nodeCount) + " nodes in " + std::to_string(size) +
           " bytes (a node takes at least one)";
  nodes.assign(nodeCount, BspNode{});
  std::vector<std::pair<size_t, int>> pending;
  size_t at = 0;
  int64_t previous = 0;
  const auto tetCount = int64_t(tets.size());
  for (size_t n = 0; n < nodeCount; ++n) {
    const auto where = [&] { return "cell grid node " + std::to_string(n) + ": "; };
    if (!pending.empty()) {
      const auto [parent, c] = pending.back();
      pending.pop_back();
      nodes[parent].child[c] = int32_t(n);
    }
    uint64_t head = 0;
    if (!getVarint(p, size, &at, &head)) return where() + "truncated or overlong";
    const int64_t delta = unzigzag(head >> 6);
    if (delta < -tetCount || delta >= tetCount || previous + delta < 0 || previous + delta >= tetCount)
      return where() + "names a tet past the last of " + std::to_string(tetCount);
    const int64_t t = previous + delta;
    const int f = int(head >> 4 & 3u);
    previous = t;
    glm::vec3 corners[4];
    for (int i = 0; i < 4; ++i) corners[i] = probes[size_t(tets[size_t(t)].v[i])];
    if (!cellGridFacePlane(corners, f, nodes[n].plane))
      return where() + "names face " + std::to_string(f) + " of tet " + std::to_string(t) + ", which is flat";
    const uint32_t codes[2] = {uint32_t(head >> 2 & 3u), uint32_t(head & 3u)};
    for (int c = 0; c < 2; ++c) {
      int32_t& child = nodes[n].child[c];
      if (codes[c] == kLeafFaceTet) {
        child = ~int32_t(t);
      } else if (codes[c] == kLeafAcross) {
        const int32_t across = tets[size_t(t)].n[f];
        if (across < 0)
          return where() + "a leaf across face " + std::to_string(f) + " of tet " + std::to_string(t) +
                 ", a hull face";
        child = ~across;
      } else if (codes[c] == kLeafExplicit) {
        uint64_t v = 0;
        if (!getVarint(p, size, &at, &v)) return where() + "truncated or overlong leaf";
        if (v == 0) {
          child = kEmptyLeaf;
        } else {
          const int64_t d = unzigzag(v - 1);
          if (d < -tetCount || d >= tetCount || t + d < 0 || t + d >= tetCount)
            return where() + "a leaf naming a tet past the last of " + std::to_string(tetCount);
          child = ~int32_t(t + d);
        }
      }
    }
    for (int c = 1; c >= 0; --c)
      if (codes[c] == kChildNode) pending.emplace_back(n, c);
  }
  if (!pending.empty()) return "cell grid: a node's child is missing (the stream ends inside a tree)";
  if (at != size) return "cell grid: " + std::to_string(size - at) + " bytes after the last node";
  return {};
}

}  // namespace tetraprobe::runtime_detail
