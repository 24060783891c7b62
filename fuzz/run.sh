#!/usr/bin/env bash
# Builds fuzz_master (clang, -fsanitize=fuzzer,address,undefined) in build-fuzz/ and runs it for a
# bounded time from the seed corpus fuzz/corpus/ (new inputs go to build-fuzz/corpus/, never to
# the repository; a crashing input is saved as build-fuzz/crash-* and the script fails).
#
#   fuzz/run.sh [SECONDS=60] [libFuzzer options…]   e.g. fuzz/run.sh 600 -runs=1000000
#   fuzz/run.sh --regen-corpus                       rewrites fuzz/corpus/ (fuzz/make_corpus.cc)
#
# Without clang it says so and exits 0 (scripts/test.sh runs it when clang is installed).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${PIEZOID_FUZZ_BUILD_DIR:-build-fuzz}
CXX=${PIEZOID_FUZZ_CXX:-clang++}
CC=${PIEZOID_FUZZ_CC:-clang}
if ! command -v "$CXX" >/dev/null 2>&1; then
  echo "fuzz: $CXX not found: fuzzing skipped (scripts/deps.sh installs clang)"
  exit 0
fi
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_C_COMPILER="$CC" -DCMAKE_CXX_COMPILER="$CXX" \
  -DCMAKE_CXX_FLAGS_RELEASE="-O1 -gline-tables-only" -DCMAKE_C_FLAGS_RELEASE="-O1 -gline-tables-only" \
  -DPIEZOID_FUZZ=ON -DPIEZOID_BUILD_TESTS=OFF -DPIEZOID_BUILD_BENCH=OFF >/dev/null
if [ "${1:-}" = "--regen-corpus" ]; then
  cmake --build "$BUILD" --target make_corpus
  rm -f fuzz/corpus/*
  "$BUILD/fuzz/make_corpus" fuzz/corpus
  ls fuzz/corpus
  exit 0
fi
SECONDS_TO_RUN=${1:-60}
shift || true
cmake --build "$BUILD" --target fuzz_master
mkdir -p "$BUILD/corpus"
# detect_leaks: the registry and protobuf keep process-lifetime allocations.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
set -x
"$BUILD/fuzz/fuzz_master" -max_total_time="$SECONDS_TO_RUN" -timeout=10 -rss_limit_mb=2048 \
  -max_len=8192 -print_final_stats=1 -artifact_prefix="$BUILD/" "$@" "$BUILD/corpus" fuzz/corpus
