#!/usr/bin/env python3
"""docs/usage.md's Kubernetes block, checked without a cluster (there is none here).

Parses the manifests its `kubectl apply -f` lines name (python3-yaml) and checks the fields the
scale-out depends on: the Deployment's selector matches its pods, the headless Service selects
the same pods on the container's port, readiness and liveness ask grpc.health.v1 about the
server's health-check name on that port, the server closes connections after an age (so clients
re-resolve), and the block's dns:/// target names the Service and its port. Then starts
shadow-server with the Deployment's own arguments (its --listen moved to 127.0.0.1:0) and checks
that it takes them, reports SERVING for that name and answers shadowctl stats.

deployment-tls.yaml, the variant with TLS and tokens, gets the same checks, its probes on its
plaintext --health-listen port and its files from Secrets; its server (certificates from
make_certs.sh) must report SERVING there and, without a token, over TLS, while other calls
without a token are UNAUTHENTICATED.

deployment-gpu.yaml, the variant for GPU nodes, gets the same checks, and asks for one
nvidia.com/gpu with the NVIDIA container toolkit's compute capability and --device nvidia. Its
server serves with those arguments where this machine has an NVIDIA device; elsewhere it must
refuse to start (exit 2, naming --device), and serve with --device 0:0 instead.

Usage: kubernetes_manifests_test.py docs/usage.md SHADOW_SERVER SHADOWCTL
"""

import pathlib
import re
import shlex
import subprocess
import sys
import tempfile

import grpc
import yaml

readme_path, server_bin, shadowctl_bin = sys.argv[1:4]
readme = pathlib.Path(readme_path)
root = next(p for p in readme.resolve().parents if (p / "deploy").is_dir())  # the repository
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


def port_of(address):
    return int(address.rsplit(":", 1)[1]) if address else None


text = block("<!-- deploy-kubernetes:")
files = [root / f for f in re.findall(r"-f (\S+)", text)]
check(len(files) == 2 and all(f.is_file() for f in files), f"the block applies {files}")
docs = [d for f in files for d in yaml.safe_load_all(f.read_text()) if d]
by_kind = {d["kind"]: d for d in docs}
deployment, service = by_kind.get("Deployment"), by_kind.get("Service")
check(deployment is not None and service is not None, "a Deployment and a Service")
health_name = re.search(r'kServiceName = "([^"]+)"',
                        (root / "server/service/server.hpp").read_text()).group(1)
check(service["apiVersion"] == "v1" and service["spec"].get("clusterIP") == "None",
      "the Service is headless (clusterIP: None): its DNS name lists every ready pod")
service_ports = service["spec"]["ports"]
dns = re.search(r"--server dns:///([^.\s]+)\.[^:\s]+:(\d+)", text)
check(dns is not None and dns.group(1) == service["metadata"]["name"]
      and int(dns.group(2)) == service_ports[0]["port"],
      f"the block dials the Service: dns:///{dns.group(1) if dns else '?'}...:"
      f"{dns.group(2) if dns else '?'}")


def check_deployment(deployment, name):
    """The fields the scale-out and the probes depend on; returns the container's args."""
    spec = deployment["spec"]
    labels = spec["template"]["metadata"]["labels"]
    check(deployment["apiVersion"] == "apps/v1" and spec["replicas"] >= 2,
          f"{name}: apps/v1 Deployment of {spec['replicas']} replicas")
    check(spec["selector"]["matchLabels"].items() <= labels.items(),
          f"{name}: its selector {spec['selector']['matchLabels']} matches its pods' labels "
          f"{labels}")
    check(service["spec"]["selector"].items() <= labels.items(),
          f"{name}: the Service selects its pods {service['spec']['selector']}")
    containers = spec["template"]["spec"]["containers"]
    check(len(containers) == 1, f"{name}: one container")
    container = containers[0]
    args = [str(a) for a in container["args"]]
    ports = {p.get("name"): p["containerPort"] for p in container["ports"]}
    listen = flag(args, "--listen")
    check(listen is not None and ports.get("grpc") == port_of(listen),
          f"{name}: --listen {listen} is the container's grpc port {ports.get('grpc')}")
    target = service_ports[0].get("targetPort")
    check(len(service_ports) == 1 and (target == "grpc" or target == ports.get("grpc"))
          and service_ports[0]["port"] == ports.get("grpc"),
          f"{name}: the Service's port {service_ports[0]['port']} reaches the container's grpc "
          "port")
    check(container["image"] in text, f"{name}: the block's shadowctl pod uses its image")
    age = flag(args, "--max-connection-age")
    check(age is not None and float(age) > 0,
          f"{name}: --max-connection-age {age} s (clients re-resolve)")
    # With TLS the probes need the plaintext health port: Kubernetes' gRPC probe cannot do TLS.
    health_listen = flag(args, "--health-listen")
    probe_port = ports.get("grpc")
    if "--tls-cert" in args:
        check(health_listen is not None and ports.get("health") == port_of(health_listen),
              f"{name}: with TLS, --health-listen {health_listen} is the container's health port "
              f"{ports.get('health')}")
        probe_port = ports.get("health")
    for probe in ("readinessProbe", "livenessProbe"):
        g = container.get(probe, {}).get("grpc", {})
        check(g.get("port") == probe_port and g.get("service") == health_name,
              f"{name}: {probe}: grpc.health.v1 on port {g.get('port')} for '{g.get('service')}'")
    # Every file the server reads lies in a Secret's mount.
    secrets = {v["name"] for v in spec["template"]["spec"].get("volumes", []) if "secret" in v}
    mounts = [m["mountPath"] for m in container.get("volumeMounts", []) if m["name"] in secrets]
    for file_flag in ("--tls-cert", "--tls-key", "--tls-client-ca", "--auth-tokens"):
        path = flag(args, file_flag)
        if path is not None:
            check(any(path.startswith(m.rstrip("/") + "/") for m in mounts),
                  f"{name}: {file_flag} {path} is in a Secret's mount {mounts}")
    return args


def start_server(args):
    """shadow-server with these arguments; returns it and the addresses it printed."""
    print("starting shadow-server " + shlex.join(args))
    server = subprocess.Popen([server_bin, *args], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True)
    addresses = {}
    for line in server.stdout:
        for prefix in ("listening on ", "health checks on "):
            if line.startswith(prefix):
                addresses[prefix.split()[0]] = line.split()[-1]
        if "listening" in addresses and ("health" in addresses or "--health-listen" not in args):
            break
    return server, addresses


def health_status(channel):
    """grpc.health.v1.Health/Check, encoded by hand: HealthCheckRequest{service = 1}."""
    name = health_name.encode()
    check_call = channel.unary_unary("/grpc.health.v1.Health/Check")
    return check_call(b"\x0a" + bytes([len(name)]) + name, timeout=30)


def status_code(call):
    try:
        call()
        return grpc.StatusCode.OK
    except grpc.RpcError as e:
        return e.code()


args = check_deployment(deployment, "deployment.yaml")
tls_deployment = yaml.safe_load((root / "deploy/kubernetes/deployment-tls.yaml").read_text())
check(tls_deployment["metadata"] == deployment["metadata"]
      and tls_deployment["spec"]["selector"] == deployment["spec"]["selector"],
      "deployment-tls.yaml replaces deployment.yaml: the same name, labels and selector")
tls_args = check_deployment(tls_deployment, "deployment-tls.yaml")
gpu_deployment = yaml.safe_load((root / "deploy/kubernetes/deployment-gpu.yaml").read_text())
check(gpu_deployment["metadata"] == deployment["metadata"]
      and gpu_deployment["spec"]["selector"] == deployment["spec"]["selector"],
      "deployment-gpu.yaml replaces deployment.yaml: the same name, labels and selector")
gpu_args = check_deployment(gpu_deployment, "deployment-gpu.yaml")
gpu_container = gpu_deployment["spec"]["template"]["spec"]["containers"][0]
gpu_limits = gpu_container.get("resources", {}).get("limits", {})
check(gpu_limits.get("nvidia.com/gpu") == 1,
      f"deployment-gpu.yaml: limits nvidia.com/gpu: {gpu_limits.get('nvidia.com/gpu')}")
gpu_env = {e["name"]: e.get("value") for e in gpu_container.get("env", [])}
check(gpu_env.get("NVIDIA_DRIVER_CAPABILITIES") == "compute,utility"
      and gpu_env.get("NVIDIA_VISIBLE_DEVICES") == "all",
      f"deployment-gpu.yaml: NVIDIA_DRIVER_CAPABILITIES={gpu_env.get('NVIDIA_DRIVER_CAPABILITIES')}"
      f" (compute: the toolkit mounts libnvidia-opencl.so.1), NVIDIA_VISIBLE_DEVICES="
      f"{gpu_env.get('NVIDIA_VISIBLE_DEVICES')}")
check(flag(gpu_args, "--device") == "nvidia",
      f"deployment-gpu.yaml: --device {flag(gpu_args, '--device')}")

# The Deployment's arguments, as shadow-server takes them (on loopback).
run_args = list(args)
run_args[run_args.index("--listen") + 1] = "127.0.0.1:0"
server, addresses = start_server(run_args)
try:
    address = addresses.get("listening")
    check(address is not None, f"shadow-server took the Deployment's arguments: {address}")
    if address:
        with grpc.insecure_channel(address) as channel:
            reply = health_status(channel)
            check(reply == b"\x08\x01", f"health check of '{health_name}': SERVING ({reply!r})")
        stats = subprocess.run([shadowctl_bin, "stats", "--server", address], capture_output=True,
                               text=True, timeout=60)
        workspaces = flag(args, "--max-concurrent")
        check(stats.returncode == 0 and f" of {workspaces} workspaces busy" in stats.stdout,
              f"shadowctl stats answers, with the Deployment's --max-concurrent {workspaces} "
              "workspaces")
finally:
    server.terminate()
    server.wait(timeout=60)

# The TLS variant's, with throw-away certificates and a token file in place of its Secrets'.
with tempfile.TemporaryDirectory() as certs:
    subprocess.run(["bash", str(pathlib.Path(__file__).parent / "make_certs.sh"), certs],
                   check=True)
    pathlib.Path(certs, "tokens").write_text("probe-test-secret ci\n")
    files = {"--tls-cert": "server.pem", "--tls-key": "server.key", "--auth-tokens": "tokens"}
    run_args = list(tls_args)
    for name, value in [*files.items(), ("--listen", None), ("--health-listen", None)]:
        run_args[run_args.index(name) + 1] = (str(pathlib.Path(certs, value)) if value
                                              else "127.0.0.1:0")
    server, addresses = start_server(run_args)
    try:
        address, health_address = addresses.get("listening"), addresses.get("health")
        check(address is not None and health_address is not None,
              f"shadow-server took deployment-tls.yaml's arguments: {address}, health checks on "
              f"{health_address}")
        if address and health_address:
            with grpc.insecure_channel(health_address) as channel:
                reply = health_status(channel)
                check(reply == b"\x08\x01",
                      f"the probes' plaintext port: '{health_name}' SERVING ({reply!r})")
                stats = channel.unary_unary("/shadow.v1.ShadowService/GetStatistics")
                code = status_code(lambda: stats(b"", timeout=30))
                check(code == grpc.StatusCode.UNIMPLEMENTED,
                      f"the probes' port answers health checks only: GetStatistics {code}")
            ca = pathlib.Path(certs, "ca.pem").read_bytes()
            with grpc.secure_channel(address, grpc.ssl_channel_credentials(ca)) as channel:
                code = status_code(lambda: health_status(channel))
                check(code == grpc.StatusCode.OK, f"health check over TLS without a token: {code}")
                stats = channel.unary_unary("/shadow.v1.ShadowService/GetStatistics")
                code = status_code(lambda: stats(b"", timeout=30))
                check(code == grpc.StatusCode.UNAUTHENTICATED,
                      f"GetStatistics over TLS without a token: {code}")
            stats = subprocess.run([shadowctl_bin, "stats", "--server", address, "--tls-ca",
                                    str(pathlib.Path(certs, "ca.pem")), "--token",
                                    "probe-test-secret"], capture_output=True, text=True,
                                   timeout=60)
            check(stats.returncode == 0 and re.search(r"^  ci +\d+ requests", stats.stdout, re.M),
                  "shadowctl stats answers with the token, as its tenant")
    finally:
        server.terminate()
        server.wait(timeout=60)

# The GPU variant's arguments: as they are where there is an NVIDIA device, else refused by name;
# and with the first device here, to show every other argument is taken.
run_args = list(gpu_args)
run_args[run_args.index("--listen") + 1] = "127.0.0.1:0"
has_nvidia = subprocess.run([server_bin, "--list-devices", "--device", "nvidia"],
                            capture_output=True, timeout=120).returncode == 0
variants = [run_args]
if not has_nvidia:
    refused = subprocess.run([server_bin, *run_args], capture_output=True, text=True, timeout=120)
    check(refused.returncode == 2 and "--device" in refused.stderr,
          f"no NVIDIA device here: deployment-gpu.yaml's server exits {refused.returncode} "
          f"naming --device ({refused.stderr.strip().splitlines()[:1]})")
    variants = [list(run_args)]
    variants[0][variants[0].index("--device") + 1] = "0:0"
for gpu_run_args in variants:
    server, addresses = start_server(gpu_run_args)
    try:
        address = addresses.get("listening")
        check(address is not None, f"shadow-server took deployment-gpu.yaml's arguments: {address}")
        if address:
            with grpc.insecure_channel(address) as channel:
                reply = health_status(channel)
                check(reply == b"\x08\x01",
                      f"deployment-gpu.yaml's server: '{health_name}' SERVING ({reply!r})")
    finally:
        server.terminate()
        server.wait(timeout=60)

if failures:
    raise SystemExit(f"{len(failures)} checks failed")
print("kubernetes manifests: passed")
