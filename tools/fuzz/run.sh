#!/usr/bin/env bash
# `make fuzz`: builds the libFuzzer harnesses (clang, ASan + UBSan, a build directory of their own so the main
# build stays GCC), makes the seed corpora from the bundled sample, and runs each harness for SECONDS.
# Usage: tools/fuzz/run.sh TETRAPROBE_BINARY FUZZ_BUILD_DIR SECONDS
# Skips (exit 0, one line) when clang cannot link a libFuzzer program (Debian 12: clang-14 and
# libclang-rt-14-dev, which tools/setup/setup.sh installs), or fails (exit 1) there when TETRAPROBE_REQUIRE_ALL
# is set to anything but "" or "0" (CI: .ci/run; tests/common/missing_capability.h reads it too). A crash, sanitizer report, leak or timeout fails
# (exit 1) and leaves the input in FUZZ_BUILD_DIR/artifacts/: reproduce with
#   FUZZ_BUILD_DIR/bin/tetraprobe_fuzz_level ARTIFACT
# then commit it as a regression input with a test that loads it through the normal build and expects a
# typed error (tests/runtime/fuzz_regressions/ or tests/scene/fuzz_regressions/, which this script also feeds
# to the fuzzers when present).
# The corpora in FUZZ_BUILD_DIR/corpus/ persist between runs, so longer local runs keep their coverage.
set -euo pipefail
TP=$1
DIR=$2
SECONDS_EACH=$3
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
CXX=${FUZZ_CXX:-clang++}
CC=${FUZZ_CC:-clang}

probe=$(mktemp -d)
trap 'rm -rf "$probe"' EXIT
echo 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }' > "$probe/f.cpp"
if ! command -v "$CXX" >/dev/null 2>&1 || ! "$CXX" -fsanitize=fuzzer "$probe/f.cpp" -o "$probe/f" 2>/dev/null; then
  why="$CXX cannot link a libFuzzer program (install clang and libclang-rt-14-dev)"
  if [ -n "${TETRAPROBE_REQUIRE_ALL:-}" ] && [ "$TETRAPROBE_REQUIRE_ALL" != 0 ]; then
    echo "fuzz: FAILED: $why; TETRAPROBE_REQUIRE_ALL is set, so the fuzzers may not be skipped" >&2
    exit 1
  fi
  echo "fuzz: skipped: $why"
  exit 0
fi

cmake -S "$ROOT" -B "$DIR" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER="$CC" \
  -DCMAKE_CXX_COMPILER="$CXX" -DTETRAPROBE_FUZZ=ON -DTETRAPROBE_BUILD_TESTS=OFF -DTETRAPROBE_BUILD_BENCH=OFF \
  ${CMAKE_CXX_COMPILER_LAUNCHER:+-DCMAKE_CXX_COMPILER_LAUNCHER=$CMAKE_CXX_COMPILER_LAUNCHER} >/dev/null
cmake --build "$DIR" --target tetraprobe_fuzz_level tetraprobe_fuzz_scene tetraprobe_fuzz_streaming -j "${JOBS:-2}"

if [ ! -d "$DIR/seeds/streaming" ]; then
  rm -rf "$DIR/seeds.tmp"
  "$ROOT/tools/fuzz/make_seeds.sh" "$TP" "$DIR/seeds.tmp"
  rm -rf "$DIR/seeds"
  mv "$DIR/seeds.tmp" "$DIR/seeds"
fi
mkdir -p "$DIR/artifacts"
status=0
for kind in level streaming scene; do
  corpus=$DIR/corpus/$kind
  mkdir -p "$corpus"
  log=$DIR/fuzz_$kind.log
  # -timeout: one input taking 10 s is a hang; -rss_limit_mb: the loaders' limits keep far below it.
  inputs=("$corpus" "$DIR/seeds/$kind")
  regressions=$ROOT/tests/${kind/level/runtime}/fuzz_regressions
  [ -d "$regressions" ] && inputs+=("$regressions")
  # TMPDIR: the scene harness writes its files in a folder of its own there, removed with $probe.
  if ! TMPDIR=$probe ASAN_OPTIONS=detect_leaks=1 "$DIR/bin/tetraprobe_fuzz_$kind" "${inputs[@]}" \
      -max_total_time="$SECONDS_EACH" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$DIR/artifacts/$kind-" >"$log" 2>&1; then
    status=1
    echo "fuzz: $kind: FAILED (log $log, input in $DIR/artifacts/):"
    grep -m 5 -E "ERROR|SUMMARY|runtime error|threw" "$log" || tail -5 "$log"
  fi
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")
  echo "fuzz: $kind: ${execs:-?} executions in ${SECONDS_EACH} s (${rate:-?}/s), corpus $(ls "$corpus" | wc -l) inputs"
done
exit $status
