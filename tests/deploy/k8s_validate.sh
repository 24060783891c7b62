#!/usr/bin/env bash
# deploy/k8s renders and validates offline:
#  1. deploy/k8s/hgann_job.json (the client Job's ConfigMap) is examples/hgann_job.json;
#  2. `kubectl kustomize deploy/k8s` renders, with every kubectl at hand: the one on PATH (if any)
#     and Debian's kubernetes-client (kubectl 1.20, kustomize v2: extracted from the package with
#     apt-get download + dpkg-deb into a temporary folder, nothing installed), so the manifests do
#     not depend on which kubectl a machine has;
#  3. tests/deploy/k8s_validate.js checks every rendered object against its Kubernetes schema (npm
#     kubernetes-models + yaml, installed into a temporary folder) and the references between them;
#  4. the validator is shown to reject broken renderings (a wrong type, a dangling reference);
#  5. the image (deploy/k8s/Containerfile; no container engine here to build it) holds what the
#     manifests use: the three programs on its PATH, the bench data where the client Job's spec
#     points (../data from /opt/piezoid/jobs), and deploy/k8s/runtime-packages.sh names the
#     packages of this build's shared libraries (when a build folder is given).
# Needs node and npm (else exit 77 = skipped); KUBECONFIG=/dev/null: no cluster is contacted.
#   tests/deploy/k8s_validate.sh [build dir]
set -euo pipefail
SRC=$(cd "$(dirname "$0")/../.." && pwd)
K8S=$SRC/deploy/k8s
skip() { echo "SKIPPED: $*"; exit 77; }
command -v node >/dev/null || skip "node is not installed (apt-get install nodejs npm)"
command -v npm >/dev/null || skip "npm is not installed (apt-get install npm)"

TMP=$(mktemp -d "${TMPDIR:-/tmp}/pz-k8s.XXXXXX")
trap 'rm -rf "$TMP"' EXIT
export KUBECONFIG=/dev/null
t0=$SECONDS

echo "== 1. deploy/k8s/hgann_job.json is examples/hgann_job.json"
cmp "$SRC/examples/hgann_job.json" "$K8S/hgann_job.json" ||
  { echo "FAIL: deploy/k8s/hgann_job.json differs: cp examples/hgann_job.json deploy/k8s/"; exit 1; }

echo "== 2. kubectl kustomize deploy/k8s"
kubectls=()
if command -v kubectl >/dev/null && kubectl version --client >/dev/null 2>&1; then
  kubectls+=("$(command -v kubectl)")
fi
if [[ $(id -u) -eq 0 ]] && command -v apt-get >/dev/null; then
  # Debian's kubectl, unpacked only (installing it could replace another kubectl).
  (cd "$TMP" && { apt-get download kubernetes-client >/dev/null 2>&1 ||
                  { apt-get update -qq >/dev/null 2>&1 && apt-get download kubernetes-client >/dev/null 2>&1; }; } &&
     dpkg-deb -x kubernetes-client_*.deb debian-kubectl) || echo "note: Debian's kubernetes-client is not available"
  [[ -x $TMP/debian-kubectl/usr/bin/kubectl ]] && kubectls+=("$TMP/debian-kubectl/usr/bin/kubectl")
fi
((${#kubectls[@]})) || skip "no kubectl: none on PATH, and Debian's kubernetes-client cannot be fetched"
renders=()
for k in "${kubectls[@]}"; do
  v=$("$k" version --client 2>/dev/null | grep -o 'v[0-9]*\.[0-9]*\.[0-9]*' | head -n 1)
  out=$TMP/rendered-${#renders[@]}.yaml
  if ! "$k" kustomize "$K8S" >"$out" 2>"$TMP/kustomize.err"; then
    cat "$TMP/kustomize.err"; echo "FAIL: $k ($v) kustomize deploy/k8s"; exit 1
  fi
  echo "rendered with $k ($v): $(grep -c '^kind:' "$out") objects"
  renders+=("$out")
done

echo "== 3. schemas (kubernetes-models) and references"
(cd "$TMP" && npm install --prefer-offline --no-audit --no-fund --no-save --silent \
   kubernetes-models@4.5.1 yaml@2.9.1 >"$TMP/npm.log" 2>&1) ||
  { cat "$TMP/npm.log"; skip "npm cannot install kubernetes-models and yaml (registry unreachable?)"; }
export NODE_PATH=$TMP/node_modules
for r in "${renders[@]}"; do
  node "$SRC/tests/deploy/k8s_validate.js" "$r"
done

echo "== 4. the validator rejects broken renderings"
r=${renders[0]}
sed 's/containerPort: 5555/containerPort: "5555"/' "$r" >"$TMP/bad-type.yaml"
sed -E 's/^( {4,}name: )piezoid-job-[a-z0-9]+$/\1piezoid-job-missing/' "$r" >"$TMP/bad-ref.yaml"
sed 's#tcp://piezoid-master:5555#tcp://piezoid-master:5557#' "$r" >"$TMP/bad-port.yaml"
for bad in bad-type bad-ref bad-port; do
  cmp -s "$r" "$TMP/$bad.yaml" && { echo "FAIL: the $bad mutation changed nothing"; exit 1; }
  if node "$SRC/tests/deploy/k8s_validate.js" "$TMP/$bad.yaml" >"$TMP/$bad.out" 2>&1; then
    cat "$TMP/$bad.out"; echo "FAIL: $bad.yaml was accepted"; exit 1
  fi
  echo "$bad rejected: $(grep -m1 FAIL "$TMP/$bad.out")"
done
echo "== 5. the image has what the manifests use"
CF=$K8S/Containerfile
for prog in piezoid-master piezoid-worker piezoid; do
  grep -q "^ *command: \[\"$prog\"\]\|^ *id=\$($prog \|^ *$prog " "$K8S"/*.yaml || { echo "FAIL: no manifest runs $prog"; exit 1; }
  grep -q "build/[a-z]*/$prog\b" "$CF" || { echo "FAIL: the Containerfile does not install $prog"; exit 1; }
done
grep -q '^ENV PATH=/opt/piezoid/bin:' "$CF" || { echo "FAIL: /opt/piezoid/bin is not on the image's PATH"; exit 1; }
grep -q 'mountPath: /opt/piezoid/jobs$' "$K8S/client-job.yaml" || { echo "FAIL: the job spec is not mounted at /opt/piezoid/jobs"; exit 1; }
grep -q 'COPY --from=build /opt/piezoid/data/ /opt/piezoid/data/' "$CF" || { echo "FAIL: the image lacks /opt/piezoid/data"; exit 1; }
csd=$(sed -n 's/.*"case_set_dir": *"\([^"]*\)".*/\1/p' "$K8S/hgann_job.json")
[[ $csd == ../data/* && -d $SRC/${csd#../} ]] ||
  { echo "FAIL: case_set_dir '$csd' does not resolve to the image's /opt/piezoid/data"; exit 1; }
echo "programs on PATH, job spec in /opt/piezoid/jobs, its cases in /opt/piezoid/${csd#../}"
B=${1:-}
if [[ -n $B && -x $B/master/piezoid-master && -x $B/worker/piezoid-worker && -x $B/client/piezoid ]] &&
   command -v dpkg-query >/dev/null; then
  pk=$("$K8S/runtime-packages.sh" "$B/master/piezoid-master" "$B/worker/piezoid-worker" "$B/client/piezoid") ||
    { echo "FAIL: runtime-packages.sh"; exit 1; }
  for need in libzmq5 libprotobuf32; do
    grep -qx "$need" <<<"$pk" || { echo "FAIL: runtime-packages.sh does not name $need"; exit 1; }
  done
  echo "runtime packages of this build: $(tr '\n' ' ' <<<"$pk")"
else
  echo "note: no build folder given: runtime-packages.sh not exercised"
fi
echo "k8s_validate: passed in $((SECONDS - t0)) s"
