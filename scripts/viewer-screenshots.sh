#!/usr/bin/env bash
# Regenerates the screenshots of docs/viewer.md: runs the viewer's browser test against a real naneyed
# on the bundled capture and on a textured scene (sim://sphere), and keeps its screenshots in docs/img/
# (viewer-board.png, viewer-scene.png).
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
node tests/browser/viewer.test.mjs --naneyed "$build/daemon/naneyed" --screenshots docs/img
