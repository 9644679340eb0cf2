#!/usr/bin/env bash
# MSAA methods against each other: every method at 2x, 4x and 8x with 5, 50 and 500 point
# lights on the city and the monastery, 1920x1080, one JSON of stats per configuration (GPU ms
# per pass from timestamp queries, bytes of every resource, compressed-pool counters).
# With --reference 4 each image's error (mean FLIP, PSNR) against a 16-sample reference.
# Summarize with scripts/msaa-table.py. Usage: bash scripts/bench-msaa.sh CULLGRAPH OUT_DIR [MONASTERY.glb]
# Environment: SCENES (default "city monastery"), SIZE (1920x1080), FRAMES (12), SAMPLES ("2 4 8").
set -euo pipefail
bin=$1
out=$2
monastery=${3:-../shared/assets/monastery.glb}
mkdir -p "$out"
size=${SIZE:-1920x1080}
frames=${FRAMES:-12}
for scene in ${SCENES:-city monastery}; do
  if [ "$scene" = city ]; then src=builtin:city; else src=$monastery; fi
  for lights in 5 50 500; do
    for method in two_phase fxaa; do
      "$bin" render --scene "$src" --lights "$lights" --size "$size" --frames "$frames" --graph "builtin:$method" \
        --reference 4 --out "$out/$scene-$method-1x-$lights.png" --stats "$out/$scene-$method-1x-$lights.json" >/dev/null
    done
    for msaa in ${SAMPLES:-2 4 8}; do
      for method in msaa_per_sample msaa_zprepass msaa_compressed msaa_compressed_claim visibility_buffer; do
        "$bin" render --scene "$src" --lights "$lights" --size "$size" --frames "$frames" --graph "builtin:$method" \
          --param "msaa=$msaa" --reference 4 --out "$out/$scene-$method-${msaa}x-$lights.png" \
          --stats "$out/$scene-$method-${msaa}x-$lights.json" >/dev/null
      done
    done
  done
done
