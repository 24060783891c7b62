#!/usr/bin/env bash
# Installs the Debian packages piezoid needs to build, test and run. Idempotent: installs only
# what is missing, and runs apt-get update only when something is.
set -euo pipefail
PKGS=(build-essential cmake ninja-build pkg-config git
      libeigen3-dev libsundials-dev libzmq3-dev cppzmq-dev libprotobuf-dev protobuf-compiler
      libspdlog-dev zlib1g-dev libgtest-dev libgmock-dev libcli11-dev libbenchmark-dev libboost-dev
      gnuplot-nox libopenblas-serial-dev
      libcpp-httplib-dev libjs-chart.js libjs-marked chromium fonts-dejavu-core  # the dashboard and its browser test
      python3-zmq python3-protobuf python3-venv python3-setuptools python3-pip   # the Python client (python/)
      clang libclang-rt-14-dev)  # clang + its sanitizer/libFuzzer runtimes: fuzz/run.sh
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "deps: all ${#PKGS[@]} packages present"
  exit 0
fi
echo "deps: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
