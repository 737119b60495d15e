#!/usr/bin/env bash
# The main job. Until the daemon exists: describe the default calibration.
set -euo pipefail
build=${1:-build}
exec "$build/tools/naneye" calib info config/calib/paper-d3.yaml
