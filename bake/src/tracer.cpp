// SceneTracer: one Embree 3 triangle geometry built from a Scene (and a second one for alpha-cutout
// triangles, with filter functions that reject hits in holes), closest-hit and any-hit queries with
// rtcIntersect1 / rtcOccluded1, queries that step over transmissive surfaces (by closest hits, which each
// surface meets once whatever the BVH's spatial splits), plus the tables the samplers need (normals, areas,
// an emissive power CDF).
// References: Embree 3 API manual (rtcNewGeometry, rtcSetNewGeometryBuffer, rtcIntersect1,
// rtcSetGeometryIntersectFilterFunction); Wald et al. 2014,
// "Embree: a kernel framework for efficient CPU ray tracing".
#include "tetraprobe/bake/tracer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "ray_tap.h"
#include "sampling.h"
#include "tetraprobe/common/error.h"
#include "tracer_impl.h"

#if defined(__SSE2__) || defined(__x86_64__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#define TETRAPROBE_BAKE_HAS_MXCSR 1
#endif

namespace tetraprobe {

namespace {

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::string where(const Scene& scene) {
  return scene.sourcePath.empty() ? std::string("scene") : scene.sourcePath;
}

void validate(const Scene& scene) {
  if (scene.triangles.empty()) throw InputError(where(scene) + ": no triangles to trace");
  for (size_t i = 0; i < scene.positions.size(); ++i)
    if (!finite(scene.positions[i]))
      throw InputError(where(scene) + ": vertex " + std::to_string(i) + " has a non-finite position");
  const size_t nv = scene.positions.size();
  for (size_t i = 0; i < scene.triangles.size(); ++i) {
    const glm::uvec3 t = scene.triangles[i];
    if (t.x >= nv || t.y >= nv || t.z >= nv)
      throw InputError(where(scene) + ": triangle " + std::to_string(i) +
                       " has a vertex index out of range (" + std::to_string(nv) + " vertices)");
  }
  if (scene.triangleMaterial.size() != scene.triangles.size())
    throw InputError(where(scene) + ": " + std::to_string(scene.triangleMaterial.size()) +
                     " triangle materials for " + std::to_string(scene.triangles.size()) + " triangles");
  for (size_t i = 0; i < scene.triangleMaterial.size(); ++i)
    if (scene.triangleMaterial[i] >= scene.materials.size())
      throw InputError(where(scene) + ": triangle " + std::to_string(i) + " uses material " +
                       std::to_string(scene.triangleMaterial[i]) + " of " +
                       std::to_string(scene.materials.size()));
  for (const Material& m : scene.materials)
    if (!finite(m.albedo) || !finite(m.emission) || glm::any(glm::lessThan(m.emission, glm::vec3(0.0f))) ||
        glm::any(glm::lessThan(m.albedo, glm::vec3(0.0f))))
      throw InputError(where(scene) + ": material '" + m.name + "' has a negative or non-finite colour");
  if (const std::string problem = transparencyProblem(scene); !problem.empty())
    throw InputError(where(scene) + ": " + problem);
}

// Alpha-cutout triangles (those listed with texture coordinates whose material has a texture), and whether
// any triangle transmits.
void buildTransparency(SceneTracer::Impl& impl) {
  const Scene& scene = *impl.scene;
  for (uint32_t m : scene.triangleMaterial) impl.anyTransmission |= scene.materials[m].transmission > 0.0f;
  for (size_t k = 0; k < scene.cutoutTriangles.size(); ++k) {
    const uint32_t tri = scene.cutoutTriangles[k];
    const Material& m = impl.material(tri);
    if (m.alphaTexture < 0) continue;
    SceneTracer::Impl::Cutout c;
    c.triangle = tri;
    for (size_t i = 0; i < 3; ++i) c.uv[i] = scene.cutoutUvs[3 * k + i];
    c.texture = &scene.alphaTextures[size_t(m.alphaTexture)];
    c.cutoff = m.alphaCutoff;
    impl.cutouts.push_back(c);
  }
}

// Embree filter of geometry 1 (intersect and occluded alike): a hit in a hole is no hit.
void cutoutFilter(const RTCFilterFunctionNArguments* args) {
  const auto* impl = static_cast<const SceneTracer::Impl*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
    if (impl->cutouts[prim].hole(RTCHitN_u(args->hit, args->N, i), RTCHitN_v(args->hit, args->N, i)))
      args->valid[i] = 0;
  }
}

// Resumes a ray past a surface met at distance t.
float pastHit(float t, float eps) {
  return std::max(t + eps, std::nextafter(t, std::numeric_limits<float>::infinity()));
}

void buildTables(SceneTracer::Impl& impl) {
  const Scene& scene = *impl.scene;
  const size_t n = scene.triangles.size();
  impl.normals.resize(n);
  impl.areas.resize(n);
  impl.areaCdf.resize(n);
  impl.emissivePdfArea.assign(n, 0.0f);
  double areaSum = 0.0;
  std::vector<double> power;
  for (size_t i = 0; i < n; ++i) {
    glm::vec3 p0, p1, p2;
    impl.vertices(uint32_t(i), p0, p1, p2);
    const glm::vec3 c = glm::cross(p1 - p0, p2 - p0);
    const float len = glm::length(c);
    impl.normals[i] = len > 0.0f ? c / len : glm::vec3(0.0f);
    impl.areas[i] = 0.5f * len;
    areaSum += impl.areas[i];
    impl.areaCdf[i] = areaSum;
    const float lum = bake_detail::luminance(impl.material(uint32_t(i)).emission);
    if (lum > 0.0f && impl.areas[i] > 0.0f) {
      impl.emissive.push_back(uint32_t(i));
      power.push_back(double(lum) * impl.areas[i] * std::numbers::pi);
      impl.emissiveArea += impl.areas[i];
    }
  }
  impl.totalArea = areaSum;
  double powerSum = 0.0;
  impl.emissiveCdf.resize(power.size());
  for (size_t k = 0; k < power.size(); ++k) impl.emissiveCdf[k] = (powerSum += power[k]);
  impl.emissivePower = powerSum;
  for (size_t k = 0; k < power.size(); ++k) {
    impl.emissiveCdf[k] /= powerSum;
    const uint32_t tri = impl.emissive[k];
    impl.emissivePdfArea[tri] = float(power[k] / powerSum / impl.areas[tri]);
  }
  if (!impl.emissiveCdf.empty()) impl.emissiveCdf.back() = 1.0;

  glm::vec3 lo, hi;
  sceneBounds(scene, lo, hi);
  const float maxAbs = bake_detail::maxComponent(glm::max(glm::abs(lo), glm::abs(hi)));
  impl.rayEpsilon = std::max(1e-6f, 5e-6f * (glm::length(hi - lo) + maxAbs));
}

void embreeError(void*, RTCError code, const char* str) {
  // Reported through rtcGetDeviceError after each call that can fail; nothing to do here.
  (void)code;
  (void)str;
}

void checkDevice(RTCDevice device, const char* what) {
  const RTCError err = rtcGetDeviceError(device);
  if (err != RTC_ERROR_NONE)
    throw std::runtime_error(std::string("Embree: ") + what + " failed (error " + std::to_string(int(err)) +
                             ")");
}

}  // namespace

SceneTracer::SceneTracer(const Scene& scene) : impl_(std::make_unique<Impl>()) {
  validate(scene);
  impl_->scene = &scene;
  buildTables(*impl_);

  bake_detail::DenormalScope denormals;
  // The BVH is built on one thread: Embree's default device builds it on every core through TBB, whatever
  // --threads says, and a tie between equally near hits is decided by the BVH's layout. One build thread
  // makes the BVH (so every hit) a function of the scene alone; tracing still runs on the caller's threads.
  // Cost: within noise (`bench bake` on Sponza, 66k triangles, load + BVH + 2 probes: 0.67-0.68 s before,
  // 0.68-0.77 s after, 2 shared cores). tests/cli/test_thread_determinism.cpp pins the result.
  // The kernels are capped at AVX2: Embree picks its widest ISA at run time, and its kernels differ in the
  // last bits of a hit (an approximate reciprocal refined differently per ISA, the BVH's node width), so the
  // same scene baked with SSE4.2 and AVX2 kernels gives different level bytes (two_rooms' visual bake:
  // measured), and an AVX-512 machine would differ from an AVX2 one. Capped, every AVX2 and AVX-512 machine
  // bakes the same bytes (CI, the visual references and a studio's farm agree); a CPU without AVX2 still
  // bakes, with its own last bits.
  impl_->device = rtcNewDevice("threads=1,max_isa=avx2");
  if (!impl_->device) throw std::runtime_error("Embree: rtcNewDevice failed");
  rtcSetDeviceErrorFunction(impl_->device, embreeError, nullptr);
  impl_->rtcScene = rtcNewScene(impl_->device);
  rtcSetSceneBuildQuality(impl_->rtcScene, RTC_BUILD_QUALITY_HIGH);
  rtcSetSceneFlags(impl_->rtcScene, RTC_SCENE_FLAG_ROBUST);
  RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                         3 * sizeof(float), scene.positions.size()));
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                            3 * sizeof(unsigned), scene.triangles.size()));
  checkDevice(impl_->device, "geometry buffers");
  for (size_t i = 0; i < scene.positions.size(); ++i)
    for (int k = 0; k < 3; ++k) vb[3 * i + k] = scene.positions[i][k];
  for (size_t i = 0; i < scene.triangles.size(); ++i)
    for (int k = 0; k < 3; ++k) ib[3 * i + k] = scene.triangles[i][k];
  buildTransparency(*impl_);
  for (const Impl::Cutout& c : impl_->cutouts)  // traced in geometry 1 instead
    for (int k = 0; k < 3; ++k) ib[3 * size_t(c.triangle) + size_t(k)] = scene.triangles[c.triangle].x;
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(impl_->rtcScene, geom, 0);
  rtcReleaseGeometry(geom);
  if (!impl_->cutouts.empty()) {
    const size_t n = impl_->cutouts.size();
    RTCGeometry cut = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* cvb = static_cast<float*>(
        rtcSetNewGeometryBuffer(cut, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * n));
    auto* cib = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(cut, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), n));
    checkDevice(impl_->device, "cutout geometry buffers");
    for (size_t i = 0; i < n; ++i) {
      glm::vec3 p[3];
      impl_->vertices(impl_->cutouts[i].triangle, p[0], p[1], p[2]);
      for (size_t j = 0; j < 3; ++j) {
        for (int k = 0; k < 3; ++k) cvb[9 * i + 3 * j + size_t(k)] = p[j][k];
        cib[3 * i + j] = unsigned(3 * i + j);
      }
    }
    rtcSetGeometryUserData(cut, impl_.get());
    rtcSetGeometryIntersectFilterFunction(cut, cutoutFilter);
    rtcSetGeometryOccludedFilterFunction(cut, cutoutFilter);
    rtcCommitGeometry(cut);
    rtcAttachGeometryByID(impl_->rtcScene, cut, 1);
    rtcReleaseGeometry(cut);
  }
  rtcCommitScene(impl_->rtcScene);
  checkDevice(impl_->device, "scene build");
}

SceneTracer::~SceneTracer() {
  if (impl_->rtcScene) rtcReleaseScene(impl_->rtcScene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

const Scene& SceneTracer::scene() const {
  return *impl_->scene;
}

float SceneTracer::rayEpsilon() const {
  return impl_->rayEpsilon;
}

float SceneTracer::transmission(uint32_t triangle) const {
  return impl_->material(triangle).transmission;
}

bool SceneTracer::hasTransmission() const {
  return impl_->anyTransmission;
}

bool SceneTracer::isHole(uint32_t triangle, float u, float v) const {
  if (impl_->cutouts.empty() || impl_->material(triangle).alphaTexture < 0) return false;
  const auto it = std::lower_bound(impl_->cutouts.begin(), impl_->cutouts.end(), triangle,
                                   [](const Impl::Cutout& c, uint32_t t) { return c.triangle < t; });
  return it != impl_->cutouts.end() && it->triangle == triangle && it->hole(u, v);
}

Hit SceneTracer::intersect(const glm::vec3& origin, const glm::vec3& dir, float tnear, float tfar,
                           float maxTransmission) const {
  Hit hit = closestHit(origin, dir, tnear, tfar);
  if (maxTransmission >= 1.0f || !impl_->anyTransmission) return hit;
  while (hit.hit && transmission(hit.triangle) > maxTransmission)
    hit = closestHit(origin, dir, pastHit(hit.t, impl_->rayEpsilon), tfar);
  return hit;
}

bool SceneTracer::occluded(const glm::vec3& origin, const glm::vec3& dir, float tnear, float tfar,
                           float maxTransmission) const {
  if (maxTransmission >= 1.0f || !impl_->anyTransmission) return anyHit(origin, dir, tnear, tfar);
  return intersect(origin, dir, tnear, tfar, maxTransmission).hit;
}

float SceneTracer::transmittance(const glm::vec3& origin, const glm::vec3& dir, float tnear,
                                 float tfar) const {
  if (!impl_->anyTransmission) return anyHit(origin, dir, tnear, tfar) ? 0.0f : 1.0f;
  float through = 1.0f;
  for (;;) {
    const Hit hit = closestHit(origin, dir, tnear, tfar);
    if (!hit.hit) return through;
    const float t = transmission(hit.triangle);
    if (!(t > 0.0f)) return 0.0f;
    through *= t;
    tnear = pastHit(hit.t, impl_->rayEpsilon);
  }
}

Hit SceneTracer::closestHit(const glm::vec3& origin, const glm::vec3& dir, float tnear, float tfar) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  rh.ray.org_x = origin.x;
  rh.ray.org_y = origin.y;
  rh.ray.org_z = origin.z;
  rh.ray.tnear = tnear;
  rh.ray.dir_x = dir.x;
  rh.ray.dir_y = dir.y;
  rh.ray.dir_z = dir.z;
  rh.ray.time = 0.0f;
  rh.ray.tfar = tfar;
  rh.ray.mask = ~0u;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->rtcScene, &context, &rh);
  if (bake_detail::RayTap* tap = bake_detail::currentRayTap()) {
    ++tap->intersects;
    if (tap->record)
      tap->record->push_back({origin, tnear, dir, tfar, 0u, rh.hit.geomID != RTC_INVALID_GEOMETRY_ID});
  }
  Hit hit;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  hit.hit = true;
  hit.t = rh.ray.tfar;
  hit.triangle = rh.hit.geomID == 0 ? rh.hit.primID : impl_->cutouts[rh.hit.primID].triangle;
  // Embree's Ng is (P1 - P0) x (P2 - P0), the counter-clockwise front normal, unnormalised. Normalising it is
  // cheaper than a lookup in Impl::normals (a cache miss outside Embree's leaf data).
  const glm::vec3 ng(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
  const float len = glm::length(ng);
  hit.geometricNormal = len > 0.0f ? ng / len : impl_->normals[hit.triangle];
  hit.frontFace = glm::dot(dir, hit.geometricNormal) < 0.0f;
  hit.u = rh.hit.u;
  hit.v = rh.hit.v;
  return hit;
}

bool SceneTracer::anyHit(const glm::vec3& origin, const glm::vec3& dir, float tnear, float tfar) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray;
  ray.org_x = origin.x;
  ray.org_y = origin.y;
  ray.org_z = origin.z;
  ray.tnear = tnear;
  ray.dir_x = dir.x;
  ray.dir_y = dir.y;
  ray.dir_z = dir.z;
  ray.time = 0.0f;
  ray.tfar = tfar;
  ray.mask = ~0u;
  ray.id = 0;
  ray.flags = 0;
  rtcOccluded1(impl_->rtcScene, &context, &ray);
  const bool blocked = ray.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
  if (bake_detail::RayTap* tap = bake_detail::currentRayTap()) {
    ++tap->occludeds;
    if (tap->record) tap->record->push_back({origin, tnear, dir, tfar, 1u, blocked});
  }
  return blocked;
}

#ifdef TETRAPROBE_BAKE_HAS_MXCSR
FlushDenormalsScope::FlushDenormalsScope() : saved_(_mm_getcsr()) {
  _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
  _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
}
FlushDenormalsScope::~FlushDenormalsScope() {
  _mm_setcsr(saved_);
}
#else
FlushDenormalsScope::FlushDenormalsScope() = default;
FlushDenormalsScope::~FlushDenormalsScope() = default;
#endif

glm::vec3 skyRadiance(const Scene& scene, const glm::vec3& dir) {
  if (!scene.hasSkyGradient()) return scene.skyRadiance;
  const float t = std::clamp(dir.y, 0.0f, 1.0f);
  return scene.skyHorizonRadiance + (scene.skyRadiance - scene.skyHorizonRadiance) * t;
}

}  // namespace tetraprobe
