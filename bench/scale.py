#!/usr/bin/env python3
"""The scale benchmark: levels of growing size baked with the defaults, measured per stage.

Builds towns of N copies (N = k x k) of a source level (default: the bundled outdoor block, three houses and a
walled yard on a 48 m ground tile), each copy turned by a multiple of 90 degrees about +Y so no two neighbours
look alike, lit by the source scene's sun and sky; bakes each with `tetraprobe bake` (defaults, or the options
given after --), and records per level: probes, tets, seconds per bake stage, peak memory (the bake process's
maximum resident set), file bytes and the lookup's GPU bytes (`tetraprobe inspect`). Then fits, over the levels
of --fit-from copies and more, the least-squares exponent of each stage's seconds and of peak memory against the
probe count (time ~ probes^e), and writes a Markdown table and a log-log SVG plot.

    bench/scale.py --copies 1,4,16 --out out/scale --markdown out/scale/scale.md --svg out/scale/scale.svg

Standard library only. The towns are deterministic; a level already baked in --out with the same options is
measured again only with --rebake.
"""
import argparse
import json
import math
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
STAGES = ["place", "tetrahedralize", "bake", "occlusion", "holes", "refine", "write", "total"]


def read_obj(path):
    """Vertices and faces (as vertex-index tuples, 0-based, with their material) of a plain OBJ."""
    verts, faces, mtllib, material = [], [], None, None
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts.append(tuple(float(x) for x in parts[1:4]))
            elif parts[0] == "f":
                idx = []
                for p in parts[1:]:
                    i = int(p.split("/")[0])
                    idx.append(i - 1 if i > 0 else len(verts) + i)
                faces.append((material, tuple(idx)))
            elif parts[0] == "usemtl":
                material = parts[1]
            elif parts[0] == "mtllib":
                mtllib = " ".join(parts[1:])
    if not verts or not faces:
        raise SystemExit(f"scale: {path} has no vertices or faces")
    return verts, faces, mtllib


def write_town(source_obj, source_scene, copies, out_dir):
    """Writes town_N.obj (+ the source's MTL copied beside it) and town_N.scene.json; returns the scene path."""
    k = int(round(math.sqrt(copies)))
    if k * k != copies:
        raise SystemExit(f"scale: {copies} copies is not a square number (1, 4, 9, 16, ...)")
    verts, faces, mtllib = read_obj(source_obj)
    lo = [min(v[a] for v in verts) for a in range(3)]
    hi = [max(v[a] for v in verts) for a in range(3)]
    cx, cz = 0.5 * (lo[0] + hi[0]), 0.5 * (lo[2] + hi[2])
    pitch = max(hi[0] - lo[0], hi[2] - lo[2])
    name = f"town_{copies}"
    obj_path = os.path.join(out_dir, name + ".obj")
    lines = [f"# {name}.obj: {k} x {k} copies of {os.path.basename(source_obj)}, written by bench/scale.py\n"]
    if mtllib:
        src_mtl = os.path.join(os.path.dirname(source_obj), mtllib)
        with open(src_mtl) as f:
            mtl = f.read()
        with open(os.path.join(out_dir, os.path.basename(mtllib)), "w") as f:
            f.write(mtl)
        lines.append(f"mtllib {os.path.basename(mtllib)}\n")
    base = 0
    for j in range(k):
        for i in range(k):
            turn = (i + 2 * j) % 4  # quarter turns about +Y, about the source's centre
            c, s = [(1, 0), (0, 1), (-1, 0), (0, -1)][turn]
            ox, oz = (i - 0.5 * (k - 1)) * pitch, (j - 0.5 * (k - 1)) * pitch
            for (x, y, z) in verts:
                dx, dz = x - cx, z - cz
                lines.append(f"v {ox + c * dx + s * dz:.6g} {y:.6g} {oz - s * dx + c * dz:.6g}\n")
            current = None
            for material, idx in faces:
                if material != current and material is not None:
                    lines.append(f"usemtl {material}\n")
                    current = material
                lines.append("f " + " ".join(str(base + i_ + 1) for i_ in idx) + "\n")
            base += len(verts)
    with open(obj_path, "w") as f:
        f.writelines(lines)
    with open(source_scene) as f:
        scene = json.load(f)
    scene = {
        "comment": f"{k} x {k} copies of {os.path.basename(source_obj)} (bench/scale.py), the source's sun and sky",
        "mesh": os.path.basename(obj_path),
        "unit_scale": scene.get("unit_scale", 1.0),
        "sky": scene.get("sky"),
        "lights": scene.get("lights", []),
    }
    scene = {key: v for key, v in scene.items() if v is not None}
    scene_path = os.path.join(out_dir, name + ".scene.json")
    with open(scene_path, "w") as f:
        json.dump(scene, f, indent=2)
    return scene_path, len(faces) * copies


def bake(tetraprobe, scene_path, level, report, log, extra):
    """Bakes under /usr/bin/time; returns peak resident memory in bytes and wall seconds."""
    cmd = ["/usr/bin/time", "-f", "scale-time %e s %M KB", tetraprobe, "bake", scene_path, "-o", level,
           "--report", report] + extra
    with open(log, "w") as f:
        rc = subprocess.call(cmd, stdout=f, stderr=subprocess.STDOUT)
    text = open(log).read()
    if rc != 0:
        raise SystemExit(f"scale: bake of {scene_path} failed (rc {rc}); see {log}")
    m = re.findall(r"scale-time ([0-9.]+) s ([0-9]+) KB", text)
    if not m:
        raise SystemExit(f"scale: no /usr/bin/time line in {log}")
    return int(m[-1][1]) * 1024, float(m[-1][0])


def gpu_bytes(tetraprobe, level):
    out = subprocess.run([tetraprobe, "inspect", level], capture_output=True, text=True, check=True).stdout
    m = re.search(r"lookup\s+([0-9]+) bytes on the GPU", out)
    return int(m.group(1)) if m else None


def fit_exponent(xs, ys):
    """Least-squares slope of log y against log x (None with fewer than two usable points)."""
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys) if x > 0 and y is not None and y > 0]
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    if sxx <= 0:
        return None
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx


def svg_plot(rows, path):
    """Log-log plot: seconds per stage and peak memory (GB, right-hand quantity drawn on the same axes as
    GB x 100) against probes."""
    w, h, m = 640, 420, 60
    series = {s: [(r["probes"], r["seconds"].get(s)) for r in rows] for s in STAGES}
    series["peak GB x100"] = [(r["probes"], r["peak_bytes"] / 1e9 * 100) for r in rows]
    xs = [r["probes"] for r in rows]
    ys = [y for pts in series.values() for _, y in pts if y and y > 0]
    if len(xs) < 2 or not ys:
        return
    lx0, lx1 = math.log10(min(xs)), math.log10(max(xs))
    ly0, ly1 = math.floor(math.log10(min(ys))), math.ceil(math.log10(max(ys)))
    lx1 = lx1 if lx1 > lx0 else lx0 + 1

    def px(x):
        return m + (math.log10(x) - lx0) / (lx1 - lx0) * (w - 2 * m)

    def py(y):
        return h - m - (math.log10(y) - ly0) / (ly1 - ly0) * (h - 2 * m)

    colors = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#7f7f7f", "#000000", "#e377c2"]
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" '
           f'font-size="11"><rect width="{w}" height="{h}" fill="white"/>']
    out.append(f'<line x1="{m}" y1="{h - m}" x2="{w - m}" y2="{h - m}" stroke="black"/>')
    out.append(f'<line x1="{m}" y1="{m}" x2="{m}" y2="{h - m}" stroke="black"/>')
    for e in range(int(ly0), int(ly1) + 1):
        y = py(10 ** e)
        out.append(f'<line x1="{m}" y1="{y:.1f}" x2="{w - m}" y2="{y:.1f}" stroke="#ddd"/>')
        out.append(f'<text x="{m - 6}" y="{y + 4:.1f}" text-anchor="end">1e{e}</text>')
    for x in xs:
        out.append(f'<text x="{px(x):.1f}" y="{h - m + 16}" text-anchor="middle">{x:,}</text>')
    out.append(f'<text x="{w / 2}" y="{h - 12}" text-anchor="middle">probes (log)</text>')
    out.append(f'<text x="14" y="{h / 2}" transform="rotate(-90 14 {h / 2})" text-anchor="middle">'
               f'seconds per stage; peak memory GB x 100 (log)</text>')
    for n, (name, pts) in enumerate(series.items()):
        pts = [(x, y) for x, y in pts if y and y > 0]
        if not pts:
            continue
        col = colors[n % len(colors)]
        d = " ".join(f"{px(x):.1f},{py(y):.1f}" for x, y in pts)
        out.append(f'<polyline points="{d}" fill="none" stroke="{col}" stroke-width="1.5"/>')
        for x, y in pts:
            out.append(f'<circle cx="{px(x):.1f}" cy="{py(y):.1f}" r="2.5" fill="{col}"/>')
        out.append(f'<text x="{w - m + 4}" y="{m + 14 * n}" fill="{col}">{name}</text>')
    out.append("</svg>\n")
    with open(path, "w") as f:
        f.write("\n".join(out))


def markdown(rows, fit_from, extra):
    lines = ["| copies | triangles | probes | tets | " + " | ".join(f"{s} s" for s in STAGES) +
             " | peak memory | file | GPU lookup |", "|" + "---|" * (len(STAGES) + 7)]
    for r in rows:
        lines.append(f"| {r['copies']} | {r['triangles']:,} | {r['probes']:,} | {r['tets']:,} | " +
                     " | ".join(f"{r['seconds'].get(s, 0):.1f}" for s in STAGES) +
                     f" | {r['peak_bytes'] / 1e9:.2f} GB | {r['file_bytes'] / 1e6:.2f} MB | " +
                     (f"{r['gpu_bytes'] / 1e6:.2f} MB" if r['gpu_bytes'] else "n/a") + " |")
    fitted = [r for r in rows if r["copies"] >= fit_from]
    lines.append("")
    if len(fitted) >= 2:
        xs = [r["probes"] for r in fitted]
        parts = []
        for s in STAGES:
            e = fit_exponent(xs, [r["seconds"].get(s) for r in fitted])
            parts.append(f"{s} {e:.2f}" if e is not None else f"{s} n/a")
        e = fit_exponent(xs, [r["peak_bytes"] for r in fitted])
        parts.append(f"peak memory {e:.2f}" if e is not None else "peak memory n/a")
        lines.append(f"Exponents (least squares of log quantity on log probes, levels of {fit_from} copies and "
                     f"more: {', '.join(str(r['copies']) for r in fitted)}): " + "; ".join(parts) + ".")
    else:
        lines.append(f"Exponents: fewer than two levels of {fit_from} copies or more; none fitted.")
    lines.append(f"Bake options: defaults{(' + ' + ' '.join(extra)) if extra else ''}.")
    lines += ["", "What hole filling and refinement did on each level (the bake's own figures: hole points are "
              "surface points whose tet's data hides all four probes; refinement's error is the mean |log2| of "
              "the lookup against the oracle at independent surface points, before and after its probes):", "",
              "| copies | hole points checked (round 1) | hole points (round 1) | hole probes | refine points | "
              "refine probes | refine mean abs log2, before -> after | reduction |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        rounds = r.get("holes", {}).get("rounds", [])
        first = rounds[0] if rounds else {}
        ref = r.get("refine", {})
        before, after = ref.get("mean_log2_error_before"), ref.get("mean_log2_error_after")
        change = f"{(before - after) / before * 100:.0f} %" if before and after is not None else "n/a"
        fig = f"{before:.4f} -> {after:.4f}" if before is not None and after is not None else "n/a"
        lines.append(f"| {r['copies']} | {first.get('points_checked', 0):,} | {first.get('hole_points', 0):,} | "
                     f"{r.get('holes', {}).get('probes_added', 0):,} | {ref.get('points', 0):,} | "
                     f"{ref.get('probes_added', 0):,} | {fig} | {change} |")
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 epilog="Options after -- go to every `tetraprobe bake`.")
    ap.add_argument("--copies", default="1,4,16,64", help="copies per level, square numbers (default 1,4,16,64)")
    ap.add_argument("--source", default=os.path.join(ROOT, "samples/outdoor/outdoor.obj"),
                    help="source OBJ (plain materials; default the bundled outdoor block)")
    ap.add_argument("--source-scene", default=None,
                    help="scene JSON whose sun, lights and sky light the town (default: SOURCE's .scene.json)")
    ap.add_argument("--tetraprobe", default=os.path.join(ROOT, "build/bin/tetraprobe"))
    ap.add_argument("--out", default=os.path.join(ROOT, "out/scale"))
    ap.add_argument("--fit-from", type=int, default=4, help="fit exponents over levels of this many copies and more")
    ap.add_argument("--markdown", help="write the table here (default: print it)")
    ap.add_argument("--svg", help="write the log-log plot here")
    ap.add_argument("--json", help="write every figure here")
    ap.add_argument("--rebake", action="store_true", help="bake even where --out holds a level of these options")
    args, extra = ap.parse_known_args()
    extra = [e for e in extra if e != "--"]
    scene_src = args.source_scene or os.path.splitext(args.source)[0] + ".scene.json"
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for copies in [int(c) for c in args.copies.split(",") if c]:
        scene_path, triangles = write_town(args.source, scene_src, copies, args.out)
        level = os.path.join(args.out, f"town_{copies}.tpb")
        report = os.path.join(args.out, f"town_{copies}.bake.json")
        log = os.path.join(args.out, f"town_{copies}.bake.log")
        meta = os.path.join(args.out, f"town_{copies}.scale.json")
        key = {"extra": extra, "tetraprobe": os.path.getmtime(args.tetraprobe)}
        cached = None
        if not args.rebake and os.path.exists(meta) and os.path.exists(level):
            cached = json.load(open(meta))
            if cached.get("key") != key:
                cached = None
        if cached:
            peak, wall = cached["peak_bytes"], cached["wall_s"]
        else:
            print(f"scale: baking {copies} copies ({triangles:,} faces) ...", file=sys.stderr, flush=True)
            peak, wall = bake(args.tetraprobe, scene_path, level, report, log, extra)
            json.dump({"key": key, "peak_bytes": peak, "wall_s": wall}, open(meta, "w"))
        rep = json.load(open(report))
        row = {
            "copies": copies, "triangles": rep["scene"]["triangles"], "probes": rep["probes"]["count"],
            "tets": rep["tets"]["count"], "seconds": {s: rep["timings_s"].get(s, 0.0) for s in STAGES},
            "peak_bytes": peak, "wall_s": wall, "file_bytes": os.path.getsize(level),
            "gpu_bytes": gpu_bytes(args.tetraprobe, level), "shell_probes": rep["probes"]["shell"],
            "refine": rep["refine"], "holes": rep["holes"],
        }
        rows.append(row)
        print(f"scale: {copies} copies: {row['probes']:,} probes, {row['seconds']['total']:.1f} s, "
              f"{peak / 1e9:.2f} GB", file=sys.stderr, flush=True)
    md = markdown(rows, args.fit_from, extra)
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write(md)
    else:
        sys.stdout.write(md)
    if args.svg:
        svg_plot(rows, args.svg)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=2)


if __name__ == "__main__":
    main()
