#!/bin/sh
# Fills fuzz/corpus/TARGET/ with seeds from the repository: recipes/,
# tests/bad/, tests/fixtures/, the lock file, the built-in profiles and
# maps/, plus the findings kept in fuzz/findings/TARGET/ (inputs that once
# failed; each is a regression test). Run from anywhere; idempotent.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
seed() { # TARGET FILE…
  t=$1; shift
  mkdir -p "$here/corpus/$t"
  for f in "$@"; do
    [ -f "$f" ] && cp "$f" "$here/corpus/$t/$(echo "$f" | sed "s|^$root/||; s|/|_|g")"
  done
  if [ -d "$here/findings/$t" ]; then cp "$here/findings/$t"/* "$here/corpus/$t/" 2>/dev/null || true; fi
}
seed recipe "$root"/recipes/*.yaml "$root"/tests/bad/*.yaml "$root"/tests/fixtures/*.yaml "$root"/tests/checks/*.yaml
seed printer "$root"/src/machine/printers/*.yaml "$root"/tests/fixtures/printers/*.yaml
seed lock "$root"/p3dp.lock
seed image "$root"/maps/* "$root"/tests/bad/*.png
seed svg "$root"/recipes/*.svg "$root"/tests/bad/svg/*.svg
seed preset_ini "$root"/tests/fixtures/presets/*.ini "$root"/docs/guide/*.ini
seed preset_json "$root"/tests/fixtures/presets/*/*.json "$root"/tests/fixtures/presets/*/*/*.json "$root"/tests/fixtures/presets/*/*/*/*.json "$root"/tests/fixtures/presets/*/*/*/*/*.json
seed include "$root"/recipes/cup.yaml "$root"/recipes/plate.yaml "$root"/tests/fixtures/*.yaml
# G-code lines: every line of the built-ins' recorded start G-code, one a file
mkdir -p "$here/corpus/gcode_line"
cat "$root"/tests/fixtures/printers/start/*.gcode | sort -u | while IFS= read -r l; do
  printf '%s' "$l" > "$here/corpus/gcode_line/$(printf '%s' "$l" | cksum | cut -d' ' -f1)"
done
if [ -d "$here/findings/gcode_line" ]; then cp "$here/findings/gcode_line"/* "$here/corpus/gcode_line/" 2>/dev/null || true; fi
# expressions: every quoted string of the recipes, one a file
mkdir -p "$here/corpus/expr"
grep -ho '"[^"]*"' "$root"/recipes/*.yaml | sed 's/^"//; s/"$//' | sort -u | while IFS= read -r e; do
  printf '%s' "$e" > "$here/corpus/expr/$(printf '%s' "$e" | cksum | cut -d' ' -f1)"
done
if [ -d "$here/findings/expr" ]; then cp "$here/findings/expr"/* "$here/corpus/expr/" 2>/dev/null || true; fi
# slicer macros: the start/end G-code of the built-in profiles and the test
# presets, one template a file
mkdir -p "$here/corpus/slicer_macro"
for f in "$root"/src/machine/printers/*.yaml "$root"/tests/fixtures/printers/*.yaml "$root"/tests/fixtures/presets/*; do
  [ -f "$f" ] || continue
  cp "$f" "$here/corpus/slicer_macro/$(echo "$f" | sed "s|^$root/||; s|/|_|g")"
done
cat > "$here/corpus/slicer_macro/constructs" <<'TEMPLATE'
M104 S[temperature] ; [printer_model] {layer_height*2}
{if printer_model =~ /MK4.*/ and not has_wipe_tower}G28{elsif layer_height > 0.1}G29{else}G30{endif}
{local t = (1, 2.5, 3); global g = repeat(2, "a"); t[1] = 7; g[0] = g[1] + "b"}{size(t)} {empty(g)} {t[1]}
{is_nil(temperature[1]) ? "nil" : "set"} {one_of(printer_model, "MINI", /MK.*/, ~"X" + "L")}
{interpolate_table(layer_height, (0, 1), (0.3, 2))} {digits(park, 6, 2)} {zdigits(7, 3)} {random(1, 6)}
{if layer_height < 0.1 then "fine" else "draft" endif}; {min(1, 2.5)} {max(3, 4)} {int(-2.7)} {round(2.5)}
TEMPLATE
if [ -d "$here/findings/slicer_macro" ]; then cp "$here/findings/slicer_macro"/* "$here/corpus/slicer_macro/" 2>/dev/null || true; fi
echo "seeded $(ls "$here"/corpus/* | wc -l) files into $here/corpus"
