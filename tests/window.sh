#!/usr/bin/env bash
# tests/window.sh BINDIR — the tests that need a real window, run inside an X server of their own
# (tools/test starts it with xvfb-run, so a developer's desktop is never typed into):
#   1. the GLFW window test in test_render (open, ten frames, screenshot, not empty);
#   2. record in a window with key presses sent through the X server (xdotool), then replay the
#      recording offscreen: the camera ends at the same place, to the last printed digit;
#   3. the same with the world's player (walk, jump, quit).
# Leak checking is off here: Mesa's X11 driver is unloaded before exit, so its leftovers cannot
# even be named in a suppression. Ends with "N passed, N failed".
set -uo pipefail
bin=${1:?usage: tests/window.sh BINDIR}
export ASAN_OPTIONS=detect_leaks=0
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0
pass() { passed=$((passed + 1)); echo "[ ok ] $1"; }
fail() { failed=$((failed + 1)); echo "[FAIL] $1"; }
# in_window TITLE SECONDS KEYS OUT COMMAND…: runs COMMAND (output to OUT), waits up to SECONDS for
# its window titled TITLE, focuses it and calls the function KEYS with the window id, then waits
# for COMMAND to end; returns its exit status.
in_window() {
  local title=$1 seconds=$2 keys=$3 out=$4 window
  shift 4
  "$@" >"$out" 2>&1 &
  local pid=$!
  if window=$(timeout "$seconds" xdotool search --sync --name "^$title\$" | head -1) && [[ -n $window ]]; then
    xdotool windowfocus --sync "$window"
    "$keys" "$window"
  fi
  timeout "$seconds" tail --pid="$pid" -f /dev/null
  wait "$pid"
}

if "$bin/test_render" --filter 'render_window/*' >"$tmp/window.log" 2>&1; then
  pass "window: ten frames and a screenshot"
else
  fail "window: ten frames and a screenshot"; sed 's/^/    /' "$tmp/window.log" | tail -20
fi

# Walk forward, then right, then quit with Escape, all through real X key events.
scene_keys() {
  xdotool keydown w; sleep 0.4; xdotool keyup w
  xdotool keydown d; sleep 0.2; xdotool keyup d
  xdotool key Escape
}
in_window gfx_scene 20 scene_keys "$tmp/record.out" "$bin/gfx_scene" --size 160x90 --record "$tmp/walk.rec"
recorded=$?
"$bin/gfx_scene" --headless --size 160x90 --replay "$tmp/walk.rec" >"$tmp/replay.out" 2>&1
replayed=$?
camera() { grep -o 'camera at ([^)]*)' "$1"; }
if [[ $recorded -eq 0 && $replayed -eq 0 && -n $(camera "$tmp/record.out") &&
      $(camera "$tmp/record.out") == "$(camera "$tmp/replay.out")" &&
      $(camera "$tmp/record.out") != "camera at (0.0000, 1.6000, 5.0000)" ]]; then
  pass "window: recorded walk replays offscreen to the same place ($(camera "$tmp/replay.out"))"
else
  fail "window: recorded walk replays offscreen to the same place"
  sed 's/^/    record: /' "$tmp/record.out" | tail -5
  sed 's/^/    replay: /' "$tmp/replay.out" | tail -5
fi

# The same with the world and its player: walk, jump, walk, quit; the replay offscreen ends with
# the player at the same place. The worlds here run with --rocks off: the debug build would spend
# 40 s building the rock tile set (the render and rock tests cover the rocks, with small sets).
walk_keys() {
  xdotool keydown w; sleep 0.5; xdotool key space; sleep 0.5; xdotool keyup w
  xdotool key Escape
}
in_window world 120 walk_keys "$tmp/terrain-record.out" \
  "$bin/world" --size 160x90 --radius 1 --levels 1 --rocks off --record "$tmp/terrain.rec"
recorded=$?
"$bin/world" --headless --size 160x90 --radius 1 --levels 1 --rocks off --replay "$tmp/terrain.rec" >"$tmp/terrain-replay.out" 2>&1
replayed=$?
player() { grep -o 'player at ([^)]*)' "$1"; }
# The window's title loses "(loading)" once the start area is in, so the keys reach a running
# game; the player must have left its spawn column (0, 0).
if [[ $recorded -eq 0 && $replayed -eq 0 && -n $(player "$tmp/terrain-record.out") &&
      $(player "$tmp/terrain-record.out") == "$(player "$tmp/terrain-replay.out")" &&
      ! $(player "$tmp/terrain-record.out") =~ \(0\.0000,\ [-0-9.]+,\ 0\.0000\) ]]; then
  pass "window: recorded terrain walk replays offscreen to the same place ($(player "$tmp/terrain-replay.out"))"
else
  fail "window: recorded terrain walk replays offscreen to the same place"
  sed 's/^/    record: /' "$tmp/terrain-record.out" | tail -5
  sed 's/^/    replay: /' "$tmp/terrain-replay.out" | tail -5
fi

# Terrain tools in a window: click to capture the mouse, look down, Tab to the sand tool, click to
# drop sand, let go, quit. The stroke is saved in the world folder; the recording replayed
# offscreen makes the same stroke.
tool_keys() {
  xdotool mousemove --window "$1" 80 45 click 1; sleep 0.3
  xdotool mousemove_relative --sync 0 240; sleep 0.3
  xdotool key Tab; sleep 0.2; xdotool key Tab; sleep 0.2
  xdotool click 1; sleep 0.5
  xdotool key Escape; sleep 0.2; xdotool key Escape
}
in_window world 120 tool_keys "$tmp/tools-record.out" \
  "$bin/world" --size 160x90 --radius 1 --levels 1 --rocks off --world "$tmp/edited" --record "$tmp/tools.rec"
recorded=$?
"$bin/world" --headless --size 160x90 --radius 1 --levels 1 --rocks off --replay "$tmp/tools.rec" >"$tmp/tools-replay.out" 2>&1
replayed=$?
strokes() { grep -o '[0-9]* tool strokes, [0-9]* edits applied' "$1"; }
if [[ $recorded -eq 0 && $replayed -eq 0 && -n $(strokes "$tmp/tools-record.out") &&
      ! $(strokes "$tmp/tools-record.out") =~ ^0\  &&
      $(strokes "$tmp/tools-record.out") == "$(strokes "$tmp/tools-replay.out")" ]] &&
   [[ $(python3 -c 'import sqlite3, sys; print(sqlite3.connect(sys.argv[1]).execute("SELECT count(*) FROM chunks").fetchone()[0])' \
        "$tmp/edited/world.db" 2>/dev/null) -gt 0 ]]; then
  pass "window: a tool stroke in a window is saved and replays offscreen ($(strokes "$tmp/tools-record.out"))"
else
  fail "window: a tool stroke in a window is saved and replays offscreen"
  sed 's/^/    record: /' "$tmp/tools-record.out" | tail -5
  sed 's/^/    replay: /' "$tmp/tools-replay.out" | tail -5
  ls -R "$tmp/edited" 2>&1 | sed 's/^/    folder: /' | head -10
fi

echo "window: $passed passed, $failed failed"
[[ $failed -eq 0 ]]
