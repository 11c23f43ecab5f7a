#!/usr/bin/env bash
# A sharded bake on one machine, as a scheduler would run it: N shard processes at once, then the merge,
# then the one-process bake with the same options; exits 1 unless the two levels are byte for byte equal.
# usage: run_local.sh TETRAPROBE SCENE N WORKDIR [bake options...]   (docs/distributed.md)
# ROUNDS=2 in the environment runs the two-round protocol (bake --round 1, merge --floor, bake --round 2).
# FARM=W in the environment runs the merge with a trace farm of W workers (merge --farm, tetraprobe worker),
# started beside it.
set -euo pipefail
if [ $# -lt 4 ]; then
  echo "usage: $0 TETRAPROBE SCENE N WORKDIR [bake options...]" >&2
  exit 2
fi
tp=$1 scene=$2 n=$3 work=$4
shift 4
rm -rf "$work"
mkdir -p "$work"
start=$(date +%s.%N)
# Runs "$tp bake $scene --shard i/n EXTRA... -o $work/PREFIXi.part" for every i at once.
shards() {
  local prefix=$1
  shift
  local pids=()
  for ((i = 0; i < n; i++)); do
    "$tp" bake "$scene" --shard "$i/$n" "${@//@I@/$i}" -o "$work/$prefix$i.part" "${opts[@]}" \
      >"$work/$prefix$i.log" 2>&1 &
    pids+=($!)
  done
  for p in "${pids[@]}"; do
    wait "$p" || { echo "run_local: a shard failed:" >&2; cat "$work/$prefix"*.log >&2; exit 1; }
  done
}
opts=("$@")
if [ "${ROUNDS:-1}" = 2 ]; then
  shards round1_ --round 1
  "$tp" merge --floor "$work"/round1_*.part -o "$work/floor.part" >"$work/floor.log" 2>&1 ||
    { cat "$work/floor.log" >&2; exit 1; }
  shards shard --round 2 --floor "$work/floor.part" --resume "$work/round1_@I@.part"
else
  shards shard
fi
shards=$(date +%s.%N)
farm=()
wpids=()
if [ "${FARM:-0}" -gt 0 ]; then
  farm=(--farm "$work/farm" --workers "$FARM")
  for ((i = 0; i < FARM; i++)); do
    "$tp" worker "$scene" --farm "$work/farm" --index "$i/$FARM" >"$work/worker$i.log" 2>&1 &
    wpids+=($!)
  done
fi
"$tp" merge "$work"/shard*.part -o "$work/merged.tpb" "${farm[@]}" >"$work/merge.log" 2>&1 ||
  { cat "$work/merge.log" "$work"/worker*.log >&2 2>/dev/null; exit 1; }
for p in "${wpids[@]}"; do
  wait "$p" || { echo "run_local: a worker failed:" >&2; cat "$work"/worker*.log >&2; exit 1; }
done
merged=$(date +%s.%N)
"$tp" bake "$scene" -o "$work/single.tpb" "$@" >"$work/single.log" 2>&1 || { cat "$work/single.log" >&2; exit 1; }
single=$(date +%s.%N)
awk -v a="$start" -v b="$shards" -v c="$merged" -v d="$single" \
  'BEGIN { printf "shards (parallel) %.1f s, merge %.1f s, one-process bake %.1f s\n", b - a, c - b, d - c }'
cmp "$work/merged.tpb" "$work/single.tpb"
echo "merged level == one-process level ($(stat -c %s "$work/single.tpb") bytes)"
