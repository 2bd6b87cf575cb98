"""deploy/k8s/ (one luxeld) and deploy/k8s/farm/ (coordinator and worker
pools): the manifests are checked against minimal JSON schemas of the kinds
used (required fields and types; kubeconform is not packaged in Debian) and
for the consistency no schema sees: probes reach a declared container port,
Services select the pod, volumeMounts name a volume or claim, the Secret keys
used exist, the ServiceMonitor finds the metrics port, the pod is locked
down; for the farm also discovery of both pools, the GPU pool, the
coordinator's --workers-dns, budgets and the autoscaler's metrics. Each rule
is also run on a broken copy that it must reject.

usage: k8s_manifests_test.py [--dir deploy/k8s]
"""
# Over 500 lines: every manifest of deploy/k8s and deploy/k8s/farm is checked against the same parsed objects and schemas.
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
    "name": S, "image": S, "args": {"type": "array", "items": S},
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
                             "nodeSelector": {"type": "object"},
                             "tolerations": {"type": "array", "items": {
                                 "type": "object", "properties": {
                                     "key": S, "operator": {"enum": ["Exists", "Equal"]},
                                     "effect": {"enum": ["NoSchedule", "PreferNoSchedule",
                                                         "NoExecute"]}}}},
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
            "selector": LABELS, "clusterIP": S, "publishNotReadyAddresses": B,
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
    ("v1", "ConfigMap"): {"type": "object", "required": ["metadata"], "properties": {
        "metadata": META, "data": {"type": "object"}}},
    ("policy/v1", "PodDisruptionBudget"): {"type": "object", "required": ["metadata", "spec"],
        "properties": {"metadata": META, "spec": {"type": "object", "required": ["selector"],
            "properties": {"selector": {"type": "object", "required": ["matchLabels"]},
                           "minAvailable": {"type": ["integer", "string"]},
                           "maxUnavailable": {"type": ["integer", "string"]},
                           "unhealthyPodEvictionPolicy": {"enum": ["IfHealthyBudget",
                                                                   "AlwaysAllow"]}}}}},
    ("autoscaling/v2", "HorizontalPodAutoscaler"): {"type": "object", "required": ["metadata", "spec"],
        "properties": {"metadata": META, "spec": {
            "type": "object", "required": ["scaleTargetRef", "maxReplicas"], "properties": {
                "scaleTargetRef": {"type": "object", "required": ["apiVersion", "kind", "name"],
                                   "properties": {"apiVersion": S, "kind": S, "name": S}},
                "minReplicas": {"type": "integer", "minimum": 1},
                "maxReplicas": {"type": "integer", "minimum": 1},
                "metrics": {"type": "array", "items": {
                    "type": "object", "required": ["type"], "properties": {
                        "type": {"enum": ["Pods", "External", "Object", "Resource",
                                          "ContainerResource"]}}}}}}}},
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


def validate_files(files):
    """Schema problems and the (file name, document) pairs that have a schema."""
    problems, docs = [], []
    for name, ds in files.items():
        for d in ds:
            key = (d.get("apiVersion"), d.get("kind"))
            if key not in SCHEMAS:
                problems.append(f"{name}: no schema for {key}")
                continue
            problems += [f"{name}: {e}" for e in validate(d, SCHEMAS[key])]
            docs.append((name, d))
    return problems, docs


def check_kustomization(files):
    kust = files.get("kustomization.yaml", [{}])[0]
    listed = set(kust.get("resources", []))
    on_disk = set(files) - {"kustomization.yaml"}
    if listed != on_disk:
        return [f"kustomization resources {sorted(listed)} != files {sorted(on_disk)}"]
    return []


def pod_labels(sts):
    return sts["spec"]["template"]["metadata"]["labels"]


def check_statefulset(sts, secrets, services, config_maps=None):
    """The pod of one StatefulSet: selector, governing Service, data dir on a
    claim, token file from the Secret, probes, ports, lock-down, resources.
    Returns (problems, {port name: containerPort})."""
    problems = []
    what = sts["metadata"]["name"]
    spec, pod = sts["spec"], sts["spec"]["template"]["spec"]
    labels = pod_labels(sts)
    if not selects(spec["selector"]["matchLabels"], labels):
        problems.append(f"{what}: StatefulSet selector does not match the pod labels")
    headless = [s for s in services if s["metadata"]["name"] == spec["serviceName"]]
    if not headless or headless[0]["spec"].get("clusterIP") != "None":
        problems.append(f"{what}: serviceName {spec['serviceName']} is not a headless Service here")
    claims = {c["metadata"]["name"] for c in spec.get("volumeClaimTemplates", [])}
    volumes = {v["name"]: v for v in pod.get("volumes", [])}
    if not claims:
        problems.append(f"{what}: no volumeClaimTemplates: the data dir would not persist")
    for v in volumes.values():
        if "secret" in v:
            sec = v["secret"]
            if sec.get("secretName") not in secrets:
                problems.append(f"volume {v['name']}: Secret {sec.get('secretName')} not defined")
            for item in sec.get("items", []):
                if item["key"] not in secrets.get(sec.get("secretName"), set()):
                    problems.append(f"volume {v['name']}: key {item['key']} not in the Secret")
        if "configMap" in v and config_maps is not None:
            cm = v["configMap"]
            if cm.get("name") not in config_maps:
                problems.append(f"volume {v['name']}: ConfigMap {cm.get('name')} not defined")
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
            elif config_maps is not None and "configMap" in volumes.get(m, {}):
                key = mounts[m].get("subPath")
                cm = config_maps.get(volumes[m]["configMap"].get("name"), set())
                if key is not None and key not in cm:
                    problems.append(f"{c['name']}: subPath {key} is no key of the ConfigMap")
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
        problems.append(f"{what}: terminationGracePeriodSeconds leaves no time for a checkpoint")
    return problems, all_ports


def check_services(services, sets, all_ports):
    """Every Service selects some pod and targets one of its ports."""
    problems = []
    for s in services:
        chosen = [x for x in sets if selects(s["spec"]["selector"], pod_labels(x))]
        if not chosen:
            problems.append(f"Service {s['metadata']['name']} does not select the pod")
        for p in s["spec"]["ports"]:
            target = p.get("targetPort", p["port"])
            if target not in all_ports and target not in all_ports.values():
                problems.append(f"Service {s['metadata']['name']}: targetPort {target} not declared")
    return problems


def check_monitors(monitors, services, expected):
    problems = []
    for sm in monitors:
        chosen = [s for s in services
                  if selects(sm["spec"]["selector"]["matchLabels"], s["metadata"].get("labels", {}))]
        if len(chosen) != expected:
            problems.append(f"ServiceMonitor selects {len(chosen)} Services, expected {expected}")
        for ep in sm["spec"]["endpoints"]:
            if not any(ep["port"] == p.get("name") for s in chosen for p in s["spec"]["ports"]):
                problems.append(f"ServiceMonitor port {ep['port']} is no port of the Service")
    if not monitors:
        problems.append("no ServiceMonitor")
    return problems


def secrets_of(docs):
    return {s["metadata"]["name"]: set(s.get("stringData", {})) | set(s.get("data", {}))
            for _, s in docs if s["kind"] == "Secret"}


def check(files):
    """Every problem found in the single-daemon manifests (empty: fine)."""
    problems, docs = validate_files(files)
    if problems:
        return problems  # the cross-checks below assume the shapes are right
    kinds = lambda k: [d for _, d in docs if d["kind"] == k]
    problems += check_kustomization(files)
    services = kinds("Service")
    sets = kinds("StatefulSet")
    if len(sets) != 1:
        return problems + [f"one StatefulSet expected, found {len(sets)}"]
    found, ports = check_statefulset(sets[0], secrets_of(docs), services)
    problems += found
    problems += check_services(services, sets, ports)
    problems += check_monitors(kinds("ServiceMonitor"), services, 1)
    return problems


# --- The build farm (deploy/k8s/farm/): coordinator + worker pools.
METRICS_CPP = os.path.join(os.path.dirname(os.path.dirname(HERE)), "server", "service", "metrics.cpp")
GPU = "nvidia.com/gpu"


def exported_metrics(path=METRICS_CPP):
    """Metric names luxeld registers (prometheus-cpp .Name("...") calls)."""
    with open(path) as f:
        return set(re.findall(r'\.Name\("([a-z_:][a-z0-9_:]*)"\)', f.read()))


def adapter_rules(files):
    """{metric name: (kind "Pods" | "External", rule)} from the adapter snippet."""
    out = {}
    for cm in files.get("adapter/prometheus-adapter-rules.yaml", []):
        config = yaml.safe_load(cm["data"]["config.yaml"])
        for key, kind in (("rules", "Pods"), ("externalRules", "External")):
            for rule in config.get(key, []):
                out[rule["name"]["as"]] = (kind, rule)
    return out


def gpu_limit(sts):
    return sum(int(c["resources"]["limits"].get(GPU, 0))
               for c in sts["spec"]["template"]["spec"]["containers"])


def check_farm(files, parent, metrics=None):
    """Every problem found in the farm manifests (empty: fine). `parent` are
    the single-daemon files, whose Namespace and Secret the farm copies."""
    metrics = exported_metrics() if metrics is None else metrics
    top = {k: v for k, v in files.items() if "/" not in k}
    problems, docs = validate_files(files)
    if problems:
        return problems
    problems += check_kustomization(top)
    for shared in ("namespace.yaml", "secret.example.yaml"):
        if files.get(shared) != parent.get(shared):
            problems.append(f"{shared} differs from the single-daemon one")
    kinds = lambda k: [d for n, d in docs if d["kind"] == k and "/" not in n]
    services, sets = kinds("Service"), kinds("StatefulSet")
    config_maps = {c["metadata"]["name"]: set(c.get("data", {})) for c in kinds("ConfigMap")}
    workers = [x for x in sets if pod_labels(x).get("app.kubernetes.io/component") == "worker"]
    coords = [x for x in sets if pod_labels(x).get("app.kubernetes.io/component") == "coordinator"]
    if len(workers) != 2 or len(coords) != 1 or len(sets) != 3:
        return problems + [f"expected 2 worker pools and 1 coordinator, found "
                           f"{len(workers)} + {len(coords)} of {len(sets)} StatefulSets"]
    ports = {}
    for x in sets:
        found, p = check_statefulset(x, secrets_of(docs), services, config_maps)
        problems += found
        ports.update(p)
    problems += check_services(services, sets, ports)
    names = {s["metadata"]["name"]: s for s in services}

    # Discovery: one headless Service, only ready pods, every pool, no coordinator.
    governing = {x["spec"]["serviceName"] for x in workers}
    if len(governing) != 1:
        problems.append(f"worker pools are governed by different Services {sorted(governing)}")
    disc = names.get(sorted(governing)[0]) if governing else None
    if disc is None:
        return problems + ["the workers' Service is missing"]
    if disc["spec"].get("publishNotReadyAddresses") is not False:
        problems.append(f"{disc['metadata']['name']}: publishNotReadyAddresses must be false")
    for x in workers:
        if not selects(disc["spec"]["selector"], pod_labels(x)):
            problems.append(f"{disc['metadata']['name']} does not select pool {x['metadata']['name']}")
    for x in coords:
        if selects(disc["spec"]["selector"], pod_labels(x)):
            problems.append(f"{disc['metadata']['name']} selects the coordinator")

    # Pools: one on GPUs (device, node selection), one without.
    gpu = [x for x in workers if gpu_limit(x) > 0]
    if len(gpu) != 1:
        problems.append(f"{len(gpu)} worker pools request {GPU}, expected 1")
    for x in gpu:
        pod = x["spec"]["template"]["spec"]
        c = pod["containers"][0]
        if c["resources"]["requests"].get(GPU, c["resources"]["limits"][GPU]) != \
                c["resources"]["limits"][GPU]:
            problems.append(f"{x['metadata']['name']}: {GPU} request differs from its limit")
        if not pod.get("nodeSelector") and "nodeAffinity" not in pod.get("affinity", {}):
            problems.append(f"{x['metadata']['name']}: no GPU node selection")
        if not any(t.get("key") == GPU for t in pod.get("tolerations", [])):
            problems.append(f"{x['metadata']['name']}: no toleration for the {GPU} taint")
        env = {e["name"]: e.get("value") for e in c.get("env", [])}
        if env.get("LUXEL_DEVICE") != "gpu":
            problems.append(f"{x['metadata']['name']}: LUXEL_DEVICE is not gpu")

    # Coordinator: one replica, its own claim, --workers-dns at the discovery name.
    for x in coords:
        if x["spec"].get("replicas", 1) != 1:
            problems.append("the coordinator must run exactly 1 replica")
        c = x["spec"]["template"]["spec"]["containers"][0]
        args = c.get("args", [])
        env = {e["name"]: e for e in c.get("env", [])}
        dns = args[args.index("--workers-dns") + 1] if "--workers-dns" in args[:-1] else ""
        m = re.fullmatch(r"([a-z0-9-]+)\.(\$\(POD_NAMESPACE\)|[a-z0-9-]+)\.svc\.cluster\.local:(\d+)",
                         dns)
        grpc_port = {p.get("name"): p["port"] for p in disc["spec"]["ports"]}.get("grpc")
        if not m or m.group(1) != disc["metadata"]["name"] or int(m.group(3)) != grpc_port:
            problems.append(f"--workers-dns {dns!r} is not {disc['metadata']['name']}.<ns>."
                            f"svc.cluster.local:{grpc_port}")
        elif m.group(2) == "$(POD_NAMESPACE)" and \
                env.get("POD_NAMESPACE", {}).get("valueFrom", {}).get("fieldRef", {}) \
                .get("fieldPath") != "metadata.namespace":
            problems.append("POD_NAMESPACE is not the pod's namespace (fieldRef)")

    # Budgets: every StatefulSet's pods under exactly one PDB, each PDB selects some.
    pdbs = kinds("PodDisruptionBudget")
    for b in pdbs:
        sel = b["spec"]["selector"]["matchLabels"]
        if not any(selects(sel, pod_labels(x)) for x in sets):
            problems.append(f"PDB {b['metadata']['name']} selects no pod")
        if "minAvailable" in b["spec"] and "maxUnavailable" in b["spec"]:
            problems.append(f"PDB {b['metadata']['name']}: minAvailable and maxUnavailable")
    for x in sets:
        n = sum(selects(b["spec"]["selector"]["matchLabels"], pod_labels(x)) for b in pdbs)
        if n != 1:
            problems.append(f"{x['metadata']['name']}: under {n} PodDisruptionBudgets, expected 1")

    # Autoscaler: on a worker StatefulSet, on metrics the adapter's rules make
    # from series luxeld exports.
    rules = adapter_rules(files)
    for rule_kind, rule in rules.values():
        series = re.match(r"\s*([a-z_:][a-z0-9_:]*)", rule["seriesQuery"]).group(1)
        used = set(re.findall(r"\b(luxel_[a-z0-9_]+)\s*\{", rule["metricsQuery"])) | {series}
        for name in sorted(used - metrics):
            problems.append(f"adapter rule {rule['name']['as']}: luxeld exports no {name}")
        for svc in re.findall(r'service="([^"]+)"', rule["seriesQuery"] + rule["metricsQuery"]):
            if svc not in names:
                problems.append(f"adapter rule {rule['name']['as']}: no Service {svc}")
    hpas = kinds("HorizontalPodAutoscaler")
    if not hpas:
        problems.append("no HorizontalPodAutoscaler")
    for h in hpas:
        ref = h["spec"]["scaleTargetRef"]
        target = [x for x in workers if ref["kind"] == "StatefulSet"
                  and ref["apiVersion"] == "apps/v1" and x["metadata"]["name"] == ref["name"]]
        if not target:
            problems.append(f"HPA {h['metadata']['name']} targets {ref['kind']} {ref['name']}, "
                            "no worker StatefulSet")
        if h["spec"].get("minReplicas", 1) > h["spec"]["maxReplicas"]:
            problems.append(f"HPA {h['metadata']['name']}: minReplicas above maxReplicas")
        for m in h["spec"].get("metrics", []):
            if m["type"] not in ("Pods", "External"):
                continue
            name = m[m["type"].lower()]["metric"]["name"]
            if rules.get(name, (None,))[0] != m["type"]:
                problems.append(f"HPA metric {name} ({m['type']}) has no adapter rule of that kind")
        if not any(m["type"] in ("Pods", "External") for m in h["spec"].get("metrics", [])):
            problems.append(f"HPA {h['metadata']['name']} scales on no queue metric")

    problems += check_monitors(kinds("ServiceMonitor"), services, 2)
    for sm in kinds("ServiceMonitor"):
        if not selects(sm["spec"]["selector"]["matchLabels"], disc["metadata"].get("labels", {})):
            problems.append("the ServiceMonitor does not scrape the workers")
    return problems


def load_tree(directory):
    """load() plus the YAML files one folder down, keyed 'folder/file'."""
    out = load(directory)
    for sub in sorted(os.listdir(directory)):
        if os.path.isdir(os.path.join(directory, sub)):
            out.update({f"{sub}/{k}": v for k, v in load(os.path.join(directory, sub)).items()})
    return out


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


class K8sFarm(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.parent = load(ARGS.dir)
        cls.files = load_tree(os.path.join(ARGS.dir, "farm"))

    def broken(self, name, fn, index=0):
        files = copy.deepcopy(self.files)
        fn(files[name][index])
        return check_farm(files, self.parent)

    def test_manifests_pass(self):
        self.assertEqual(check_farm(self.files, self.parent), [])

    def test_kinds_present(self):
        kinds = sorted(d["kind"] for ds in self.files.values() for d in ds)
        for k in ("StatefulSet", "Service", "PodDisruptionBudget", "HorizontalPodAutoscaler",
                  "ServiceMonitor", "ConfigMap", "Secret", "Namespace"):
            self.assertIn(k, kinds)

    def test_queue_metric_is_luxelds(self):
        # The adapter rules start from luxeld's own queue gauge.
        self.assertIn("luxel_queue_depth", exported_metrics())
        queries = [r["seriesQuery"] for _, r in adapter_rules(self.files).values()]
        self.assertTrue(queries and all(q.startswith("luxel_queue_depth{") for q in queries))

    def test_broken_farms_fail(self):
        wc, wg = "worker-cpu.yaml", "worker-gpu.yaml"
        cases = {
            "headless Service selects the CPU pool only": ("service-workers.yaml", 0,
                lambda d: d["spec"]["selector"].update({"luxel.dev/pool": "cpu"})),
            "headless Service publishes unready pods": ("service-workers.yaml", 0,
                lambda d: d["spec"].update(publishNotReadyAddresses=True)),
            "headless Service is not headless": ("service-workers.yaml", 0,
                lambda d: d["spec"].pop("clusterIP")),
            "GPU pool under another name label": (wg, 0,
                lambda d: (d["spec"]["selector"]["matchLabels"].update(
                    {"app.kubernetes.io/name": "luxel-gpu"}),
                    pod_labels(d).update({"app.kubernetes.io/name": "luxel-gpu"}))),
            "GPU pool without a GPU": (wg, 0,
                lambda d: container(d)["resources"]["limits"].pop(GPU)),
            "GPU pool without the taint's toleration": (wg, 0,
                lambda d: d["spec"]["template"]["spec"].pop("tolerations")),
            "GPU pool on any node": (wg, 0,
                lambda d: d["spec"]["template"]["spec"].pop("nodeSelector")),
            "GPU pool on the CPU device": (wg, 0,
                lambda d: [e.update(value="cpu") for e in container(d)["env"]
                           if e["name"] == "LUXEL_DEVICE"]),
            "GPU pool's ICD ConfigMap missing": ("nvidia-icd.yaml", 0,
                lambda d: d["metadata"].update(name="other")),
            "pools governed by different Services": (wc, 0,
                lambda d: d["spec"].update(serviceName="luxel-coordinator-headless")),
            "two coordinators": ("coordinator.yaml", 0, lambda d: d["spec"].update(replicas=2)),
            "coordinator without a claim": ("coordinator.yaml", 0,
                lambda d: d["spec"].pop("volumeClaimTemplates")),
            "coordinator resolves another Service": ("coordinator.yaml", 0,
                lambda d: container(d).update(args=["--workers-dns",
                    "luxel-coordinator.$(POD_NAMESPACE).svc.cluster.local:50051"])),
            "coordinator on another port": ("coordinator.yaml", 0,
                lambda d: container(d).update(args=["--workers-dns",
                    "luxel-workers.luxel.svc.cluster.local:9464"])),
            "coordinator without --workers-dns": ("coordinator.yaml", 0,
                lambda d: container(d).pop("args")),
            "POD_NAMESPACE not from the pod": ("coordinator.yaml", 0,
                lambda d: [e.update(valueFrom={"fieldRef": {"fieldPath": "metadata.name"}})
                           for e in container(d)["env"] if e["name"] == "POD_NAMESPACE"]),
            "coordinator token as env var": ("coordinator.yaml", 0,
                lambda d: container(d)["env"].append({"name": "LUXELD_TOKEN", "value": "t"})),
            "worker root filesystem writable": (wc, 0,
                lambda d: container(d)["securityContext"].update(readOnlyRootFilesystem=False)),
            "worker readiness on an undeclared port": (wc, 0,
                lambda d: container(d)["readinessProbe"]["grpc"].update(port=50052)),
            "worker memory request above limit": (wc, 0,
                lambda d: container(d)["resources"]["requests"].update(memory="8Gi")),
            "worker PDB selects nothing": ("pdb.yaml", 0,
                lambda d: d["spec"]["selector"]["matchLabels"].update(
                    {"app.kubernetes.io/name": "luxeld"})),
            "worker PDB covers the CPU pool only": ("pdb.yaml", 0,
                lambda d: d["spec"]["selector"]["matchLabels"].update({"luxel.dev/pool": "cpu"})),
            "coordinator PDB selects the workers": ("pdb.yaml", 1,
                lambda d: d["spec"]["selector"]["matchLabels"].update(
                    {"app.kubernetes.io/name": "luxel-worker"})),
            "PDB with a bad eviction policy (schema)": ("pdb.yaml", 0,
                lambda d: d["spec"].update(unhealthyPodEvictionPolicy="Never")),
            "HPA on the coordinator": ("hpa.yaml", 0,
                lambda d: d["spec"]["scaleTargetRef"].update(name="luxel-coordinator")),
            "HPA on a Deployment": ("hpa.yaml", 0,
                lambda d: d["spec"]["scaleTargetRef"].update(kind="Deployment")),
            "HPA min above max": ("hpa.yaml", 0, lambda d: d["spec"].update(minReplicas=64)),
            "HPA metric without an adapter rule": ("hpa.yaml", 0,
                lambda d: d["spec"]["metrics"][0]["pods"]["metric"].update(name="queue")),
            "HPA metric of the wrong kind": ("hpa.yaml", 0,
                lambda d: d["spec"]["metrics"][1].update(type="Pods",
                                                         pods=d["spec"]["metrics"][1]["external"])),
            "adapter rule on a metric luxeld lacks": ("adapter/prometheus-adapter-rules.yaml", 0,
                lambda d: d["data"].update({"config.yaml": d["data"]["config.yaml"].replace(
                    "luxel_queue_depth{", "luxel_queue_length{")})),
            "adapter rule on a Service not here": ("adapter/prometheus-adapter-rules.yaml", 0,
                lambda d: d["data"].update({"config.yaml": d["data"]["config.yaml"].replace(
                    'service="luxel-workers"', 'service="luxeld-workers"')})),
            "ServiceMonitor misses the workers": ("servicemonitor.yaml", 0,
                lambda d: d["spec"]["selector"]["matchLabels"].update(
                    {"app.kubernetes.io/component": "coordinator"})),
            "namespace copy drifted": ("namespace.yaml", 0,
                lambda d: d["metadata"]["labels"].update(
                    {"pod-security.kubernetes.io/enforce": "baseline"})),
        }
        for what, (name, index, fn) in cases.items():
            with self.subTest(what):
                self.assertNotEqual(self.broken(name, fn, index), [], what)

    def test_unlisted_file_fails(self):
        files = dict(self.files, **{"extra.yaml": self.files["hpa.yaml"]})
        self.assertNotEqual(check_farm(files, self.parent), [])


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--dir", default=K8S_DIR)
    ARGS, rest = p.parse_known_args()
    unittest.main(argv=[sys.argv[0], "-v", *rest])
