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

for program in bench trace_report hello_systems; do
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

echo "programs: $passed passed, $failed failed"
[[ $failed -eq 0 ]]
