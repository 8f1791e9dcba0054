#!/usr/bin/env python3
"""The Python client against a real shadow-server on loopback, with TLS and a token.

Runs client/python/examples/render_example.py, then renders the same requests through the C++
client library (render-dump) and checks that every texture is bit-identical and every matrix,
cube face and channel name equal. Independently of either client it checks the arrays' meaning:
the camera's world->NDC matrix maps each pixel's world position (POSITION) to that pixel's
centre, each cube face's matrix maps a point ahead of the light on the face's axis to the face's
centre, and the float64 SAT equals numpy's double cumulative sums of the map. Also: no token is
UNAUTHENTICATED, a bad field is INVALID_ARGUMENT naming it, several targets work, and
RenderResult.virtual_pages reads the header's virtual page counts (None without them).

With a sixth argument "resume" it checks only the client's resume: across a server restart (a
sequence whose server is killed with SIGKILL mid-call and started again on its port 2 s later
completes, bit-identical to a run without the kill) and against a stand-in service.

Usage: python_client_test.py SHADOW_SERVER RENDER_DUMP MAKE_CERTS PYTHONPATH EXAMPLE [resume]
"""

import importlib.util
import math
import os
import pathlib
import subprocess
import sys
import tempfile
import threading
import time

import numpy as np

server_bin, dump_bin, make_certs, python_path, example = sys.argv[1:6]
sys.path.insert(0, python_path)
import shadow_client as sc  # noqa: E402

failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        failures.append(what)


def start_server(work, args, listen="127.0.0.1:0", log_name="server.log"):
    log = open(work / log_name, "w")
    proc = subprocess.Popen([server_bin, "--listen", listen, *args], stdout=subprocess.PIPE,
                            stderr=log, text=True)
    for line in proc.stdout:  # ends when the server exits
        if line.startswith("listening on "):
            return proc, line.split()[-1]
    raise SystemExit("shadow-server exited before listening: " + (work / log_name).read_text())


def read_txt(path):
    matrices, faces, channels = {}, [], []
    for line in path.read_text().splitlines():
        key, *rest = line.split()
        if key == "face":
            faces.append(rest[0])
        elif key == "channel":
            channels.append(rest[0])
        else:
            m = np.array([float(v) for v in rest], dtype=np.float32).reshape(4, 4)
            matrices.setdefault(key, []).append(m)
    return matrices, faces, channels


def compare_with_cpp(work, name, target, tls):
    py = np.load(work / "py" / f"{name}.npz")
    cpp_dir = work / "cpp" / name
    cpp_dir.mkdir(parents=True)
    subprocess.run([dump_bin, target, str(work / "py" / f"{name}.request.pb"), str(cpp_dir), *tls],
                   check=True, timeout=600)
    request = sc.pb.RenderRequest.FromString((work / "py" / f"{name}.request.pb").read_bytes())
    check(sc.scene_key(request.scene) == (cpp_dir / "scene_key").read_text(),
          f"{name}: the same x-scene-id from both clients")
    names = sorted(p.stem for p in cpp_dir.glob("*.bin"))
    check(names == sorted(k for k in py.files if "." not in k),
          f"{name}: same textures from both clients: {names}")
    for t in names:
        data = py[t]
        cpp = (cpp_dir / f"{t}.bin").read_bytes()
        check(data.dtype.isnative and data.tobytes() == cpp,
              f"{name}/{t}: {data.shape} {data.dtype} bit-identical to the C++ client")
        matrices, faces, channels = read_txt(cpp_dir / f"{t}.txt")
        check(np.array_equal(py[t + ".world_to_ndc"], matrices["world_to_ndc"][0])
              and np.array_equal(py[t + ".world_to_camera"], matrices["world_to_camera"][0]),
              f"{name}/{t}: world_to_ndc and world_to_camera equal")
        if faces:
            same = list(py[t + ".faces"]) == faces and all(
                np.array_equal(py[f"{t}.face{i}.world_to_ndc"], m)
                for i, m in enumerate(matrices["face_world_to_ndc"]))
            check(same, f"{name}/{t}: cube faces {faces} and their matrices equal")
        if channels:
            check(list(py[t + ".channels"]) == channels, f"{name}/{t}: channel names equal")


def project(m, points):
    ones = np.ones(points.shape[:-1] + (1,))
    h = np.concatenate([points, ones], axis=-1) @ m.astype(np.float64).T
    return h[..., :3] / h[..., 3:4]


def check_meaning(result_sun, result_point):
    # The camera's matrix places each pixel's world position at that pixel's centre.
    pos = result_sun["position"]
    vis = result_sun["visibility"]
    h, w = pos.data.shape[:2]
    seen = ~np.isnan(pos.data[..., 0])
    ndc = project(vis.world_to_ndc, pos.data[seen].astype(np.float64))
    jj, ii = np.nonzero(seen)
    err = np.maximum(np.abs(ndc[:, 0] * w - (ii + 0.5)), np.abs(ndc[:, 1] * h - (jj + 0.5)))
    print(f"      camera matrix: {seen.sum()} pixels, worst {err.max():.2e} px from their centre")
    check(seen.sum() > 0.5 * w * h and err.max() < 1e-4,  # measured 3.1e-5
          "visibility.world_to_ndc maps POSITION to the pixel centres (< 1e-4 px)")
    # The shadow map's matrix puts the seen receivers inside the map, in front of the light.
    sm = project(result_sun["shadowmap"].world_to_ndc, pos.data[seen].astype(np.float64))
    check(np.all((sm[:, :2] >= 0) & (sm[:, :2] <= 1)) and np.all(sm[:, 2] <= 1 + 1e-6),
          "shadowmap.world_to_ndc maps every seen point into the map")
    # SAT: float64, inclusive sums of the map. A 512^2 sum of float32 depths in [0, 1] needs
    # 18 + 24 bits, within a double's 53: both routes are exact, so they must agree exactly.
    sat = result_sun["shadowmap_sat"].data[..., 0]
    ref = np.cumsum(np.cumsum(result_sun["shadowmap"].data[..., 0].astype(np.float64), 0), 1)
    rel = np.max(np.abs(sat - ref)) / ref[-1, -1]
    print(f"      SAT: {sat.dtype} {sat.shape}, worst |SAT - cumsum| / total = {rel:.2e}")
    check(sat.dtype == np.float64 and rel == 0, "shadowmap_sat equals numpy's double cumsums")
    basis = result_sun["csm_basis"]
    check(basis.channel_names == [f"sin{k}" for k in range(1, 5)] + [f"cos{k}" for k in range(1, 5)]
          and basis.data.shape[-1] == 8, f"csm_basis channels {basis.channel_names}")
    # Cube faces: a point ahead of the light along a face's axis lands at the face's centre.
    cube = result_point["shadowmap_cube"]
    light = np.array([2.0, 4.0, 1.0])
    axes = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0),
            "+z": (0, 0, 1), "-z": (0, 0, -1)}
    worst = 0.0
    for f in cube.cube_faces:
        c = project(f.world_to_ndc, (light + 3 * np.array(axes[f.name]))[None, :])[0]
        worst = max(worst, abs(c[0] - 0.5), abs(c[1] - 0.5))
    print(f"      cube: faces {[f.name for f in cube.cube_faces]}, data {cube.data.shape}, "
          f"worst centre offset {worst:.1e}")
    check(cube.is_cube and cube.data.shape[0] == len(cube.cube_faces) >= 1 and worst < 1e-5,
          "each cube face's matrix centres its axis")


def check_restarts():
    """Against a stand-in service: UNAVAILABLE before a reply is retried by gRPC's retry policy
    (the service config), a reply that breaks off after its header is asked for again, and so is
    a resumed call that the server refuses before any reply (as a proxy does while its upstream
    restarts) more often than the retry policy tries (4 attempts)."""
    from concurrent import futures

    import grpc
    from shadow_client._proto.shadow.v1 import shadow_pb2_grpc as pb_grpc

    def serve(behave):
        class Fake(pb_grpc.ShadowServiceServicer):
            def Render(self, request, context):
                yield from behave(context)

        server = grpc.server(futures.ThreadPoolExecutor(max_workers=2))
        pb_grpc.add_ShadowServiceServicer_to_server(Fake(), server)
        port = server.add_insecure_port("127.0.0.1:0")
        server.start()
        return server, f"127.0.0.1:{port}"

    header = sc.pb.RenderResponse(header=sc.pb.RenderHeader(passes=["fake"]))
    calls = []

    def retried_then_broken(context):
        attempts = dict(context.invocation_metadata()).get("grpc-previous-rpc-attempts", "-")
        calls.append(attempts)
        if len(calls) == 1:
            context.abort(grpc.StatusCode.UNAVAILABLE, "going away")
        yield header
        if len(calls) == 2:
            context.abort(grpc.StatusCode.INTERNAL, "reset")

    server, target = serve(retried_then_broken)
    try:
        with sc.Client(target) as client:
            result = client.render(sc.pb.RenderRequest())
            check(list(result.header.passes) == ["fake"] and calls == ["-", "1", "-"]
                  and client.stream_restarts == 1,
                  f"retried before a reply, restarted after one: attempts {calls}, "
                  f"restarts {client.stream_restarts}")
    finally:
        server.stop(None)

    refusals = 6
    calls.clear()

    def broken_then_not_back(context):
        calls.append(1)
        if 2 <= len(calls) <= 1 + refusals:
            context.abort(grpc.StatusCode.UNAVAILABLE, "no upstream")
        yield header
        if len(calls) == 1:
            context.abort(grpc.StatusCode.UNAVAILABLE, "died")

    server, target = serve(broken_then_not_back)
    try:
        with sc.Client(target) as client:
            result = client.render(sc.pb.RenderRequest(), timeout=30)
            check(list(result.header.passes) == ["fake"] and len(calls) == 2 + refusals
                  and client.stream_restarts >= 2,
                  f"a resume refused {refusals} times is resumed until answered: {len(calls)} "
                  f"calls, restarts {client.stream_restarts}")
    except sc.RpcError as e:
        check(False, f"a resume refused {refusals} times is resumed until answered: {e}")
    finally:
        server.stop(None)

    # Without a timeout the resumes are counted: a stream that always breaks is given up after
    # MAX_RESUMES_WITHOUT_TIMEOUT of them (pauses shortened here; the count is what is checked).
    calls.clear()

    def always_broken(context):
        calls.append(1)
        yield header
        context.abort(grpc.StatusCode.UNAVAILABLE, "died")

    from shadow_client import _client
    server, target = serve(always_broken)
    saved = _client.RESUME_BACKOFF_MAX
    _client.RESUME_BACKOFF_MAX = 0.01
    try:
        with sc.Client(target) as client:
            client.render(sc.pb.RenderRequest(), timeout=None)
        check(False, "without a timeout, a stream that always breaks is given up")
    except sc.RpcError as e:
        resumes = len(calls) - 1
        check(e.code.name == "UNAVAILABLE" and resumes == _client.MAX_RESUMES_WITHOUT_TIMEOUT,
              f"without a timeout, a stream that always breaks is given up after {resumes} "
              f"resumes: {e}")
    finally:
        _client.RESUME_BACKOFF_MAX = saved
        server.stop(None)


RESTART_DELAY = 2.0  # longer than resumes that do not wait last (issue 40 saw 3 within 2.2 s)


def fingerprint(result):
    return [(t.name, t.data.tobytes(), t.world_to_ndc.tobytes()) for t in result.textures]


class Restart:
    """Kills `server` with SIGKILL and, on a thread, starts another on its address RESTART_DELAY
    later; outage() waits for it and says how long the address had no server."""

    def __init__(self, work, server, target):
        server.kill()
        server.wait()
        self.killed = time.monotonic()
        self.server = None
        self.error = None

        def restart():
            time.sleep(RESTART_DELAY)
            try:
                self.server, _ = start_server(work, ["--log-format", "none"], listen=target,
                                              log_name="restarted.log")
                self.listening = time.monotonic()
            except BaseException as e:  # noqa: B036 (SystemExit too): reported by outage()
                self.error = e

        self.thread = threading.Thread(target=restart)
        self.thread.start()

    def outage(self):
        self.thread.join()
        if self.error is not None:
            raise self.error
        return self.listening - self.killed

    def stop(self):
        self.thread.join()
        if self.server is not None:
            self.server.kill()
            self.server.wait()


def check_resume_across_restart(work):
    """The client's resume across a server restart (issue 40): a 24-frame sequence whose server is
    killed with SIGKILL after frame 1 and started again on its port RESTART_DELAY later
    completes, every frame once, bit-identical to a run without the kill."""
    spec = importlib.util.spec_from_file_location("render_example", example)
    render_example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(render_example)
    P = sc.pb
    base = P.RenderRequest()
    base.CopyFrom(render_example.requests()["sun"])
    base.ClearField("filter")
    del base.products[:]
    base.products.extend([P.PRODUCT_SHADOW_MAP, P.PRODUCT_VISIBILITY])
    # 1024^2 maps (4 MiB a frame): far more than the sockets and HTTP/2 windows hold, so after
    # frame 1 the server is still sending.
    base.shadow_map.size = 1024
    frames = 24
    seq = P.SequenceRequest(base=base)
    for k in range(frames):
        f = seq.frames.add()
        f.camera.CopyFrom(base.camera)
        f.camera.eye.x = 12 * math.sin(2 * math.pi * k / frames)
        f.camera.eye.z = 12 * math.cos(2 * math.pi * k / frames)

    server, target = start_server(work, ["--log-format", "none"])
    restart = None
    try:
        with sc.Client(target) as client:
            reference = [fingerprint(f) for f in client.sequence(seq, timeout=120)]
            check(len(reference) == frames, f"resume: the reference run has {frames} frames")
            arrived = [0] * frames
            equal = 0
            start = time.monotonic()
            try:
                for f in client.sequence(seq, timeout=60):
                    arrived[f.frame] += 1
                    equal += fingerprint(f) == reference[f.frame]
                    if f.frame == 1 and restart is None:
                        restart = Restart(work, server, target)
                error = None
            except sc.RpcError as e:
                error = e
            took = time.monotonic() - start
            check(restart is not None, "resume: the server was killed mid-sequence")
            if restart is None:
                return
            outage = restart.outage()
            print(f"      sequence: killed after frame 1, listening again {outage:.2f} s later; "
                  f"done in {took:.2f} s with {client.stream_restarts} resume(s), "
                  f"{equal} of {frames} frames equal")
            check(error is None, f"resume: the sequence completed across the restart ({error})")
            check(arrived == [1] * frames and equal == frames,
                  "resume: every frame once, bit-identical to the run without the kill")
            check(client.stream_restarts >= 1 and took < 50,
                  f"resume: the kill broke the stream and the call resumed "
                  f"({client.stream_restarts} resume(s), {took:.1f} s)")
            server = restart.server
            restart = None
    finally:
        # SIGKILL: only the client is under test here, and a graceful stop can take seconds.
        if restart is not None:
            restart.stop()
        server.kill()
        server.wait()


def check_virtual_pages():
    """RenderResult.virtual_pages: RenderHeader.virtual_pages's counts, None without them."""
    P = sc.pb
    header = P.RenderHeader(virtual_pages=P.VirtualPages(
        requested=412, resident=400, rendered=37, coarsened_pixels=1234, pool_bytes=64 << 20))
    got = sc.RenderResult(textures=[], header=header).virtual_pages
    check(got == sc.VirtualPages(412, 400, 37, 1234, 64 << 20),
          f"virtual_pages holds the header's counts: {got}")
    zero = sc.RenderResult(textures=[], header=P.RenderHeader(virtual_pages=P.VirtualPages()))
    check(zero.virtual_pages == sc.VirtualPages(0, 0, 0, 0, 0),
          "virtual_pages: zero counts are counts")
    check(sc.RenderResult(textures=[], header=P.RenderHeader()).virtual_pages is None,
          "virtual_pages is None without virtual")


def main():
    if sys.argv[6:7] == ["resume"]:
        with tempfile.TemporaryDirectory() as tmp:
            check_resume_across_restart(pathlib.Path(tmp))
        check_restarts()
        if failures:
            raise SystemExit(f"{len(failures)} checks failed")
        print("python client resume: passed")
        return
    check_virtual_pages()
    with tempfile.TemporaryDirectory() as tmp:
        work = pathlib.Path(tmp)
        subprocess.run(["bash", make_certs, str(work / "certs")], check=True)
        (work / "tokens").write_text("py-secret farm\n")
        certs = work / "certs"
        server, target = start_server(work, ["--tls-cert", str(certs / "server.pem"), "--tls-key",
                                             str(certs / "server.key"), "--auth-tokens",
                                             str(work / "tokens"), "--log-format", "none"])
        try:
            tls = ["--tls-ca", str(certs / "ca.pem"), "--token", "py-secret"]
            env = dict(os.environ, PYTHONPATH=python_path)
            run = subprocess.run([sys.executable, example, "--server", target, *tls, "--out",
                                  str(work / "py"), "--save-requests"], env=env, text=True,
                                 capture_output=True, timeout=600)
            print(run.stdout, run.stderr)
            check(run.returncode == 0, "the example ran")
            if run.returncode != 0:
                raise SystemExit("the example failed: nothing else to check")
            for name in ("sun", "point"):
                compare_with_cpp(work, name, target, tls)

            P = sc.pb
            requests = {n: P.RenderRequest.FromString((work / "py" / f"{n}.request.pb")
                                                      .read_bytes()) for n in ("sun", "point")}
            # Several targets (here the one server twice) go through round_robin.
            with sc.Client([target, target], tls_ca=str(certs / "ca.pem"),
                           token="py-secret") as client:
                sun = client.render(requests["sun"])
                point = client.render(requests["point"])
                check_meaning(sun, point)
                check(sun.virtual_pages is None, "no virtual pages without TECHNIQUE_VIRTUAL")
                # Two lights in one request: each light's textures carry its index, and the
                # point light's visibility is the one it has alone.
                both = P.RenderRequest()
                both.CopyFrom(requests["point"])
                both.lights.insert(0, P.Light(directional=requests["sun"].lights[0].directional))
                del both.products[:]
                both.products.append(P.PRODUCT_VISIBILITY)
                two = client.render(both)
                names = {t.name: t.light for t in two.textures}
                check(names == {"visibility_light0": 0, "visibility_light1": 1},
                      f"two lights: textures and their light index {names}")
                check(two["visibility_light1"].data.tobytes() == point["visibility"].data.tobytes(),
                      "two lights: the point light's visibility is bit-identical to its own render")
                # Float16 outputs decode as float16 arrays: numpy's own rounding of the float32
                # products, bit for bit; SATs stay float64.
                half = P.RenderRequest()
                half.CopyFrom(requests["sun"])
                half.pixel_format = P.PIXEL_FORMAT_FLOAT16
                halves = client.render(half)
                for t in sun.textures:
                    h = halves[t.name].data
                    want = t.data if t.data.dtype == np.float64 else t.data.astype(np.float16)
                    check(h.dtype == want.dtype and h.tobytes() == want.tobytes(),
                          f"float16: {t.name} is numpy's rounding of the float32 product")
                # Estimate: the price without a render, a sequence's for all its frames.
                price = client.estimate(requests["sun"])
                check(price.admitted and price.device_ms > 0 and price.reply_bytes > 0,
                      f"estimate of the sun's request: {price}")
                frames = P.SequenceRequest(base=requests["sun"], frames=[P.Frame()] * 10)
                whole = client.estimate(frames)
                check(whole.frames == 10 and abs(whole.device_ms - 10 * price.device_ms) <=
                      1e-6 * whole.device_ms, f"estimate of ten frames: {whole}")
                # Scenes by id and sequences: the uploaded scene's id is scene_key(); by id
                # renders what inline does; each frame of a sequence equals that frame alone.
                scene_id = client.upload_scene(requests["sun"].scene)
                check(scene_id == sc.scene_key(requests["sun"].scene), "upload_scene's id")
                by_id = P.RenderRequest()
                by_id.CopyFrom(requests["sun"])
                by_id.scene_id = scene_id
                same = all(t.data.tobytes() == sun[t.name].data.tobytes()
                           for t in client.render(by_id).textures)
                check(same, "render by scene id equals the inline render")
                seq = P.SequenceRequest(base=by_id)
                for k in range(3):
                    f = seq.frames.add()
                    f.camera.CopyFrom(requests["sun"].camera)
                    f.camera.eye.x += 0.5 * k
                frames = list(client.sequence(seq))
                check([f.frame for f in frames] == [0, 1, 2], "sequence: three frames in order")
                for k, f in enumerate(frames):
                    alone = P.RenderRequest()
                    alone.CopyFrom(requests["sun"])
                    alone.camera.CopyFrom(seq.frames[k].camera)
                    ref = client.render(alone)
                    check(all(t.data.tobytes() == ref[t.name].data.tobytes() for t in f.textures),
                          f"sequence frame {k} equals that frame alone")
                check("scene" in frames[1].reused, f"sequence: frame 1 kept {frames[1].reused}")
                bad = P.RenderRequest()
                bad.CopyFrom(requests["point"])
                bad.camera.width = 0
                try:
                    client.render(bad)
                    check(False, "a zero camera width is refused")
                except sc.RpcError as e:
                    check(e.code.name == "INVALID_ARGUMENT" and "camera.width" in e.message,
                          f"a zero camera width: {e}")
                stats = client.statistics()
                check([t.tenant for t in stats.tenants] == ["farm"],
                      "statistics name the token's tenant")
            with sc.Client(target, tls_ca=str(certs / "ca.pem")) as anonymous:
                try:
                    anonymous.render(requests["point"])
                    check(False, "no token is refused")
                except sc.RpcError as e:
                    check(e.code.name == "UNAUTHENTICATED", f"no token: {e}")
        finally:
            server.terminate()
            server.wait(timeout=60)
    check_restarts()
    if failures:
        raise SystemExit(f"{len(failures)} checks failed")
    print("python client: passed")


main()
