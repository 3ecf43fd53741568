#!/usr/bin/env bash
# Installs ballbar's build and test dependencies from Debian 12's packages.
# Every package is named here with the reason it is needed; see README.md "Dependencies".
set -euo pipefail

packages=(
  # build
  build-essential cmake pkg-config git clang-format
  ninja-build          # the presets' generator: compiles across targets' boundaries, which make's per-target order does not
  lld                  # links the ~90 executables four times faster than GNU ld (CMakeLists.txt, BALLBAR_LLD)
  # libraries the product links
  libeigen3-dev        # analysis: kinematics, SSM, identification (the only dependency of analysis/)
  libsqlite3-dev       # storage: every session in one SQLite file
  nettle-dev           # storage: SHA-256 of imported files (duplicate imports are recognised)
  libusb-1.0-0-dev     # device: vendor-class USB bulk link
  libhidapi-dev        # device: USB HID link (hidraw backend)
  libserialport-dev    # device: USB CDC serial link (port enumeration with VID/PID, modem lines)
  libmodbus-dev        # device: Modbus RTU digital indicators (modbus: URIs, docs/instruments.md)
  libcli11-dev         # app: command line parsing
  nlohmann-json3-dev   # app/storage: JSON in and out (solve, export, --json)
  libfmt-dev           # app: output formatting
  libcairo2-dev        # reports: vector PDF
  libcpp-httplib-dev   # webui/: `ballbar serve`'s HTTP server (Server-Sent Events for the live reading)
  libpq-dev            # fleet/: PostgreSQL's own client library, for `ballbar sync` to a plant's server
  linuxcnc-uspace-dev  # linuxcnc/: LinuxCNC's headers (kinematics.h, hal.h, rtapi.h), the ballbarkins module is built against them
  # tests and benchmarks
  libgtest-dev libgmock-dev   # unit and integration tests
  libbenchmark-dev            # bench/
  umockdev libumockdev-dev libglib2.0-dev  # fake USB/HID/tty devices so the real libraries run in tests
  sqlite3                     # the sqlite3 shell: benchmark comparison, inspection
  poppler-utils               # pdftotext/pdfinfo: report tests
  linuxcnc-uspace             # LinuxCNC itself: its headless simulator runs the ballbarkins module's tests
  chromium chromium-driver python3-selenium  # the browser test of `ballbar serve` (headless Chromium, one command: matching versions)
  postgresql                  # a throwaway PostgreSQL server the fleet tests start and stop (ctest label postgres); psql, their oracle
  clang libclang-rt-14-dev    # libFuzzer targets of every parser (fuzz/, scripts/fuzz.sh)
  # packaging
  help2man                    # man pages generated from the commands' own --help
  lintian                     # checks the Debian package (CI)
  mmdebstrap                  # scripts/test-package.sh: a clean Debian 12 root to install the package into
)

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
echo "install-deps: all ${#packages[@]} packages present"
