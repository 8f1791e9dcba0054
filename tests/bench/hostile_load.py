#!/usr/bin/env python3
"""hostile_load: shadow-server under hostile-but-fair clients (issue 40's benchmark).

Starts shadow-server itself, one server per phase with the flags that phase needs, samples its
RSS (VmRSS from /proc/PID/status) every 100 ms, and runs the selected phases. Beside every
attack a bystander renders a small request (tiny scene, 320x240, 512^2 map) every 0.5 s and its
wait is reported. Each phase prints one JSON line; --markdown FILE writes the results as a table.

  a deadlines       3 clients render a ~5.5 MiB inline height field with random 2-120 ms
                    deadlines, a quarter of the calls cancelled by the client instead
  b slow-sequences  4 RenderSequence calls of 400 frames read one message every 4 s
  c idle-uploads    a render, then 2 UploadScene streams that declare all but 8 bytes of
                    --memory-budget between them and send nothing (--stall-timeout short);
                    1280x720 renders beside them
  d heavy           2 and 4 concurrent heavy legal requests (point-light cubes) under a
                    --memory-budget that fits one at a time
  e large-inline    one, then 10 and 16 concurrent ~200 MiB inline requests under
                    --memory-budget 2e9
  f soak            mixed load: renders with and without deadlines, cancels, uploads then
                    renders by scene id, short sequences, malformed requests

Exits 1 when the server died (or could not render afterwards) in any phase.

Usage (scripts/bench-hostile runs it with the defaults; Debian's python3, with python3-grpcio):
  hostile_load.py build/server/service/shadow-server [--phases a,b,...] [--soak-seconds 600]
      [--markdown docs/bench/hostile.md] [--client-python build/client/python]
"""

import argparse
import collections
import json
import math
import os
import platform
import random
import shlex
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import grpc
import numpy as np

PHASES = {"a": "deadlines", "b": "slow-sequences", "c": "idle-uploads", "d": "heavy",
          "e": "large-inline", "f": "soak"}
SERVICE = "/shadow.v1.ShadowService/"
UPLOAD_CHUNK_BYTES = 2 << 20  # the proto allows at most 4 MiB a chunk


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("server", help="the shadow-server binary")
    p.add_argument("--phases", default="a,b,c,d,e,f",
                   help="letters or names, comma-separated (default all): " +
                   ", ".join(f"{k} {v}" for k, v in PHASES.items()))
    p.add_argument("--client-python", help="folder holding the shadow_client package "
                   "(default: BUILD/client/python, BUILD three levels above the server)")
    p.add_argument("--markdown", help="write the results as a Markdown table to this file")
    p.add_argument("--server-flags", default="",
                   help="more shadow-server flags for every phase, e.g. '--overtake-max-cost 0'")
    p.add_argument("--seed", type=int, default=40)
    p.add_argument("--bystander-interval", type=float, default=0.5, help="seconds")
    p.add_argument("--attack-seconds", type=float, default=120, help="phase a's length")
    p.add_argument("--sequence-seconds", type=float, default=30, help="phase b's length")
    p.add_argument("--sequence-read-interval", type=float, default=4,
                   help="phase b: seconds between two messages an attacker reads")
    p.add_argument("--upload-budget", type=int, default=2_000_000_000,
                   help="phase c: --memory-budget, bytes")
    p.add_argument("--upload-stall-timeout", type=float, default=5,
                   help="phase c: --stall-timeout, seconds")
    p.add_argument("--heavy-lights", type=int, default=16, help="phase d: point lights")
    p.add_argument("--heavy-map-size", type=int, default=2048, help="phase d: cube face edge")
    p.add_argument("--heavy-clients", default="2,4", help="phase d: concurrent requests per run")
    p.add_argument("--heavy-budget", type=int,
                   help="phase d: --memory-budget (default: 1.5x the device memory one heavy "
                   "request alone peaks at, measured first)")
    p.add_argument("--large-clients", default="1,10,16",
                   help="phase e: concurrent requests per run (1: the request alone)")
    p.add_argument("--large-mib", type=float, default=200, help="phase e: request size, MiB")
    p.add_argument("--large-budget", type=int, default=2_000_000_000,
                   help="phase e: --memory-budget, bytes")
    p.add_argument("--soak-seconds", type=float, default=600, help="phase f's length")
    args = p.parse_args()
    names = []
    for item in args.phases.split(","):
        item = item.strip()
        name = PHASES.get(item, item)
        if name not in PHASES.values():
            p.error(f"--phases: unknown phase {item!r}")
        names.append(name)
    args.phases = names
    args.heavy_clients = [int(n) for n in args.heavy_clients.split(",")]
    args.large_clients = [int(n) for n in args.large_clients.split(",")]
    return args


ARGS = parse_args()
BUILD_DIR = Path(ARGS.server).resolve().parents[2]
sys.path.insert(0, ARGS.client_python or str(BUILD_DIR / "client" / "python"))
import shadow_client as sc  # noqa: E402

pb = sc.pb


# Statistics ------------------------------------------------------------------------------------

def percentile(values, p):
    """Nearest rank; None without values."""
    if not values:
        return None
    ordered = sorted(values)
    return ordered[max(0, math.ceil(p / 100 * len(ordered)) - 1)]


def ms(seconds):
    return None if seconds is None else round(seconds * 1000, 1)


def counts(outcomes):
    """{code: n} of a list of codes, most frequent first."""
    return dict(collections.Counter(outcomes).most_common())


def spell_counts(by_code):
    return ", ".join(f"{code} {n}" for code, n in by_code.items()) or "none"


# Scenes and requests ---------------------------------------------------------------------------

def vec(x, y, z):
    return pb.Vec3(x=x, y=y, z=z)


def transform(scale=1.0, tx=0.0, ty=0.0, tz=0.0):
    """Column-major Mat4 of a uniform scale then a translation."""
    return pb.Mat4(m=[scale, 0, 0, 0, 0, scale, 0, 0, 0, 0, scale, 0, tx, ty, tz, 1])


def height_field(n, extent=40.0, amplitude=3.0):
    """An n x n grid of vertices over [-extent/2, extent/2]^2 with rolling hills: 12 n^2 bytes of
    positions and 24 (n-1)^2 of indices, counter-clockwise seen from above."""
    axis = np.linspace(-extent / 2, extent / 2, n, dtype=np.float32)
    x, z = np.meshgrid(axis, axis, indexing="ij")
    y = amplitude * np.sin(x * 0.4) * np.cos(z * 0.3) + 0.5 * amplitude * np.sin(x * z * 0.02)
    positions = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n - 1, dtype=np.uint32), np.arange(n - 1, dtype=np.uint32),
                       indexing="ij")
    v00 = (i * n + j).ravel()
    v01, v10, v11 = v00 + 1, v00 + n, v00 + n + 1
    indices = np.concatenate([np.stack([v00, v01, v10], 1), np.stack([v10, v01, v11], 1)])
    return sc.mesh(positions, indices)


def height_field_for(mib):
    """The height field whose mesh bytes come closest to `mib` MiB (36 bytes a vertex)."""
    return height_field(max(2, round(math.sqrt(mib * (1 << 20) / 36))))


def tiny_scene(offset=0.0):
    """A ground quad and two floating quads: 3 instances of one 2-triangle mesh."""
    quad = height_field(2, extent=1.0, amplitude=0.0)
    return pb.Scene(meshes=[quad], instances=[
        pb.Instance(mesh=0, transform=transform(30.0)),
        pb.Instance(mesh=0, transform=transform(4.0, -3.0 + offset, 3.0, 0.0)),
        pb.Instance(mesh=0, transform=transform(2.0, 4.0, 1.5, 2.0 + offset))])


def sun(angle=0.0):
    return pb.Light(directional=pb.DirectionalLight(
        direction=vec(-math.cos(angle), -2.0, -0.5 - math.sin(angle))))


def request(scene=None, scene_id=None, width=320, height=240, map_size=512, lights=None):
    r = pb.RenderRequest(
        camera=pb.Camera(eye=vec(0, 18, 26), target=vec(0, 0, 0), width=width, height=height),
        shadow_map=pb.ShadowMapSettings(size=map_size),
        products=[pb.PRODUCT_VISIBILITY])
    r.lights.extend(lights or [sun()])
    if scene_id is not None:
        r.scene_id = scene_id
    else:
        r.scene.CopyFrom(scene)
    return r


def small_request():
    return request(tiny_scene())


def heavy_request(lights, map_size):
    """Point lights above a 200^2 height field, each a cube map of map_size^2 faces, seen at
    1280x720: the cost grows with lights x faces x map_size^2."""
    ring = [pb.Light(point=pb.PointLight(position=vec(14 * math.cos(a), 8.0, 14 * math.sin(a))))
            for a in np.linspace(0, 2 * math.pi, lights, endpoint=False)]
    return request(pb.Scene(meshes=[height_field(200)], instances=[pb.Instance(mesh=0)]),
                   width=1280, height=720, map_size=map_size, lights=ring)


def malformed_requests():
    """(name, method, request) that the server must refuse with INVALID_ARGUMENT."""
    bad = []

    def render(name, edit):
        r = small_request()
        edit(r)
        bad.append((name, "Render", r))

    render("camera.width 0", lambda r: setattr(r.camera, "width", 0))
    render("zero light direction",
           lambda r: r.lights[0].directional.direction.CopyFrom(vec(0, 0, 0)))
    render("shadow_map.size 100", lambda r: setattr(r.shadow_map, "size", 100))
    render("index past the vertices",
           lambda r: setattr(r.scene.meshes[0], "indices",
                             np.array([0, 1, 99], dtype="<u4").tobytes()))
    render("positions of 13 bytes", lambda r: setattr(r.scene.meshes[0], "positions", b"\0" * 13))
    render("Mat4 of 15 values", lambda r: r.scene.instances[0].transform.m.pop())
    render("instance of mesh 7", lambda r: setattr(r.scene.instances[1], "mesh", 7))
    render("fov 180", lambda r: setattr(r.camera, "fov_deg", 180.0))
    render("no product", lambda r: r.ClearField("products"))
    bad.append(("sequence of no frame", "RenderSequence", pb.SequenceRequest(base=small_request())))
    bad.append(("upload of bytes that are no Scene", "UploadScene",
                [pb.SceneUpload(total_bytes=4, data=b"\xff\xff\xff\xff")]))
    bad.append(("upload without total_bytes", "UploadScene", [pb.SceneUpload(data=b"\x0a\x00")]))
    return bad


# The server ------------------------------------------------------------------------------------

class RssSampler(threading.Thread):
    """VmRSS of a process every 100 ms, in MiB, while it lives."""

    def __init__(self, pid):
        super().__init__(daemon=True)
        self.path = f"/proc/{pid}/status"
        self.samples = []  # (monotonic seconds, MiB)
        self.stopped = threading.Event()
        self.start()

    def run(self):
        while not self.stopped.is_set():
            try:
                with open(self.path) as f:
                    for line in f:
                        if line.startswith("VmRSS:"):
                            self.samples.append((time.monotonic(), int(line.split()[1]) / 1024))
                            break
            except OSError:
                return  # the process is gone
            self.stopped.wait(0.1)

    def since(self, start):
        values = [mib for t, mib in self.samples if t >= start]
        return (min(values), max(values)) if values else (None, None)


class Server:
    """shadow-server on a free loopback port, its stderr in a log file."""

    def __init__(self, flags, name, log_dir):
        self.flags = flags
        self.log_path = Path(log_dir) / f"{name}.log"
        env = dict(os.environ)
        env.setdefault("POCL_CACHE_DIR", str(BUILD_DIR / "pocl-cache"))
        with open(self.log_path, "w") as log:
            self.proc = subprocess.Popen([ARGS.server, "--listen", "127.0.0.1:0", *flags],
                                         stdout=subprocess.PIPE, stderr=log, text=True, env=env)
        self.address = None
        for line in self.proc.stdout:  # ends when the server exits
            if line.startswith("listening on "):
                self.address = line.split()[-1]
                break
        if self.address is None:
            raise SystemExit(f"shadow-server {' '.join(flags)} exited before listening:\n" +
                             self.log_path.read_text()[-2000:])
        # Keep reading stdout so the server never blocks on a full pipe.
        threading.Thread(target=self.proc.stdout.read, daemon=True).start()
        self.rss = RssSampler(self.proc.pid)
        self.started = time.monotonic()
        self.died_at = None
        threading.Thread(target=self._watch, daemon=True).start()

    def _watch(self):
        self.proc.wait()
        self.died_at = time.monotonic()

    def alive(self):
        return self.proc.poll() is None

    def death(self):
        """How it ended, or None while it runs."""
        code = self.proc.poll()
        if code is None:
            return None
        how = f"signal {signal.Signals(-code).name}" if code < 0 else f"exit code {code}"
        return f"{how} {self.died_at - self.started:.1f} s after start"

    def cpu_seconds(self):
        """User and system CPU time so far; None once it has exited."""
        try:
            with open(f"/proc/{self.proc.pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            return round((int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK"), 1)
        except (OSError, IndexError, ValueError):
            return None

    def log_tail(self, lines=8):
        return self.log_path.read_text(errors="replace").splitlines()[-lines:]

    def stop(self):
        self.rss.stopped.set()
        if self.alive():
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


# Calls -----------------------------------------------------------------------------------------

def _serialize(message):
    """Requests serialized once (large scenes) go out as they are."""
    return message if isinstance(message, bytes) else message.SerializeToString()


class Caller:
    """One connection of its own (not shared with other Callers), the raw ShadowService methods.
    Replies stay unparsed: a call's status and its message count are all that is measured."""

    def __init__(self, address):
        self.last_details = ""  # the status message of the last stream() that failed
        self.channel = grpc.insecure_channel(address, options=[
            ("grpc.max_receive_message_length", 64 << 20),
            ("grpc.max_send_message_length", -1),
            ("grpc.use_local_subchannel_pool", 1)])
        raw = dict(request_serializer=_serialize, response_deserializer=None)
        self.methods = {
            "Render": self.channel.unary_stream(SERVICE + "Render", **raw),
            "RenderSequence": self.channel.unary_stream(SERVICE + "RenderSequence", **raw),
            "UploadScene": self.channel.stream_unary(
                SERVICE + "UploadScene", request_serializer=_serialize,
                response_deserializer=pb.SceneRef.FromString),
            "GetStatistics": self.channel.unary_unary(
                SERVICE + "GetStatistics", request_serializer=_serialize,
                response_deserializer=pb.Statistics.FromString),
        }

    def close(self):
        self.channel.close()

    def stream(self, method, message, timeout=None, cancel_after=None):
        """Runs a Render or RenderSequence to its end: (code name, seconds, messages)."""
        start = time.monotonic()
        call = self.methods[method](message, timeout=timeout)
        timer = None
        if cancel_after is not None:
            timer = threading.Timer(cancel_after, call.cancel)
            timer.start()
        messages = 0
        try:
            for _ in call:
                messages += 1
            code = "OK"
        except grpc.RpcError as e:
            code = e.code().name
            self.last_details = e.details() or ""
        finally:
            if timer:
                timer.cancel()
        return code, time.monotonic() - start, messages

    def render(self, message, **kw):
        return self.stream("Render", message, **kw)

    def upload(self, scene_bytes, timeout=120):
        """UploadScene of a serialized Scene: (code name, seconds, scene id or None)."""
        chunks = [pb.SceneUpload(data=scene_bytes[at:at + UPLOAD_CHUNK_BYTES])
                  for at in range(0, len(scene_bytes), UPLOAD_CHUNK_BYTES)]
        chunks[0].total_bytes = len(scene_bytes)
        return self.upload_chunks(chunks, timeout)

    def upload_chunks(self, chunks, timeout=120):
        start = time.monotonic()
        try:
            ref = self.methods["UploadScene"](iter(chunks), timeout=timeout)
            return "OK", time.monotonic() - start, ref.scene_id
        except grpc.RpcError as e:
            return e.code().name, time.monotonic() - start, None

    def statistics(self):
        return self.methods["GetStatistics"](pb.StatisticsRequest(), timeout=10)


class Bystander(threading.Thread):
    """Renders the small request every `interval` s (one at a time: a starved call delays the
    next), recording each call's status and latency."""

    def __init__(self, address, message=None, interval=None, delay=0.0):
        super().__init__(daemon=True)
        self.caller = Caller(address)
        self.message = (message or small_request()).SerializeToString()
        self.interval = interval if interval is not None else ARGS.bystander_interval
        self.delay = delay
        self.calls = []  # (code, seconds)
        self.stopped = threading.Event()
        self.start()

    def run(self):
        if self.stopped.wait(self.delay):
            return
        while not self.stopped.is_set():
            began = time.monotonic()
            code, seconds, _ = self.caller.render(self.message, timeout=300)
            self.calls.append((code, seconds))
            self.stopped.wait(max(0.0, self.interval - (time.monotonic() - began)))

    def finish(self):
        self.stopped.set()
        self.join()
        self.caller.close()
        latencies = [s for code, s in self.calls if code == "OK"]
        return {"calls": len(self.calls), "outcomes": counts([c for c, _ in self.calls]),
                "p50_ms": ms(percentile(latencies, 50)), "p99_ms": ms(percentile(latencies, 99)),
                "max_ms": ms(max(latencies, default=None))}


def final_render_ok(server):
    """The server still serves: alive, and a small render completes."""
    if not server.alive():
        return False
    caller = Caller(server.address)
    try:
        return caller.render(small_request(), timeout=120)[0] == "OK"
    finally:
        caller.close()


class Phase:
    """One phase's server, RSS window and result."""

    def __init__(self, name, flags, log_dir):
        self.name = name
        flags = [*flags, *shlex.split(ARGS.server_flags)]
        print(f"hostile_load: {name}: shadow-server {' '.join(flags)}", file=sys.stderr,
              flush=True)
        self.server = Server(flags, name, log_dir)
        self.began = time.monotonic()
        self.client_cpu = sum(os.times()[:2])
        self.result = {"phase": name, "server_flags": " ".join(flags) or "(defaults)"}

    def finish(self, **fields):
        server = self.server
        self.result.update(fields)
        self.result["final_render_ok"] = final_render_ok(server)
        low, high = server.rss.since(self.began)
        self.result["rss_mib"] = [round(low or 0), round(high or 0)]
        self.result["seconds"] = round(time.monotonic() - self.began, 1)
        # The client shares the machine with the server: what each used of it.
        self.result["client_cpu_s"] = round(sum(os.times()[:2]) - self.client_cpu, 1)
        self.result["server_cpu_s"] = server.cpu_seconds()
        death = server.death()
        self.result["survived"] = death is None and self.result["final_render_ok"]
        if death:
            self.result["death"] = death
            self.result["server_log_tail"] = server.log_tail()
        server.stop()
        print(json.dumps(self.result), flush=True)
        return self.result


def run_threads(count, target):
    threads = [threading.Thread(target=target, args=(i,), daemon=True) for i in range(count)]
    for t in threads:
        t.start()
    return threads


# Phases ----------------------------------------------------------------------------------------

def phase_deadlines(log_dir, rng):
    phase = Phase("deadlines", [], log_dir)
    scene = pb.Scene(meshes=[height_field_for(5.5)], instances=[pb.Instance(mesh=0)])
    message = request(scene, width=640, height=360, map_size=2048).SerializeToString()
    # The attack request once to its end first: how long a render the deadlines cut short.
    probe = Caller(phase.server.address)
    alone_code, alone_seconds, _ = probe.render(message, timeout=300)
    probe.close()
    outcomes = collections.Counter()
    lock = threading.Lock()
    end = time.monotonic() + ARGS.attack_seconds
    bystander = Bystander(phase.server.address)

    def attacker(i):
        caller, local = Caller(phase.server.address), random.Random(rng.random())
        while time.monotonic() < end and phase.server.alive():
            if local.random() < 0.25:
                mode = "cancel"
                code, _, _ = caller.render(message, timeout=120,
                                           cancel_after=local.uniform(0.0, 0.15))
            else:
                mode = "deadline"
                code, _, _ = caller.render(message, timeout=local.uniform(0.002, 0.120))
            with lock:
                outcomes[(mode, code)] += 1
        caller.close()

    for t in run_threads(3, attacker):
        t.join()
    return phase.finish(
        load=f"3 clients, {len(message) / (1 << 20):.1f} MiB inline scene, 640x360, 2048^2; "
        f"3 in 4 with a 2-120 ms deadline, 1 in 4 cancelled after 0-150 ms; "
        f"{ARGS.attack_seconds:g} s",
        attack_request_alone={"code": alone_code, "ms": ms(alone_seconds)},
        calls=sum(outcomes.values()),
        outcomes={f"{m} {c}": n for (m, c), n in outcomes.most_common()},
        bystander=bystander.finish())


def phase_slow_sequences(log_dir, rng):
    phase = Phase("slow-sequences", [], log_dir)
    base = request(tiny_scene(), width=640, height=360, map_size=1024)
    frames = [pb.Frame(lights=[sun(0.01 * k)]) for k in range(400)]
    message = pb.SequenceRequest(base=base, frames=frames).SerializeToString()
    calls, attackers = [], []
    end = time.monotonic() + ARGS.sequence_seconds
    stop = threading.Event()

    def attacker(i):
        caller = Caller(phase.server.address)
        call = caller.methods["RenderSequence"](message, timeout=3600)
        calls.append(call)
        read, began, code = 0, time.monotonic(), "OK"
        try:
            for _ in call:
                read += 1
                stop.wait(ARGS.sequence_read_interval)
        except grpc.RpcError as e:
            code = e.code().name
        ended = time.monotonic()
        attackers.append({"code": code, "messages_read": read,
                          "ended_after_s": round(ended - began, 1),
                          "ended_by": "client" if ended >= end else "server"})
        caller.close()

    threads = run_threads(4, attacker)
    bystander = Bystander(phase.server.address, delay=2.0)
    while time.monotonic() < end and any(t.is_alive() for t in threads):
        time.sleep(0.2)
    stop.set()
    for call in calls:
        call.cancel()
    for t in threads:
        t.join()
    return phase.finish(
        load=f"4 sequences x 400 frames (640x360, 1024^2), one message read every "
        f"{ARGS.sequence_read_interval:g} s; cancelled after {ARGS.sequence_seconds:g} s",
        attackers=attackers, bystander=bystander.finish())


def phase_idle_uploads(log_dir, rng):
    budget, stall = ARGS.upload_budget, ARGS.upload_stall_timeout
    phase = Phase("idle-uploads",
                  ["--memory-budget", str(budget), "--stall-timeout", f"{stall:g}"], log_dir)
    caller = Caller(phase.server.address)
    # A render that leaves more than 256 MiB of scratch buffers first, so that the uploads
    # arrive within --idle-trim-delay of it: the idle trimmer then runs beside them.
    warm = caller.render(heavy_request(4, 2048), timeout=120)[0]
    # Each just under the half of the budget an upload may declare; together 8 bytes short of it.
    declared = [budget // 2 - 4, budget - (budget // 2 - 4) - 8]
    release = threading.Event()
    uploads = []

    def idle_chunks(total):
        yield pb.SceneUpload(total_bytes=total)
        release.wait()

    opened = time.monotonic()
    for total in declared:
        future = caller.methods["UploadScene"].future(idle_chunks(total), timeout=600)
        entry = {"declared_bytes": total, "future": future}
        future.add_done_callback(lambda f, e=entry: e.setdefault("ended", time.monotonic()))
        uploads.append(entry)
    time.sleep(1.0)
    large = request(tiny_scene(), width=1280, height=720, map_size=2048).SerializeToString()
    renders = []
    bound = opened + max(30.0, 4 * stall)
    while time.monotonic() < bound and phase.server.alive():
        renders.append(caller.render(large, timeout=60)[:2])
        if all(u["future"].done() for u in uploads) and len(renders) >= 3:
            break
        time.sleep(1.0)
    release.set()
    results = []
    for u in uploads:
        f = u["future"]
        if not f.done():
            f.cancel()
        code = f.code().name
        ended = u.get("ended")
        results.append({"declared_bytes": u["declared_bytes"], "code": code,
                        "details": f.details(),
                        "ended_after_s": round(ended - opened, 1) if ended else None,
                        "ended_by": "server" if ended and ended < bound else "client"})
    caller.close()
    first = renders[0] if renders else (None, None)
    return phase.finish(
        load=f"a 4-cube render, then 2 UploadScene streams declaring {declared[0]} + {declared[1]} "
        f"bytes (8 bytes short of the budget) that send nothing; 1280x720 renders beside",
        warm_render=warm,
        uploads=results,
        bystander={"calls": len(renders), "outcomes": counts([c for c, _ in renders]),
                   "first_code": first[0], "first_ms": ms(first[1]),
                   "max_ms": ms(max((s for _, s in renders), default=None))})


def phase_heavy(log_dir, rng):
    message = heavy_request(ARGS.heavy_lights, ARGS.heavy_map_size).SerializeToString()
    budget = ARGS.heavy_budget
    alone = []
    if budget is None:
        # One alone, without a budget, to learn what it holds at its peak.
        probe = Phase("heavy-alone", ["--max-request-cost", "0"], log_dir)
        watcher = Caller(probe.server.address)
        peak, done = [0], threading.Event()

        def watch():
            while not done.is_set():
                try:
                    peak[0] = max(peak[0], watcher.statistics().device_memory_bytes)
                except grpc.RpcError:
                    pass
                done.wait(0.05)

        threading.Thread(target=watch, daemon=True).start()
        code, seconds, _ = Caller(probe.server.address).render(message, timeout=600)
        done.set()
        watcher.close()
        budget = max(int(peak[0] * 1.5), 1 << 28)
        alone = [probe.finish(load="the heavy request alone, to size the budget", code=code,
                              seconds_alone=round(seconds, 2),
                              peak_device_memory_bytes=peak[0])]
    flags = ["--max-request-cost", "0", "--memory-budget", str(budget)]
    phase = Phase("heavy", flags, log_dir)
    runs = []
    bystander = Bystander(phase.server.address)
    for clients in ARGS.heavy_clients:
        results = [None] * clients
        began = time.monotonic()

        def client(i):
            caller = Caller(phase.server.address)
            code, seconds, _ = caller.render(message, timeout=600)
            results[i] = (code, round(time.monotonic() - began, 2), caller.last_details)
            caller.close()

        for t in run_threads(clients, client):
            t.join()
        runs.append({"clients": clients, "outcomes": counts([c for c, _, _ in results]),
                     "finished_after_s": sorted(s for _, s, _ in results),
                     "errors": sorted({d for c, _, d in results if c != "OK"})})
        if not phase.server.alive():
            break
    return alone + [phase.finish(
        load=f"{ARGS.heavy_lights} point lights, cubes of {ARGS.heavy_map_size}^2, 1280x720, "
        f"200^2 height field; {', '.join(map(str, ARGS.heavy_clients))} at once",
        budget_bytes=budget, runs=runs, bystander=bystander.finish())]


def phase_large_inline(log_dir, rng):
    budget = ARGS.large_budget
    scene = pb.Scene(meshes=[height_field_for(ARGS.large_mib)], instances=[pb.Instance(mesh=0)])
    message = request(scene, width=640, height=360, map_size=2048).SerializeToString()
    max_request = max(len(message) + (16 << 20), 512 << 20)
    phase = Phase("large-inline", ["--memory-budget", str(budget),
                                   "--max-request-bytes", str(max_request)], log_dir)
    bystander = Bystander(phase.server.address)
    runs = []
    for clients in ARGS.large_clients:
        began = time.monotonic()
        results = [None] * clients

        def client(i):
            caller = Caller(phase.server.address)
            code, _, _ = caller.render(message, timeout=900)
            results[i] = (code, round(time.monotonic() - began, 1), caller.last_details)
            caller.close()

        for t in run_threads(clients, client):
            t.join()
        low, high = phase.server.rss.since(began)
        runs.append({"clients": clients, "outcomes": counts([c for c, _, _ in results]),
                     "last_finished_after_s": max(s for _, s, _ in results),
                     "errors": sorted({d for c, _, d in results if c != "OK"}),
                     "peak_rss_mib": round(high or 0),
                     "peak_rss_x_budget": round((high or 0) * (1 << 20) / budget, 2)})
        if not phase.server.alive():
            break
    return phase.finish(
        load=f"{', '.join(map(str, ARGS.large_clients))} concurrent "
        f"{len(message) / (1 << 20):.0f} MiB inline requests (640x360, 2048^2)",
        budget_bytes=budget, runs=runs, bystander=bystander.finish())


# The mixed soak's call kinds and the statuses each may end with.
SOAK_EXPECTED = {
    "small": {"OK"},
    "deadline": {"OK", "DEADLINE_EXCEEDED"},
    "cancel": {"OK", "CANCELLED"},
    "upload": {"OK"},
    "by-id": {"OK"},
    "sequence": {"OK"},
    "sequence-deadline": {"OK", "DEADLINE_EXCEEDED"},
    "malformed": {"INVALID_ARGUMENT"},
}


def phase_soak(log_dir, rng):
    phase = Phase("soak", [], log_dir)
    address = phase.server.address
    end = time.monotonic() + ARGS.soak_seconds
    lock = threading.Lock()
    outcomes = collections.Counter()
    small_latencies = []
    bad_codes = collections.Counter()  # malformed requests that were not INVALID_ARGUMENT
    field = pb.Scene(meshes=[height_field_for(5.5)], instances=[pb.Instance(mesh=0)])
    field_request = request(field, width=640, height=360, map_size=2048).SerializeToString()
    small = small_request().SerializeToString()
    malformed = malformed_requests()

    def record(kind, code, seconds=None):
        with lock:
            outcomes[(kind, code)] += 1
            if kind == "small" and code == "OK":
                small_latencies.append(seconds)

    def running():
        return time.monotonic() < end and phase.server.alive()

    def small_client(i):
        caller = Caller(address)
        while running():
            code, seconds, _ = caller.render(small, timeout=120)
            record("small", code, seconds)
        caller.close()

    def deadline_client(i):
        caller, local = Caller(address), random.Random(rng.random())
        while running():
            record("deadline", caller.render(field_request,
                                             timeout=local.uniform(0.002, 0.120))[0])
        caller.close()

    def cancel_client(i):
        caller, local = Caller(address), random.Random(rng.random())
        while running():
            record("cancel", caller.render(field_request, timeout=120,
                                           cancel_after=local.uniform(0.0, 0.2))[0])
        caller.close()

    def upload_client(i):
        # A new tiny scene each time (a new id), every 10th a new 5.5 MiB height field.
        caller, local, n = Caller(address), random.Random(rng.random()), 0
        while running():
            n += 1
            if n % 10 == 0:
                scene = pb.Scene(meshes=field.meshes, instances=[
                    pb.Instance(mesh=0, transform=transform(1.0, local.uniform(-1, 1)))])
            else:
                scene = tiny_scene(local.uniform(-2, 2))
            code, _, scene_id = caller.upload(scene.SerializeToString(deterministic=True))
            record("upload", code)
            if scene_id:
                record("by-id", caller.render(request(scene_id=scene_id), timeout=120)[0])
            time.sleep(0.1)
        caller.close()

    def sequence_client(i):
        caller, local = Caller(address), random.Random(rng.random())
        base = small_request()
        while running():
            frames = [pb.Frame(lights=[sun(local.uniform(0, 6.28))]) for _ in range(8)]
            message = pb.SequenceRequest(base=base, frames=frames)
            if local.random() < 0.3:
                record("sequence-deadline", caller.stream(
                    "RenderSequence", message, timeout=local.uniform(0.02, 0.5))[0])
            else:
                record("sequence", caller.stream("RenderSequence", message, timeout=120)[0])
        caller.close()

    def malformed_client(i):
        caller, k = Caller(address), 0
        while running():
            name, method, message = malformed[k % len(malformed)]
            k += 1
            if method == "UploadScene":
                code = caller.upload_chunks(message, timeout=30)[0]
            else:
                code = caller.stream(method, message, timeout=30)[0]
            record("malformed", code)
            if code != "INVALID_ARGUMENT":
                with lock:
                    bad_codes[f"{name}: {code}"] += 1
            time.sleep(0.05)
        caller.close()

    threads = []
    for worker, count in ((small_client, 2), (deadline_client, 1), (cancel_client, 1),
                          (upload_client, 1), (sequence_client, 1), (malformed_client, 1)):
        threads += run_threads(count, worker)
    for t in threads:
        t.join()
    by_kind = collections.defaultdict(dict)
    for (kind, code), n in sorted(outcomes.items()):
        by_kind[kind][code] = n
    unexpected = sum(n for (kind, code), n in outcomes.items()
                     if code not in SOAK_EXPECTED[kind])
    return phase.finish(
        load=f"{ARGS.soak_seconds:g} s: 2 small-render clients back to back; 5.5 MiB inline "
        "renders with 2-120 ms deadlines; ones cancelled after 0-200 ms; uploads then renders "
        "by id; 8-frame sequences (3 in 10 with a 20-500 ms deadline); malformed requests",
        calls=sum(outcomes.values()), unexpected=unexpected, outcomes=dict(by_kind),
        malformed_not_invalid_argument=dict(bad_codes),
        small={"renders": len(small_latencies), "p50_ms": ms(percentile(small_latencies, 50)),
               "p99_ms": ms(percentile(small_latencies, 99))})


# Report ----------------------------------------------------------------------------------------

def bystander_cell(b):
    if not b:
        return ""
    if "first_code" in b:
        return (f"1280x720: first {b['first_code']} in {b['first_ms']} ms; "
                f"{spell_counts(b['outcomes'])}; max {b['max_ms']} ms")
    calls = f"{b['calls']} call" + ("s" if b["calls"] != 1 else "")
    cell = f"{b['p50_ms']} / {b['p99_ms']} / {b['max_ms']} ms ({calls}"
    bad = {c: n for c, n in b["outcomes"].items() if c != "OK"}
    return cell + (f"; {spell_counts(bad)})" if bad else ")")


def outcome_cell(r):
    name = r["phase"]
    if name == "deadlines":
        alone = r["attack_request_alone"]
        return (f"{r['calls']} calls: {spell_counts(r['outcomes'])} (the request alone: "
                f"{alone['code']} in {alone['ms']} ms)")
    if name == "slow-sequences":
        alike = collections.Counter(f"{a['code']} by the {a['ended_by']} after "
                                    f"{round(a['ended_after_s'])} s, {a['messages_read']} "
                                    "messages read" for a in r["attackers"])
        return "; ".join(f"{n} x {what}" for what, n in alike.items())
    if name == "idle-uploads":
        uploads = "; ".join(f"{u['declared_bytes']} B declared: {u['code']} by the "
                            f"{u['ended_by']} after {u['ended_after_s']} s" for u in r["uploads"])
        return f"the render before: {r['warm_render']}; uploads: {uploads}"
    if name == "heavy-alone":
        return (f"{r['code']} in {r['seconds_alone']} s; device memory peak "
                f"{r['peak_device_memory_bytes'] / 1e6:.0f} MB")
    if name == "heavy":
        return "; ".join(f"{x['clients']} at once: {spell_counts(x['outcomes'])}, done after "
                         f"{', '.join(map(str, x['finished_after_s']))} s" for x in r["runs"])
    if name == "large-inline":
        return "; ".join(f"{x['clients']} at once: {spell_counts(x['outcomes'])} in "
                         f"{x['last_finished_after_s']} s, peak RSS {x['peak_rss_mib']} MiB = "
                         f"{x['peak_rss_x_budget']}x budget" for x in r["runs"])
    if name == "soak":
        kinds = "; ".join(f"{k}: {spell_counts(v)}" for k, v in r["outcomes"].items())
        return (f"{r['calls']} calls, {r['unexpected']} unexpected ({kinds}); small renders "
                f"p50 / p99 {r['small']['p50_ms']} / {r['small']['p99_ms']} ms")
    return ""


def write_markdown(path, results, context):
    lines = [
        "# Hostile load (issue 40)",
        "",
        f"`tests/bench/hostile_load.py`, {context}. Bystander: a 320x240 render with a 512^2 "
        f"map of a tiny scene every {ARGS.bystander_interval:g} s, one at a time.",
        "",
        "| phase | server flags | load | outcomes | bystander p50 / p99 / max | server RSS | "
        "survived |",
        "| --- | --- | --- | --- | --- | ---: | --- |",
    ]
    for r in results:
        survived = "yes" if r["survived"] else f"**no**: {r.get('death', 'no final render')}"
        flags = r["server_flags"]
        cells = [r["phase"], f"`{flags}`" if flags.startswith("--") else flags,
                 r.get("load", ""), outcome_cell(r), bystander_cell(r.get("bystander")),
                 f"{r['rss_mib'][0]}–{r['rss_mib'][1]} MiB", survived]
        lines.append("| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |")
    notes = [f"- {r['phase']}, {x['clients']} at once: {error[:300]}"
             for r in results for x in r.get("runs", []) for error in x.get("errors", [])]
    notes += [f"- {r['phase']}: the server died ({r['death']}; the JSON line has its log's end)"
              for r in results if r.get("death")]
    if notes:
        lines += ["", "Refusals' status messages and deaths:", ""] + notes
    Path(path).write_text("\n".join(lines) + "\n")


def machine_context():
    model = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo")
                  if line.startswith("model name")), platform.machine())
    try:
        commit = subprocess.run(["git", "-C", str(Path(__file__).parent), "describe", "--always",
                                 "--dirty"], capture_output=True, text=True).stdout.strip()
    except OSError:
        commit = ""
    return (f"{os.cpu_count()} cores ({model}), load average {os.getloadavg()[0]:.1f} at the "
            f"start" + (f", commit {commit}" if commit else ""))


def main():
    rng = random.Random(ARGS.seed)
    context = machine_context()
    runs = {"deadlines": phase_deadlines, "slow-sequences": phase_slow_sequences,
            "idle-uploads": phase_idle_uploads, "heavy": phase_heavy,
            "large-inline": phase_large_inline, "soak": phase_soak}
    results = []
    with tempfile.TemporaryDirectory(prefix="hostile-load-") as log_dir:
        for name in ARGS.phases:
            outcome = runs[name](log_dir, rng)  # heavy: its sizing run, then the phase
            results += outcome if isinstance(outcome, list) else [outcome]
            if ARGS.markdown:  # after each phase: an interrupted run keeps what it measured
                write_markdown(ARGS.markdown, results, context)
    died = [r["phase"] for r in results if not r["survived"]]
    if died:
        print(f"hostile_load: the server did not survive: {', '.join(died)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
