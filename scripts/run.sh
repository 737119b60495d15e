#!/usr/bin/env bash
# The main job: naneyed with the in-tree configuration. With no NanEye readout board attached, the
# source "auto" falls back to the bundled simulated capture (tests/data/sim-d3-mono), replayed in a
# loop at real time. Stop with Ctrl-C.
set -euo pipefail
build=${1:-build}
cat <<'MSG'
naneyed is starting on http://127.0.0.1:8080 (Ctrl-C stops it). Try:
  curl -s http://127.0.0.1:8080/v1/status
  curl -s http://127.0.0.1:8080/v1/depth
  curl -s 'http://127.0.0.1:8080/v1/depth/at?u=125&v=110'
  curl -s http://127.0.0.1:8080/v1/points.ply -o points.ply
  a browser on http://127.0.0.1:8080/v1/frames/left.png?overlay=1
MSG
exec "$build/daemon/naneyed" --config config/naneyed.toml
