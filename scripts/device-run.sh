#!/usr/bin/env bash
# Runs the carried release binary on the benchmark machine (NVIDIA GPU, no Vulkan loader
# installed). Expects, in the repository root there:
#   .gl/*.deb          the loader packages (see docs/building.md)
#   .bench/cullgraph   the release binary built on the development machine
# Usage: bash scripts/device-run.sh cullgraph-arguments...
set -euo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -f "$icd" ] && [ -z "${VK_DRIVER_FILES:-}" ]; then
  export VK_DRIVER_FILES="$icd"
fi
exec ./.bench/cullgraph "$@"
