#!/usr/bin/env python3
"""The README's Kubernetes block, checked without a cluster (there is none here).

Parses the manifests its `kubectl apply -f` lines name (python3-yaml) and checks the fields the
scale-out depends on: the Deployment's selector matches its pods, the headless Service selects
the same pods on the container's port, readiness and liveness ask grpc.health.v1 about the
server's health-check name on that port, the server closes connections after an age (so clients
re-resolve), and the block's dns:/// target names the Service and its port. Then starts
shadow-server with the Deployment's own arguments (its --listen moved to 127.0.0.1:0) and checks
that it takes them, reports SERVING for that name and answers shadowctl stats.

Usage: kubernetes_manifests_test.py README.md SHADOW_SERVER SHADOWCTL
"""

import pathlib
import re
import shlex
import subprocess
import sys

import grpc
import yaml

readme_path, server_bin, shadowctl_bin = sys.argv[1:4]
readme = pathlib.Path(readme_path)
root = readme.parent
failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        failures.append(what)


def block(marker):
    lines = readme.read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(marker))
    begin = next(i for i in range(start, len(lines)) if lines[i].startswith("```sh")) + 1
    end = next(i for i in range(begin, len(lines)) if lines[i].startswith("```"))
    return "\n".join(lines[begin:end]).replace("\\\n", " ")


def flag(args, name):
    return args[args.index(name) + 1] if name in args else None


text = block("<!-- deploy-kubernetes:")
files = [root / f for f in re.findall(r"-f (\S+)", text)]
check(len(files) == 2 and all(f.is_file() for f in files), f"the block applies {files}")
docs = [d for f in files for d in yaml.safe_load_all(f.read_text()) if d]
by_kind = {d["kind"]: d for d in docs}
deployment, service = by_kind.get("Deployment"), by_kind.get("Service")
check(deployment is not None and service is not None, "a Deployment and a Service")
health_name = re.search(r'kServiceName = "([^"]+)"',
                        (root / "server/service/server.hpp").read_text()).group(1)

spec = deployment["spec"]
labels = spec["template"]["metadata"]["labels"]
check(deployment["apiVersion"] == "apps/v1" and spec["replicas"] >= 2,
      f"apps/v1 Deployment of {spec['replicas']} replicas")
check(spec["selector"]["matchLabels"].items() <= labels.items(),
      f"its selector {spec['selector']['matchLabels']} matches its pods' labels {labels}")
containers = spec["template"]["spec"]["containers"]
check(len(containers) == 1, "one container")
container = containers[0]
args = [str(a) for a in container["args"]]
ports = {p.get("name"): p["containerPort"] for p in container["ports"]}
listen = flag(args, "--listen")
check(listen is not None and ports.get("grpc") == int(listen.rsplit(":", 1)[1]),
      f"--listen {listen} is the container's grpc port {ports.get('grpc')}")
age = flag(args, "--max-connection-age")
check(age is not None and float(age) > 0, f"--max-connection-age {age} s (clients re-resolve)")
for probe in ("readinessProbe", "livenessProbe"):
    g = container.get(probe, {}).get("grpc", {})
    check(g.get("port") == ports.get("grpc") and g.get("service") == health_name,
          f"{probe}: grpc.health.v1 on port {g.get('port')} for '{g.get('service')}'")

check(service["apiVersion"] == "v1" and service["spec"].get("clusterIP") == "None",
      "the Service is headless (clusterIP: None): its DNS name lists every ready pod")
check(service["spec"]["selector"].items() <= labels.items(),
      f"the Service selects the Deployment's pods {service['spec']['selector']}")
service_ports = service["spec"]["ports"]
target = service_ports[0].get("targetPort")
check(len(service_ports) == 1 and (target == "grpc" or target == ports.get("grpc"))
      and service_ports[0]["port"] == ports.get("grpc"),
      f"the Service's port {service_ports[0]['port']} reaches the container's grpc port")
dns = re.search(r"--server dns:///([^.\s]+)\.[^:\s]+:(\d+)", text)
check(dns is not None and dns.group(1) == service["metadata"]["name"]
      and int(dns.group(2)) == service_ports[0]["port"],
      f"the block dials the Service: dns:///{dns.group(1) if dns else '?'}...:"
      f"{dns.group(2) if dns else '?'}")
check(container["image"] in text, "the block's shadowctl pod uses the Deployment's image")

# The Deployment's arguments, as shadow-server takes them (on loopback).
run_args = list(args)
run_args[run_args.index("--listen") + 1] = "127.0.0.1:0"
print("starting shadow-server " + shlex.join(run_args))
server = subprocess.Popen([server_bin, *run_args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True)
try:
    address = None
    for line in server.stdout:
        if line.startswith("listening on "):
            address = line.split()[-1]
            break
    check(address is not None, f"shadow-server took the Deployment's arguments: {address}")
    if address:
        with grpc.insecure_channel(address) as channel:
            # grpc.health.v1.Health/Check, encoded by hand: HealthCheckRequest{service = 1}.
            name = health_name.encode()
            check_call = channel.unary_unary("/grpc.health.v1.Health/Check")
            reply = check_call(b"\x0a" + bytes([len(name)]) + name, timeout=30)
            check(reply == b"\x08\x01", f"health check of '{health_name}': SERVING ({reply!r})")
        stats = subprocess.run([shadowctl_bin, "stats", "--server", address], capture_output=True,
                               text=True, timeout=60)
        workspaces = flag(args, "--max-concurrent")
        check(stats.returncode == 0 and f'"workspaces": {workspaces}' in stats.stdout,
              f"shadowctl stats answers, with the Deployment's --max-concurrent {workspaces} "
              "workspaces")
finally:
    server.terminate()
    server.wait(timeout=60)

if failures:
    raise SystemExit(f"{len(failures)} checks failed")
print("kubernetes manifests: passed")
