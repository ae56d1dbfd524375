#!/usr/bin/env bash
# tests/fuzz/run.sh [SECONDS] [NAME…] — builds every libFuzzer target tests/fuzz/fuzz_*.c (or
# only the NAMEs given, e.g. fuzz_walk) with clang (-fsanitize=fuzzer,address,undefined, linked
# with the engine, the modules and the game) into bin/fuzz/ and runs each for SECONDS (default
# 15). Seeds come from tests/fuzz/corpus/NAME/ when it exists; what a run finds is kept in
# out/fuzz/NAME/ for the next run. A crash leaves its input in out/fuzz/.
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
build_ok=1
while IFS= read -r source; do
  object=bin/fuzz/obj/$(echo "${source%.c}" | tr / _).o
  clang "${cflags[@]}" -fsanitize=fuzzer-no-link -c "$source" -o "$object" || build_ok=0
done < <(find engine modules game -name '*.c' ! -path game/main.c | sort)   # main.c is a program
rm -f bin/fuzz/libengine_fuzz.a
ar rcs bin/fuzz/libengine_fuzz.a bin/fuzz/obj/*.o || build_ok=0
platform_libs=(-lglfw -lhidapi-hidraw -lmeshoptimizer -lsqlite3 -ldl)
passed=0 failed=0
for target in "${targets[@]}"; do
  name=$(basename "$target" .c)
  target=tests/fuzz/$name.c
  [[ -e $target ]] || { echo "[FAIL] $name: no $target"; failed=$((failed + 1)); continue; }
  if [[ $build_ok -eq 0 ]] || ! clang "${cflags[@]}" -fsanitize=fuzzer "$target" bin/fuzz/libengine_fuzz.a \
        "${platform_libs[@]}" -lm -pthread -o "bin/fuzz/$name"; then
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
