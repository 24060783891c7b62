#!/usr/bin/env bash
# Installs what is missing, builds, and runs the test suite; then, when clang is installed, the
# records and client tests under AddressSanitizer + UndefinedBehaviorSanitizer (scripts/sanitize.sh,
# built in build-fuzz/; PIEZOID_SANITIZE=0 skips it) and the libFuzzer targets for a bounded time
# (fuzz/run.sh in the same build-fuzz/: the master's decoders, the record-set reader, the fit.json
# loader; PIEZOID_FUZZ_SECONDS, default 60 in all, 0 = skip). Extra arguments go to ctest. Without
# them, the numerical tests run a second time under another arithmetic (scripts/second_arithmetic.sh;
# PIEZOID_SECOND_ARITHMETIC=0 skips it).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh
scripts/build.sh
(cd "${PIEZOID_BUILD_DIR:-build}" && ctest --output-on-failure -j"$(nproc)" --timeout 600 "$@")
if [ "${PIEZOID_SECOND_ARITHMETIC:-1}" != 0 ] && [ $# -eq 0 ]; then
  scripts/second_arithmetic.sh
fi
if ! command -v "${PIEZOID_FUZZ_CXX:-clang++}" >/dev/null 2>&1; then
  echo "test: clang++ not installed: sanitizer tests and fuzzing skipped"
  exit 0
fi
if [ "${PIEZOID_SANITIZE:-1}" != 0 ]; then
  scripts/sanitize.sh
fi
FUZZ_SECONDS=${PIEZOID_FUZZ_SECONDS:-60}
if [ "$FUZZ_SECONDS" != 0 ]; then
  fuzz/run.sh "$FUZZ_SECONDS"
fi
