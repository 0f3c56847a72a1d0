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
# expressions: every quoted string of the recipes, one a file
mkdir -p "$here/corpus/expr"
grep -ho '"[^"]*"' "$root"/recipes/*.yaml | sed 's/^"//; s/"$//' | sort -u | while IFS= read -r e; do
  printf '%s' "$e" > "$here/corpus/expr/$(printf '%s' "$e" | cksum | cut -d' ' -f1)"
done
if [ -d "$here/findings/expr" ]; then cp "$here/findings/expr"/* "$here/corpus/expr/" 2>/dev/null || true; fi
echo "seeded $(ls "$here"/corpus/* | wc -l) files into $here/corpus"
