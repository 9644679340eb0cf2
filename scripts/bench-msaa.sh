#!/usr/bin/env bash
# MSAA methods against each other: every method at 2x, 4x and 8x with 5, 50 and 500 point
# lights on the city and the monastery, 1920x1080, one JSON of stats per configuration (GPU ms
# per pass from timestamp queries, bytes of every resource, compressed-pool counters).
# Summarize with scripts/msaa-table.py. Usage: bash scripts/bench-msaa.sh CULLGRAPH OUT_DIR [MONASTERY.glb]
set -euo pipefail
bin=$1
out=$2
monastery=${3:-../shared/assets/monastery.glb}
mkdir -p "$out"
size=${SIZE:-1920x1080}
frames=${FRAMES:-12}
for scene in city monastery; do
  if [ "$scene" = city ]; then src=builtin:city; else src=$monastery; fi
  for lights in 5 50 500; do
    "$bin" render --scene "$src" --lights "$lights" --size "$size" --frames "$frames" --graph builtin:two_phase \
      --out "$out/$scene-noaa-1x-$lights.png" --stats "$out/$scene-noaa-1x-$lights.json" >/dev/null
    for msaa in 2 4 8; do
      for method in msaa_per_sample msaa_zprepass msaa_compressed; do
        "$bin" render --scene "$src" --lights "$lights" --size "$size" --frames "$frames" --graph "builtin:$method" \
          --param "msaa=$msaa" --out "$out/$scene-$method-${msaa}x-$lights.png" \
          --stats "$out/$scene-$method-${msaa}x-$lights.json" >/dev/null
      done
    done
  done
done
