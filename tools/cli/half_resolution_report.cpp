// halfResolutionReport, halfResolutionJson, printHalfResolution: the half-resolution lookup's figures for
// bench render and eval.
#include "half_resolution_report.h"

#include <cstdio>

namespace tetraprobe::cli {

HalfResolutionReport halfResolutionReport(const RenderResult& r, double fullMs, double gridMs) {
  HalfResolutionReport h;
  h.halfMs = r.timings.passMs("lookup_half");
  h.upsampleMs = r.timings.passMs("upsample");
  h.edgesMs = r.timings.passMs("lookup_edges");
  h.totalMs = h.halfMs + h.upsampleMs + h.edgesMs;
  h.fullMs = fullMs;
  h.gridMs = gridMs;
  h.error = halfResolutionError(r.color, r.halfResolution);
  return h;
}

nlohmann::json halfResolutionJson(const HalfResolutionReport& h) {
  const HalfResolutionError& e = h.error;
  nlohmann::json j = {
      {"lookup_half_ms", h.halfMs},
      {"upsample_ms", h.upsampleMs},
      {"lookup_edges_ms", h.edgesMs},
      {"total_ms", h.totalMs},
      {"ratio_to_full", h.fullMs > 0.0 ? h.totalMs / h.fullMs : 0.0},
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
  if (h.gridMs > 0.0) j["ratio_to_grid"] = h.totalMs / h.gridMs;
  return j;
}

void printHalfResolution(const HalfResolutionReport& h) {
  const HalfResolutionError& e = h.error;
  std::printf(
      "  half resolution (engine option)               %9.3f ms  (lookup a 2x2 block %.3f + upsample %.3f + "
      "edge lookups %.3f; %.2f x full",
      h.totalMs, h.halfMs, h.upsampleMs, h.edgesMs, h.fullMs > 0.0 ? h.totalMs / h.fullMs : 0.0);
  if (h.gridMs > 0.0) std::printf(", %.2f x grid", h.totalMs / h.gridMs);
  std::printf(")\n");
  std::printf(
      "    pixels: %.1f %% interpolated, %.1f %% their block's lookup, %.2f %% looked up at full resolution; "
      "vs full: mean %.4f, p95 %.4f, p99 %.4f, max %.3f, %.2f %% over 5 %%, %.3f %% over 25 %%\n",
      100 * e.interpolated, 100 * e.copied, 100 * e.fullLookup, e.meanRel, e.p95Rel, e.p99Rel, e.maxRel,
      100 * e.over5, 100 * e.over25);
}

}  // namespace tetraprobe::cli
