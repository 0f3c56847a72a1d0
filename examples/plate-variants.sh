#!/usr/bin/env bash
# Batch-produce plate variants with a plain shell loop: the same files as
#   p3dp build recipes/plate.yaml --sweep cycles=3,4,5,6 --sweep amplitude=1..3:0.5 -o out/plates
# byte for byte. Choose the values with CYCLES and AMPLITUDES, the binary with P3DP.
#   bash examples/plate-variants.sh [OUT]
set -euo pipefail
cd "$(dirname "$0")/.."
P3DP=${P3DP:-target/release/p3dp}
[ -x "$P3DP" ] || cargo build --release
out=${1:-out/plates}
mkdir -p "$out"
for cycles in ${CYCLES:-3 4 5 6}; do
  for amplitude in ${AMPLITUDES:-1 1.5 2 2.5 3}; do
    name="plate_cycles-${cycles}_amplitude-${amplitude}"
    "$P3DP" build recipes/plate.yaml --set "cycles=$cycles" --set "amplitude=$amplitude" \
      -o "$out/$name.gcode" --stats-json "$out/$name.json"
  done
done
