// Path-traced reference image: primary rays through the renderer's pixel centres (a CPU G-buffer), then
// progressive passes of referenceIrradiance per hit pixel merged into a running mean and variance, and the
// CPU probe lookup at the same points.
// References: Chan, Golub & LeVeque 1979 ("Updating formulae and a pairwise algorithm for computing sample
// variances") for merging the passes; PBRT 4th ed. ch. 5 (pinhole camera rays).
#include "tetraprobe/eval/reference_image.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include <glm/geometric.hpp>

#include "tetraprobe/bake/bake.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/common/parallel.h"
#include "tetraprobe/common/progress.h"
#include "tetraprobe/common/splitmix.h"
#include "tetraprobe/runtime/luminance.h"

namespace tetraprobe {

namespace {

constexpr double kFloor = 0.01;  // W/m^2, the evaluation's floor (evaluate.h)

void checkViewSize(const RenderView& view) {
  if (view.width < 1 || view.height < 1 || view.width > 16384 || view.height > 16384)
    throw InputError("reference image: size " + std::to_string(view.width) + "x" +
                     std::to_string(view.height) + " is outside 1..16384 pixels a side");
}

// Running mean and sum of squared deviations of one pixel's paths, per channel.
struct PixelAccumulator {
  double n = 0.0;
  glm::dvec3 mean{0.0}, m2{0.0};

  // Merges a batch of `count` samples with mean `batchMean` and standard error `batchStderr` (which
  // referenceIrradiance reports as sqrt(m2 / (count - 1) / count)).
  void merge(int count, const glm::vec3& batchMean, const glm::vec3& batchStderr) {
    const double nb = double(count);
    const glm::dvec3 mb(batchMean);
    const glm::dvec3 se(batchStderr);
    const glm::dvec3 m2b = count > 1 ? se * se * (nb * (nb - 1.0)) : glm::dvec3(0.0);
    const double total = n + nb;
    const glm::dvec3 delta = mb - mean;
    mean += delta * (nb / total);
    m2 += m2b + delta * delta * (n * nb / total);
    n = total;
  }
  glm::dvec3 stderror() const { return n > 1.0 ? glm::sqrt(m2 / (n - 1.0) / n) : glm::dvec3(0.0); }
};

}  // namespace

size_t ReferenceGBuffer::hitCount() const {
  size_t count = 0;
  for (uint8_t h : hit) count += h;
  return count;
}

double ReferenceImage::meanRelStderr() const {
  double sum = 0.0;
  size_t count = 0;
  for (size_t i = 0; i < gbuffer.hit.size(); ++i) {
    if (!gbuffer.hit[i]) continue;
    const double y = luminance(glm::dvec3(irradiance[i]));
    sum += luminance(glm::dvec3(stderror[i])) / std::sqrt(y * y + kFloor);
    ++count;
  }
  return count ? sum / double(count) : 0.0;
}

namespace {
constexpr int kMaxBackFaces = 64;  // back faces a primary ray steps through before the pixel counts as empty
}  // namespace

ReferenceGBuffer traceReferenceGBuffer(const SceneTracer& tracer, const RenderView& view, int threads) {
  checkViewSize(view);
  ReferenceGBuffer g;
  g.width = view.width;
  g.height = view.height;
  const size_t n = size_t(view.width) * size_t(view.height);
  g.hit.assign(n, 0);
  g.position.assign(n, glm::dvec3(0.0));
  g.normal.assign(n, glm::vec3(0.0f));
  g.triangle.assign(n, 0);
  const Scene& scene = tracer.scene();
  const glm::vec3 eye = view.eye;
  parallelFor(size_t(view.height), threads, [&](size_t y) {
    FlushDenormalsScope denormals;
    for (int x = 0; x < view.width; ++x) {
      const size_t i = y * size_t(view.width) + size_t(x);
      const glm::vec3 dir(pixelRayDirection(view, x + 0.5, double(y) + 0.5));
      // The first front face: the Vulkan G-buffer culls back faces, so a cut-away view (a camera above a
      // closed room, looking through the back of its ceiling) shows what lies behind them.
      Hit hit;
      float tnear = 0.0f;
      for (int k = 0; k < kMaxBackFaces; ++k) {
        hit = tracer.intersect(eye, dir, tnear, std::numeric_limits<float>::infinity());
        if (!hit.hit || hit.frontFace) break;
        tnear = std::max(hit.t + tracer.rayEpsilon(),
                         std::nextafter(hit.t, std::numeric_limits<float>::infinity()));
      }
      if (!hit.hit || !hit.frontFace) continue;
      const glm::uvec3 tri = scene.triangles[hit.triangle];
      const glm::dvec3 a(scene.positions[tri[0]]), b(scene.positions[tri[1]]), c(scene.positions[tri[2]]);
      g.hit[i] = 1;
      g.position[i] = a * (1.0 - double(hit.u) - double(hit.v)) + b * double(hit.u) + c * double(hit.v);
      g.normal[i] = hit.geometricNormal;
      g.triangle[i] = hit.triangle;
    }
  });
  return g;
}

ReferenceImage renderReferenceImage(const SceneTracer& tracer, const RenderView& view,
                                    const ReferenceImageOptions& options) {
  if (options.samplesPerPixel < 1 || options.samplesPerPass < 1)
    throw InputError("reference image: samples per pixel and per pass must be >= 1 (got " +
                     std::to_string(options.samplesPerPixel) + " and " +
                     std::to_string(options.samplesPerPass) + ")");
  if (options.bounces < 0)
    throw InputError("reference image: bounces must be >= 0 (got " + std::to_string(options.bounces) + ")");
  if (!(options.maxSeconds >= 0.0))
    throw InputError("reference image: max seconds must be >= 0 (got " + std::to_string(options.maxSeconds) +
                     ")");
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };

  ReferenceImage image;
  image.gbuffer = traceReferenceGBuffer(tracer, view, options.threads);
  const ReferenceGBuffer& g = image.gbuffer;
  std::vector<uint32_t> pixels;  // hit pixels in image order
  for (size_t i = 0; i < g.hit.size(); ++i)
    if (g.hit[i]) pixels.push_back(uint32_t(i));

  BakeOptions bake;
  bake.bounces = options.bounces;
  bake.content = options.content;
  bake.threads = 1;
  bake.progress = false;
  std::vector<PixelAccumulator> acc(pixels.size());
  Progress progress("reference image", uint64_t(pixels.size()) * uint64_t(options.samplesPerPixel), "paths",
                    options.progress);
  int done = 0;
  while (done < options.samplesPerPixel) {
    const int count = std::min(options.samplesPerPass, options.samplesPerPixel - done);
    const uint64_t pass = uint64_t(image.passes);
    parallelFor(
        pixels.size(), options.threads,
        [&](size_t k) {
          const size_t i = pixels[k];
          const uint64_t seed = splitmix64(options.seed ^ splitmix64(uint64_t(i) ^ splitmix64(pass)));
          const ReferenceIrradiance r =
              referenceIrradiance(tracer, g.position[i], g.normal[i], count, seed, bake);
          acc[k].merge(r.samples, r.irradiance, r.stderror);
          progress.advance(uint64_t(count));
        },
        16);
    done += count;
    ++image.passes;
    if (options.maxSeconds > 0.0 && elapsed() >= options.maxSeconds) break;
  }
  progress.finish();
  image.samplesPerPixel = done;

  image.irradiance.assign(g.hit.size(), glm::vec3(0.0f));
  image.stderror.assign(g.hit.size(), glm::vec3(0.0f));
  for (size_t k = 0; k < pixels.size(); ++k) {
    image.irradiance[pixels[k]] = glm::vec3(acc[k].mean);
    image.stderror[pixels[k]] = glm::vec3(acc[k].stderror());
  }
  image.seconds = elapsed();
  return image;
}

std::vector<glm::vec3> probeLookupImage(const ProbeQuery& query, const ReferenceGBuffer& gbuffer,
                                        int threads) {
  std::vector<glm::dvec3> positions;
  std::vector<glm::vec3> normals;
  std::vector<uint32_t> pixels;
  for (size_t i = 0; i < gbuffer.hit.size(); ++i) {
    if (!gbuffer.hit[i]) continue;
    positions.push_back(gbuffer.position[i]);
    normals.push_back(gbuffer.normal[i]);
    pixels.push_back(uint32_t(i));
  }
  std::vector<glm::vec3> values(pixels.size());
  // Pixels in image order are coherent: the batch tries each item's predecessor's tet first.
  query.irradianceBatch(positions.data(), normals.data(), values.data(), values.size(), threads);
  std::vector<glm::vec3> out(gbuffer.hit.size(), glm::vec3(0.0f));
  for (size_t k = 0; k < pixels.size(); ++k) out[pixels[k]] = values[k];
  return out;
}

}  // namespace tetraprobe
