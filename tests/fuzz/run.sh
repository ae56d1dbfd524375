#!/usr/bin/env bash
# tests/fuzz/run.sh [SECONDS] [NAME…] — builds every libFuzzer target tests/fuzz/fuzz_*.c (or
# only the NAMEs given, e.g. fuzz_walk) with clang (-fsanitize=fuzzer,address,undefined, linked
# with the engine, the modules and the game) into bin/fuzz/ and runs each for SECONDS (default
# 15). Seeds come from tests/fuzz/corpus/NAME/ when it exists; what a run finds is kept in
# out/fuzz/NAME/ for the next run. A crash leaves its input in out/fuzz/. Objects compile and
# targets run as many at a time as there are cores.
# Ends with "N passed, N failed".
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
seconds=${1:-15}
shift || true
targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=(tests/fuzz/fuzz_*.c)
mkdir -p bin/fuzz out/fuzz
# The engine, the modules and the game, compiled once with the sanitizers and fuzzer coverage,
# into an archive: each target pulls in only the objects it uses, so the renderer's (GL) objects
# stay out and no target needs a GL library. The GL loader's header comes from the normal build.
[[ -f build/glad/include/glad/gl.h ]] || tools/build debug glad >/dev/null
cflags=(-g -O1 -fsanitize=address,undefined -fno-sanitize-recover=undefined -std=c11 -D_GNU_SOURCE
        -Iengine -Imodules -I. -Ibuild/glad/include -Wall -Wextra -Werror)
rm -rf bin/fuzz/obj && mkdir -p bin/fuzz/obj
# Both steps use every core: the objects compile side by side, and the targets run side by side
# (each libFuzzer run is one process on one core), so the step takes its time over the cores.
jobs=$(nproc 2>/dev/null || echo 2)
compile_object() {
  clang "${cflags[@]}" -fsanitize=fuzzer-no-link -c "$1" -o "bin/fuzz/obj/$(echo "${1%.c}" | tr / _).o"
}
export -f compile_object
export cflags_text="${cflags[*]}"
build_ok=1
find engine modules game -name '*.c' ! -path game/main.c | sort |   # main.c is a program
  xargs -P "$jobs" -I{} bash -c 'cflags=($cflags_text); compile_object "$1"' _ {} || build_ok=0
rm -f bin/fuzz/libengine_fuzz.a
ar rcs bin/fuzz/libengine_fuzz.a bin/fuzz/obj/*.o || build_ok=0
platform_libs=(-lglfw -lhidapi-hidraw -lmeshoptimizer -lsqlite3 -ldl)

# One target: built, then run for $seconds; its verdict line goes to out/fuzz/NAME.result.
run_target() {
  local name=$1 target=tests/fuzz/$1.c result=out/fuzz/$1.result
  if [[ ! -e $target ]]; then echo "[FAIL] $name: no $target" >"$result"; return; fi
  if [[ $build_ok -eq 0 ]] || ! clang "${cflags[@]}" -fsanitize=fuzzer "$target" bin/fuzz/libengine_fuzz.a \
        "${platform_libs[@]}" -lm -pthread -o "bin/fuzz/$name"; then
    echo "[FAIL] $name: does not build" >"$result"
    return
  fi
  local corpus=out/fuzz/$name seeds=()
  mkdir -p "$corpus"
  [[ -d tests/fuzz/corpus/$name ]] && seeds=("tests/fuzz/corpus/$name")
  if "bin/fuzz/$name" -max_total_time="$seconds" -print_final_stats=0 -artifact_prefix=out/fuzz/ \
        "$corpus" "${seeds[@]}" >"out/fuzz/$name.log" 2>&1; then
    echo "[ ok ] $name: $(grep -Eo '#[0-9]+' "out/fuzz/$name.log" | tail -1 | tr -d '#') inputs in ${seconds} s" >"$result"
  else
    { echo "[FAIL] $name: see out/fuzz/$name.log"; tail -30 "out/fuzz/$name.log"; } >"$result"
  fi
}

names=()
for target in "${targets[@]}"; do names+=("$(basename "$target" .c)"); done
running=0
for name in "${names[@]}"; do
  rm -f "out/fuzz/$name.result"
  run_target "$name" &
  running=$((running + 1))
  if [[ $running -ge $jobs ]]; then wait -n; running=$((running - 1)); fi
done
wait
passed=0 failed=0
for name in "${names[@]}"; do
  result=out/fuzz/$name.result
  [[ -f $result ]] || echo "[FAIL] $name: no verdict" >"$result"
  cat "$result"
  if head -1 "$result" | grep -q '^\[ ok \]'; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
done
echo "fuzz: $passed passed, $failed failed"
[[ $failed -eq 0 ]]
