#!/usr/bin/env bash
# Regenerates the gallery's pictures, docs/previews/NAME.png: a 600 × 450
# preview of every recipe in recipes/ (and docs/guide/NAME.png of the
# guide's recipes), each in the colour mode and view that
# show it best, and docs/previews/SOURCES: the SHA-256 of the G-code each
# picture was drawn from (`p3dp hash`). The pictures are deterministic: the
# same recipes give the same bytes. tests/it/gallery_docs.rs fails when a
# recipe has no picture, when SOURCES disagrees with p3dp.lock (the G-code
# changed since the pictures were made), or when a few pictures redrawn
# differ from the committed ones (the renderer changed): run this script.
# Usage: docs/make-previews.sh    (builds p3dp in release first)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
p3dp=target/release/p3dp
mkdir -p docs/previews
# recipe                 colour          view
while read -r name color view; do
  "$p3dp" preview "recipes/$name.yaml" -o "docs/previews/$name.png" \
    --size 600x450 --color "$color" --view "$view" >/dev/null
done <<'LIST'
bowl                     speed           iso
bracket                  order           iso
brush                    order           iso
bumpy-prism              speed           iso
ca-extinction            cross-section   iso
ca-split-merge           cross-section   iso
ca-stripes               cross-section   iso
ca-waves                 cross-section   iso
cardioid                 order           top
chain-mail               order           iso
cup                      speed           iso
cup-solid-base           order           iso
deformed-sphere          speed           iso
filled-shapes            order           iso
flexible-circles         order           iso
globe                    cross-section   iso
hairs                    order           iso
heart-plate              flow            iso
hex-prism                order           iso
hilbert                  order           iso
koch-tower               speed           iso
lamp-shade               speed           iso
lamp-shade-textured      cross-section   iso
lamp-shade-tiers         order           iso
nonplanar-star           order           iso
nonplanar-vase           order           iso
olympic-rings            order           top
pine-tree                speed           iso
plate                    flow            iso
plate-sampler            flow            iso
ruffled-star             cross-section   iso
rule30-prism             speed           iso
self-organised-stripes   speed           iso
sphere                   speed           iso
star-vase                order           iso
string-art-parabola      order           top
svg-drawing              order           top
twisted-heart-vase       speed           iso
vase                     order           iso
LIST
"$p3dp" hash recipes/*.yaml > docs/previews/SOURCES
# the guide's own recipes, their pictures beside them
for r in docs/guide/*.yaml; do
  grep -q '^p3dp: 1' "$r" || continue   # a printer profile
  "$p3dp" preview "$r" -o "${r%.yaml}.png" --size 600x450 --color order --view iso >/dev/null
done
