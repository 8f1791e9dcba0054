#!/usr/bin/env bash
# shadowctl against a real shadow-server on a loopback port: the demo renders and writes all six
# files (and with zstd chunks, another EXR compression and no previews, the same shadow map);
# a bad flag value and a request the server rejects both fail with the reason; a point
# light with an explicit uniform technique is rejected; the demo under a point light without
# --technique renders the cube: shadowmap_cube.exr and .png, and the report's face list; a
# three-frame sequence writes each frame and keeps what did not change; upload and --scene-id
# render over a scene the server holds; stats prints one screen, --json the whole document; long
# work prints its progress.
# Usage: shadowctl_e2e.sh SHADOW_SERVER SHADOWCTL
set -euo pipefail
server_bin=$1
ctl=$2
dir=$(mktemp -d)
server=
cleanup() {
  if [[ -n $server ]]; then
    kill "$server" 2>/dev/null || true
    # An idle server exits at once on SIGTERM; never let a stuck one hang the suite.
    for _ in $(seq 100); do kill -0 "$server" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$server" 2>/dev/null || true
    wait "$server" 2>/dev/null || true
  fi
  rm -rf "$dir"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*" >&2
  exit 1
}

"$server_bin" --listen 127.0.0.1:0 >"$dir/server.log" 2>&1 &
server=$!
address=
for _ in $(seq 1200); do
  address=$(sed -n 's/^listening on //p' "$dir/server.log")
  [[ -n $address ]] && break
  kill -0 "$server" 2>/dev/null || fail "server exited: $(cat "$dir/server.log")"
  sleep 0.1
done
[[ -n $address ]] || fail "server did not start"

"$ctl" render --server "$address" --scene builtin:demo --out "$dir/out" --map-size 512 \
  --size 320x180 >"$dir/report.txt" || fail "demo render: $(cat "$dir/report.txt")"
for name in shadowmap visibility position; do
  for ext in exr png; do
    [[ -s $dir/out/$name.$ext ]] || fail "no $name.$ext"
    grep -q "$dir/out/$name.$ext" "$dir/report.txt" || fail "report does not name $name.$ext"
  done
done
grep -q "512x512, 1 channel float32" "$dir/report.txt" || fail "report lacks the map size"
grep -q "^passes: " "$dir/report.txt" || fail "report lacks the passes"
grep -q "^  total " "$dir/report.txt" || fail "report lacks the timings"
grep -q "^  all files written " "$dir/report.txt" || fail "report lacks the client's timeline"

# zstd chunks, piz EXRs and no previews: the same shadow map, bit for bit, and no PNG.
"$ctl" render --server "$address" --scene builtin:demo --out "$dir/zstd" --map-size 512 \
  --size 320x180 --chunk-compression zstd --exr-compression piz --preview none \
  >"$dir/zstd.txt" || fail "zstd render: $(cat "$dir/zstd.txt")"
[[ -s $dir/zstd/shadowmap.exr && ! -e $dir/zstd/shadowmap.png ]] || fail "--preview none"
idiff -fail 0 -warn 0 "$dir/out/shadowmap.exr" "$dir/zstd/shadowmap.exr" >"$dir/idiff.txt" ||
  fail "the zstd/piz shadow map differs: $(cat "$dir/idiff.txt")"

# A flag error never reaches the server; exit 2 names the flag.
set +e
"$ctl" render --server "$address" --scene builtin:demo --out "$dir/bad" --eye 1,2 2>"$dir/err1"
rc=$?
"$ctl" render --server "$address" --scene builtin:demo --out "$dir/bad" --near -1 2>"$dir/err2"
rc2=$?
set -e
[[ $rc == 2 ]] && grep -q -- "--eye: expected X,Y,Z" "$dir/err1" || fail "bad --eye: rc $rc, $(cat "$dir/err1")"
# near <= 0 breaks the server's rule, which shadowctl checks itself: exit 2, the flag and field.
[[ $rc2 == 2 ]] && grep -q -- "--near: camera.near" "$dir/err2" ||
  fail "near -1: rc $rc2, $(cat "$dir/err2")"
# What only the server knows is its to refuse, and shadowctl passes that on with exit 1: a scene
# id it does not hold.
set +e
"$ctl" render --server "$address" --scene-id "$(printf '0%.0s' $(seq 64))" --eye 1,1,1   --target 0,0,0 --light directional:0,-1,0 --out "$dir/bad" 2>"$dir/err9"
rc9=$?
set -e
[[ $rc9 == 1 ]] && grep -q "said NOT_FOUND: scene_id" "$dir/err9" ||
  fail "unknown scene id: rc $rc9, $(cat "$dir/err9")"
[[ ! -e $dir/bad ]] || fail "a failed render left an output directory"
for flag in --preview --exr-compression --chunk-compression; do
  set +e
  "$ctl" render --server "$address" --scene builtin:demo --out "$dir/bad" $flag lossy 2>"$dir/err5"
  rc5=$?
  set -e
  [[ $rc5 == 2 ]] && grep -q -- "$flag: " "$dir/err5" || fail "bad $flag: rc $rc5, $(cat "$dir/err5")"
done

# A hostile scene file is refused before the server: exit 2, naming file, line and token.
printf 'v 0 0 0\nv nan 1 0\nv 0 1 0\nf 1 2 3\n' >"$dir/nan.obj"
set +e
"$ctl" render --server "$address" --scene "$dir/nan.obj" --out "$dir/bad" 2>"$dir/err4"
rc4=$?
set -e
[[ $rc4 == 2 ]] && grep -q "nan.obj:2: coordinate 'nan' is not a finite float" "$dir/err4" ||
  fail "nan.obj: rc $rc4, $(cat "$dir/err4")"

# An explicit technique is never replaced: uniform with a point light breaks the server's rule.
set +e
"$ctl" render --server "$address" --scene builtin:demo --out "$dir/bad" --map-size 256 \
  --size 64x36 --light point:0,5,0 --technique uniform 2>"$dir/err3"
rc3=$?
set -e
[[ $rc3 == 2 ]] && grep -q -- "--light point:PX,PY,PZ: lights\[0\].point: " "$dir/err3" ||
  fail "point light with uniform: rc $rc3, $(cat "$dir/err3")"

"$ctl" render --server "$address" --scene builtin:demo --out "$dir/cube" --map-size 256 \
  --size 320x180 --light point:0,5,0 --products shadowmap,visibility >"$dir/cube.txt" ||
  fail "point-light render: $(cat "$dir/cube.txt")"
for ext in exr png; do
  [[ -s $dir/cube/shadowmap_cube.$ext ]] || fail "no shadowmap_cube.$ext: $(cat "$dir/cube.txt")"
done
grep -q "256x256, 1 channel float32, [1-6] faces" "$dir/cube.txt" ||
  fail "report lacks the cube's faces: $(cat "$dir/cube.txt")"
grep -q "^  cube: [1-6] of 6 faces rendered" "$dir/cube.txt" ||
  fail "report lacks the face count: $(cat "$dir/cube.txt")"
for face in +x -x +y -y +z -z; do
  grep -q -- "^    $face " "$dir/cube.txt" || fail "report does not list face $face"
done
[[ -s $dir/cube/visibility.exr ]] || fail "no visibility.exr under the point light"
# A sequence: the demo scene uploaded once, three frames (a moved camera with --fit scene keeps
# the sun's map; then a moved sun renders it again), each frame's files, its report line.
cat >"$dir/frames.json" <<'JSON'
{"frames": [{}, {"camera": {"eye": {"x": 12, "y": 9, "z": 15}, "target": {"x": 0, "y": 1, "z": 0},
  "width": 160, "height": 90}},
 {"lights": [{"directional": {"direction": {"x": 0.5, "y": -1, "z": 0}}}]}]}
JSON
"$ctl" sequence --server "$address" --scene builtin:demo --frames "$dir/frames.json" \
  --out "$dir/seq" --map-size 256 --size 160x90 --fit scene --products shadowmap,visibility \
  >"$dir/seq.txt" || fail "sequence: $(cat "$dir/seq.txt")"
for f in 0000 0001 0002; do
  [[ -s $dir/seq/frame_$f/visibility.exr && -s $dir/seq/frame_$f/shadowmap.exr ]] ||
    fail "frame $f: no files: $(cat "$dir/seq.txt")"
done
# Frame 1 moves the camera; frame 2 the sun, and the camera back.
grep -q "^frame 0001 .*kept: scene shadow_map, ran again: gbuffer gbuffer.resolve$" "$dir/seq.txt" ||
  fail "frame 1 did not keep the scene and the map: $(cat "$dir/seq.txt")"
grep -q "^frame 0002 .*kept: scene, ran again: shadow_map gbuffer gbuffer.resolve$" \
  "$dir/seq.txt" ||
  fail "frame 2 should keep only the scene (a new sun, the first camera back): $(cat "$dir/seq.txt")"
grep -q "^after the first frame: " "$dir/seq.txt" || fail "no summary: $(cat "$dir/seq.txt")"
# A shadow atlas of an OBJ with UVs (one mesh: a ground and an occluder above it, each its own
# chart): written, with its tiles as an EXR attribute; without --fit scene the server says why.
cat >"$dir/atlas.obj" <<'OBJ'
v -5 0 -5
v 5 0 -5
v 5 0 5
v -5 0 5
v -1 2 -1
v 1 2 -1
v 1 2 1
v -1 2 1
vt 0 0
vt 0.5 0
vt 0.5 1
vt 0 1
vt 0.6 0
vt 1 0
vt 1 0.4
vt 0.6 0.4
f 1/1 3/3 2/2
f 1/1 4/4 3/3
f 5/5 7/7 6/6
f 5/5 8/8 7/7
OBJ
"$ctl" render --server "$address" --scene "$dir/atlas.obj" --out "$dir/atlas" --eye 0,8,8 \
  --target 0,0,0 --light directional:0,-1,0 --size 64x36 --map-size 256 \
  --products shadow_atlas,shadow_atlas_mips,shadow_atlas_sat --fit scene --atlas-tile 64 \
  >"$dir/atlas.txt" || fail "atlas: $(cat "$dir/atlas.txt")"
grep -q "shadow_atlas.exr *64x64, 1 channel float32" "$dir/atlas.txt" ||
  fail "no 64x64 atlas: $(cat "$dir/atlas.txt")"
[[ -s $dir/atlas/shadow_atlas_mips.exr ]] || fail "no atlas mips: $(ls "$dir/atlas")"
oiiotool --info -v "$dir/atlas/shadow_atlas_sat.exr" | grep -q 'coverage.lo' ||
  fail "the atlas SAT lacks its coverage: $(oiiotool --info -v "$dir/atlas/shadow_atlas_sat.exr")"
oiiotool --info -v "$dir/atlas/shadow_atlas.exr" | grep -q 'shadow:atlas_tiles: "0 0 0 64"' ||
  fail "the atlas EXR lacks its tiles: $(oiiotool --info -v "$dir/atlas/shadow_atlas.exr")"
# A texel's world size: sqrt(104 m^2 of surface over 0.66 of UV area) / 64 texels.
oiiotool --info -v "$dir/atlas/shadow_atlas.exr" |
  grep -q 'shadow:atlas_texel_world_sizes: "0.196139"' ||
  fail "the atlas EXR lacks its texel sizes: $(oiiotool --info -v "$dir/atlas/shadow_atlas.exr")"
"$ctl" render --server "$address" --scene "$dir/atlas.obj" --out "$dir/atlas_soft" --eye 0,8,8 \
  --target 0,0,0 --light directional:0,-1,0 --light-size 5 --size 64x36 --map-size 256 \
  --products visibility --fit scene --filter atlas_mip >"$dir/atlas_soft.txt" ||
  fail "atlas_mip: $(cat "$dir/atlas_soft.txt")"
grep -q "atlas.mips" "$dir/atlas_soft.txt" || fail "atlas_mip ran no atlas mips: $(cat "$dir/atlas_soft.txt")"
# The same OBJ without UVs: the server lays it out and returns the layout per triangle corner.
grep -v '^vt' "$dir/atlas.obj" | sed 's|/[0-9]*||g' >"$dir/atlas_nouv.obj"
"$ctl" render --server "$address" --scene "$dir/atlas_nouv.obj" --out "$dir/atlas_nouv" \
  --eye 0,8,8 --target 0,0,0 --light directional:0,-1,0 --size 64x36 --map-size 256 \
  --products shadow_atlas,atlas_uvs --fit scene --atlas-tile 64 >"$dir/atlas_nouv.txt" ||
  fail "atlas without UVs: $(cat "$dir/atlas_nouv.txt")"
grep -q "atlas_uvs_mesh0.exr *3x4, 2 channel" "$dir/atlas_nouv.txt" ||
  fail "no generated layout: $(cat "$dir/atlas_nouv.txt")"
# No --fit: the atlas gets the scene fit it needs (issue 43); --fit view, named, is refused.
"$ctl" render --server "$address" --scene "$dir/atlas.obj" --out "$dir/atlas2" --eye 0,8,8 \
  --target 0,0,0 --light directional:0,-1,0 --products shadow_atlas >"$dir/atlas2.txt" 2>&1 &&
  [[ -f "$dir/atlas2/shadow_atlas.exr" ]] || fail "atlas without --fit: $(cat "$dir/atlas2.txt")"
set +e
"$ctl" render --server "$address" --scene "$dir/atlas.obj" --out "$dir/atlas3" --eye 0,8,8 \
  --target 0,0,0 --light directional:0,-1,0 --products shadow_atlas --fit view 2>"$dir/err6"
rc6=$?
set -e
[[ $rc6 == 2 ]] && grep -q "shadow_map.fit: " "$dir/err6" && grep -q -- "--fit" "$dir/err6" ||
  fail "atlas with --fit view: rc $rc6, $(cat "$dir/err6")"
# A quality goal instead of a technique and size: the report names the pick and its predictions,
# and the map written is the picked size.
"$ctl" render --server "$address" --scene builtin:demo --out "$dir/quality" --size 64x36 \
  --max-error 2 --products shadowmap,visibility >"$dir/quality.txt" ||
  fail "quality goal: $(cat "$dir/quality.txt")"
pick=$(grep -o 'quality goal: [a-z]* [0-9]*' "$dir/quality.txt" | awk '{print $4}')
[[ -n $pick ]] && grep -q "shadowmap.exr *${pick}x${pick}" "$dir/quality.txt" ||
  fail "no quality pick, or a map of another size: $(cat "$dir/quality.txt")"
set +e
"$ctl" render --server "$address" --scene builtin:demo --out "$dir/quality2" --max-error 2 \
  --map-size 1024 --products visibility 2>"$dir/err7"
rc7=$?
set -e
[[ $rc7 == 2 ]] && grep -q -- "--map-size" "$dir/err7" || fail "goal beside a size: rc $rc7, $(cat "$dir/err7")"
# Frames that are not a frame list are refused naming the flag.
echo '{"base": {}, "frames": [{}]}' >"$dir/bad_frames.json"
set +e
"$ctl" sequence --server "$address" --scene builtin:demo --frames "$dir/bad_frames.json" \
  --out "$dir/seq2" 2>"$dir/err5"
rc5=$?
set -e
[[ $rc5 == 2 ]] && grep -q -- "--frames" "$dir/err5" || fail "bad frames: rc $rc5, $(cat "$dir/err5")"
# --estimate: the server's price without a render (no --out); exit 0 when it would be admitted,
# 1 with the refusal when not; a sequence is priced as a whole.
"$ctl" render --server "$address" --scene builtin:demo --size 320x180 --estimate \
  >"$dir/price.txt" || fail "estimate: $(cat "$dir/price.txt")"
grep -q "^estimate: .* of device time" "$dir/price.txt" && grep -q "^admitted: yes" "$dir/price.txt" ||
  fail "estimate report: $(cat "$dir/price.txt")"
set +e
"$ctl" render --server "$address" --scene builtin:demo --size 8192x8192 --products visibility --filter pcss --light-size 3 \
  --pcss-blocker-samples 64 --pcss-filter-samples 64 --estimate >"$dir/price2.txt" 2>"$dir/err8"
rc8=$?
set -e
[[ $rc8 == 1 ]] && grep -q "^admitted: no, over request cost" "$dir/price2.txt" &&
  grep -q -- "--max-request-cost" "$dir/err8" || fail "refused estimate: rc $rc8, $(cat "$dir/err8")"
"$ctl" sequence --server "$address" --scene builtin:demo --frames "$dir/frames.json" --estimate \
  >"$dir/price3.txt" || fail "sequence estimate: $(cat "$dir/price3.txt")"
grep -q "for 3 frames" "$dir/price3.txt" || fail "sequence estimate: $(cat "$dir/price3.txt")"
# upload prints the scene's id alone; render --scene-id and a --request naming it render over
# the scene the server holds: the same map as the scene sent inline.
id=$("$ctl" upload --server "$address" --scene builtin:demo) || fail "upload: $id"
[[ $id =~ ^[0-9a-f]{64}$ ]] || fail "upload printed '$id', not an id"
request='"camera": {"eye": {"x": 13, "y": 9, "z": 15}, "target": {"y": 1}},
 "lights": [{"directional": {"direction": {"x": 0.9, "y": -1, "z": -0.3}}}],
 "shadow_map": {"size": 512}, "products": ["PRODUCT_SHADOW_MAP"]'
echo "{$request}" >"$dir/inline.json"
echo "{\"scene_id\": \"$id\", $request}" >"$dir/by_id.json"
"$ctl" render --server "$address" --request "$dir/inline.json" --scene builtin:demo \
  --size 320x180 --out "$dir/inline" >/dev/null || fail "render of the request inline"
"$ctl" render --server "$address" --request "$dir/by_id.json" --size 320x180 \
  --out "$dir/by_id_json" >"$dir/by_id_json.txt" || fail "--request by id: $(cat "$dir/by_id_json.txt")"
"$ctl" render --server "$address" --request "$dir/inline.json" --scene-id "$id" --size 320x180 \
  --out "$dir/by_id" >"$dir/by_id.txt" || fail "render --scene-id: $(cat "$dir/by_id.txt")"
for by_id in by_id by_id_json; do
  idiff -fail 0 -warn 0 "$dir/$by_id/shadowmap.exr" "$dir/inline/shadowmap.exr" >"$dir/idiff2.txt" ||
    fail "$by_id: the map differs from the inline scene's: $(cat "$dir/idiff2.txt")"
done
# stats: one screen, and the whole document with --json.
"$ctl" stats --server "$address" >"$dir/stats.txt" || fail "stats: $(cat "$dir/stats.txt")"
(($(wc -l <"$dir/stats.txt") <= 80)) || fail "stats printed $(wc -l <"$dir/stats.txt") lines"
grep -q "^device: " "$dir/stats.txt" && grep -q "^requests: .*OK [0-9]" "$dir/stats.txt" &&
  grep -q "^passes, by device time:" "$dir/stats.txt" || fail "stats summary: $(cat "$dir/stats.txt")"
"$ctl" stats --server "$address" --json >"$dir/stats.json" || fail "stats --json"
python3 -c 'import json, sys; d = json.load(open(sys.argv[1])); assert d["total"]["passes"]' \
  "$dir/stats.json" || fail "stats --json: $(head -c 300 "$dir/stats.json")"
# Progress (issue 54): work of about a second prints lines with its percentage on stderr (not a
# terminal here); --quiet prints none.
# (Estimated at 0.73 s, over the 0.5 s after which the server sends progress.)
heavy=(--scene builtin:demo --size 2048x2048 --map-size 4096 --filter pcss
  --pcss-blocker-samples 64 --pcss-filter-samples 64 --products visibility --preview none)
"$ctl" render --server "$address" "${heavy[@]}" --out "$dir/heavy" >/dev/null 2>"$dir/progress.txt" ||
  fail "heavy render: $(cat "$dir/progress.txt")"
grep -qE '^progress: +[0-9]+% ' "$dir/progress.txt" || fail "no progress lines: $(cat "$dir/progress.txt")"
"$ctl" render --server "$address" "${heavy[@]}" --out "$dir/heavy" --quiet >/dev/null \
  2>"$dir/quiet.txt" || fail "quiet render: $(cat "$dir/quiet.txt")"
[[ ! -s $dir/quiet.txt ]] || fail "--quiet printed: $(cat "$dir/quiet.txt")"
echo "shadowctl end to end: ok"
