#!/usr/bin/env bash
# Writes the fuzzers' seed corpora (nothing here is committed: seeds are made from the bundled sample).
# Usage: tools/fuzz/make_seeds.sh TETRAPROBE_BINARY OUT_DIR
#   OUT_DIR/level/  real levels baked from samples/two_rooms with 14 user probes (a few seconds each): one with
#                   occlusion planes, one with shadow maps, one L1; each with outer cells, cell grid, kinds
#   OUT_DIR/streaming/  the same levels with a streaming index (`tetraprobe stream`, 2 m coarse spacing), for
#                   fuzz_streaming.cpp
#   OUT_DIR/scene/  inputs of fuzz_scene.cpp (byte 0 = format, then the file, "#--", its companion):
#                   the sample's OBJ + MTL, its scene JSON + a small OBJ, a glTF with a data URI and with b.bin,
#                   a glb
set -euo pipefail
TP=$1
OUT=$2
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
SAMPLE=$ROOT/samples/two_rooms
mkdir -p "$OUT/level" "$OUT/streaming" "$OUT/scene"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

# --- levels: user probes in both rooms and the doorway of the sample (x in [0, 8.2], y in [0, 3], z in [0, 4])
cat > "$TMP/probes.csv" <<'CSV'
0.5,0.5,0.5
3.5,0.5,0.5
0.5,2.5,0.5
3.5,2.5,3.5
0.5,0.5,3.5
2.0,1.5,2.0
4.1,1.2,2.0
4.1,2.0,1.6
5.0,0.5,0.5
7.7,0.5,3.5
7.7,2.5,0.5
5.0,2.5,3.5
6.5,1.5,2.0
2.5,0.3,3.0
CSV
fast=(--probes "$TMP/probes.csv" --placement none --samples 16 --noise 0 --fill-holes 0 --probe-budget 0
      --threads 1)
"$TP" bake "$SAMPLE/two_rooms.scene.json" -o "$OUT/level/planes.tpb" "${fast[@]}" --occlusion planes >/dev/null
"$TP" bake "$SAMPLE/two_rooms.scene.json" -o "$OUT/level/shadow_maps.tpb" "${fast[@]}" --occlusion shadow-maps \
  >/dev/null
"$TP" bake "$SAMPLE/two_rooms.scene.json" -o "$OUT/level/l1.tpb" "${fast[@]}" --occlusion none --sh-order 1 \
  >/dev/null
for level in planes shadow_maps l1; do
  "$TP" stream "$OUT/level/$level.tpb" -o "$OUT/streaming/$level.tpb" --coarse-spacing 2 >/dev/null
done

# --- scenes
sep=$'\n#--\n'
{ printf '\x00'; sed 's/^mtllib .*/mtllib m.mtl/' "$SAMPLE/two_rooms.obj"; printf '%s' "$sep"; cat "$SAMPLE/two_rooms.mtl"; } \
  > "$OUT/scene/obj_two_rooms"
cube_obj='mtllib m.mtl
o cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vn 0 0 -1
vt 0 0
vt 1 1
usemtl light
f 1/1/1 3/2/1 2/1/1
f 1 4 3
usemtl wall
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
'
cube_mtl='newmtl light
Kd 0.8 0.8 0.8
Ke 5 5 5
newmtl wall
Kd 0.5 0.4 0.3
d 0.5
map_Kd missing.png
'
{ printf '\x00'; printf '%s' "$cube_obj"; printf '%s' "$sep"; printf '%s' "$cube_mtl"; } > "$OUT/scene/obj_cube"
{ printf '\x03'; sed 's/"two_rooms.obj"/"m.obj"/' "$SAMPLE/two_rooms.scene.json"; printf '%s' "$sep"
  printf '%s' "$cube_obj" | sed '/^mtllib/d;/^usemtl/d'; } > "$OUT/scene/json_cube"
cat > "$TMP/lights.json" <<'JSON'
{ "mesh": "m.obj", "unit_scale": 0.5, "textures": "ignore", "sky": { "zenith": [1, 1, 1], "horizon": [0.2, 0.2, 0.2] },
  "lights": [ { "type": "point", "name": "bulb", "position": [2, 2.5, 2], "intensity": [10, 9, 8], "radius": 0.05 },
    { "type": "spot", "position": [6, 2.9, 2], "direction": [0, -1, 0], "intensity": 50, "inner_cone_deg": 20, "outer_cone_deg": 35 },
    { "type": "sun", "direction": [0.3, -1, 0.2], "irradiance": [900, 850, 800], "angular_radius_deg": 0.27 } ],
  "cameras": [ { "name": "c", "eye": [4, 9, -3], "target": [4, 0, 2], "up": [0, 1, 0], "fov_deg": 60 } ],
  "fine_volumes": [ { "name": "v", "min": [0, 0, 0], "max": [1, 1, 1] } ],
  "materials": { "cube": { "emission_scale": 2.0, "albedo": [0.3, 0.3, 0.3] } } }
JSON
{ printf '\x03'; cat "$TMP/lights.json"; printf '%s' "$sep"; printf '%s' "$cube_obj" | sed '/^mtllib/d;/^usemtl/d'; } \
  > "$OUT/scene/json_lights"
# One triangle: positions (3 x vec3 float) then indices (3 x u16, padded to 4): 36 + 8 = 44 bytes.
printf '\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x80\x3f\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x80\x3f\x00\x00\x00\x00\x00\x00\x01\x00\x02\x00\x00\x00' \
  > "$TMP/b.bin"
gltf() {  # $1 = buffer uri
  printf '{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0,"translation":[0,1,0]}],'
  printf '"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}],'
  printf '"materials":[{"pbrMetallicRoughness":{"baseColorFactor":[0.5,0.5,0.5,1]},"emissiveFactor":[1,1,1]}],'
  printf '"buffers":[{"byteLength":44%s}],' "$1"
  printf '"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],'
  printf '"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},'
  printf '{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}]}'
}
{ printf '\x01'; gltf ',"uri":"b.bin"'; printf '%s' "$sep"; cat "$TMP/b.bin"; } > "$OUT/scene/gltf_file_buffer"
{ printf '\x01'; gltf ",\"uri\":\"data:application/octet-stream;base64,$(base64 -w0 "$TMP/b.bin")\""; } \
  > "$OUT/scene/gltf_data_uri"
# glb: header (magic, version 2, length), JSON chunk (padded with spaces to 4), BIN chunk (44 bytes).
gltf '' > "$TMP/j.json"
while [ $(( $(stat -c %s "$TMP/j.json") % 4 )) -ne 0 ]; do printf ' ' >> "$TMP/j.json"; done
le32() { printf "\\x$(printf %02x $(($1 & 255)))\\x$(printf %02x $((($1 >> 8) & 255)))\\x$(printf %02x $((($1 >> 16) & 255)))\\x$(printf %02x $((($1 >> 24) & 255)))"; }
jl=$(stat -c %s "$TMP/j.json")
{ printf '\x02glTF'; le32 2; le32 $((12 + 8 + jl + 8 + 44)); le32 "$jl"; printf 'JSON'; cat "$TMP/j.json"
  le32 44; printf 'BIN\x00'; cat "$TMP/b.bin"; } > "$OUT/scene/glb_triangle"
echo "seeds: $(ls "$OUT/level" | wc -l) levels, $(ls "$OUT/streaming" | wc -l) streamed levels, $(ls "$OUT/scene" | wc -l) scenes in $OUT"
