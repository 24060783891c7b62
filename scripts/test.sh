#!/usr/bin/env bash
# Installs what is missing, builds, and runs the test suite; then, when clang is installed, the
# libFuzzer target of the master's decoders for a bounded time (fuzz/run.sh, built in build-fuzz/;
# PIEZOID_FUZZ_SECONDS, default 60, 0 = skip). Extra arguments go to ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh
scripts/build.sh
(cd "${PIEZOID_BUILD_DIR:-build}" && ctest --output-on-failure -j"$(nproc)" --timeout 600 "$@")
FUZZ_SECONDS=${PIEZOID_FUZZ_SECONDS:-60}
if [ "$FUZZ_SECONDS" != 0 ]; then
  if command -v "${PIEZOID_FUZZ_CXX:-clang++}" >/dev/null 2>&1; then
    fuzz/run.sh "$FUZZ_SECONDS"
  else
    echo "test: clang++ not installed: fuzzing skipped"
  fi
fi
