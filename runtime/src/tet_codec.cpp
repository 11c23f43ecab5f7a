// The packed tet probe indices of the level file (TETM): the contract and the layout are in tet_codec.h.
#include "tet_codec.h"

#include <algorithm>

#include "varint.h"

namespace tetraprobe::runtime_detail {
namespace {

constexpr int kListSize = 15;    // nibbles 0..14 name a list position
constexpr uint32_t kGiven = 15;  // the nibble of a vertex given by a varint

// The move-to-front list of the probes last named, most recent first.
class RecentProbes {
 public:
  // The position of `v`, or -1.
  int find(int32_t v) const {
    for (int i = 0; i < size_; ++i)
      if (list_[i] == v) return i;
    return -1;
  }
  int size() const { return size_; }
  int32_t at(int i) const { return list_[i]; }
  // Moves the probe at `position` (or, for -1, a new probe v) to the front.
  void touch(int position, int32_t v) {
    if (position < 0) position = size_ < kListSize ? size_++ : kListSize - 1;
    std::copy_backward(list_, list_ + position, list_ + position + 1);
    list_[0] = v;
  }

 private:
  int32_t list_[kListSize] = {};
  int size_ = 0;
};

}  // namespace

void encodeTetProbes(const std::vector<Tet>& tets, std::string& out) {
  out.reserve(out.size() + 4 * tets.size());
  RecentProbes recent;
  int64_t lastGiven = 0;
  std::string given;
  for (const Tet& t : tets) {
    uint32_t nibbles[4];
    given.clear();
    for (int i = 0; i < 4; ++i) {
      const int position = recent.find(t.v[i]);
      if (position >= 0) {
        nibbles[i] = uint32_t(position);
      } else {
        nibbles[i] = kGiven;
        putVarint(given, zigzag(int64_t(t.v[i]) - lastGiven));
        lastGiven = t.v[i];
      }
      recent.touch(position, t.v[i]);
    }
    out.push_back(char(uint8_t(nibbles[0] | nibbles[1] << 4)));
    out.push_back(char(uint8_t(nibbles[2] | nibbles[3] << 4)));
    out += given;
  }
}

std::string decodeTetProbes(const uint8_t* p, size_t size, size_t tetCount, size_t probeCount,
                            std::vector<Tet>& tets) {
  if (tetCount > size / 2)
    return std::to_string(tetCount) + " tets in " + std::to_string(size) +
           " bytes (a tet takes at least two)";
  tets.assign(tetCount, Tet{});
  RecentProbes recent;
  int64_t lastGiven = 0;
  size_t at = 0;
  for (size_t t = 0; t < tetCount; ++t) {
    const auto where = [t] { return "tet " + std::to_string(t) + ": "; };
    if (size - at < 2) return where() + "truncated";
    const uint32_t control = uint32_t(p[at]) | uint32_t(p[at + 1]) << 8;
    at += 2;
    Tet& tet = tets[t];
    for (int i = 0; i < 4; ++i) {
      const uint32_t nibble = control >> (4 * i) & 15u;
      int32_t v = 0;
      int position = -1;
      if (nibble == kGiven) {
        uint64_t z = 0;
        if (!getVarint(p, size, &at, &z)) return where() + "truncated or overlong probe index";
        const int64_t d = unzigzag(z);
        const auto count = int64_t(probeCount);
        if (d < -count || d >= count || lastGiven + d < 0 || lastGiven + d >= count)
          return where() + "vertex out of range (" + std::to_string(probeCount) + " probes)";
        v = int32_t(lastGiven + d);
        lastGiven = v;
        position = recent.find(v);  // a given probe may still be on the list (a writer need not use it)
      } else {
        position = int(nibble);
        if (position >= recent.size())
          return where() + "names recent probe " + std::to_string(position) + " of " +
                 std::to_string(recent.size());
        v = recent.at(position);
      }
      for (int j = 0; j < i; ++j)
        if (tet.v[j] == v) return where() + "vertex " + std::to_string(v) + " repeated";
      tet.v[i] = v;
      tet.n[i] = -1;
      recent.touch(position, v);
    }
  }
  if (at != size) return "tets: " + std::to_string(size - at) + " bytes after the last tet";
  return {};
}

}  // namespace tetraprobe::runtime_detail
