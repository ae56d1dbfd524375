#!/usr/bin/env bash
# tests/fuzz/run.sh [SECONDS] — builds every libFuzzer target tests/fuzz/fuzz_*.c with clang
# (-fsanitize=fuzzer,address,undefined, linked with the engine's sources) into bin/fuzz/ and runs
# each for SECONDS (default 15). Seeds come from tests/fuzz/corpus/NAME/ when it exists; what a
# run finds is kept in out/fuzz/NAME/ for the next run. A crash leaves its input in out/fuzz/.
# Ends with "N passed, N failed".
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
seconds=${1:-15}
mkdir -p bin/fuzz out/fuzz
# Every engine and module source but the renderer (no fuzz target draws); input needs GLFW and
# hidapi, terrain meshoptimizer.
mapfile -t engine_sources < <(find engine modules -name '*.c' -not -path 'engine/gfx/*' | sort)
platform_libs=(-lglfw -lhidapi-hidraw -lmeshoptimizer -ldl)
passed=0 failed=0
for target in tests/fuzz/fuzz_*.c; do
  [[ -e $target ]] || continue
  name=$(basename "$target" .c)
  if ! clang -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
        -std=c11 -D_GNU_SOURCE -Iengine -Imodules -Wall -Wextra -Werror \
        "$target" "${engine_sources[@]}" "${platform_libs[@]}" -lm -pthread -o "bin/fuzz/$name"; then
    echo "[FAIL] $name: does not build"
    failed=$((failed + 1))
    continue
  fi
  corpus=out/fuzz/$name
  mkdir -p "$corpus"
  seeds=()
  [[ -d tests/fuzz/corpus/$name ]] && seeds=("tests/fuzz/corpus/$name")
  if "bin/fuzz/$name" -max_total_time="$seconds" -print_final_stats=0 -artifact_prefix=out/fuzz/ \
        "$corpus" "${seeds[@]}" >"out/fuzz/$name.log" 2>&1; then
    echo "[ ok ] $name: $(grep -Eo '#[0-9]+' "out/fuzz/$name.log" | tail -1 | tr -d '#') inputs in ${seconds} s"
    passed=$((passed + 1))
  else
    echo "[FAIL] $name: see out/fuzz/$name.log"
    tail -30 "out/fuzz/$name.log"
    failed=$((failed + 1))
  fi
done
echo "fuzz: $passed passed, $failed failed"
[[ $failed -eq 0 ]]
