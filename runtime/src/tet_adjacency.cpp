// Face matching by counting sort: each of the 4T faces is filed under its smallest probe, then each bucket
// (the faces around one probe: a few dozen) is sorted by its other two probes. Equal keys are the two sides
// of one face. Buckets are filled in (tet, face) order and sorted with the tet as the last key, so the result
// does not depend on the sort's stability.
#include "tetraprobe/runtime/tet_adjacency.h"

#include <algorithm>
#include <cstdint>

namespace tetraprobe {
namespace {

struct FaceRef {
  uint64_t key;  // the face's second and third smallest probes, (mid << 32) | max (the smallest: the bucket)
  int32_t tet;
  int32_t face;  // 0..3: the face opposite tets[tet].v[face]
};

bool keyLess(const FaceRef& a, const FaceRef& b) {
  return a.key != b.key ? a.key < b.key : a.tet != b.tet ? a.tet < b.tet : a.face < b.face;
}

// A bucket holds the faces around one probe (about 4 T / P, a few dozen): insertion sort beats std::sort
// there; long buckets (a probe with thousands of tets) take std::sort.
void sortBucket(FaceRef* first, FaceRef* last) {
  if (last - first < 2) return;
  if (last - first > 64) {
    std::sort(first, last, keyLess);
    return;
  }
  for (FaceRef* i = first + 1; i < last; ++i) {
    const FaceRef x = *i;
    FaceRef* j = i;
    for (; j > first && keyLess(x, *(j - 1)); --j) *j = *(j - 1);
    *j = x;
  }
}

// The face opposite v[f], its probes sorted ascending.
void sortedFace(const Tet& t, int f, int32_t out[3]) {
  int k = 0;
  for (int i = 0; i < 4; ++i)
    if (i != f) out[k++] = t.v[i];
  if (out[0] > out[1]) std::swap(out[0], out[1]);
  if (out[1] > out[2]) std::swap(out[1], out[2]);
  if (out[0] > out[1]) std::swap(out[0], out[1]);
}

}  // namespace

std::string linkTetNeighbours(std::vector<Tet>& tets, size_t probeCount) {
  std::vector<size_t> start(probeCount + 1, 0);
  int32_t key[3];
  for (const Tet& t : tets)
    for (int f = 0; f < 4; ++f) {
      sortedFace(t, f, key);
      ++start[size_t(key[0]) + 1];
    }
  for (size_t p = 0; p < probeCount; ++p) start[p + 1] += start[p];
  std::vector<FaceRef> faces(start[probeCount]);
  std::vector<size_t> cursor(start.begin(), start.end() - 1);
  for (size_t t = 0; t < tets.size(); ++t) {
    Tet& tet = tets[t];
    for (int f = 0; f < 4; ++f) {
      sortedFace(tet, f, key);
      faces[cursor[size_t(key[0])]++] = {uint64_t(uint32_t(key[1])) << 32 | uint32_t(key[2]), int32_t(t), f};
      tet.n[f] = -1;
    }
  }
  for (size_t p = 0; p < probeCount; ++p) {
    FaceRef *first = faces.data() + start[p], *last = faces.data() + start[p + 1];
    sortBucket(first, last);
    for (FaceRef* i = first; i != last;) {
      FaceRef* j = i + 1;
      while (j != last && j->key == i->key) ++j;
      if (j - i > 2)
        return "the face on probes (" + std::to_string(p) + ", " + std::to_string(i->key >> 32) + ", " +
               std::to_string(i->key & 0xFFFFFFFFu) + ") is shared by " + std::to_string(j - i) + " tets (" +
               std::to_string(i->tet) + ", " + std::to_string((i + 1)->tet) + ", " +
               std::to_string((i + 2)->tet) + (j - i > 3 ? ", ..." : "") + "): not a tetrahedralization";
      if (j - i == 2) {
        tets[size_t(i->tet)].n[i->face] = (i + 1)->tet;
        tets[size_t((i + 1)->tet)].n[(i + 1)->face] = i->tet;
      }
      i = j;
    }
  }
  return {};
}

}  // namespace tetraprobe
