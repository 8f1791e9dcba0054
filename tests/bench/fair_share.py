#!/usr/bin/env python3
"""fair_share: a bystander's shadowctl renders beside legal heavy work (issue 51's benchmark).

Each case starts shadow-server with its default flags (plus --server-flags), samples its RSS
every 100 ms, starts the heavy clients, and then runs the bystander: 20 `shadowctl render` calls
one after another (builtin:demo under a spot light, 1024x768, a 1024^2 map, --products
visibility), each timed as a whole process. Cases:

  sequences  two clients each stream a 1000-frame RenderSequence: PCSS 64/64, a 3-degree sun
             moving every frame, 8192^2 map, 1080p, visibility
  csm6       one client, six concurrent CSM requests (M = 8, 8192^2 map, 1280x720), in a loop
  newcomer   CSM M = 16 at 8192^2, visibility and shadowmap_sat (1280x720), in a loop
  uploads    240 UploadScene calls of 16 MiB scenes, 8 at a time (no bystander: peak RSS)
  sigterm    SIGTERM while a request of several seconds renders, and on an idle server: the
             request's outcome, calls sent during the drain, and the time to exit

Prints one JSON line per case; --markdown FILE writes a table. Exits 1 when a goal is missed:
the slowest bystander call over 1 s, peak RSS over half the host's memory, or a drain that
loses its request or takes over 1 s to exit.

  fair_share.py build/server/service/shadow-server [--cases sequences,csm6,...]
      [--shadowctl build/client/shadowctl/shadowctl] [--markdown docs/bench/fair_share.md]
"""

import argparse
import json
import math
import os
import platform
import shlex
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import grpc
import numpy as np

CASES = ["sequences", "csm6", "newcomer", "uploads", "sigterm"]
SERVICE = "/shadow.v1.ShadowService/"


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("server", help="the shadow-server binary")
    p.add_argument("--cases", default=",".join(CASES), help="comma-separated: " + ", ".join(CASES))
    p.add_argument("--shadowctl", help="default: BUILD/client/shadowctl/shadowctl")
    p.add_argument("--client-python", help="default: BUILD/client/python")
    p.add_argument("--server-flags", default="", help="more shadow-server flags for every case")
    p.add_argument("--bystander-calls", type=int, default=20)
    p.add_argument("--warm-up", type=float, default=4.0,
                   help="seconds the heavy clients run before the bystander starts")
    p.add_argument("--markdown", help="write the results as a Markdown table to this file")
    args = p.parse_args()
    args.cases = [c for c in args.cases.split(",") if c]
    for c in args.cases:
        if c not in CASES:
            p.error(f"--cases: unknown case {c!r}")
    return args


ARGS = parse_args()
BUILD = Path(ARGS.server).resolve().parents[2]
SHADOWCTL = ARGS.shadowctl or str(BUILD / "client" / "shadowctl" / "shadowctl")
sys.path.insert(0, ARGS.client_python or str(BUILD / "client" / "python"))
import shadow_client as sc  # noqa: E402

pb = sc.pb
HALF_HOST_MIB = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") / 2 / 2**20


def vec(x, y, z):
    return pb.Vec3(x=x, y=y, z=z)


def ground_and_boxes(cells=64, boxes=24, seed=51):
    """A 40 x 40 ground of cells^2 quads and `boxes` boxes on it: one mesh each."""
    rng = np.random.default_rng(seed)
    xs = np.linspace(-20, 20, cells + 1)
    gx, gz = np.meshgrid(xs, xs)
    positions = np.stack([gx.ravel(), np.zeros(gx.size), gz.ravel()], axis=1)
    quads = np.arange(cells * (cells + 1)).reshape(cells, cells + 1)[:, :cells].ravel()
    tris = np.concatenate([np.stack([quads, quads + cells + 1, quads + 1], 1),
                           np.stack([quads + 1, quads + cells + 1, quads + cells + 2], 1)])
    meshes = [sc.mesh(positions, tris)]
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    for _ in range(boxes):
        size = rng.uniform(0.5, 3.0, 3)
        at = np.array([rng.uniform(-15, 15), 0, rng.uniform(-15, 15)])
        meshes.append(sc.mesh(corners * size + at, faces))
    identity = pb.Mat4(m=[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])
    return pb.Scene(meshes=meshes,
                    instances=[pb.Instance(mesh=i, transform=identity) for i in range(len(meshes))])


def sun(frame=0, size=3.0):
    a = 0.002 * frame  # moves every frame
    return pb.Light(directional=pb.DirectionalLight(direction=vec(-math.cos(a), -2.0,
                                                                  -0.5 - math.sin(a))),
                    size=size)


def heavy(width, height, map_size, filt, products=(pb.PRODUCT_VISIBILITY,)):
    r = pb.RenderRequest(scene=ground_and_boxes(),
                         camera=pb.Camera(eye=vec(0, 14, 24), target=vec(0, 0, 0), width=width,
                                          height=height),
                         shadow_map=pb.ShadowMapSettings(size=map_size), filter=filt,
                         products=list(products))
    r.lights.append(sun())
    return r


def pcss_sequence(frames):
    base = heavy(1920, 1080, 8192, pb.Filter(pcss=pb.PcssSettings(blocker_samples=64,
                                                                   filter_samples=64)))
    return pb.SequenceRequest(base=base, frames=[pb.Frame(lights=[sun(i)]) for i in range(frames)])


def csm(terms, map_size, products=(pb.PRODUCT_VISIBILITY,)):
    return heavy(1280, 720, map_size, pb.Filter(csm=pb.CsmSettings(terms=terms)), products)


class Server:
    """shadow-server on a free loopback port, its RSS sampled every 100 ms."""

    def __init__(self, name, log_dir, flags=()):
        flags = [*flags, *shlex.split(ARGS.server_flags)]
        self.log = Path(log_dir) / f"{name}.log"
        env = dict(os.environ)
        env.setdefault("POCL_CACHE_DIR", str(BUILD / "pocl-cache"))
        with open(self.log, "w") as log:
            self.proc = subprocess.Popen([ARGS.server, "--listen", "127.0.0.1:0", *flags],
                                         stdout=subprocess.PIPE, stderr=log, text=True, env=env)
        self.address = None
        for line in self.proc.stdout:
            if line.startswith("listening on "):
                self.address = line.split()[-1]
                break
        if not self.address:
            raise SystemExit(f"{name}: the server exited before listening:\n" +
                             self.log.read_text()[-2000:])
        threading.Thread(target=self.proc.stdout.read, daemon=True).start()
        self.peak_mib, self.baseline_mib = 0.0, None
        self.done = threading.Event()
        threading.Thread(target=self._sample, daemon=True).start()

    def rss_mib(self):
        try:
            with open(f"/proc/{self.proc.pid}/status") as f:
                for line in f:
                    if line.startswith("VmRSS:"):
                        return int(line.split()[1]) / 1024
        except OSError:
            return None

    def _sample(self):
        while not self.done.wait(0.1):
            mib = self.rss_mib()
            if mib is None:
                return
            if self.baseline_mib is None:
                self.baseline_mib = mib
            self.peak_mib = max(self.peak_mib, mib)

    def stop(self):
        self.done.set()
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


class Caller:
    """One channel; Render and RenderSequence run to their end, replies unparsed."""

    def __init__(self, address):
        self.channel = grpc.insecure_channel(address, options=[
            ("grpc.max_receive_message_length", 64 << 20), ("grpc.max_send_message_length", -1),
            ("grpc.use_local_subchannel_pool", 1)])
        raw = dict(request_serializer=lambda m: m.SerializeToString(), response_deserializer=None)
        self.render = self.channel.unary_stream(SERVICE + "Render", **raw)
        self.sequence = self.channel.unary_stream(SERVICE + "RenderSequence", **raw)
        self.upload = self.channel.stream_unary(SERVICE + "UploadScene",
                                                request_serializer=lambda m: m.SerializeToString(),
                                                response_deserializer=pb.SceneRef.FromString)

    def run(self, method, message, stop=None, timeout=None):
        """(status name, its message, seconds, messages); cancelled once `stop` is set."""
        start = time.monotonic()
        call = method(message, timeout=timeout)
        watcher = None
        if stop is not None:
            watcher = threading.Thread(target=lambda: stop.wait() and call.cancel(), daemon=True)
            watcher.start()
        n = 0
        try:
            for _ in call:
                n += 1
            return "OK", "", time.monotonic() - start, n
        except grpc.RpcError as e:
            return e.code().name, e.details() or "", time.monotonic() - start, n


class Load:
    """`count` threads each calling `work(caller, stop)` until stopped; outcomes counted."""

    def __init__(self, address, count, work, shared_channel=False):
        self.stop = threading.Event()
        self.outcomes = {}
        self.details = {}
        self.lock = threading.Lock()
        shared = Caller(address) if shared_channel else None
        self.threads = [threading.Thread(target=self._loop, args=(shared or Caller(address), work),
                                         daemon=True) for _ in range(count)]
        for t in self.threads:
            t.start()

    def _loop(self, caller, work):
        while not self.stop.is_set():
            code, details, _, _ = work(caller, self.stop)
            with self.lock:
                self.outcomes[code] = self.outcomes.get(code, 0) + 1
                self.details.setdefault(code, details[:200])

    def finish(self):
        self.stop.set()
        for t in self.threads:
            t.join(timeout=120)
        return {"outcomes": self.outcomes,
                "first_refusal": next((d for c, d in self.details.items()
                                       if c not in ("OK", "CANCELLED")), "")}


def bystander(address, out_dir):
    """ARGS.bystander_calls shadowctl renders one after another: each one's seconds."""
    command = [SHADOWCTL, "render", "--server", address, "--scene", "builtin:demo",
               "--light", "spot:6,14,6:-0.4,-0.85,-0.4:60", "--size", "1024x768",
               "--map-size", "1024", "--products", "visibility", "--out", out_dir]
    times, failures = [], []
    for _ in range(ARGS.bystander_calls):
        start = time.monotonic()
        done = subprocess.run(command, capture_output=True, text=True)
        times.append(time.monotonic() - start)
        if done.returncode != 0:
            failures.append(done.stderr.strip()[-300:])
    return {"calls": len(times), "failed": len(failures), "first_failure": failures[:1],
            "min_s": round(min(times), 3), "median_s": round(statistics.median(times), 3),
            "max_s": round(max(times), 3)}


def with_load(name, log_dir, start_load):
    server = Server(name, log_dir)
    load = start_load(server.address)
    time.sleep(ARGS.warm_up)
    with tempfile.TemporaryDirectory() as out:
        waited = bystander(server.address, out)
    result = {"case": name, "bystander": waited, **load.finish(),
              "peak_rss_mib": round(server.peak_mib), "baseline_rss_mib": round(server.baseline_mib or 0)}
    server.stop()
    result["ok"] = (waited["failed"] == 0 and waited["max_s"] <= 1.0 and
                    server.peak_mib <= HALF_HOST_MIB)
    return result


def case_sequences(log_dir):
    message = pcss_sequence(1000)
    return with_load("sequences", log_dir, lambda address: Load(
        address, 2, lambda c, stop: c.run(c.sequence, message, stop)))


def case_csm6(log_dir):
    message = csm(8, 8192)
    return with_load("csm6", log_dir, lambda address: Load(
        address, 6, lambda c, stop: c.run(c.render, message, stop), shared_channel=True))


def case_newcomer(log_dir):
    message = csm(16, 8192, products=(pb.PRODUCT_VISIBILITY, pb.PRODUCT_SHADOW_MAP_SAT))
    return with_load("newcomer", log_dir, lambda address: Load(
        address, 1, lambda c, stop: c.run(c.render, message, stop)))


def case_uploads(log_dir):
    server = Server("uploads", log_dir)
    outcomes, lock = {}, threading.Lock()
    payload = np.random.default_rng(7).standard_normal(16 << 18).astype("<f4").tobytes()

    def uploader(i):
        caller = Caller(server.address)
        for k in range(30):  # 8 x 30 = 240
            # A distinct 16 MiB scene each: a mesh whose positions are the payload, shifted.
            scene = pb.Scene(meshes=[pb.Mesh(positions=payload[: (len(payload) // 12) * 12 - 12] +
                                             np.float32([i, k, 0]).tobytes(),
                                             indices=np.arange(3, dtype="<u4").tobytes())],
                             instances=[pb.Instance(mesh=0)])
            data = scene.SerializeToString()
            chunks = [pb.SceneUpload(data=data[at:at + (2 << 20)])
                      for at in range(0, len(data), 2 << 20)]
            chunks[0].total_bytes = len(data)
            try:
                caller.upload(iter(chunks), timeout=300)
                code = "OK"
            except grpc.RpcError as e:
                code = e.code().name
            with lock:
                outcomes[code] = outcomes.get(code, 0) + 1

    threads = [threading.Thread(target=uploader, args=(i,)) for i in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    result = {"case": "uploads", "outcomes": outcomes, "peak_rss_mib": round(server.peak_mib),
              "baseline_rss_mib": round(server.baseline_mib or 0)}
    server.stop()
    result["ok"] = server.peak_mib <= HALF_HOST_MIB
    return result


def case_sigterm(log_dir):
    result = {"case": "sigterm"}
    # An idle server.
    server = Server("sigterm-idle", log_dir)
    sent = time.monotonic()
    server.proc.send_signal(signal.SIGTERM)
    server.proc.wait(timeout=60)
    result["idle_exit_s"] = round(time.monotonic() - sent, 3)
    server.done.set()
    # A request of several seconds, SIGTERM a second into it; a call sent during the drain.
    server = Server("sigterm-busy", log_dir)
    caller = Caller(server.address)
    outcome = {}
    worker = threading.Thread(target=lambda: outcome.update(
        zip(("code", "details", "seconds", "messages"),
            caller.run(caller.render, csm(16, 4096), timeout=120))))
    worker.start()
    time.sleep(1.0)
    server.proc.send_signal(signal.SIGTERM)
    time.sleep(0.3)
    late = Caller(server.address).run(Caller(server.address).render, csm(4, 256), timeout=10)
    worker.join()
    finished = time.monotonic()
    server.proc.wait(timeout=60)
    server.done.set()
    result.update(request=outcome["code"], request_s=round(outcome["seconds"], 2),
                  exit_after_request_s=round(time.monotonic() - finished, 3),
                  call_during_drain=late[0])
    result["ok"] = (result["idle_exit_s"] <= 1.0 and outcome["code"] == "OK" and
                    result["exit_after_request_s"] <= 1.0 and late[0] == "UNAVAILABLE")
    return result


def markdown(results):
    rows = ["| case | bystander min / median / max (s) | heavy clients' outcomes | peak RSS "
            "(MiB, baseline) | goal met |", "| --- | --- | --- | --- | --- |"]
    for r in results:
        if r["case"] == "sigterm":
            rows.append(f"| sigterm | | idle server exits in {r['idle_exit_s']} s; the "
                        f"{r['request_s']} s request {r['request']}, exit {r['exit_after_request_s']}"
                        f" s after it; a call during the drain {r['call_during_drain']} | | "
                        f"{'yes' if r['ok'] else 'NO'} |")
            continue
        b = r.get("bystander")
        waited = f"{b['min_s']} / {b['median_s']} / {b['max_s']}" if b else ""
        outcomes = ", ".join(f"{k} {v}" for k, v in sorted(r["outcomes"].items()))
        if r.get("first_refusal"):
            outcomes += f" ({r['first_refusal'][:120]})"
        rows.append(f"| {r['case']} | {waited} | {outcomes} | {r['peak_rss_mib']} "
                    f"({r['baseline_rss_mib']}) | {'yes' if r['ok'] else 'NO'} |")
    return "\n".join(rows) + "\n"


def main():
    print(f"fair_share: {platform.node()}, {os.cpu_count()} cores, half the host "
          f"{HALF_HOST_MIB:.0f} MiB", file=sys.stderr)
    results = []
    with tempfile.TemporaryDirectory() as log_dir:
        for case in ARGS.cases:
            print(f"fair_share: {case}...", file=sys.stderr, flush=True)
            r = globals()["case_" + case](log_dir)
            print(json.dumps(r), flush=True)
            results.append(r)
    if ARGS.markdown:
        Path(ARGS.markdown).write_text(markdown(results))
    return 0 if all(r["ok"] for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
