#!/usr/bin/env bash
# Regenerates the README's gallery, docs/previews/NAME.png: 600 × 450 previews
# of the papers' recipes, each in the colour mode that shows it best.
# Usage: docs/make-previews.sh    (builds p3dp in release first)
# The images are deterministic: the same recipes give the same bytes.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
p3dp=target/release/p3dp
mkdir -p docs/previews
# recipe            colour          view
while read -r name color view; do
  "$p3dp" preview "recipes/$name.yaml" -o "docs/previews/$name.png" \
    --size 600x450 --color "$color" --view "$view"
done <<'LIST'
sphere              speed           iso
globe               cross-section   iso
plate               flow            iso
vase                order           iso
bowl                speed           iso
lamp-shade-textured cross-section   iso
twisted-heart-vase  speed           iso
olympic-rings       order           top
koch-tower          speed           iso
pine-tree           speed           iso
cardioid            order           top
nonplanar-vase      order           iso
LIST
