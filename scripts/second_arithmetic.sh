#!/usr/bin/env bash
# Runs the numerical tests a second time under another arithmetic (issue 44), so that a pin that
# holds only on the machine it was made on fails here before it fails on a user's machine
# (docs/architecture.md, "Arithmetic"): OpenBLAS's kernels for another CPU core than this one's
# (OPENBLAS_CORETYPE), and glibc's maths without its FMA / AVX2 variants (GLIBC_TUNABLES). The
# fingerprint of `piezoid doctor` must differ from this machine's own, or the run proves nothing
# and the script fails. Extra arguments go to ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${PIEZOID_BUILD_DIR:-build}
PIEZOID="$BUILD/client/piezoid"
native_core=$("$PIEZOID" doctor | sed -n 's/^dense: .*core=\([A-Za-z0-9_]*\).*/\1/p')
other_core=Sandybridge
[ "$native_core" = Sandybridge ] && other_core=Haswell
export OPENBLAS_CORETYPE=$other_core
export GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-AVX512F
native=$(env -u OPENBLAS_CORETYPE -u GLIBC_TUNABLES "$PIEZOID" doctor --profile)
other=$("$PIEZOID" doctor --profile)
echo "second arithmetic: OPENBLAS_CORETYPE=$OPENBLAS_CORETYPE (native core ${native_core:-none})," \
     "GLIBC_TUNABLES=$GLIBC_TUNABLES"
echo "  native: $native"
echo "  now:    $other"
if [ "$native" = "$other" ]; then
  echo "second arithmetic: the fingerprint did not change: this machine cannot show another" \
       "arithmetic this way" >&2
  exit 1
fi
# The numerical libraries' tests, the client's records tests and the HGANN service run (its pinned
# digest): every regression pin (tests/testing/pinned.h) takes its tolerance path here.
(cd "$BUILD" && ctest --output-on-failure -j"$(nproc)" --timeout 600 \
   -L '^(model|opt|records|hgann|diagnose|complete)$' "$@")
(cd "$BUILD" && ctest --output-on-failure --timeout 600 -R '^system_(hgann|arithmetic)_test$' "$@")
