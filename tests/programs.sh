#!/usr/bin/env bash
# tests/programs.sh BINDIR — how every program treats its command line and bad input:
# unknown flags and bad values give a usage message and exit 2; --help exits 0; an unwritable
# --trace fails at start-up with a message naming the path; trace_report reports bad files.
# Ends with "N passed, N failed".
set -uo pipefail
bin=${1:?usage: tests/programs.sh BINDIR}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0

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

for program in bench trace_report hello_systems hello_scene; do
  p=$bin/$program
  expect "$program: unknown flag" 2 "unknown option '--no-such-flag'.*" -- "$p" --no-such-flag
  expect "$program: usage on error" 2 "usage: $program" -- "$p" --no-such-flag
  expect "$program: --help" 0 "usage: $program" -- "$p" --help
  expect "$program: bad --threads" 2 "bad value for '--threads': 'many' is not a whole number" -- "$p" --threads many
  expect "$program: negative --threads" 2 "bad value for '--threads'.*out of range" -- "$p" --threads -3
  expect "$program: --threads without value" 2 "option '--threads' needs a value" -- "$p" --threads
done

# An unwritable trace fails before any work, naming the path.
expect "bench: unwritable --trace" 2 "/nonexistent-dir/t.json" -- "$bin/bench" --filter none --trace /nonexistent-dir/t.json
expect "hello_systems: unwritable --trace" 2 "/nonexistent-dir/t.json" -- "$bin/hello_systems" --trace /nonexistent-dir/t.json
expect "hello_systems: --frames out of range" 2 "bad value for '--frames'" -- "$bin/hello_systems" --frames 0
expect "bench: unwritable --json" 2 "cannot write --json" -- "$bin/bench" --filter none --json /nonexistent-dir/b.json

# trace_report on files that are not traces.
expect "trace_report: no file" 2 "missing" -- "$bin/trace_report"
expect "trace_report: missing file" 1 "$tmp/absent.json" -- "$bin/trace_report" "$tmp/absent.json"
printf 'this is not json' >"$tmp/garbage.json"
expect "trace_report: not JSON" 1 "garbage.json" -- "$bin/trace_report" "$tmp/garbage.json"
printf '{"traceEvents":[{"ph":"E","name":"frame","ts":5,"pid":1,"tid":1}]}' >"$tmp/unbalanced.json"
expect "trace_report: unbalanced zones" 1 "unbalanced|without|no matching" -- "$bin/trace_report" "$tmp/unbalanced.json"

# End to end: the example runs, writes a trace, and the report reads its frames and phases.
expect "hello_systems: runs with a trace" 0 "" -- "$bin/hello_systems" --frames 30 --threads 2 --trace "$tmp/run.json"
expect "trace_report: frames of the run" 0 "30 frames" -- "$bin/trace_report" "$tmp/run.json"
expect "trace_report: phases in the run" 0 "(^| )cull( |$)" -- "$bin/trace_report" "$tmp/run.json"
expect "trace_report: svg beside the trace" 0 "^<svg|<svg " -- cat "$tmp/run.frames.svg"

# The platform example: flags, a headless run with a screenshot and a trace, shader errors.
expect "hello_scene: bad --size" 2 "bad value for '--size': '640by360'" -- "$bin/hello_scene" --size 640by360
expect "hello_scene: tiny --size" 2 "bad value for '--size'" -- "$bin/hello_scene" --size 8x8
expect "hello_scene: headless run" 0 "10 frames.*offscreen 160x90" -- \
  "$bin/hello_scene" --headless --size 160x90 --frames 10 --screenshot "$tmp/scene.png" --trace "$tmp/scene.json"
expect "hello_scene: screenshot is a PNG" 0 "^ *137 80 78 71" -- od -An -tu1 -N4 "$tmp/scene.png"
expect "hello_scene: screenshot is 160 x 90" 0 "^ *0 0 0 160 0 0 0 90" -- od -An -tu1 -j16 -N8 "$tmp/scene.png"
expect "trace_report: GPU lane of the run" 0 "scene" -- "$bin/trace_report" "$tmp/scene.json"
expect "hello_scene: unwritable --screenshot" 1 "/nonexistent-dir/s.png" -- \
  "$bin/hello_scene" --headless --size 64x64 --frames 2 --screenshot /nonexistent-dir/s.png
expect "hello_scene: missing --bindings" 1 "$tmp/absent-bindings.txt" -- \
  "$bin/hello_scene" --headless --frames 1 --bindings "$tmp/absent-bindings.txt"
mkdir -p "$tmp/shaders"
cp "$(dirname "$0")"/../shaders/* "$tmp/shaders/"
printf '#version 450 core\n#include "common.glsl"\nout vec4 c;\nvoid main() { c = vec4(oops); }\n' >"$tmp/shaders/scene.frag"
expect "hello_scene: shader error at file:line, exit 1" 1 "shaders/scene.frag:4:" -- \
  env ENGINE_SHADERS="$tmp/shaders" "$bin/hello_scene" --headless --frames 1

echo "programs: $passed passed, $failed failed"
[[ $failed -eq 0 ]]
