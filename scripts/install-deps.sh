#!/usr/bin/env bash
# Installs the Debian 12 packages naneye builds and tests with. Idempotent: installs only what is missing.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config clang clang-format
  libeigen3-dev libopencv-dev libspdlog-dev libfmt-dev nlohmann-json3-dev libcli11-dev
  libcpp-httplib-dev libssl-dev libusb-1.0-0-dev libsystemd-dev libtomlplusplus-dev zlib1g-dev
  libreaderwriterqueue-dev libgtest-dev libgmock-dev libbenchmark-dev libpng-dev
  libumockdev-dev umockdev curl file chromium libyaml-cpp-dev libyaml-dev opencv-doc
  libclang-rt-14-dev  # libFuzzer for scripts/fuzz.sh (clang itself does not pull it in)
)
# The viewer's browser test (tests/browser) drives Debian's chromium with puppeteer-core from npm;
# node comes with the machine, or from Debian (node 18 is enough for puppeteer-core 24).
command -v node >/dev/null 2>&1 || packages+=(nodejs npm)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
browser_tests="$(dirname "$0")/../tests/browser"
if [ ! -d "$browser_tests/node_modules/puppeteer-core" ]; then
  echo "install-deps: npm ci in tests/browser (puppeteer-core, pinned by its package-lock.json)"
  npm ci --prefix "$browser_tests" --no-audit --no-fund --loglevel=error
fi
