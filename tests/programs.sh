#!/usr/bin/env bash
# tests/programs.sh BINDIR — how every program treats its command line and bad input:
# unknown flags and bad values give a usage message and exit 2; --help exits 0; an unwritable
# --trace fails at start-up with a message naming the path; trace_report reports bad files;
# every example in tools/examples/ prints what its closing "Expected output:" comment says.
# Ends with "N passed, N failed".
set -uo pipefail
bin=${1:?usage: tests/programs.sh BINDIR}
# System libraries' leftovers (OSMesa) are not ours: the same suppressions tools/test uses.
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$(cd "$(dirname "$0")" && pwd)/lsan.supp:print_suppressions=0}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0
root=$(cd "$(dirname "$0")/.." && pwd)
# The examples, tools/examples/AREA/MODULE_FEATURE.c, each built as the program MODULE_FEATURE.
mapfile -t example_sources < <(find "$root/tools/examples" -name '*.c' | sort)

# expect NAME STATUS PATTERN -- COMMAND…: COMMAND exits STATUS within 60 s and its output
# (stdout and stderr together) matches the extended regular expression PATTERN ("" = any).
expect() {
  local name=$1 want=$2 pattern=$3
  shift 4
  timeout 60 "$@" >"$tmp/out" 2>&1
  local got=$?
  if [[ $got -eq $want ]] && { [[ -z $pattern ]] || grep -Eq -- "$pattern" "$tmp/out"; }; then
    passed=$((passed + 1))
    echo "[ ok ] $name"
  else
    failed=$((failed + 1))
    echo "[FAIL] $name: exit $got (wanted $want), output:"
    sed 's/^/    /' "$tmp/out" | head -20
  fi
}

# Every program: an unknown flag is named, with the usage, exit 2; --help exits 0; bad --threads
# values are refused. (The examples made after the first nine share these through
# CORE_COMMON_OPTIONS: one --threads check each keeps their runs few.)
for program in bench trace_report ecs_systems gfx_scene terrain_rings terrain_edit grass_meadow terrain_water rocks_pile rocks_blocks game_setup_system world; do
  p=$bin/$program
  expect "$program: unknown flag" 2 "unknown option '--no-such-flag'.*" -- "$p" --no-such-flag
  cp "$tmp/out" "$tmp/unknown.txt"
  expect "$program: usage on error" 0 "usage: $program" -- cat "$tmp/unknown.txt"
  expect "$program: --help" 0 "usage: $program" -- "$p" --help
  expect "$program: bad --threads" 2 "bad value for '--threads': 'many' is not a whole number" -- "$p" --threads many
  expect "$program: negative --threads" 2 "bad value for '--threads'.*out of range" -- "$p" --threads -3
  expect "$program: --threads without value" 2 "option '--threads' needs a value" -- "$p" --threads
done
for source in "${example_sources[@]}"; do
  program=$(basename "$source" .c)
  case " ecs_systems gfx_scene terrain_rings terrain_edit grass_meadow terrain_water rocks_pile rocks_blocks game_setup_system " in
    *" $program "*) continue ;;
  esac
  p=$bin/$program
  expect "$program: unknown flag" 2 "unknown option '--no-such-flag'.*" -- "$p" --no-such-flag
  cp "$tmp/out" "$tmp/unknown.txt"
  expect "$program: usage on error" 0 "usage: $program" -- cat "$tmp/unknown.txt"
  expect "$program: --help" 0 "usage: $program" -- "$p" --help
  expect "$program: bad --threads" 2 "bad value for '--threads': 'many' is not a whole number" -- "$p" --threads many
done

# Every example whose source ends with a comment
#     /* Expected output:
#      * Run: ARGUMENTS
#      * PATTERN
#      * ...
#      */
# runs with ARGUMENTS (split on spaces; $TMP is this script's temporary folder, for files later
# checks read; "Run: skip: REASON" leaves it out), exits 0 within 60 s, and each PATTERN (an
# extended regular expression) matches a line of its standard output, in order. The time each
# took is in its line. tools/examples/README.md says how to write one.
expect_output() {
  local name=$1 source=$2 block run line i=0
  block=$(sed -n '/^\/\* Expected output:/,/\*\//p' "$source" | sed '1d;$d' | sed -E 's/^ \* ?//')
  [[ -z $block ]] && return
  run=$(grep -m1 '^Run:' <<<"$block" | sed -E 's/^Run: *//')
  [[ $run == skip* ]] && { echo "[skip] $name: expected output (${run#skip: })"; return; }
  local -a args patterns
  read -ra args <<<"${run//\$TMP/$tmp}"
  mapfile -t patterns < <(grep -v '^Run:' <<<"$block")
  local start=$EPOCHREALTIME
  timeout 60 "$bin/$name" "${args[@]}" >"$tmp/out" 2>"$tmp/err"
  local got=$? seconds
  seconds=$(awk "BEGIN { printf \"%.2f\", $EPOCHREALTIME - $start }")
  while IFS= read -r line; do
    if (( i < ${#patterns[@]} )) && [[ $line =~ ${patterns[i]} ]]; then i=$((i + 1)); fi
  done <"$tmp/out"
  if [[ $got -eq 0 && $i -eq ${#patterns[@]} ]]; then
    passed=$((passed + 1))
    echo "[ ok ] $name: expected output (${seconds} s)"
  else
    failed=$((failed + 1))
    echo "[FAIL] $name: expected output: exit $got (wanted 0), ${seconds} s; no line matched, in order:"
    echo "    ${patterns[i]:-}"
    echo "  its output:"
    cat "$tmp/out" "$tmp/err" | sed 's/^/    /' | head -30
  fi
}
for source in "${example_sources[@]}"; do
  expect_output "$(basename "$source" .c)" "$source"
done

# An unwritable trace fails before any work, naming the path.
expect "bench: unwritable --trace" 2 "/nonexistent-dir/t.json" -- "$bin/bench" --filter none --trace /nonexistent-dir/t.json
expect "ecs_systems: unwritable --trace" 2 "/nonexistent-dir/t.json" -- "$bin/ecs_systems" --trace /nonexistent-dir/t.json
expect "ecs_systems: --frames out of range" 2 "bad value for '--frames'" -- "$bin/ecs_systems" --frames 0
expect "bench: unwritable --json" 2 "cannot write --json" -- "$bin/bench" --filter none --json /nonexistent-dir/b.json

# trace_report on files that are not traces.
expect "trace_report: no file" 2 "missing" -- "$bin/trace_report"
expect "trace_report: missing file" 1 "$tmp/absent.json" -- "$bin/trace_report" "$tmp/absent.json"
printf 'this is not json' >"$tmp/garbage.json"
expect "trace_report: not JSON" 1 "garbage.json" -- "$bin/trace_report" "$tmp/garbage.json"
printf '{"traceEvents":[{"ph":"E","name":"frame","ts":5,"pid":1,"tid":1}]}' >"$tmp/unbalanced.json"
expect "trace_report: unbalanced zones" 1 "unbalanced|without|no matching" -- "$bin/trace_report" "$tmp/unbalanced.json"
printf '{"traceEvents":[{"ph":"B","name":"frame","ts":0,"pid":1,"tid":1},{"ph":"E","ts":1' >"$tmp/truncated.json"
expect "trace_report: truncated trace" 1 "truncated.json: not valid JSON: line 1" -- "$bin/trace_report" "$tmp/truncated.json"
expect "trace_report: --slowest 0" 2 "bad value for '--slowest': '0' is out of range" -- "$bin/trace_report" --slowest 0 "$tmp/unbalanced.json"
expect "trace_report: --slowest -2" 2 "bad value for '--slowest'" -- "$bin/trace_report" --slowest -2 "$tmp/unbalanced.json"
expect "trace_report: --slowest many" 2 "bad value for '--slowest': 'many' is not a whole number" -- "$bin/trace_report" --slowest many "$tmp/unbalanced.json"
expect "trace_report: --slowest without N" 2 "option '--slowest' needs a value" -- "$bin/trace_report" "$tmp/unbalanced.json" --slowest

# A hand-built trace (ms): frame 0 0-10 with A 2-8 (args chunk 3,0,-2) holding B 3-5 (A self
# 4, B 2, frame 4); frame 1 10-40 with a stolen job gen 12-36 (args chunk 1,0,0) inside a wait
# 11-38 (gen self 24, wait 3, frame 3); counter mem 100 @5, 300 @20, 200 @39.
cat >"$tmp/drill.json" <<'JSON'
{"traceEvents":[
{"ph":"B","name":"frame","ts":0,"pid":1,"tid":1},
{"ph":"B","name":"A","ts":2000,"pid":1,"tid":1,"args":{"chunk":"3,0,-2"}},
{"ph":"B","name":"B","ts":3000,"pid":1,"tid":1},
{"ph":"C","name":"mem","ts":5000,"pid":1,"tid":1,"args":{"value":100}},
{"ph":"E","ts":5000,"pid":1,"tid":1},
{"ph":"E","ts":8000,"pid":1,"tid":1},
{"ph":"E","ts":10000,"pid":1,"tid":1},
{"ph":"B","name":"frame","ts":10000,"pid":1,"tid":1},
{"ph":"B","name":"wait","ts":11000,"pid":1,"tid":1},
{"ph":"B","name":"gen","ts":12000,"pid":1,"tid":1,"args":{"chunk":"1,0,0"}},
{"ph":"C","name":"mem","ts":20000,"pid":1,"tid":1,"args":{"value":300}},
{"ph":"E","ts":36000,"pid":1,"tid":1},
{"ph":"E","ts":38000,"pid":1,"tid":1},
{"ph":"C","name":"mem","ts":39000,"pid":1,"tid":1,"args":{"value":200}},
{"ph":"E","ts":40000,"pid":1,"tid":1}
]}
JSON
expect "trace_report: self beside total (gen 24 of 24)" 0 "^gen +1 +24\\.000 +24\\.000 " -- "$bin/trace_report" "$tmp/drill.json"
expect "trace_report: frame self 4 + 3 of 40" 0 "^frame +2 +7\\.000 +40\\.000 " -- "$bin/trace_report" "$tmp/drill.json"
expect "trace_report: counter min max mean last" 0 "^mem +3 +100 +300 +200 +200$" -- "$bin/trace_report" "$tmp/drill.json"
expect "trace_report: --slowest 1 is frame 1" 0 "^frame 1 +at 10\\.000 ms +30\\.000 ms$" -- "$bin/trace_report" --slowest 1 "$tmp/drill.json"
expect "trace_report: --slowest lists its zones with args" 0 "^  gen +24\\.000 +1 +24\\.000 +chunk=1,0,0$" -- \
  "$bin/trace_report" --slowest 1 "$tmp/drill.json"
expect "trace_report: --slowest shows counters at the frame's end" 0 "counters at its end: mem 200$" -- \
  "$bin/trace_report" --slowest 1 "$tmp/drill.json"
expect "trace_report: --slowest 5 lists both frames" 0 "^frame 0 +at 0\\.000 ms +10\\.000 ms$" -- \
  "$bin/trace_report" --slowest 5 "$tmp/drill.json"
# --over: frame 1 (30 ms) alone is over 20 ms, and its gen (self 24, none in frame 0) leads the
# zones; by the mem counter at the frames' ends (100 and 200), 150 leaves frame 1 over too.
expect "trace_report: --over 20 counts frame 1" 0 "^frames over 20\\.000 ms \\(frame duration\\): 1 of 2 \\(50\\.00%\\) in 1 runs$" -- \
  "$bin/trace_report" --over 20 "$tmp/drill.json"
expect "trace_report: --over lists what the over frames spend more on" 0 "^  gen +24\\.000 +0\\.000 +\\+24\\.000$" -- \
  "$bin/trace_report" --over 20 "$tmp/drill.json"
expect "trace_report: --over by a counter" 0 "^frames over 150\\.000 ms \\(mem\\): 1 of 2 " -- \
  "$bin/trace_report" --over 150 --series mem "$tmp/drill.json"
expect "trace_report: --series without --over" 2 "'--series' needs '--over MS'" -- "$bin/trace_report" --series mem "$tmp/drill.json"
expect "trace_report: --series absent" 2 "no counter series \"absent\"" -- "$bin/trace_report" --over 5 --series absent "$tmp/drill.json"
expect "trace_report: --over 0" 2 "bad value for '--over'" -- "$bin/trace_report" --over 0 "$tmp/drill.json"

# End to end: the example runs, writes a trace, and the report reads its frames and phases.
expect "trace_report: frames of the run" 0 "30 frames" -- "$bin/trace_report" "$tmp/run.json"
expect "trace_report: phases in the run" 0 "(^| )cull( |$)" -- "$bin/trace_report" "$tmp/run.json"
expect "trace_report: memory counter of the run" 0 "^memory\\.bytes +[0-9]+ +[0-9]" -- "$bin/trace_report" "$tmp/run.json"
expect "trace_report: --slowest 3 of the run" 0 "^slowest 3 frames" -- "$bin/trace_report" --slowest 3 "$tmp/run.json"
expect "trace_report: svg beside the trace" 0 "^<svg|<svg " -- cat "$tmp/run.frames.svg"

# The platform example: flags, a headless run with a screenshot and a trace, shader errors.
expect "gfx_scene: bad --size" 2 "bad value for '--size': '640by360'" -- "$bin/gfx_scene" --size 640by360
expect "gfx_scene: tiny --size" 2 "bad value for '--size'" -- "$bin/gfx_scene" --size 8x8
expect "gfx_scene: screenshot is a PNG" 0 "^ *137 +80 +78 +71" -- od -An -tu1 -N4 "$tmp/scene.png"
expect "gfx_scene: screenshot is 160 x 90" 0 "^ *0 +0 +0 +160 +0 +0 +0 +90" -- od -An -tu1 -j16 -N8 "$tmp/scene.png"
expect "trace_report: GPU lane of the run" 0 "gpu scene" -- "$bin/trace_report" "$tmp/scene.json"
expect "gfx_scene: unwritable --screenshot" 1 "/nonexistent-dir/s.png" -- \
  "$bin/gfx_scene" --headless --size 64x64 --frames 2 --screenshot /nonexistent-dir/s.png
expect "gfx_scene: missing --bindings" 1 "$tmp/absent-bindings.txt" -- \
  "$bin/gfx_scene" --headless --frames 1 --bindings "$tmp/absent-bindings.txt"
mkdir -p "$tmp/shaders"
cp "$(dirname "$0")"/../shaders/* "$tmp/shaders/"
printf '#version 450 core\n#include "common.glsl"\nout vec4 c;\nvoid main() { c = vec4(oops); }\n' >"$tmp/shaders/scene.frag"
expect "gfx_scene: shader error at file:line, exit 1" 1 "shaders/scene.frag:4:" -- \
  env ENGINE_SHADERS="$tmp/shaders" "$bin/gfx_scene" --headless --frames 1

# hidreplay: its command line, bad files, and a decode end to end.
p=$bin/hidreplay
expect "hidreplay: unknown flag" 2 "unknown option '--no-such-flag'" -- "$p" --no-such-flag
expect "hidreplay: usage on error" 2 "usage: hidreplay" -- "$p" --no-such-flag
expect "hidreplay: --help" 0 "usage: hidreplay" -- "$p" --help
expect "hidreplay: no arguments" 2 "usage: hidreplay" -- "$p"
expect "hidreplay: no file" 2 "missing" -- "$p" 054c:09cc
expect "hidreplay: bad VID:PID" 2 "bad VID:PID 'sony'.*" -- "$p" sony "$tmp/absent.bin"
expect "hidreplay: VID:PID usage" 2 "usage: hidreplay" -- "$p" 054c:09cc0 "$tmp/absent.bin"
expect "hidreplay: bad --dead-zone" 2 "bad value for '--dead-zone'" -- "$p" 054c:09cc "$tmp/absent.bin" --dead-zone 2
expect "hidreplay: bad --threads" 2 "bad value for '--threads'" -- "$p" 054c:09cc "$tmp/absent.bin" --threads many
expect "hidreplay: missing file" 1 "$tmp/absent.bin" -- "$p" 054c:09cc "$tmp/absent.bin"
# A DualShock 4: a reduced Bluetooth report (left stick left, right stick right, cross, R2 full),
# one byte short of it, then a record whose length promises more than the file holds.
printf '\x0a\x00\x01\x00\x80\xff\x80\x28\x00\x00\x00\xff' >"$tmp/ds4.bin"
printf '\x09\x00\x01\x00\x80\xff\x80\x28\x00\x00\x00' >>"$tmp/ds4.bin"
printf '\x0a\x00\x01\x00' >"$tmp/cut.bin"
cat "$tmp/ds4.bin" "$tmp/cut.bin" >"$tmp/ds4_cut.bin"
expect "hidreplay: unknown pad needs --descriptor" 1 "1234:5678 is not a known pad.*--descriptor" -- \
  "$p" 1234:5678 "$tmp/ds4.bin"
expect "hidreplay: missing --descriptor file" 1 "$tmp/absent-desc.bin" -- \
  "$p" 1234:5678 "$tmp/ds4.bin" --descriptor "$tmp/absent-desc.bin"
printf '\x05\x01\xa1\x01' >"$tmp/bad-desc.bin"
expect "hidreplay: unusable descriptor" 1 "unusable report descriptor" -- \
  "$p" 1234:5678 "$tmp/ds4.bin" --descriptor "$tmp/bad-desc.bin"
expect "hidreplay: DualShock 4 report" 0 \
  '^\{"lx":-1,"ly":0\.003921569,"rx":1,"ry":0\.003921569,"lt":0,"rt":1,"buttons":\["south"\]\}$' -- \
  "$p" 054c:09cc "$tmp/ds4.bin"
expect "hidreplay: short report is an error line" 0 '^\{"error":"report too short: 9 bytes, need 10"\}$' -- \
  "$p" 054c:09cc "$tmp/ds4.bin"
expect "hidreplay: truncated record, exit 1" 1 '^\{"error":"truncated record' -- "$p" 054c:09cc "$tmp/ds4_cut.bin"
# Left stick a little off centre (0x88, 0x80: |(0.067, 0.004)| < 0.2) reads 0 inside the dead zone.
printf '\x0a\x00\x01\x88\x80\xff\x80\x08\x00\x00\x00\x00' >"$tmp/near.bin"
expect "hidreplay: --dead-zone" 0 '^\{"lx":0,"ly":0,"rx":0\.99999' -- "$p" 054c:09cc "$tmp/near.bin" --dead-zone 0.2
expect "hidreplay: no dead zone by default" 0 '^\{"lx":0\.06666667,"ly":0\.003921569,"rx":1,' -- "$p" 054c:09cc "$tmp/near.bin"
# A generic pad through its descriptor: X Y Z Rz, a hat, 12 buttons; hat 2 (right) + button 1.
printf '\x05\x01\x09\x05\xa1\x01\x09\x30\x09\x31\x09\x32\x09\x35\x15\x00\x26\xff\x00\x75\x08\x95\x04\x81\x02' >"$tmp/desc.bin"
printf '\x09\x39\x15\x00\x25\x07\x75\x04\x95\x01\x81\x42\x05\x09\x19\x01\x29\x0c\x25\x01\x75\x01\x95\x0c\x81\x02\xc0' >>"$tmp/desc.bin"
printf '\x06\x00\xff\x00\x80\x80\x12\x00' >"$tmp/generic.bin"
expect "hidreplay: generic pad" 0 '^\{"lx":1,"ly":-1,"rx":0\.003921569,"ry":0\.003921569,"lt":0,"rt":0,"buttons":\["south","dpad_right"\]\}$' -- \
  "$p" 0079:0006 "$tmp/generic.bin" --descriptor "$tmp/desc.bin"
expect "hidreplay: unwritable --trace" 2 "/nonexistent-dir/t.json" -- \
  "$p" 054c:09cc "$tmp/ds4.bin" --trace /nonexistent-dir/t.json

# terrain_export and terrain_mesh: flags, an export of a small region meshed again from its
# field file, and field files that are wrong in each way (size, header, a NaN value).
for program in terrain_export terrain_mesh; do
  p=$bin/$program
  expect "$program: unknown flag" 2 "unknown option '--no-such-flag'" -- "$p" --no-such-flag
  expect "$program: usage on error" 2 "usage: $program" -- "$p" --no-such-flag
  expect "$program: --help" 0 "usage: $program" -- "$p" --help
  expect "$program: bad --threads" 2 "bad value for '--threads'" -- "$p" --threads many
done
p=$bin/terrain_export
expect "terrain_export: no --region" 2 "missing '--region X,Y,Z:NX,NY,NZ'" -- "$p" --out "$tmp/t"
expect "terrain_export: usage without --region" 2 "usage: terrain_export" -- "$p" --out "$tmp/t"
expect "terrain_export: no --out" 2 "missing '--out" -- "$p" --region 0,0,0:8,8,8
expect "terrain_export: bad --seed" 2 "bad value for '--seed': 'soil'" -- "$p" --seed soil --region 0,0,0:8,8,8 --out "$tmp/t"
expect "terrain_export: --region without counts" 2 "bad value for '--region': '1,2,3'.*expected ':'" -- \
  "$p" --region 1,2,3 --out "$tmp/t"
expect "terrain_export: --region count too small" 2 "NY = 1 must be 2 … 1024" -- "$p" --region 0,0,0:8,1,8 --out "$tmp/t"
expect "terrain_export: --region count too large" 2 "NZ = 5000 must be 2 … 1024" -- "$p" --region 0,0,0:8,8,5000 --out "$tmp/t"
expect "terrain_export: --region not numbers" 2 "first coordinate is not a whole number" -- "$p" --region a,b,c:1,2,3 --out "$tmp/t"
expect "terrain_export: --region trailing text" 2 "unexpected ',9' at the end" -- "$p" --region 0,0,0:8,8,8,9 --out "$tmp/t"
expect "terrain_export: bad --sigma" 2 "bad value for '--sigma'" -- "$p" --sigma 99 --region 0,0,0:8,8,8 --out "$tmp/t"
expect "terrain_export: unwritable --out" 2 "cannot write --out /nonexistent-dir/t" -- \
  "$p" --region 0,0,0:8,8,8 --out /nonexistent-dir/t
# A region across a chunk corner, from below the ground to above it.
expect "terrain_export: a region" 0 "40 x 64 x 40 samples.*[1-9][0-9]* triangles" -- \
  "$p" --seed 3 --region -20,-24,-20:40,64,40 --out "$tmp/region"
expect "terrain_export: the header" 0 '^\{"dims":\[40,64,40\],"origin":\[-20,-24,-20\],"spacing":1\}$' -- cat "$tmp/region.json"
expect "terrain_export: raw is 40·64·40 floats" 0 "^409600$" -- stat -c %s "$tmp/region.raw"
expect "terrain_export: a binary PLY" 0 "format binary_little_endian 1.0" -- head -c 200 "$tmp/region.ply"

# rocks_export: flags, and two small tiles written as PLY with their JSON index.
p=$bin/rocks_export
expect "rocks_export: unknown flag" 2 "unknown option '--no-such-flag'" -- "$p" --no-such-flag
expect "rocks_export: --help" 0 "usage: rocks_export" -- "$p" --help
expect "rocks_export: no --out" 2 "--out DIR is required" -- "$p" --tiles 2
expect "rocks_export: bad --tiles" 2 "bad value for '--tiles'" -- "$p" --tiles 300 --out "$tmp/rocks"
expect "rocks_export: bad --cells" 2 "bad value for '--cells'" -- "$p" --cells 3 --out "$tmp/rocks"
expect "rocks_export: bad --shape" 2 "--shape must be round, slab or mixed" -- "$p" --shape cubes --out "$tmp/rocks"
expect "rocks_export: unwritable --out" 2 "cannot write into /proc/rocks" -- "$p" --out /proc/rocks
expect "rocks_export: two tiles" 0 "2 tiles, [1-9][0-9]* rocks" -- \
  "$p" --tiles 2 --cells 4 --voxels 4 --shape round --out "$tmp/rocks"
expect "rocks_export: a binary PLY" 0 "format binary_little_endian 1.0" -- head -c 200 "$tmp/rocks/tile_001.ply"
expect "rocks_export: the index" 0 '"tile":1,"ply":"tile_001.ply","colours":\[1,0,0,0,0,0,0,0\]' -- cat "$tmp/rocks/tiles.json"
expect "rocks_export: bad --region" 2 "is not X,Y,Z:NX,NY,NZ" -- "$p" --region 1,2 --out "$tmp/rocks-region"
expect "rocks_export: a region of seed 1" 0 "[1-9][0-9]* rocks in \\[40.0, 0.0, 0.0\\]" -- \
  "$p" --seed 1 --region 40,0,0:32,64,32 --cells 4 --voxels 4 --out "$tmp/rocks-region"
expect "rocks_export: the region's PLY" 0 "comment rocks placed by rocks_export" -- head -c 200 "$tmp/rocks-region.ply"
expect "rocks_export: the region's JSON" 0 '"count":[1-9][0-9]*,"rocks":' -- cat "$tmp/rocks-region.json"
p=$bin/terrain_mesh
expect "terrain_mesh: no file" 2 "missing" -- "$p"
expect "terrain_mesh: the exported field" 0 \
  '^\{"vertices":[1-9][0-9]*,"triangles":[1-9][0-9]*,"area":[0-9.e+]+,"ms":[0-9.e+-]+,"threads":[1-9][0-9]*\}$' -- "$p" "$tmp/region.json"
# The same mesh as the export's PLY: same face count.
faces=$(head -c 400 "$tmp/region.ply" | grep -a -m1 '^element face' | cut -d' ' -f3)
expect "terrain_mesh: as many triangles as the export" 0 "\"triangles\":$faces," -- "$p" "$tmp/region.json"
expect "terrain_mesh: by prefix and .raw too" 0 "\"triangles\":$faces," -- "$p" "$tmp/region.raw"
expect "terrain_mesh: --repeat on two threads, the same mesh" 0 "\"triangles\":$faces,.*\"threads\":2\}" -- \
  "$p" "$tmp/region.json" --repeat 3 --threads 2
expect "terrain_mesh: --repeat 0" 2 "bad value for '--repeat'" -- "$p" "$tmp/region.json" --repeat 0
expect "terrain_mesh: missing file" 1 "cannot open $tmp/absent.json" -- "$p" "$tmp/absent.json"
cp "$tmp/region.json" "$tmp/short.json"
head -c 409596 "$tmp/region.raw" >"$tmp/short.raw"
expect "terrain_mesh: raw of the wrong size" 1 "short.raw holds 409596 bytes.*need 409600" -- "$p" "$tmp/short.json"
printf '{"dims":[40,64],"origin":[0,0,0],"spacing":1}' >"$tmp/bad.json"
cp "$tmp/region.raw" "$tmp/bad.raw"
expect "terrain_mesh: bad header" 1 'bad.json: "dims" must be an array of 3 numbers' -- "$p" "$tmp/bad.json"
printf '{"dims":[40,64,40],"origin":[0,0,0],"spacing":1' >"$tmp/cut.json"
cp "$tmp/region.raw" "$tmp/cut.raw"
expect "terrain_mesh: header not JSON" 1 "cut.json: not JSON: line 1" -- "$p" "$tmp/cut.json"
cp "$tmp/region.json" "$tmp/nan.json"
cp "$tmp/region.raw" "$tmp/nan.raw"
printf '\x00\x00\xc0\x7f' | dd of="$tmp/nan.raw" bs=1 seek=400 conv=notrunc status=none
expect "terrain_mesh: a NaN value" 1 "nan.raw: value 100 \(x 20, y 2, z 0\) is NaN" -- "$p" "$tmp/nan.json"
expect "terrain_mesh: unwritable --ply" 2 "cannot write --ply /nonexistent-dir/m.ply" -- \
  "$p" "$tmp/region.json" --ply /nonexistent-dir/m.ply

# The terrain example: a headless run generates, meshes and draws, and writes its screenshot.
# --radius 1 is 2 × 2 chunks each way of full detail (16 column chunks), and one coarser ring.
expect "terrain_rings: screenshot is a PNG" 0 "^ *137 +80 +78 +71" -- od -An -tu1 -N4 "$tmp/terrain.png"
expect "terrain_rings: bad --radius" 2 "bad value for '--radius'" -- "$bin/terrain_rings" --radius 99

# The grass example: a meadow drawn headless, with grass placed and drawn; bad qualities refused.
expect "grass_meadow: screenshot is a PNG" 0 "^ *137 +80 +78 +71" -- od -An -tu1 -N4 "$tmp/grass.png"
expect "grass_meadow: bad --grass" 2 "bad value for '--grass'" -- "$bin/grass_meadow" --grass lush

# The cliff-blocks example: a block tile replicated over a wall, meshed and drawn headless.
expect "rocks_blocks: screenshot is a PNG" 0 "^ *137 +80 +78 +71" -- od -An -tu1 -N4 "$tmp/blocks.png"
expect "rocks_blocks: bad --type" 2 "bad value for '--type'" -- "$bin/rocks_blocks" --type granite

# The water example: a lake drawn headless at each quality; bad qualities refused.
for quality in high; do   # low: the example's expected output
  expect "terrain_water: headless run ($quality)" 0 "terrain_water: water $quality, [1-9][0-9]* planes drawn" -- \
    "$bin/terrain_water" --headless --size 96x64 --frames 4 --water $quality --screenshot "$tmp/water.png"
done
expect "terrain_water: screenshot is a PNG" 0 "^ *137 +80 +78 +71" -- od -An -tu1 -N4 "$tmp/water.png"
expect "terrain_water: off draws no plane" 0 "terrain_water: water off, 0 planes drawn" -- \
  "$bin/terrain_water" --headless --size 96x64 --frames 2 --water off
expect "terrain_water: bad --water" 2 "bad value for '--water'" -- "$bin/terrain_water" --water deep

# The examples' pictures (tools/example_pictures, tools/examples/README.md). The pictures the
# runs above wrote hold more than one colour; the tool itself, run on this build for the
# platform example, writes one too. Its PNG reader on pictures made here by hand, one row per
# filter (none, Up; Sub, Paeth, Average): grey (10,20,30) everywhere is refused as one colour;
# the second picture holds it and (11,21,31), worked out from the filters: 2 colours.
expect "example_pictures: the runs' pictures are not one colour" 0 "" -- \
  "$root/tools/example_pictures" --check "$tmp/scene.png" "$tmp/terrain.png" "$tmp/blocks.png" "$tmp/water.png" "$tmp/grass.png"
expect "example_pictures: a picture of gfx_scene" 0 "gfx_scene.png 160x90, ([2-9]|[1-9][0-9]+) colours" -- \
  env -u DISPLAY "$root/tools/example_pictures" --bin "$bin" --out "$tmp/pictures" --size 160x90 gfx_scene
# png FILE W H ROW…: an 8-bit RGB PNG whose rows are given in hex, each its filter byte first.
png() {
  python3 -c 'import struct, sys, zlib
path, width, height = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
def chunk(kind, body): return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
open(path, "wb").write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
    + chunk(b"IDAT", zlib.compress(bytes.fromhex("".join(sys.argv[4:])))) + chunk(b"IEND", b""))' "$@"
}
png "$tmp/flat.png" 2 2 000a141e0a141e 02000000000000
expect "example_pictures: one colour refused" 1 "flat.png: every pixel is the same colour" -- \
  "$root/tools/example_pictures" --check "$tmp/flat.png"
png "$tmp/two.png" 2 3 010a141e000000 04000000010101 03050a0f000000
expect "example_pictures: two colours through the filters" 0 "two.png 2x3, 2 colours" -- \
  "$root/tools/example_pictures" --check "$tmp/two.png"
# Every example that draws (a --screenshot option) has its picture, under 150 KB, linked.
for source in "${example_sources[@]}"; do
  grep -q '"screenshot"' "$source" || continue
  program=$(basename "$source" .c)
  expect "$program: its picture, under 150 KB" 0 "^[0-9]+$" -- \
    bash -c 's=$(stat -c %s "$1") && ((s < 150 * 1024)) && echo "$s"' _ "$root/tools/examples/pictures/$program.png"
  expect "$program: its picture in the README" 0 "\\(pictures/$program\\.png\\)" -- cat "$root/tools/examples/README.md"
done
expect "world: bad --grass" 2 "bad value for '--grass': 'lush' is not off, low or high" -- "$bin/world" --grass lush
expect "world: --grass without value" 2 "option '--grass' needs a value" -- "$bin/world" --grass
expect "world: bad --water" 2 "bad value for '--water': 'deep' is not off, low, medium or high" -- "$bin/world" --water deep
expect "world: bad --detail" 2 "bad value for '--detail': 'high' is not on or off" -- "$bin/world" --detail high
expect "world: bad --cliffs" 2 "bad value for '--cliffs': 'tall' is not on or off" -- "$bin/world" --cliffs tall
expect "world: bad --simplify" 2 "bad value for '--simplify': 'some' is not none, coarse or all" -- "$bin/world" --simplify some
expect "terrain_streaming: bad --simplify" 2 "bad value for '--simplify': 'some' is not none, coarse or all" -- "$bin/terrain_streaming" --simplify some
expect "world: --help lists --simplify" 0 "--simplify none\|coarse\|all" -- "$bin/world" --help
expect "world: bad --shadows" 2 "bad value for '--shadows': 'soft' is not off, low or high" -- "$bin/world" --shadows soft
expect "world: bad --shadows gets the usage" 2 "usage: world" -- "$bin/world" --shadows soft
expect "world: --shadows without value" 2 "option '--shadows' needs a value" -- "$bin/world" --shadows
expect "world: --help lists --shadows" 0 "--shadows off\|low\|high +sun shadows \(default low\)" -- "$bin/world" --help

# The walkable world: bad values get usage; a short scripted walk over generated terrain gets
# there, the eye never enters the ground, the trace has every phase of the pipeline and the
# streaming counters, and the screenshot is a PNG.
expect "world: bad --walk" 2 "bad value for '--walk': sideways:5: cannot open" -- "$bin/world" --walk sideways:5
expect "world: negative --walk" 2 "bad value for '--walk': straight:-5: the distance must be" -- "$bin/world" --walk straight:-5
printf 'relative\n10 10\n10 ten\n' >"$tmp/bad.walk"
expect "world: bad waypoint file" 2 "bad value for '--walk': .*bad.walk:3: z: 'ten' is not a number" -- \
  "$bin/world" --walk "$tmp/bad.walk"
expect "world: bad --size" 2 "bad value for '--size'" -- "$bin/world" --size 10x10000000
expect "world: --record with --replay" 2 "cannot be used together" -- "$bin/world" --record a --replay b
# A system of the developer's own through game_app_desc.setup: the sun after 30 frames of 1/60 s
# with a 1 s day stands at π(0.1 + 0.8 · 0.5) = π/2 along (cos, sin, 0.3): asin(1/√1.09) = 73°.
expect "game_setup_system: bad --day" 2 "bad value for '--day'" -- "$bin/game_setup_system" --day 0
expect "world: missing replay" 1 "$tmp/none.rec" -- "$bin/world" --headless --rocks off --replay "$tmp/none.rec"
# --gamepad-mappings: an unreadable file fails at start-up naming it; a bad line is reported with
# its file and line number and skipped, and the run goes on.
expect "world: missing --gamepad-mappings" 1 "cannot open gamepad mappings $tmp/none-pads.txt" -- \
  "$bin/world" --headless --rocks off --frames 1 --gamepad-mappings "$tmp/none-pads.txt"
printf '# pads\n030000005e0400008e02000014010001,Typo,a:b0,leftshoulderr:b4,\n030000005e0400008e02000014010000,Good,a:b0,leftx:a0,platform:Linux,\n' >"$tmp/pads.txt"
expect "world: bad --gamepad-mappings line skipped" 0 "pads.txt:2: unknown output 'leftshoulderr' \(line skipped\)" -- \
  "$bin/world" --headless --frames 1 --size 160x90 --radius 1 --levels 1 --rocks off --cliffs off --grass off \
  --water off --gamepad-mappings "$tmp/pads.txt"
expect "world: --help lists --gamepad-mappings" 0 "--gamepad-mappings FILE" -- "$bin/world" --help
expect "world: bad --memory" 2 "bad value for '--memory'" -- "$bin/world" --memory 1
expect "world: negative --pixel-error" 2 "bad value for '--pixel-error': '-1' is out of range" -- "$bin/world" --pixel-error -1
expect "world: --pixel-error not a number" 2 "bad value for '--pixel-error': 'x' is not a number" -- "$bin/world" --pixel-error x
expect "world: --help lists --pixel-error" 0 "--pixel-error P +detail by screen-space error" -- "$bin/world" --help
expect "world: --trace-frames without --trace" 2 "'--trace-frames' needs '--trace FILE'" -- "$bin/world" --trace-frames 5
expect "world: negative --trace-frames" 2 "bad value for '--trace-frames'" -- "$bin/world" --trace-frames -1 --trace "$tmp/ring.json"
# --at X,Y,Z and --look YAW,PITCH: each malformed form named, with the usage; a view asked for is
# where the player ends two frames later (feet = eye − 1.62 m), looking that way.
expect "world: --at of two numbers" 2 "bad value for '--at': '1,2' is not X,Y,Z" -- "$bin/world" --at 1,2
expect "world: bad --at gets the usage" 2 "usage: world" -- "$bin/world" --at 1,2
expect "world: --at of four numbers" 2 "bad value for '--at': '1,2,3,4' is not X,Y,Z" -- "$bin/world" --at 1,2,3,4
expect "world: --at with trailing junk" 2 "bad value for '--at': '1,2,3m' is not X,Y,Z" -- "$bin/world" --at 1,2,3m
expect "world: --at with an empty number" 2 "bad value for '--at': '1,,3' is not X,Y,Z" -- "$bin/world" --at 1,,3
expect "world: --at of NaN" 2 "bad value for '--at': 'nan,2,3': X is not a finite number" -- "$bin/world" --at nan,2,3
expect "world: --at of infinity" 2 "bad value for '--at': '1,-inf,3': Y is not a finite number" -- "$bin/world" --at 1,-inf,3
expect "world: --at far out" 2 "bad value for '--at': '0,0,-2e9': Z is beyond" -- "$bin/world" --at 0,0,-2e9
expect "world: --at far up" 2 "bad value for '--at': '0,1e6,0': Y is beyond" -- "$bin/world" --at 0,1e6,0
expect "world: --look of one number" 2 "bad value for '--look': '90' is not YAW,PITCH" -- "$bin/world" --look 90
expect "world: bad --look gets the usage" 2 "usage: world" -- "$bin/world" --look 90
expect "world: --look with trailing junk" 2 "bad value for '--look': '90,0,' is not YAW,PITCH" -- "$bin/world" --look 90,0,
expect "world: --look of NaN" 2 "bad value for '--look': 'NaN,0': YAW is not a finite number" -- "$bin/world" --look NaN,0
expect "world: --look past straight up" 2 "bad value for '--look': '0,90': PITCH is beyond ±89" -- "$bin/world" --look 0,90
expect "world: --look past straight down" 2 "bad value for '--look': '0,-89.5': PITCH is beyond" -- "$bin/world" --look 0,-89.5
# Every world here runs with --rocks off: the rock tile set would take the debug build most of a
# minute to make on a clean clone (test_rocks and test_render_rocks cover rocks, rocks_pile
# the module's example; tools/play makes the set for the game).
# Checks about other things run without the cliff blocks (their tiles and presence cost the
# debug build seconds a world: the walk with its trace came near its 60 s); one world keeps the
# default and must report blocks raised.
# One run for two checks (each world start is seconds in the debug build): the view asked for,
# and the cliff blocks that are on by default.
expect "world: cliff blocks on by default" 0 "world: cliffs [1-9][0-9]* blocks raised on steep bedrock walls" -- \
  "$bin/world" --headless --rocks off --size 64x48 --radius 1 --levels 1 --frames 2 --at 10,80,20 --look 90,-20
cp "$tmp/out" "$tmp/at_look.txt"
expect "world: --at and --look" 0 "player at \(10\.0000, 78\.3800, 20\.0000\), looking 90\.0,-20\.0" -- cat "$tmp/at_look.txt"
expect "world: scripted walk, eye always in the air" 0 "walked ([5-9][0-9]|1[0-9][0-9])\.[0-9] m .*eye in solid on 0 frames" -- \
  "$bin/world" --headless --rocks off --size 64x48 --radius 1 --levels 1 --walk straight:55 --seed 5 --trace "$tmp/walk.json" \
  --screenshot "$tmp/world.png" --cliffs off
expect "world: screenshot is a PNG" 0 "^ *137 +80 +78 +71" -- od -An -tu1 -N4 "$tmp/world.png"
# One report of the walk's trace (a second each in the debug build), read by the checks below.
expect "world: the walk's trace reads back" 0 "frames" -- "$bin/trace_report" "$tmp/walk.json"
cp "$tmp/out" "$tmp/walk_report.txt"
for phase in input game stream generate stabilize mesh lod cull draw; do
  expect "world: the walk's trace has phase $phase" 0 "(^| )$phase( |$)" -- cat "$tmp/walk_report.txt"
done
expect "world: the walk's trace has streaming jobs" 0 "terrain stream mesh" -- cat "$tmp/walk_report.txt"
expect "world: the walk's trace has the shadow pass" 0 "gpu shadows" -- cat "$tmp/walk_report.txt"
# The editing example: carve, sweep, deposit, stabilize, save, reload the same bytes; a world
# folder that cannot be made is reported.
touch "$tmp/edit_file"
expect "terrain_edit: unwritable --world" 1 "edit_file" -- "$bin/terrain_edit" --world "$tmp/edit_file"

# A world folder: a file in its place is refused, its seed is kept and another one refused, a
# damaged world.txt is reported.
touch "$tmp/not_a_folder"
expect "world: --world that is a file" 1 "cannot (create|read)" -- "$bin/world" --headless --rocks off --frames 1 --world "$tmp/not_a_folder"
mkdir -p "$tmp/saved"
echo "seed 9" >"$tmp/saved/world.txt"
expect "world: --world of another seed" 1 "holds the world of seed 9 \(run with --seed 9" -- \
  "$bin/world" --headless --rocks off --size 64x48 --frames 1 --seed 3 --world "$tmp/saved" --cliffs off
echo "not a seed" >"$tmp/saved/world.txt"
expect "world: damaged world.txt" 1 "world.txt does not say 'seed N'" -- \
  "$bin/world" --headless --rocks off --size 64x48 --frames 1 --seed 3 --world "$tmp/saved" --cliffs off
# A world folder's database: it records its seed, a damaged one is set aside (the run goes on),
# and a world another process holds is refused (python3's sqlite3 holds SQLite's lock here).
# (Small worlds without rocks: the checks are about the database, and the debug build takes 20 s
# to load the default rings.)
expect "world: a new world folder" 0 "player at" -- \
  "$bin/world" --headless --size 64x48 --radius 1 --levels 1 --rocks off --frames 1 --seed 9 --world "$tmp/db" \
  --trace "$tmp/db.json" --cliffs off
expect "world: the save shows in the trace" 0 "terrain.store.save" -- "$bin/trace_report" "$tmp/db.json"
expect "world: world.db of another seed" 1 "holds the world of seed 9 \(run with --seed 9" -- \
  "$bin/world" --headless --rocks off --size 64x48 --frames 1 --seed 3 --world "$tmp/db" --cliffs off
mkdir -p "$tmp/damaged_db"
echo "not a database at all, a line of text long enough to be read" >"$tmp/damaged_db/world.db"
expect "world: a damaged world.db is set aside" 0 "world.db: .*set aside as .*world.db.bad" -- \
  "$bin/world" --headless --size 64x48 --radius 1 --levels 1 --rocks off --frames 1 --world "$tmp/damaged_db" \
  --cliffs off
python3 -c 'import sqlite3, sys, time
c = sqlite3.connect(sys.argv[1], isolation_level=None)
c.execute("PRAGMA locking_mode = EXCLUSIVE"); c.execute("BEGIN EXCLUSIVE")
open(sys.argv[1] + ".held", "w").close(); time.sleep(60)' "$tmp/db/world.db" &
holder=$!
for _ in $(seq 100); do [[ -e $tmp/db/world.db.held ]] && break; sleep 0.1; done
expect "world: a world another process has open" 1 "world.db: in use by another process" -- \
  "$bin/world" --headless --rocks off --size 64x48 --frames 1 --seed 9 --world "$tmp/db" --cliffs off
kill "$holder" 2>/dev/null; wait "$holder" 2>/dev/null

# tools/play with no display: the tour; the user's --trace and --screenshot win over the defaults,
# are written, and are the paths it reports (the release build first: tools/play uses it).
"$root/tools/build" release world trace_report >/dev/null 2>&1
expect "tools/play: the user's --trace is written and reported" 0 "^trace: $tmp/p.json \(open" -- \
  env -u DISPLAY -u WAYLAND_DISPLAY "$root/tools/play" --size 96x64 --trace "$tmp/p.json" --screenshot "$tmp/p.png"
if grep -q "^pictures: $tmp/p.png (side by side)" "$tmp/out" && [[ -s $tmp/p.json && -s $tmp/p.png && -s $tmp/p-4.png ]] &&
   grep -q "frames" "$tmp/out" && ! grep -q "out/play" "$tmp/out"; then
  passed=$((passed + 1)); echo "[ ok ] tools/play: the user's --screenshot holds the tour's pictures, no default path named"
else
  failed=$((failed + 1)); echo "[FAIL] tools/play: the user's --screenshot holds the tour's pictures, no default path named"
  sed 's/^/    /' "$tmp/out" | tail -20
fi

echo "programs: $passed passed, $failed failed"
[[ $failed -eq 0 ]]
