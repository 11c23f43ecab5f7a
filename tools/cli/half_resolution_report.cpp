// halfResolutionJson, printHalfResolution: the half-resolution lookup's figures for bench render and eval.
#include "half_resolution_report.h"

#include <cstdio>

#include "tetraprobe/eval/half_resolution_error.h"

namespace tetraprobe::cli {

namespace {

double passMs(const RenderResult& r, const char* name) {
  for (const PassTiming& p : r.timings.passes)
    if (p.name == name) return p.ms;
  return 0.0;
}

struct HalfTimes {
  double half, upsample, edges, total;
};

HalfTimes halfTimes(const RenderResult& r) {
  HalfTimes t{passMs(r, "lookup_half"), passMs(r, "upsample"), passMs(r, "lookup_edges"), 0.0};
  t.total = t.half + t.upsample + t.edges;
  return t;
}

}  // namespace

nlohmann::json halfResolutionJson(const RenderResult& r, double fullMs, double gridMs) {
  const HalfTimes t = halfTimes(r);
  const HalfResolutionError e = halfResolutionError(r.color, r.halfResolution);
  nlohmann::json j = {
      {"lookup_half_ms", t.half},
      {"upsample_ms", t.upsample},
      {"lookup_edges_ms", t.edges},
      {"total_ms", t.total},
      {"ratio_to_full", fullMs > 0.0 ? t.total / fullMs : 0.0},
      {"pixels_interpolated", e.interpolated},
      {"pixels_own_lookup", e.copied},
      {"pixels_full_lookup", e.fullLookup},
      {"error_vs_full",
       {{"mean_rel", e.meanRel},
        {"p95_rel", e.p95Rel},
        {"p99_rel", e.p99Rel},
        {"max_rel", e.maxRel},
        {"share_over_5pct", e.over5},
        {"share_over_25pct", e.over25},
        {"floor", e.floor},
        {"definition",
         "per geometry pixel |Y(half) - Y(full)| / max(Y(full), floor), Y = Rec. 709 luminance, floor = "
         "max(5 % of the mean Y(full), 0.01)"}}}};
  if (gridMs > 0.0) j["ratio_to_grid"] = t.total / gridMs;
  return j;
}

void printHalfResolution(const RenderResult& r, double fullMs, double gridMs) {
  const HalfTimes t = halfTimes(r);
  const HalfResolutionError e = halfResolutionError(r.color, r.halfResolution);
  std::printf(
      "  half resolution (engine option)               %9.3f ms  (lookup a 2x2 block %.3f + upsample %.3f + "
      "edge lookups %.3f; %.2f x full",
      t.total, t.half, t.upsample, t.edges, fullMs > 0.0 ? t.total / fullMs : 0.0);
  if (gridMs > 0.0) std::printf(", %.2f x grid", t.total / gridMs);
  std::printf(")\n");
  std::printf(
      "    pixels: %.1f %% interpolated, %.1f %% their block's lookup, %.2f %% looked up at full resolution; "
      "vs full: mean %.4f, p95 %.4f, p99 %.4f, max %.3f, %.2f %% over 5 %%, %.3f %% over 25 %%\n",
      100 * e.interpolated, 100 * e.copied, 100 * e.fullLookup, e.meanRel, e.p95Rel, e.p99Rel, e.maxRel,
      100 * e.over5, 100 * e.over25);
}

}  // namespace tetraprobe::cli
