#!/usr/bin/env bash
# Opens p3dp's HTML previews in a real browser: headless Chromium (Debian's
# `chromium` package, installed here when missing and run as root) with
# software WebGL (SwiftShader). For each recipe it
#   - writes the preview with `p3dp preview RECIPE -o NAME.html`,
#   - loads it from file:// with no network and takes a screenshot,
#   - fails on any console message but the viewer's own `P3DP-OK N points
#     drawn` (and Chromium's note that the screenshot's read-back stalled
#     the GPU): uncaught exceptions, console.error, WebGL errors all fail,
#   - checks that the viewer drew as many points as p3dp says the file holds,
#   - and that the screenshot is not blank (enough pixels unlike the
#     background, in enough colours).
#
# Usage: tests/browser/check-html.sh [RECIPE…]  (default: the sphere and the globe)
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
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
recipes=("$@")
[ ${#recipes[@]} -gt 0 ] || recipes=(recipes/sphere.yaml recipes/globe.yaml)

fail=0
for recipe in "${recipes[@]}"; do
  name=$(basename "$recipe" .yaml)
  html="$out/$name.html"
  shot="$out/$name.png"
  said=$("$bin" preview "$recipe" -o "$html")
  points=$(sed -n 's/.*HTML viewer, \([0-9]*\) points.*/\1/p' <<<"$said")
  profile=$(mktemp -d -p "$out")
  timeout 120 chromium --headless --no-sandbox --disable-gpu \
    --use-gl=swiftshader --enable-unsafe-swiftshader \
    --disable-background-networking --disable-component-update --disable-sync \
    --no-first-run --user-data-dir="$profile" --window-size=1200,900 \
    --virtual-time-budget=5000 --screenshot="$shot" \
    --enable-logging=stderr --v=0 "file://$html" 2>"$out/$name.log" >/dev/null || true
  console=$(grep -E ':CONSOLE[:(]' "$out/$name.log" || true)
  bad=$(grep -v -e '"P3DP-OK [0-9]* points drawn"' -e 'GPU stall due to ReadPixels' <<<"$console" | grep . || true)
  drawn=$(sed -n 's/.*"P3DP-OK \([0-9]*\) points drawn".*/\1/p' <<<"$console" | head -n 1)
  verdict=$(python3 - "$shot" <<'PY'
import struct, sys, zlib
def pixels(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, hdr = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            hdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    w, h, depth, ctype, _, _, interlace = hdr
    assert depth == 8 and ctype in (2, 6) and interlace == 0, "unexpected PNG kind %r" % (hdr,)
    bpp = 3 if ctype == 2 else 4
    raw, stride, prev, rows = zlib.decompress(idat), w * bpp, bytearray(w * bpp), []
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1: line[i] = (line[i] + a) & 255
            elif f == 2: line[i] = (line[i] + b) & 255
            elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return w, h, bpp, rows
w, h, bpp, rows = pixels(sys.argv[1])
bg = tuple(rows[h // 2][0:3])  # the left edge, mid-height: background
# the model sits in the middle third of the window, clear of the panels
differ, colours = 0, set()
for y in range(h // 3, 2 * h // 3):
    for x in range(w // 3, 2 * w // 3):
        px = tuple(rows[y][x * bpp:x * bpp + 3])
        if sum(abs(p - q) for p, q in zip(px, bg)) > 30:
            differ += 1
            colours.add(px)
share = differ / ((h // 3) * (w // 3))
print("ok" if share > 0.05 and len(colours) > 50 else "blank",
      "%dx%d, %.0f%% of the middle unlike the background, %d colours" % (w, h, 100 * share, len(colours)))
PY
) || verdict="unreadable screenshot"
  problems=()
  [ -s "$shot" ] || problems+=("no screenshot")
  [ -z "$bad" ] || problems+=("console: $bad")
  [ "$drawn" = "$points" ] || problems+=("drew '${drawn}' points, the file holds '${points}'")
  [[ "$verdict" == ok* ]] || problems+=("screenshot: $verdict")
  if [ ${#problems[@]} -eq 0 ]; then
    echo "ok    $recipe: $points points drawn, no console errors; screenshot ${verdict#ok }"
  else
    fail=1
    echo "FAIL  $recipe:" >&2
    printf '  %s\n' "${problems[@]}" >&2
  fi
done
exit $fail
