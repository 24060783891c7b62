#!/usr/bin/env bash
# The main job: installs what is missing, builds, and scores the nine bundled bench cases
# (data/bimorph-fin/nominal) with the plant at the bench's nominal parameters.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh
scripts/build.sh
BIN="${PIEZOID_BUILD_DIR:-build}/client/piezoid"
echo
echo "== piezoid pi: the nine bench cases of data/bimorph-fin/nominal against the plant at nominal parameters"
"$BIN" pi --cases data/bimorph-fin/nominal "$@"
