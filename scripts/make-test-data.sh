#!/usr/bin/env bash
# Remakes the bundled simulator captures in tests/data/ (tests/data/README.md describes them).
# The same build of `naneye sim` with the same seeds gives the same bytes.
#   scripts/make-test-data.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
sim="$build/tools/naneye sim"
out=tests/data
# Dataset 3 (5.99 mm squares at ~70 mm), monochrome: the default sensor, mostly whole boards.
$sim --preset paper-d3 --pairs 12 --seed 1 -o "$out/sim-d3-mono"
# Dataset 3, GRBG colour sensor.
$sim --preset paper-d3 --pairs 6 --seed 2 --bayer -o "$out/sim-d3-bayer"
# Dataset 1 (2.25 mm at ~20 mm) with the board cut by the image edge or absent in most pairs.
$sim --preset paper-d1 --pairs 3 --seed 5 --partial-share 0.5 --absent-share 0.3 -o "$out/sim-d1-cut"
