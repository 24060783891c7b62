// Validates the objects that `kubectl kustomize deploy/k8s` rendered (a multi-document YAML file):
// each against its Kubernetes JSON schema (npm package kubernetes-models), then the references
// between them that a schema cannot see (selectors, Service ports, ConfigMaps, named ports, the
// master address of workers and client, the container image).
//   NODE_PATH=<dir with node_modules> node k8s_validate.js rendered.yaml
// Prints one line per object and per failed check; exit status 1 on any failure.
"use strict";
const fs = require("fs");
const YAML = require("yaml");

const file = process.argv[2];
const docs = YAML.parseAllDocuments(fs.readFileSync(file, "utf8"));
const errors = [];
const fail = (what, msg) => errors.push(`${what}: ${msg}`);

const objects = [];
for (const d of docs) {
  if (d.errors.length) {
    fail(file, d.errors.map((e) => e.message).join("; "));
    continue;
  }
  const o = d.toJS();
  if (o) objects.push(o);
}

// 1. Schemas.
const groupModule = (apiVersion) => "kubernetes-models/" + apiVersion;  // "v1", "apps/v1", ...
for (const o of objects) {
  const what = `${o.kind}/${o.metadata && o.metadata.name}`;
  let Model;
  try {
    Model = require(groupModule(o.apiVersion))[o.kind];
  } catch (e) {
    Model = undefined;
  }
  if (!Model) {
    fail(what, `no schema for apiVersion ${o.apiVersion} kind ${o.kind}`);
    continue;
  }
  try {
    new Model(o).validate();
    console.log(`schema ok: ${o.apiVersion} ${what}`);
  } catch (e) {
    fail(what, `schema: ${e.message}`);
  }
}

// 2. References.
const byKind = (k) => objects.filter((o) => o.kind === k);
const find = (k, name) => objects.find((o) => o.kind === k && o.metadata.name === name);
const matches = (selector, labels) =>
  Object.entries(selector || {}).every(([k, v]) => labels && labels[k] === v);
const podSpecs = [];
for (const o of [...byKind("StatefulSet"), ...byKind("Deployment"), ...byKind("Job")]) {
  const what = `${o.kind}/${o.metadata.name}`;
  const tpl = o.spec.template;
  podSpecs.push({ what, o, labels: tpl.metadata && tpl.metadata.labels, spec: tpl.spec });
  if (o.spec.selector && o.spec.selector.matchLabels &&
      !matches(o.spec.selector.matchLabels, tpl.metadata && tpl.metadata.labels))
    fail(what, "spec.selector.matchLabels does not select its own pod template");
}

for (const s of byKind("Service")) {
  const what = `Service/${s.metadata.name}`;
  const pods = podSpecs.filter((p) => p.o.kind !== "Job" && matches(s.spec.selector, p.labels));
  if (!pods.length) {
    fail(what, "selects no pod template");
    continue;
  }
  for (const port of s.spec.ports) {
    const target = port.targetPort === undefined ? port.port : port.targetPort;
    const found = pods.some((p) =>
      p.spec.containers.some((c) => (c.ports || []).some((cp) =>
        typeof target === "string" ? cp.name === target : cp.containerPort === target)));
    if (!found) fail(what, `port ${port.name || port.port}: no container port ${target}`);
  }
}

for (const ss of byKind("StatefulSet")) {
  const what = `StatefulSet/${ss.metadata.name}`;
  const gov = find("Service", ss.spec.serviceName);
  if (!gov) fail(what, `serviceName ${ss.spec.serviceName}: no such Service`);
  else if (gov.spec.clusterIP !== "None") fail(what, `serviceName ${ss.spec.serviceName} is not headless`);
  const claims = (ss.spec.volumeClaimTemplates || []).map((c) => c.metadata.name);
  for (const c of ss.spec.template.spec.containers)
    for (const m of c.volumeMounts || [])
      if (!claims.includes(m.name) && !(ss.spec.template.spec.volumes || []).some((v) => v.name === m.name))
        fail(what, `container ${c.name} mounts ${m.name}: no such volume or claim template`);
}

const endpointArgs = (c) => [...(c.command || []), ...(c.args || [])].join(" ") + " " +
  (c.env || []).map((e) => e.value || "").join(" ");
for (const p of podSpecs) {
  const volumes = p.spec.volumes || [];
  for (const v of volumes)
    if (v.configMap && !find("ConfigMap", v.configMap.name))
      fail(p.what, `volume ${v.name}: ConfigMap ${v.configMap.name} is not rendered`);
  for (const c of [...(p.spec.initContainers || []), ...p.spec.containers]) {
    if (!/^[^:@]+(:[\w.-]+)?(@sha256:[0-9a-f]{64})?$/.test(c.image) || c.image === "piezoid")
      fail(p.what, `container ${c.name}: image '${c.image}' (kustomization images: did not apply?)`);
    const ports = (c.ports || []).map((x) => x.name);
    for (const probe of [c.readinessProbe, c.livenessProbe, c.startupProbe].filter(Boolean)) {
      const port = (probe.tcpSocket || probe.httpGet || {}).port;
      if (typeof port === "string" && !ports.includes(port))
        fail(p.what, `container ${c.name}: probe on port '${port}', which it does not name`);
    }
    if (p.o.kind !== "StatefulSet" && p.o.kind !== "Job")
      for (const m of c.volumeMounts || [])
        if (!volumes.some((v) => v.name === m.name)) fail(p.what, `container ${c.name} mounts unknown volume ${m.name}`);
    // Every tcp://host:port a container is given must be a Service's port.
    for (const [, host, port] of endpointArgs(c).matchAll(/tcp:\/\/([A-Za-z0-9.-]+):(\d+)/g)) {
      const svc = find("Service", host.split(".")[0]);
      if (!svc) fail(p.what, `container ${c.name}: tcp://${host}:${port}: no Service ${host}`);
      else if (!svc.spec.ports.some((x) => x.port === Number(port)))
        fail(p.what, `container ${c.name}: tcp://${host}:${port}: Service ${host} has no port ${port}`);
      else console.log(`reference ok: ${p.what} -> Service/${host}:${port}`);
    }
  }
}

for (const np of byKind("NetworkPolicy")) {
  const targets = podSpecs.filter((p) => matches(np.spec.podSelector.matchLabels, p.labels));
  if (!targets.length) fail(`NetworkPolicy/${np.metadata.name}`, "selects no pod template");
  for (const rule of np.spec.ingress || [])
    for (const from of rule.from || [])
      if (from.podSelector) {
        const peers = podSpecs.filter((p) => matches(from.podSelector.matchLabels, p.labels)).map((p) => p.what);
        for (const need of ["Deployment/", "Job/"])
          if (!peers.some((w) => w.startsWith(need)))
            fail(`NetworkPolicy/${np.metadata.name}`, `ingress does not admit the ${need.slice(0, -1)}'s pods`);
      }
}

const kinds = objects.map((o) => o.kind);
for (const need of ["StatefulSet", "Service", "Deployment", "Job", "ConfigMap"])
  if (!kinds.includes(need)) fail(file, `no ${need} rendered`);

for (const e of errors) console.log("FAIL " + e);
console.log(`${objects.length} objects, ${errors.length} problem(s)`);
process.exit(errors.length ? 1 : 0);
