"""deploy/k8s/: the manifests are checked against minimal JSON schemas of the
kinds used (required fields and types; kubeconform is not packaged in Debian)
and for the consistency no schema sees: probes reach a declared container
port, Services select the pod, volumeMounts name a volume or claim, the
Secret keys used exist, the ServiceMonitor finds the metrics port, the pod
is locked down. Each rule is also run on a broken copy that it must reject.

usage: k8s_manifests_test.py [--dir deploy/k8s]
"""
import argparse
import copy
import os
import re
import sys
import unittest

import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
K8S_DIR = os.path.join(os.path.dirname(os.path.dirname(HERE)), "deploy", "k8s")

# --- a JSON Schema subset: type, required, properties, items, enum, minimum.
TYPES = {"object": dict, "array": list, "string": str, "integer": int, "boolean": bool}


def validate(doc, schema, path="$"):
    errors = []
    t = schema.get("type")
    if t:
        ok = any(isinstance(doc, TYPES[x]) and not (x == "integer" and isinstance(doc, bool))
                 for x in (t if isinstance(t, list) else [t]))
        if not ok:
            return [f"{path}: expected {t}, got {type(doc).__name__}"]
    if "enum" in schema and doc not in schema["enum"]:
        errors.append(f"{path}: {doc!r} not in {schema['enum']}")
    if "minimum" in schema and isinstance(doc, int) and doc < schema["minimum"]:
        errors.append(f"{path}: {doc} < {schema['minimum']}")
    if isinstance(doc, dict):
        errors += [f"{path}.{k}: required" for k in schema.get("required", []) if k not in doc]
        for k, sub in schema.get("properties", {}).items():
            if k in doc:
                errors += validate(doc[k], sub, f"{path}.{k}")
    if isinstance(doc, list) and "items" in schema:
        for i, item in enumerate(doc):
            errors += validate(item, schema["items"], f"{path}[{i}]")
    return errors


S, I, B = {"type": "string"}, {"type": "integer"}, {"type": "boolean"}
LABELS = {"type": "object"}
META = {"type": "object", "required": ["name"], "properties": {"name": S, "labels": LABELS}}
PORT_NUM = {"type": "integer", "minimum": 1}
PROBE = {"type": "object", "properties": {
    "grpc": {"type": "object", "required": ["port"], "properties": {"port": PORT_NUM, "service": S}},
    "periodSeconds": I, "timeoutSeconds": I, "failureThreshold": I}}
CONTAINER = {"type": "object", "required": ["name", "image"], "properties": {
    "name": S, "image": S,
    "env": {"type": "array", "items": {"type": "object", "required": ["name"],
                                       "properties": {"name": S, "value": S}}},
    "ports": {"type": "array", "items": {"type": "object", "required": ["containerPort"],
                                         "properties": {"name": S, "containerPort": PORT_NUM,
                                                        "protocol": {"enum": ["TCP", "UDP"]}}}},
    "livenessProbe": PROBE, "readinessProbe": PROBE, "startupProbe": PROBE,
    "resources": {"type": "object", "required": ["requests", "limits"]},
    "securityContext": {"type": "object", "properties": {
        "runAsNonRoot": B, "readOnlyRootFilesystem": B, "allowPrivilegeEscalation": B}},
    "volumeMounts": {"type": "array", "items": {"type": "object",
                                                "required": ["name", "mountPath"],
                                                "properties": {"name": S, "mountPath": S}}}}}
SCHEMAS = {
    ("apps/v1", "StatefulSet"): {"type": "object", "required": ["metadata", "spec"], "properties": {
        "metadata": META,
        "spec": {"type": "object", "required": ["serviceName", "selector", "template"],
                 "properties": {
                     "serviceName": S, "replicas": {"type": "integer", "minimum": 0},
                     "selector": {"type": "object", "required": ["matchLabels"]},
                     "template": {"type": "object", "required": ["metadata", "spec"], "properties": {
                         "metadata": {"type": "object", "required": ["labels"]},
                         "spec": {"type": "object", "required": ["containers"], "properties": {
                             "terminationGracePeriodSeconds": I,
                             "containers": {"type": "array", "items": CONTAINER},
                             "volumes": {"type": "array", "items": {
                                 "type": "object", "required": ["name"]}}}}}},
                     "volumeClaimTemplates": {"type": "array", "items": {
                         "type": "object", "required": ["metadata", "spec"],
                         "properties": {"metadata": META, "spec": {
                             "type": "object", "required": ["accessModes", "resources"]}}}}}}}},
    ("v1", "Service"): {"type": "object", "required": ["metadata", "spec"], "properties": {
        "metadata": META,
        "spec": {"type": "object", "required": ["selector", "ports"], "properties": {
            "selector": LABELS, "clusterIP": S,
            "ports": {"type": "array", "items": {"type": "object", "required": ["port"],
                                                 "properties": {"name": S, "port": PORT_NUM,
                                                                "targetPort": {"type": ["string", "integer"]}}}}}}}},
    ("v1", "Secret"): {"type": "object", "required": ["metadata"], "properties": {
        "metadata": META, "type": S, "stringData": {"type": "object"}, "data": {"type": "object"}}},
    ("v1", "Namespace"): {"type": "object", "required": ["metadata"], "properties": {"metadata": META}},
    ("monitoring.coreos.com/v1", "ServiceMonitor"): {"type": "object", "required": ["metadata", "spec"],
        "properties": {"metadata": META, "spec": {"type": "object", "required": ["selector", "endpoints"],
            "properties": {"selector": {"type": "object", "required": ["matchLabels"]},
                           "endpoints": {"type": "array", "items": {"type": "object", "required": ["port"],
                                                                    "properties": {"port": S, "path": S}}}}}}},
    ("kustomize.config.k8s.io/v1beta1", "Kustomization"): {"type": "object", "required": ["resources"],
        "properties": {"resources": {"type": "array", "items": S}, "namespace": S}},
}


def load(directory):
    """{file name: [documents]}"""
    out = {}
    for name in sorted(os.listdir(directory)):
        if name.endswith((".yaml", ".yml")):
            with open(os.path.join(directory, name)) as f:
                out[name] = [d for d in yaml.safe_load_all(f) if d is not None]
    return out


def quantity(q):
    """Kubernetes quantity -> float (bytes or cores)."""
    m = re.fullmatch(r"([0-9.]+)(m|Ki|Mi|Gi|Ti|k|M|G)?", str(q))
    if not m:
        raise ValueError(f"bad quantity {q!r}")
    scale = {None: 1, "m": 1e-3, "k": 1e3, "M": 1e6, "G": 1e9,
             "Ki": 2**10, "Mi": 2**20, "Gi": 2**30, "Ti": 2**40}[m.group(2)]
    return float(m.group(1)) * scale


def selects(selector, labels):
    return bool(selector) and all(labels.get(k) == v for k, v in selector.items())


def check(files):
    """Every problem found in the manifests (empty: fine)."""
    problems = []
    docs = []
    for name, ds in files.items():
        for d in ds:
            key = (d.get("apiVersion"), d.get("kind"))
            if key not in SCHEMAS:
                problems.append(f"{name}: no schema for {key}")
                continue
            problems += [f"{name}: {e}" for e in validate(d, SCHEMAS[key])]
            docs.append((name, d))
    if problems:
        return problems  # the cross-checks below assume the shapes are right
    kinds = lambda k: [d for _, d in docs if d["kind"] == k]
    kust = files.get("kustomization.yaml", [{}])[0]
    listed = set(kust.get("resources", []))
    on_disk = set(files) - {"kustomization.yaml"}
    if listed != on_disk:
        problems.append(f"kustomization resources {sorted(listed)} != files {sorted(on_disk)}")
    secrets = {s["metadata"]["name"]: set(s.get("stringData", {})) | set(s.get("data", {}))
               for s in kinds("Secret")}
    services = kinds("Service")
    sets = kinds("StatefulSet")
    if len(sets) != 1:
        return problems + [f"one StatefulSet expected, found {len(sets)}"]
    sts = sets[0]
    spec, pod = sts["spec"], sts["spec"]["template"]["spec"]
    labels = sts["spec"]["template"]["metadata"]["labels"]
    if not selects(spec["selector"]["matchLabels"], labels):
        problems.append("StatefulSet selector does not match the pod labels")
    headless = [s for s in services if s["metadata"]["name"] == spec["serviceName"]]
    if not headless or headless[0]["spec"].get("clusterIP") != "None":
        problems.append(f"serviceName {spec['serviceName']} is not a headless Service here")
    claims = {c["metadata"]["name"] for c in spec.get("volumeClaimTemplates", [])}
    volumes = {v["name"]: v for v in pod.get("volumes", [])}
    if not claims:
        problems.append("no volumeClaimTemplates: the data dir would not persist")
    for v in volumes.values():
        if "secret" in v:
            sec = v["secret"]
            if sec.get("secretName") not in secrets:
                problems.append(f"volume {v['name']}: Secret {sec.get('secretName')} not defined")
            for item in sec.get("items", []):
                if item["key"] not in secrets.get(sec.get("secretName"), set()):
                    problems.append(f"volume {v['name']}: key {item['key']} not in the Secret")
    pod_sc = pod.get("securityContext", {})
    annotations = sts["spec"]["template"]["metadata"].get("annotations", {})
    all_ports = {}
    for c in pod["containers"]:
        ports = {p["containerPort"]: p for p in c.get("ports", [])}
        names = {p.get("name"): p["containerPort"] for p in c.get("ports", [])}
        all_ports.update(names)
        for probe in ("livenessProbe", "readinessProbe", "startupProbe"):
            pr = c.get(probe)
            if not pr:
                problems.append(f"{c['name']}: {probe} missing")
                continue
            if "grpc" not in pr:
                problems.append(f"{c['name']}: {probe} is not a gRPC health probe")
            elif pr["grpc"]["port"] not in ports:
                problems.append(f"{c['name']}: {probe} port {pr['grpc']['port']} not declared")
        env = {e["name"]: e for e in c.get("env", [])}
        listen = env.get("LUXELD_LISTEN", {}).get("value", "")
        if not listen.endswith(f":{names.get('grpc')}"):
            problems.append(f"LUXELD_LISTEN {listen!r} is not the grpc containerPort")
        metrics = env.get("LUXELD_METRICS_LISTEN", {}).get("value", "")
        if not metrics.endswith(f":{names.get('metrics')}") or \
                annotations.get("prometheus.io/port") != str(names.get("metrics")):
            problems.append("metrics port, LUXELD_METRICS_LISTEN and prometheus.io/port disagree")
        if annotations.get("prometheus.io/scrape") != "true":
            problems.append("prometheus.io/scrape annotation missing")
        mounts = {m["name"]: m for m in c.get("volumeMounts", [])}
        for m in mounts:
            if m not in volumes and m not in claims:
                problems.append(f"{c['name']}: volumeMount {m} names no volume or claim")
        data = env.get("LUXELD_DATA_DIR", {}).get("value")
        if not any(m["mountPath"] == data and m["name"] in claims for m in mounts.values()):
            problems.append(f"LUXELD_DATA_DIR {data} is not a PersistentVolumeClaim mount")
        token = env.get("LUXELD_TOKEN_FILE", {}).get("value", "")
        token_ok = False
        for m in mounts.values():
            v = volumes.get(m["name"], {})
            for item in v.get("secret", {}).get("items", []):
                token_ok |= token == f"{m['mountPath']}/{item['path']}"
        if not token_ok or "LUXELD_TOKEN" in env:
            problems.append("the token is not a file from the Secret volume")
        sc = c.get("securityContext", {})
        if not (sc.get("runAsNonRoot") or pod_sc.get("runAsNonRoot")):
            problems.append(f"{c['name']}: runAsNonRoot not set")
        if sc.get("readOnlyRootFilesystem") is not True:
            problems.append(f"{c['name']}: readOnlyRootFilesystem not set")
        if sc.get("allowPrivilegeEscalation") is not False:
            problems.append(f"{c['name']}: allowPrivilegeEscalation not false")
        if "ALL" not in sc.get("capabilities", {}).get("drop", []) or \
                sc.get("capabilities", {}).get("add"):
            problems.append(f"{c['name']}: capabilities not dropped (ALL)")
        if c["image"].endswith(":latest") or ":" not in c["image"]:
            problems.append(f"{c['name']}: image {c['image']} untagged or latest")
        res = c["resources"]
        for r in ("cpu", "memory"):
            if r not in res["requests"] or r not in res["limits"]:
                problems.append(f"{c['name']}: {r} request/limit missing")
            elif quantity(res["requests"][r]) > quantity(res["limits"][r]):
                problems.append(f"{c['name']}: {r} request above its limit")
    if pod.get("terminationGracePeriodSeconds", 30) < 60:
        problems.append("terminationGracePeriodSeconds leaves no time for a checkpoint")
    for s in services:
        if not selects(s["spec"]["selector"], labels):
            problems.append(f"Service {s['metadata']['name']} does not select the pod")
        for p in s["spec"]["ports"]:
            target = p.get("targetPort", p["port"])
            if target not in all_ports and target not in all_ports.values():
                problems.append(f"Service {s['metadata']['name']}: targetPort {target} not declared")
    for sm in kinds("ServiceMonitor"):
        chosen = [s for s in services
                  if selects(sm["spec"]["selector"]["matchLabels"], s["metadata"].get("labels", {}))]
        if len(chosen) != 1:
            problems.append(f"ServiceMonitor selects {len(chosen)} Services, expected 1")
        for ep in sm["spec"]["endpoints"]:
            if not any(ep["port"] == p.get("name") for s in chosen for p in s["spec"]["ports"]):
                problems.append(f"ServiceMonitor port {ep['port']} is no port of the Service")
    if not kinds("ServiceMonitor"):
        problems.append("no ServiceMonitor")
    return problems


def mutate(files, name, fn):
    broken = copy.deepcopy(files)
    fn(broken[name][0])
    return broken


def container(d):
    return d["spec"]["template"]["spec"]["containers"][0]


class K8sManifests(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.files = load(ARGS.dir)

    def test_manifests_pass(self):
        self.assertEqual(check(self.files), [])

    def test_kinds_present(self):
        kinds = sorted(d["kind"] for ds in self.files.values() for d in ds)
        for k in ("Kustomization", "Secret", "Service", "ServiceMonitor", "StatefulSet"):
            self.assertIn(k, kinds)

    def test_broken_manifests_fail(self):
        def set_(path, value):
            def fn(d):
                *head, last = path
                for k in head:
                    d = d[k]
                d[last] = value
            return fn
        cases = {
            "readiness probe on an undeclared port": ("statefulset.yaml",
                lambda d: container(d)["readinessProbe"]["grpc"].update(port=50052)),
            "probe port as a string (schema)": ("statefulset.yaml",
                lambda d: container(d)["livenessProbe"]["grpc"].update(port="grpc")),
            "Service selector off": ("service.yaml",
                set_(["spec", "selector"], {"app.kubernetes.io/name": "luxel"})),
            "targetPort undeclared": ("service.yaml",
                lambda d: d["spec"]["ports"][0].update(targetPort="http")),
            "mount of an undeclared volume": ("statefulset.yaml",
                lambda d: container(d)["volumeMounts"][0].update(name="state")),
            "Secret key missing": ("secret.example.yaml",
                set_(["stringData"], {"bearer": "x"})),
            "root filesystem writable": ("statefulset.yaml",
                lambda d: container(d)["securityContext"].update(readOnlyRootFilesystem=False)),
            "capabilities kept": ("statefulset.yaml",
                lambda d: container(d)["securityContext"]["capabilities"].update(drop=["NET_RAW"])),
            "no claim for the data dir": ("statefulset.yaml",
                lambda d: d["spec"].pop("volumeClaimTemplates")),
            "ServiceMonitor on an unknown port": ("servicemonitor.yaml",
                lambda d: d["spec"]["endpoints"][0].update(port="prometheus")),
            "missing required field": ("service.yaml", lambda d: d["spec"].pop("ports")),
            "latest image": ("statefulset.yaml",
                lambda d: container(d).update(image="luxeld:latest")),
            "memory request above limit": ("statefulset.yaml",
                lambda d: container(d)["resources"]["requests"].update(memory="64Gi")),
            "token as env var": ("statefulset.yaml",
                lambda d: container(d)["env"].append({"name": "LUXELD_TOKEN", "value": "t"})),
        }
        for what, (name, fn) in cases.items():
            with self.subTest(what):
                self.assertNotEqual(check(mutate(self.files, name, fn)), [], what)

    def test_unknown_file_not_in_kustomization_fails(self):
        broken = dict(self.files, **{"extra.yaml": self.files["namespace.yaml"]})
        self.assertNotEqual(check(broken), [])


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--dir", default=K8S_DIR)
    ARGS, rest = p.parse_known_args()
    unittest.main(argv=[sys.argv[0], "-v", *rest])
