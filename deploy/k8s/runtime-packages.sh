#!/usr/bin/env bash
# Prints the Debian packages that hold the shared libraries the given programs load (ldd), one per
# line: what the runtime stage of deploy/k8s/Containerfile installs. Fails, naming the library,
# when a library is missing or belongs to no package.
#   deploy/k8s/runtime-packages.sh build/master/piezoid-master build/worker/piezoid-worker ...
set -euo pipefail
(($#)) || { echo "usage: $0 PROGRAM..." >&2; exit 2; }
if ldd "$@" | grep -q "not found"; then
  ldd "$@" | grep "not found" >&2
  exit 1
fi
owner() {  # the package of a file, under merged /usr too (/lib/x -> /usr/lib/x)
  local f
  for f in "$1" "$(readlink -f "$1")" "/usr${1#/usr}" "${1#/usr}"; do
    dpkg-query -S "$f" 2>/dev/null | head -n 1 | cut -d: -f1 && return 0
  done
  echo "runtime-packages: $1 belongs to no Debian package" >&2
  return 1
}
ldd "$@" | awk '$2 == "=>" && $3 ~ /^\// {print $3}' | sort -u | while read -r lib; do
  owner "$lib" || exit 1
done | sort -u
