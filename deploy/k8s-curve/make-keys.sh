#!/usr/bin/env bash
# Makes the key pairs of deploy/k8s-curve (master, worker, client) in a keys folder beside this script with
# `piezoid keygen` (PIEZOID: the piezoid program, default: from PATH). Existing keys are kept.
set -euo pipefail
cd "$(dirname "$0")"
PIEZOID=${PIEZOID:-piezoid}
mkdir -p keys
chmod 700 keys
for n in master worker client; do
  [[ -f keys/$n.key ]] || "$PIEZOID" keygen --out keys --name "$n"
done
