#!/usr/bin/env bash
# `p3dp watch` in a real browser: headless Chromium (Debian's `chromium`,
# installed here when missing and run as root) with software WebGL. It
#   - starts `p3dp watch` on a small recipe in a scratch folder (--port 0),
#   - opens the page in Chromium with a DevTools port, and reads the page's
#     title from http://127.0.0.1:DEVTOOLS/json: the viewer publishes there
#     `p3dp: ok bbox WxDxH · build B · loads L · cam YAW/PITCH/DIST · NAME`
#     or `p3dp: error · …`,
#   - changes the helix's radius on disk and sees the bounding box follow
#     within 2 s, breaks the recipe and sees the error, fixes it and sees
#     the model again, each within 2 s,
#   - checks that the page was never reloaded (loads stays 1) and that the
#     camera stayed where it was (a reset would refit it to the new size),
#   - fails on any console message but the viewer's own `P3DP-OK` (and
#     SwiftShader's note that reading pixels back stalled the GPU),
#   - stops the server with SIGINT: status 0 within 2 s, the port closed,
#     no temp files left.
# Every process it starts is stopped on exit, failed or not.
#
# Usage: tests/browser/watch.sh
# Needs: cargo, python3 (standard library only), chromium.
set -euo pipefail
cd "$(dirname "$0")/../.."

if ! command -v chromium >/dev/null 2>&1; then
  if [ "$(id -u)" -ne 0 ]; then
    echo "chromium is not installed; as root: apt-get install -y chromium" >&2
    exit 1
  fi
  echo "== installing chromium (Debian's package)"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
fi

cargo build --quiet
bin="$PWD/target/debug/p3dp"
work=$(mktemp -d)
watch_pid=""
chrome_pid=""
cleanup() {
  for pid in $chrome_pid $watch_pid; do
    kill "$pid" 2>/dev/null || true
  done
  for pid in $chrome_pid $watch_pid; do
    wait "$pid" 2>/dev/null || true
  done
  rm -rf "$work"
}
trap cleanup EXIT

fail() {
  echo "FAIL  p3dp watch in Chromium: $*" >&2
  echo "--- p3dp watch said:" >&2
  cat "$work/watch.out" "$work/watch.err" >&2 || true
  exit 1
}

recipe="$work/recipe.yaml"
cat >"$recipe" <<'YAML'
p3dp: 1
name: watched
printer: generic-220
material: pla
parts:
  - primitive:
      helix: { radius: 10, height: 2, pitch: 0.5 }
YAML
save() { # as editors do: a new file renamed over the old one
  printf '%s\n' "$1" >"$recipe.tmp"
  mv "$recipe.tmp" "$recipe"
}

"$bin" watch "$recipe" --port 0 -j 1 </dev/null >"$work/watch.out" 2>"$work/watch.err" &
watch_pid=$!
url=""
for _ in $(seq 1 200); do
  url=$(grep -o 'http://127\.0\.0\.1:[0-9]*/' "$work/watch.out" || true)
  [ -n "$url" ] && break
  kill -0 "$watch_pid" 2>/dev/null || fail "p3dp watch exited before serving"
  sleep 0.05
done
[ -n "$url" ] || fail "no URL printed within 10 s"
port=${url#http://127.0.0.1:}
port=${port%/}

devtools=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
profile="$work/profile"
# #view=top: the camera starts at the top view, so that it differs from any
# default a reset would bring back
chromium --headless=new --no-sandbox --disable-gpu \
  --use-gl=swiftshader --enable-unsafe-swiftshader \
  --disable-background-networking --disable-component-update --disable-sync \
  --no-first-run --user-data-dir="$profile" --window-size=1200,900 \
  --remote-debugging-address=127.0.0.1 --remote-debugging-port="$devtools" \
  --enable-logging=stderr --v=0 "${url}#view=top" \
  </dev/null >/dev/null 2>"$work/chromium.log" &
chrome_pid=$!

# the page's title, or nothing while DevTools does not answer
title() {
  python3 - "$devtools" <<'PY' 2>/dev/null || true
import json, sys, urllib.request
# straight to loopback, whatever proxy the environment names
direct = urllib.request.build_opener(urllib.request.ProxyHandler({}))
with direct.open("http://127.0.0.1:%s/json" % sys.argv[1], timeout=2) as r:
    pages = [t for t in json.load(r) if t.get("type") == "page"]
print(pages[0]["title"] if pages else "")
PY
}

# waits up to $2 seconds for a title matching the regex $1; prints it
wait_title() {
  local re=$1 limit=$2 t start now
  start=$(date +%s%N)
  while :; do
    t=$(title)
    if [[ "$t" =~ $re ]]; then
      now=$(date +%s%N)
      echo "$t" >"$work/title"
      echo "$(( (now - start) / 1000000 ))" >"$work/ms"
      return 0
    fi
    now=$(date +%s%N)
    if (( (now - start) / 1000000 > limit * 1000 )); then
      fail "no title matching '$re' within $limit s; the title is '$t'"
    fi
    kill -0 "$chrome_pid" 2>/dev/null || fail "chromium exited; its log: $(tail -5 "$work/chromium.log")"
    sleep 0.05
  done
}
field() { # the value after "$1 " in the last title
  sed -n "s/.*$1 \([^ ]*\).*/\1/p" "$work/title"
}
width() { # the bounding box's x extent in the last title
  field bbox | cut -dx -f1
}
near() { # whether $1 is within 0.5 of $2
  python3 -c "import sys; sys.exit(0 if abs(float('$1') - float('$2')) <= 0.5 else 1)"
}

wait_title '^p3dp: ok bbox ' 60
first=$(cat "$work/title")
near "$(width)" 20 || fail "first model: expected 20 mm across, the title is '$first'"
[ "$(field loads)" = 1 ] || fail "first model: loads is not 1: '$first'"
camera=$(field cam)
echo "ok    first model: $first"

save "$(sed 's/radius: 10/radius: 15/' "$recipe")"
wait_title '^p3dp: ok bbox 3[0-9.]*x.* build [2-9]' 2
near "$(width)" 30 || fail "after the radius edit: expected 30 mm across: '$(cat "$work/title")'"
[ "$(field loads)" = 1 ] || fail "the page was reloaded: '$(cat "$work/title")'"
[ "$(field cam)" = "$camera" ] || fail "the camera moved from $camera: '$(cat "$work/title")'"
echo "ok    radius 10 → 15: $(cat "$work/title") (in $(cat "$work/ms") ms)"

save "$(sed 's/radius: 15/radious: 15/' "$recipe")"
wait_title '^p3dp: error ' 2
[ "$(field loads)" = 1 ] || fail "the page was reloaded: '$(cat "$work/title")'"
echo "ok    a misspelt key: $(cat "$work/title") (in $(cat "$work/ms") ms)"

save "$(sed 's/radious: 15/radius: 12/' "$recipe")"
wait_title '^p3dp: ok bbox 2[0-9.]*x' 2
near "$(width)" 24 || fail "after the fix: expected 24 mm across: '$(cat "$work/title")'"
[ "$(field loads)" = 1 ] || fail "the page was reloaded: '$(cat "$work/title")'"
[ "$(field cam)" = "$camera" ] || fail "the camera moved from $camera: '$(cat "$work/title")'"
echo "ok    fixed (radius 12): $(cat "$work/title") (in $(cat "$work/ms") ms)"

kill "$chrome_pid" 2>/dev/null || true
wait "$chrome_pid" 2>/dev/null || true
chrome_pid=""
console=$(grep -E ':CONSOLE[:(]' "$work/chromium.log" || true)
bad=$(grep -v -e '"P3DP-OK [0-9]* points drawn"' -e 'GPU stall due to ReadPixels' <<<"$console" | grep . || true)
[ -z "$bad" ] || fail "console: $bad"

kill -INT "$watch_pid"
status=""
for _ in $(seq 1 40); do
  if ! kill -0 "$watch_pid" 2>/dev/null; then
    wait "$watch_pid" && status=0 || status=$?
    break
  fi
  sleep 0.05
done
[ -n "$status" ] || fail "p3dp watch still runs 2 s after SIGINT"
watch_pid=""
[ "$status" = 0 ] || fail "p3dp watch exited with $status after SIGINT"
if python3 -c "import socket; socket.create_connection(('127.0.0.1', $port), timeout=1)" 2>/dev/null; then
  fail "port $port still answers after the stop"
fi
left=$(find "$work" -maxdepth 1 -name '.p3dp-*' | head -n 1)
[ -z "$left" ] || fail "temp file left: $left"
echo "ok    SIGINT: status 0, port $port closed, no temp files"
