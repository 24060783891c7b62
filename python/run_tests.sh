#!/usr/bin/env bash
# Builds the Python client from this checkout (protobuf bindings generated from proto/) into a venv
# of the build folder that sees Debian's python3-zmq / python3-protobuf, and runs its tests against
# the master, worker and CLI of that build.   Usage: python/run_tests.sh BUILD_DIR
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=$(cd "${1:?usage: python/run_tests.sh BUILD_DIR [unittest args]}" && pwd)
shift
py=/usr/bin/python3
[[ -x $py ]] || py=$(command -v python3)
venv="$build/pyenv"
[[ -x $venv/bin/python ]] || "$py" -m venv --system-site-packages "$venv"
"$venv/bin/python" -m pip install -q --no-build-isolation --no-deps --no-index "$here" >"$build/pyenv-install.log" 2>&1 ||
  { cat "$build/pyenv-install.log" >&2; exit 1; }
cd "$here/tests"
PIEZOID_BUILD_DIR="$build" exec "$venv/bin/python" -m unittest -v "${@:-test_service}"
