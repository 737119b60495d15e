#!/bin/bash
# Builds the libFuzzer targets (clang, ASan + UBSan, build dir build-fuzz) and runs each for SECONDS
# on a copy of its seed corpus (tests/fuzz/corpus/<target>; what the fuzzer adds stays in
# build-fuzz/corpus/, crashes go to build-fuzz/artifacts/). Prints each target's exec/s, executions,
# coverage and features, and fails if any target crashed.
#
#   scripts/fuzz.sh SECONDS [TARGET...]        (default: every target; see tests/fuzz/fuzz_entries.hpp)
#   FUZZ_FLAGS="-runs=10000000" scripts/fuzz.sh 0 uri   (extra libFuzzer flags; 0 s: no time limit)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:?usage: scripts/fuzz.sh SECONDS [TARGET...]}
shift
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(parser neyd calib_yaml daemon_toml device_profile source_uri http_query v4l2_unpack image)
fi
build=${FUZZ_BUILD:-build-fuzz}
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DNANEYE_FUZZ=ON -DNANEYE_BUILD_BENCH=OFF \
  -DNANEYE_BROWSER_TESTS=OFF "${launcher[@]}" >/dev/null
cmake --build "$build" -j "${JOBS:-2}" --target "${targets[@]/#/fuzz_}"
# OpenCV checks an image's claimed size against this before it allocates (default 2^30 pixels).
export OPENCV_IO_MAX_IMAGE_PIXELS=16777216
mkdir -p "$build/artifacts"
failed=0
for t in "${targets[@]}"; do
  mkdir -p "$build/corpus/$t"
  log="$build/fuzz_$t.log"
  time_flag=()
  [ "$seconds" -gt 0 ] && time_flag=(-max_total_time="$seconds")
  # -timeout 10 s: any input that slow is a hang; -rss_limit_mb 2048: libFuzzer's default, stated.
  # shellcheck disable=SC2086
  if ! "$build/tests/fuzz/fuzz_$t" "${time_flag[@]}" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$build/artifacts/$t-" ${FUZZ_FLAGS:-} "$build/corpus/$t" "tests/fuzz/corpus/$t" \
      >"$log" 2>&1; then
    failed=1
    echo "fuzz_$t: FAILED (see $log and $build/artifacts/)"
  fi
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  speed=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -o 'cov: [0-9]* ft: [0-9]*' "$log" | tail -1 || echo "cov: ? ft: ?")
  printf 'fuzz_%-15s %10s execs  %7s exec/s  %s\n' "$t" "$runs" "$speed" "$cov"
done
exit $failed
