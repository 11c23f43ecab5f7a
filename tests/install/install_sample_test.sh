#!/usr/bin/env bash
# Installs the engine-side package into a fresh prefix, builds samples/engine_integration against it through
# find_package(tetraprobe), proves no build-side library is linked, bakes a small level of the bundled
# sample and runs the sample on it. Any failed step fails the test with a line naming it.
# Usage: install_sample_test.sh BUILD_DIR SOURCE_DIR TETRAPROBE_CLI WORK_DIR CMAKE CXX
set -euo pipefail
build=$1 src=$2 cli=$3 work=$4 cmake=$5 cxx=$6
fail() { echo "install test: $*" >&2; exit 1; }
# What the engine side must never pull in (licence boundary, docs/architecture.md).
forbidden='cgal|tetgen|embree|tbb|gmp|mpfr'

rm -rf "$work"
mkdir -p "$work"
"$cmake" --install "$build" --prefix "$work/prefix" > "$work/install.log" || fail "cmake --install failed"

# 1. The exported targets name no build-side library in their link interface.
targets=$(ls "$work"/prefix/lib*/cmake/tetraprobe/tetraprobeTargets*.cmake)
links=$(grep -h 'INTERFACE_LINK_LIBRARIES' $targets || true)
[ -n "$links" ] || fail "no INTERFACE_LINK_LIBRARIES in $targets"
if echo "$links" | grep -iqE "$forbidden"; then fail "installed targets link a build-side library: $links"; fi
echo "installed link interfaces:"; echo "$links" | sed 's/^ */  /'
# ...and nothing but the runtime libraries, their headers, the GLSL includes and the package files is installed.
extra=$(cd "$work/prefix" && find . -type f | grep -vE '^\./include/tetraprobe/runtime/[a-z0-9_]+\.h$|^\./lib[^/]*/libtetraprobe_runtime(_vulkan)?\.a$|^\./lib[^/]*/cmake/tetraprobe/[A-Za-z_-]+\.cmake$|^\./share/tetraprobe/shaders/tetraprobe[a-z_]*\.glsl$' || true)
[ -z "$extra" ] || fail "unexpected files installed: $extra"

# 2. The sample builds against the installed package only (a separate CMake project).
"$cmake" -S "$src/samples/engine_integration" -B "$work/sample" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_PREFIX_PATH="$work/prefix" > "$work/configure.log" 2>&1 ||
  { cat "$work/configure.log"; fail "configuring the sample against the installed package failed"; }
"$cmake" --build "$work/sample" > "$work/build.log" 2>&1 || { cat "$work/build.log"; fail "building the sample failed"; }
bin="$work/sample/engine_integration"
grep -q "^tetraprobe_DIR:PATH=$work/prefix/" "$work/sample/CMakeCache.txt" ||
  fail "find_package(tetraprobe) did not find the package installed in $work/prefix"

# 3. The binary: no build-side shared library needed, no build-side symbol linked in statically.
needed=$(readelf -d "$bin" | grep NEEDED || true)
echo "sample NEEDED:"; echo "$needed" | sed 's/^ */  /'
if echo "$needed" | grep -iqE "$forbidden"; then fail "sample needs a build-side library: $needed"; fi
if nm -C "$bin" | grep -E ' [TtWwBbDdRr] ' | grep -E 'CGAL::|tbb::|rtc[A-Z][a-zA-Z]+|__gmp|tetgenio|embree' | head -5 | grep -q .; then
  fail "sample contains build-side symbols"
fi

# 4. A small level of the bundled sample (coarse and quick: the sample checks behaviour, not accuracy).
"$cli" bake "$src/samples/two_rooms/two_rooms.scene.json" -o "$work/two_rooms.tpb" --spacing 1 --samples 64 \
  --max-samples 256 --path-budget 200000 --probe-budget 0 > "$work/bake.log" 2>&1 ||
  { cat "$work/bake.log"; fail "baking the level failed"; }

# 5. The sample runs and checks itself (its GPU lighting pass against the CPU's answers too); a missing level
# is a one-line error with exit code 2. Without a Vulkan device the sample skips its GPU side (a failure when
# TETRAPROBE_REQUIRE_ALL=1, as CI sets).
"$bin" "$work/two_rooms.tpb" > "$work/sample.log" || { cat "$work/sample.log"; fail "the sample failed on $work/two_rooms.tpb"; }
grep -E '^GPU' "$work/sample.log"
nogpu=0
if grep -q 'no Vulkan device' "$work/sample.log"; then
  [ "${TETRAPROBE_REQUIRE_ALL:-0}" != 1 ] || fail "no Vulkan device, and TETRAPROBE_REQUIRE_ALL=1"
  nogpu=1
fi
[ "$nogpu" = 1 ] || grep -qE '^GPU: lighting pass \(tetraprobe.glsl\) over [1-9][0-9]* surface points' "$work/sample.log" ||
  fail "the sample's lighting pass did not run"
set +e
"$bin" "$work/missing.tpb" 2> "$work/missing.err"; code=$?
set -e
[ "$code" -eq 2 ] || fail "missing level: exit code $code, expected 2"
# 6. Streamed by sector on the GPU: the bundled rooms scaled 12x (84 sectors of 16 m; coarse and quick), the
# streaming index added, and the sample's loop with a fixed-size GPU pool of at most 25 % of the level's GPU
# bytes; it checks the budget, at least 20 loads and evictions, the GPU's buffers against the pool's, and that
# its lighting pass (its own shader including the installed tetraprobe.glsl) shades every pixel the pool answers
# from loaded sectors exactly as over the whole level.
printf '{"mesh": "%s/samples/two_rooms/two_rooms.obj", "unit_scale": 12, "sky": {"radiance": [0.2, 0.2, 0.2]}}\n' \
  "$src" > "$work/big.scene.json"
"$cli" bake "$work/big.scene.json" -o "$work/big.tpb" --spacing 6 --max-spacing 24 --samples 32 --noise 0 \
  --probe-budget 0 --fill-holes 0 > "$work/big_bake.log" 2>&1 || { cat "$work/big_bake.log"; fail "baking the large level failed"; }
"$cli" stream "$work/big.tpb" -o "$work/big_streamed.tpb" --coarse-spacing 24 > "$work/stream.log" 2>&1 ||
  { cat "$work/stream.log"; fail "tetraprobe stream failed"; }
"$bin" "$work/big_streamed.tpb" --stream 0.25 96 > "$work/streamed.log" ||
  { tail -5 "$work/streamed.log"; fail "the streamed fly-through failed"; }
grep -E '^streaming' "$work/streamed.log"
[ "$nogpu" = 1 ] || grep -qE '^streaming: lighting pass: [1-9][0-9]* of [0-9]+ geometry pixels shaded from loaded sectors, 0 of them differ' \
  "$work/streamed.log" || fail "the streamed lighting pass checked no pixel"
echo "install test: ok"
