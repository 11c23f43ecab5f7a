// Per-tet occlusion data against light leaking (Valient, "Taking Killzone Shadow Fall image quality into the
// next generation", GDC 2014; as described in Bowald 2016 §2.1): for every tet cut by geometry, choose the
// cheapest of {nothing, 1-3 splitting planes, a 16-texel shadow map per probe} that answers sampled
// point-to-probe visibility like the ray tracer does. Contract: occlusion/build_occlusion.h; run-time
// evaluation: runtime/src/occlusion.cpp; layout and selection rule: docs/occlusion.md.
#include "tetraprobe/occlusion/build_occlusion.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vector_relational.hpp>

#include "tet_geometry.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/common/parallel.h"
#include "tetraprobe/common/progress.h"

namespace tetraprobe {

using namespace occlusion_detail;

namespace {

constexpr double kMinPolygonArea = 1e-8;   // x scale^2: a triangle touching the tet only on its boundary
constexpr double kClusterCos = 0.9659258;  // cos 15 deg: polygons within it share a plane...
constexpr double kClusterOffset = 0.03;    // ...when their centroids are within this x scale of it
constexpr size_t kCandidateClusters = 8;   // planes are chosen among the largest clusters
constexpr double kRayOffset = 1e-5;        // x scale: surface samples start this far off the surface
constexpr int kTexelRays = 9;              // shadow-map rays per texel (3x3 subdivision of its sub-triangle)
constexpr int kTexelRank = 4;              // a texel stores the median of their hit fractions

// One sampled shading point and the rays' answers for the tet's four probes.
struct Sample {
  glm::vec3 local{0.0f};
  glm::vec3 normal{0.0f};   // zero for volume samples
  glm::vec4 weights{0.0f};  // raw barycentrics from the BaryFrame (as the runtime computes them)
  uint32_t visible = 0;     // bit i: probe v[i] visible according to the rays
};

struct Polygon {
  std::vector<glm::dvec3> points;
  glm::dvec3 normal{0.0};  // unit, the triangle's (counter-clockwise) normal
  glm::dvec3 centroid{0.0};
  double area = 0.0;
};

struct Candidate {
  TetOcclusion rec;
  std::array<OcclusionPlane, 3> planes{};
  std::array<uint8_t, kShadowMapBlockBytes> texels{};
  uint64_t agreeing = 0, leaking = 0;
  uint64_t surfaceAgreeing = 0;  // of the answers for surface samples
};

struct TetResult {
  Candidate chosen;
  bool hasGeometry = false;
  uint64_t answers = 0;
  uint64_t surfaceAnswers = 0;
  uint64_t rays = 0;
  uint64_t blackouts = 0;  // of the chosen data (countBlackouts)
};

struct Context {
  const SceneTracer& tracer;
  const Level& level;
  const OcclusionOptions& options;
  std::vector<glm::dvec3> local;  // scene positions in the level's local frame
  std::unique_ptr<TriangleGrid> grid;
};

glm::vec3 toWorld(const Level& level, const glm::dvec3& local) {
  return glm::vec3(level.origin + local);
}

// The triangles cutting the tet, clipped to it.
std::vector<Polygon> clippedGeometry(const Context& ctx, const TetFrame& frame,
                                     std::vector<uint32_t>& scratch) {
  std::vector<Polygon> out;
  glm::dvec3 lo = frame.p[0], hi = frame.p[0];
  for (int i = 1; i < 4; ++i) {
    lo = glm::min(lo, frame.p[i]);
    hi = glm::max(hi, frame.p[i]);
  }
  ctx.grid->query(lo, hi, scratch);
  const Scene& scene = ctx.tracer.scene();
  for (uint32_t t : scratch) {
    if (ctx.tracer.transmission(t) > kOcclusionWallTransmission) continue;  // see-through: no wall
    const glm::uvec3 tri = scene.triangles[t];
    const glm::dvec3 &a = ctx.local[tri.x], &b = ctx.local[tri.y], &c = ctx.local[tri.z];
    const glm::dvec3 tlo = glm::min(a, glm::min(b, c)), thi = glm::max(a, glm::max(b, c));
    if (glm::any(glm::lessThan(thi, lo)) || glm::any(glm::greaterThan(tlo, hi))) continue;
    const glm::dvec3 n = glm::cross(b - a, c - a);
    const double len = glm::length(n);
    if (!(len > 0.0)) continue;
    Polygon p;
    p.points = clipTriangleToTet(frame, a, b, c, p.area);
    if (p.points.empty() || !(p.area > kMinPolygonArea * frame.scale * frame.scale)) continue;
    p.normal = n / len;
    for (const glm::dvec3& q : p.points) p.centroid += q;
    p.centroid /= double(p.points.size());
    out.push_back(std::move(p));
  }
  return out;
}

// Volume samples (stratified, no normal) and surface samples (area-uniform on the clipped geometry, each
// from both sides), answered by rays to the four probes.
std::vector<Sample> makeSamples(const Context& ctx, const TetFrame& frame, const Tet& tet,
                                const BaryFrame& bary, const std::vector<Polygon>& polys, uint64_t& rays) {
  std::vector<Sample> samples;
  const int nv = ctx.options.volumeSamples, ns = ctx.options.surfaceSamples;
  samples.reserve(size_t(nv) + 2 * size_t(ns));
  // Where each probe's light is seen from: the probe itself, or for a dilated probe the probe whose SH it
  // carries (OcclusionOptions::visibilitySource).
  glm::vec3 probeWorld[4];
  glm::dvec3 probeLocal[4];
  for (int i = 0; i < 4; ++i) {
    const std::vector<uint32_t>& src = ctx.options.visibilitySource;
    probeLocal[i] = src.empty() ? frame.p[i] : glm::dvec3(ctx.level.probes[src[size_t(tet.v[i])]]);
    probeWorld[i] = toWorld(ctx.level, probeLocal[i]);
  }

  auto answer = [&](Sample& s, const glm::dvec3& x, const glm::dvec3& n) {
    s.local = glm::vec3(x);
    s.normal = glm::vec3(n);
    s.weights = baryWeights(bary, s.local);
    const double offset = std::max(double(ctx.tracer.rayEpsilon()), kRayOffset * frame.scale);
    const glm::vec3 origin = toWorld(ctx.level, x + n * offset);
    for (int i = 0; i < 4; ++i) {
      if (glm::dot(probeLocal[i] - x, n) < 0.0) continue;  // behind the surface the sample lies on
      const glm::vec3 d = probeWorld[i] - origin;
      const float dist = glm::length(d);
      bool blocked = false;
      if (dist > 0.0f) {
        blocked = ctx.tracer.occluded(origin, d / dist, 0.0f, dist, kOcclusionWallTransmission);
        ++rays;
      }
      if (!blocked) s.visible |= 1u << i;
    }
    samples.push_back(s);
  };

  for (int k = 0; k < nv; ++k) {
    const glm::dvec4 b = foldCubeToTet(kronecker3(uint32_t(k)));
    const glm::dvec3 x = b.x * frame.p[0] + b.y * frame.p[1] + b.z * frame.p[2] + b.w * frame.p[3];
    Sample s;
    answer(s, x, glm::dvec3(0.0));
  }

  // Fan triangles of all polygons, picked by area.
  struct Fan {
    glm::dvec3 a, b, c, n;
    double area;
  };
  std::vector<Fan> fans;
  double total = 0.0;
  for (const Polygon& p : polys)
    for (size_t k = 1; k + 1 < p.points.size(); ++k) {
      const double area =
          0.5 * glm::length(glm::cross(p.points[k] - p.points[0], p.points[k + 1] - p.points[0]));
      if (!(area > 0.0)) continue;
      fans.push_back({p.points[0], p.points[k], p.points[k + 1], p.normal, area});
      total += area;
    }
  if (fans.empty() || !(total > 0.0)) return samples;
  for (int k = 0; k < ns; ++k) {
    const glm::dvec3 r = kronecker3(uint32_t(k + 7919));  // a different stretch than the volume samples
    double pick = r.x * total;
    size_t f = 0;
    while (f + 1 < fans.size() && pick >= fans[f].area) pick -= fans[f++].area;
    const double su = std::sqrt(r.y);
    const glm::dvec3 x = fans[f].a * (1.0 - su) + fans[f].b * (su * (1.0 - r.z)) + fans[f].c * (su * r.z);
    for (double side : {1.0, -1.0}) {
      Sample s;
      answer(s, x, side * fans[f].n);
    }
  }
  return samples;
}

void score(Candidate& c, const std::vector<Sample>& samples, const BaryFrame& bary) {
  c.agreeing = c.leaking = c.surfaceAgreeing = 0;
  const OcclusionPlane* planes = c.planes.data();
  const uint8_t* texels = c.texels.data();
  for (const Sample& s : samples) {
    const glm::vec4 vis = evaluateTetOcclusion(c.rec, planes, texels, bary, s.weights, s.normal);
    for (int i = 0; i < 4; ++i) {
      const bool stored = vis[i] > 0.5f, truth = (s.visible >> i & 1u) != 0;
      if (stored == truth) ++c.agreeing;
      if (stored == truth && (s.normal.x != 0.0f || s.normal.y != 0.0f || s.normal.z != 0.0f))
        ++c.surfaceAgreeing;
      if (stored && !truth) ++c.leaking;
    }
  }
}

// Samples the chosen data sends to the run-time fallback (applyOcclusion's share > 0) where the rays' answer
// would not: points that see a probe by rays but none by the data.
uint64_t countBlackouts(const Candidate& c, const std::vector<Sample>& samples, const BaryFrame& bary) {
  uint64_t n = 0;
  for (const Sample& s : samples) {
    float storedFallback = 0.0f, truthFallback = 0.0f;
    applyOcclusion(s.weights,
                   evaluateTetOcclusion(c.rec, c.planes.data(), c.texels.data(), bary, s.weights, s.normal),
                   &storedFallback);
    const glm::vec4 truthVis(float(s.visible & 1u), float(s.visible >> 1 & 1u), float(s.visible >> 2 & 1u),
                             float(s.visible >> 3 & 1u));
    applyOcclusion(s.weights, truthVis, &truthFallback);
    n += storedFallback > 0.0f && !(truthFallback > 0.0f);
  }
  return n;
}

// Polygons grouped by plane, largest total area first (ties: first met).
struct Cluster {
  glm::dvec3 normal, point;
  double area;
};
std::vector<Cluster> clusterPlanes(const std::vector<Polygon>& polys, double scale) {
  std::vector<size_t> order(polys.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return polys[a].area > polys[b].area; });
  std::vector<Cluster> clusters;
  for (size_t i : order) {
    const Polygon& p = polys[i];
    bool merged = false;
    for (Cluster& c : clusters)
      if (std::abs(glm::dot(c.normal, p.normal)) >= kClusterCos &&
          std::abs(glm::dot(c.normal, p.centroid - c.point)) <= kClusterOffset * scale) {
        c.area += p.area;
        merged = true;
        break;
      }
    if (!merged) clusters.push_back({p.normal, p.centroid, p.area});
  }
  std::stable_sort(clusters.begin(), clusters.end(),
                   [](const Cluster& a, const Cluster& b) { return a.area > b.area; });
  return clusters;
}

// Planes candidate with the first `count` clusters; each cell's mask is the samples' majority answer.
bool makePlanes(Candidate& c, const std::vector<Cluster>& clusters, uint32_t count, const TetFrame& frame,
                const BaryFrame& bary, const std::vector<Sample>& samples) {
  for (uint32_t k = 0; k < count; ++k) {
    double d[4];
    for (int i = 0; i < 4; ++i) d[i] = glm::dot(clusters[k].normal, frame.p[i] - clusters[k].point);
    // Stored in snorm16, so the cells below see what loads; the zero plane: every probe on the cluster's plane.
    c.planes[k] = makeOcclusionPlane(d[0], d[1], d[2], d[3]);
    if (c.planes[k].isZero()) return false;
  }
  int votes[8][4][2] = {};
  for (const Sample& s : samples) {
    const glm::vec4 w = biasWeights(bary, s.weights, s.normal);
    uint32_t cell = 0;
    for (uint32_t k = 0; k < count; ++k) {
      const glm::vec4 pc(c.planes[k].value(0), c.planes[k].value(1), c.planes[k].value(2),
                         c.planes[k].value(3));
      if (glm::dot(pc, w) >= 0.0f) cell |= 1u << k;
    }
    for (int i = 0; i < 4; ++i) ++votes[cell][i][(s.visible >> i) & 1u];
  }
  uint32_t cells = 0;
  for (uint32_t cell = 0; cell < (1u << count); ++cell)
    for (int i = 0; i < 4; ++i)
      if (votes[cell][i][1] >= votes[cell][i][0]) cells |= 1u << (4 * cell + uint32_t(i));
  c.rec = makeTetOcclusion(kOcclusionPlanes, count, 0, cells);
  return true;
}

// One ray per lattice vertex of each probe's opposite face (15 per probe): the depth the runtime
// interpolates harmonically inside each of the 16 sub-triangles.
void makeShadowMaps(Candidate& c, const Context& ctx, const TetFrame& frame, uint64_t& rays) {
  c.texels.fill(kShadowMapNoHit);
  for (int i = 0; i < 4; ++i) {
    int slot[3], n = 0;
    for (int j = 0; j < 4; ++j)
      if (j != i) slot[n++] = j;
    const glm::vec3 probe = toWorld(ctx.level, frame.p[i]);
    for (int b = 0; b <= 4; ++b)
      for (int a = 0; a + b <= 4; ++a) {
        const double u = a / 4.0, v = b / 4.0;
        const glm::dvec3 target =
            frame.p[slot[0]] * (1.0 - u - v) + frame.p[slot[1]] * u + frame.p[slot[2]] * v;
        const glm::vec3 d = toWorld(ctx.level, target) - probe;
        const float len = glm::length(d);
        uint8_t q = kShadowMapNoHit;
        if (len > 0.0f) {
          const Hit hit = ctx.tracer.intersect(probe, d / len, 0.0f, len, kOcclusionWallTransmission);
          ++rays;
          if (hit.hit)
            q = uint8_t(std::min(254.0, std::round(double(hit.t) / double(len) * double(kShadowMapScale))));
        }
        c.texels[size_t(i * kShadowMapTexels + shadowMapVertex(a, b))] = q;
      }
  }
  c.rec = makeTetOcclusion(kOcclusionShadowMaps, 0, 0, 0);
}

// The data options.mode asks for, scored against the samples (see buildOcclusion).
Candidate chooseCandidate(const Context& ctx, const TetFrame& frame, const BaryFrame& bary,
                          const std::vector<Polygon>& polys, const std::vector<Sample>& samples,
                          uint64_t& rays) {
  const double need = ctx.options.minAgreement * 4.0 * double(samples.size());
  const OcclusionMode mode = ctx.options.mode;

  // Candidates in order of cost; auto takes the first that is good enough, else the best.
  Candidate none;
  score(none, samples, bary);
  Candidate best = none;
  bool haveBest = mode == OcclusionMode::kAuto;
  auto consider = [&](const Candidate& c) {
    if (!haveBest || c.agreeing > best.agreeing) best = c;
    haveBest = true;
  };
  auto goodEnough = [&](const Candidate& c) { return double(c.agreeing) >= need; };
  if (mode == OcclusionMode::kAuto && goodEnough(none)) return none;
  if (mode == OcclusionMode::kAuto || mode == OcclusionMode::kPlanes) {
    // Greedy forward selection: each added plane is the candidate cluster (largest kCandidateClusters by
    // area) that answers the most samples right together with the planes already chosen (ties: larger area).
    std::vector<Cluster> clusters = clusterPlanes(polys, frame.scale);
    if (clusters.size() > kCandidateClusters) clusters.resize(kCandidateClusters);
    std::vector<Cluster> chosen;
    std::vector<bool> used(clusters.size(), false);
    for (uint32_t count = 1; count <= 3 && count <= clusters.size(); ++count) {
      Candidate bestAdd;
      size_t bestIndex = clusters.size();
      chosen.push_back(Cluster{});
      for (size_t k = 0; k < clusters.size(); ++k) {
        if (used[k]) continue;
        chosen.back() = clusters[k];
        Candidate c;
        if (!makePlanes(c, chosen, count, frame, bary, samples)) continue;
        score(c, samples, bary);
        if (bestIndex == clusters.size() || c.agreeing > bestAdd.agreeing) {
          bestAdd = c;
          bestIndex = k;
        }
      }
      if (bestIndex == clusters.size()) break;
      used[bestIndex] = true;
      chosen.back() = clusters[bestIndex];
      consider(bestAdd);
      if (mode == OcclusionMode::kAuto && goodEnough(bestAdd)) return bestAdd;
    }
  }

  if (mode == OcclusionMode::kAuto || mode == OcclusionMode::kShadowMaps) {
    Candidate c;
    makeShadowMaps(c, ctx, frame, rays);
    score(c, samples, bary);
    consider(c);
  }
  return haveBest ? best : none;
}

TetResult processTet(const Context& ctx, size_t index, std::vector<uint32_t>& scratch) {
  TetResult r;
  const Tet& tet = ctx.level.tets[index];
  const BaryFrame bary = baryFrame(tet, ctx.level.probes);  // the runtime's weights (occlusion.h)
  glm::dvec3 p[4];
  for (int i = 0; i < 4; ++i) p[i] = glm::dvec3(ctx.level.probes[size_t(tet.v[i])]);
  const TetFrame frame = makeTetFrame(p);
  if (!frame.valid) return r;
  const std::vector<Polygon> polys = clippedGeometry(ctx, frame, scratch);
  if (polys.empty()) return r;
  r.hasGeometry = true;
  const std::vector<Sample> samples = makeSamples(ctx, frame, tet, bary, polys, r.rays);
  r.answers = 4 * uint64_t(samples.size());
  for (const Sample& s : samples)
    if (s.normal != glm::vec3(0.0f)) r.surfaceAnswers += 4;
  r.chosen = chooseCandidate(ctx, frame, bary, polys, samples, r.rays);
  r.blackouts = countBlackouts(r.chosen, samples, bary);
  return r;
}

using TetKey = std::array<int32_t, 4>;

TetKey tetKey(const Tet& t) {
  return {t.v[0], t.v[1], t.v[2], t.v[3]};
}

}  // namespace

struct OcclusionCache::Impl {
  // What the results were computed for.
  const SceneTracer* tracer = nullptr;
  glm::dvec3 origin{0.0};
  OcclusionMode mode = OcclusionMode::kNone;
  double minAgreement = 0.0;
  int volumeSamples = 0, surfaceSamples = 0;
  std::vector<glm::vec3> probes;  // the previous call's level.probes
  std::vector<uint32_t> sources;  // and visibility sources (i where none was given)
  // The previous call's tets, sorted by key: those with geometry with their result, the others (whose
  // result is TetResult{}) by key alone.
  std::vector<std::pair<TetKey, TetResult>> withGeometry;
  std::vector<TetKey> without;
  size_t reused = 0, computed = 0;

  // Whether results computed for the stored state hold for this call.
  bool validFor(const SceneTracer& t, const Level& level, const OcclusionOptions& o) const {
    if (tracer != &t || origin != level.origin || mode != o.mode || minAgreement != o.minAgreement ||
        volumeSamples != o.volumeSamples || surfaceSamples != o.surfaceSamples ||
        probes.size() > level.probes.size())
      return false;
    for (size_t i = 0; i < probes.size(); ++i) {
      const uint32_t src = o.visibilitySource.empty() ? uint32_t(i) : o.visibilitySource[i];
      if (std::memcmp(&probes[i], &level.probes[i], sizeof(glm::vec3)) != 0 || sources[i] != src)
        return false;
    }
    return true;
  }

  // The stored result of a tet with these four probes, or null.
  const TetResult* find(const TetKey& key, bool& found) const {
    found = false;
    auto it =
        std::lower_bound(withGeometry.begin(), withGeometry.end(), key,
                         [](const std::pair<TetKey, TetResult>& e, const TetKey& k) { return e.first < k; });
    if (it != withGeometry.end() && it->first == key) {
      found = true;
      return &it->second;
    }
    found = std::binary_search(without.begin(), without.end(), key);
    return nullptr;
  }
};

OcclusionCache::OcclusionCache() : impl_(std::make_unique<Impl>()) {}
OcclusionCache::~OcclusionCache() = default;
size_t OcclusionCache::reused() const {
  return impl_->reused;
}
size_t OcclusionCache::computed() const {
  return impl_->computed;
}

bool parseOcclusionMode(const std::string& text, OcclusionMode& mode) {
  for (OcclusionMode m :
       {OcclusionMode::kAuto, OcclusionMode::kNone, OcclusionMode::kPlanes, OcclusionMode::kShadowMaps})
    if (text == occlusionModeName(m)) {
      mode = m;
      return true;
    }
  return false;
}

const char* occlusionModeName(OcclusionMode mode) {
  switch (mode) {
    case OcclusionMode::kAuto:
      return "auto";
    case OcclusionMode::kNone:
      return "none";
    case OcclusionMode::kPlanes:
      return "planes";
    case OcclusionMode::kShadowMaps:
      return "shadow-maps";
  }
  return "?";
}

LevelOcclusion buildOcclusion(const SceneTracer& tracer, const Level& level, const OcclusionOptions& options,
                              OcclusionStats* stats, OcclusionCache* cache) {
  const auto start = std::chrono::steady_clock::now();
  if (const LevelResult check = validateLevel(level); !check)
    throw InputError("occlusion: invalid level: " + check.message);
  if (!(options.minAgreement >= 0.0 && options.minAgreement <= 1.0))
    throw InputError("occlusion: minAgreement " + std::to_string(options.minAgreement) + " outside [0, 1]");
  if (options.volumeSamples < 0 || options.surfaceSamples < 0)
    throw InputError("occlusion: negative sample count (volume " + std::to_string(options.volumeSamples) +
                     ", surface " + std::to_string(options.surfaceSamples) + ")");
  if (!options.visibilitySource.empty()) {
    if (options.visibilitySource.size() != level.probes.size())
      throw InputError("occlusion: " + std::to_string(options.visibilitySource.size()) +
                       " visibility sources for " + std::to_string(level.probes.size()) + " probes");
    for (uint32_t v : options.visibilitySource)
      if (v >= level.probes.size())
        throw InputError("occlusion: visibility source " + std::to_string(v) + " is not a probe");
  }

  OcclusionStats st;
  st.tets = level.tets.size();
  LevelOcclusion out;
  if (options.mode == OcclusionMode::kNone || level.tets.empty()) {
    st.none = st.tets;
    st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (stats) *stats = st;
    return out;
  }

  Context ctx{tracer, level, options, {}, nullptr};
  const Scene& scene = tracer.scene();
  ctx.local.reserve(scene.positions.size());
  for (const glm::vec3& p : scene.positions) ctx.local.push_back(glm::dvec3(p) - level.origin);
  glm::dvec3 lo(level.probes[0]), hi(level.probes[0]);
  for (const glm::vec3& p : level.probes) {
    lo = glm::min(lo, glm::dvec3(p));
    hi = glm::max(hi, glm::dvec3(p));
  }
  ctx.grid = std::make_unique<TriangleGrid>(scene, ctx.local, lo, hi);

  std::vector<TetResult> results(level.tets.size());
  OcclusionCache::Impl* reuse = cache ? cache->impl_.get() : nullptr;
  const bool cacheValid = reuse && reuse->validFor(tracer, level, options);
  std::vector<uint8_t> wasReused(level.tets.size(), 0);
  std::unique_ptr<Progress> progress;
  if (options.progress) progress = std::make_unique<Progress>("occlusion", level.tets.size(), "tets");
  parallelFor(
      level.tets.size(), options.threads,
      [&](size_t t) {
        if (cacheValid) {
          bool found = false;
          const TetResult* earlier = reuse->find(tetKey(level.tets[t]), found);
          if (found) {
            results[t] = earlier ? *earlier : TetResult{};
            wasReused[t] = 1;
            if (progress) progress->advance();
            return;
          }
        }
        thread_local std::vector<uint32_t> scratch;
        FlushDenormalsScope denormals;
        results[t] = processTet(ctx, t, scratch);
        if (progress) progress->advance();
      },
      16);
  if (progress) progress->finish();
  if (reuse) {
    // Keep this call's tets for the next one.
    reuse->reused = size_t(std::count(wasReused.begin(), wasReused.end(), uint8_t(1)));
    reuse->computed = level.tets.size() - reuse->reused;
    reuse->tracer = &tracer;
    reuse->origin = level.origin;
    reuse->mode = options.mode;
    reuse->minAgreement = options.minAgreement;
    reuse->volumeSamples = options.volumeSamples;
    reuse->surfaceSamples = options.surfaceSamples;
    reuse->probes = level.probes;
    reuse->sources.resize(level.probes.size());
    for (size_t i = 0; i < level.probes.size(); ++i)
      reuse->sources[i] = options.visibilitySource.empty() ? uint32_t(i) : options.visibilitySource[i];
    reuse->withGeometry.clear();
    reuse->without.clear();
    for (size_t t = 0; t < level.tets.size(); ++t) {
      if (results[t].hasGeometry)
        reuse->withGeometry.emplace_back(tetKey(level.tets[t]), results[t]);
      else
        reuse->without.push_back(tetKey(level.tets[t]));
    }
    std::sort(reuse->withGeometry.begin(), reuse->withGeometry.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    std::sort(reuse->without.begin(), reuse->without.end());
  }

  // Sequential pass: offsets in tet order, so the arrays are the same for any thread count.
  out.tets.resize(level.tets.size());
  bool any = false;
  for (size_t t = 0; t < results.size(); ++t) {
    const TetResult& r = results[t];
    st.rays += r.rays;
    if (r.hasGeometry) {
      ++st.tetsWithGeometry;
      st.answers += r.answers;
      st.agreeing += r.chosen.agreeing;
      st.leaking += r.chosen.leaking;
      st.blackouts += r.blackouts;
      st.surfaceAnswers += r.surfaceAnswers;
      st.surfaceAgreeing += r.chosen.surfaceAgreeing;
      if (double(r.chosen.agreeing) < options.minAgreement * double(r.answers)) ++st.belowMinAgreement;
    }
    const TetOcclusion& rec = r.chosen.rec;
    if (rec.kind() == kOcclusionPlanes) {
      const size_t offset = out.planes.size();
      if (offset > kOcclusionMaxOffset)
        throw InputError("occlusion: more planes than 28-bit offsets address");
      out.tets[t] = makeTetOcclusion(kOcclusionPlanes, rec.planeCount(), uint32_t(offset), rec.cells);
      out.planes.insert(out.planes.end(), r.chosen.planes.begin(),
                        r.chosen.planes.begin() + rec.planeCount());
      ++st.planeTets;
      ++st.planeTetsByCount[rec.planeCount()];
      any = true;
    } else if (rec.kind() == kOcclusionShadowMaps) {
      const size_t block = out.shadowMaps.size() / kShadowMapBlockBytes;
      if (block > kOcclusionMaxOffset)
        throw InputError("occlusion: more shadow maps than 28-bit offsets address");
      out.tets[t] = makeTetOcclusion(kOcclusionShadowMaps, 0, uint32_t(block), 0);
      out.shadowMaps.insert(out.shadowMaps.end(), r.chosen.texels.begin(), r.chosen.texels.end());
      ++st.shadowMapTets;
      any = true;
    } else {
      ++st.none;
    }
  }
  if (!any) out = LevelOcclusion{};  // leave out what the level does not need
  st.planes = out.planes.size();
  st.bytes = out.bytes();
  st.agreement = st.answers > 0 ? double(st.agreeing) / double(st.answers) : 1.0;
  st.surfaceAgreement = st.surfaceAnswers > 0 ? double(st.surfaceAgreeing) / double(st.surfaceAnswers) : 1.0;
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats) *stats = st;
  return out;
}

}  // namespace tetraprobe
