#!/usr/bin/env python3
"""The Python client against a real shadow-server on loopback, with TLS and a token.

Runs client/python/examples/render_example.py, then renders the same requests through the C++
client library (render-dump) and checks that every texture is bit-identical and every matrix,
cube face and channel name equal. Independently of either client it checks the arrays' meaning:
the camera's world->NDC matrix maps each pixel's world position (POSITION) to that pixel's
centre, each cube face's matrix maps a point ahead of the light on the face's axis to the face's
centre, and the float64 SAT equals numpy's double cumulative sums of the map. Also: no token is
UNAUTHENTICATED, a bad field is INVALID_ARGUMENT naming it, several targets work.

Usage: python_client_test.py SHADOW_SERVER RENDER_DUMP MAKE_CERTS PYTHONPATH EXAMPLE
"""

import os
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

server_bin, dump_bin, make_certs, python_path, example = sys.argv[1:6]
sys.path.insert(0, python_path)
import shadow_client as sc  # noqa: E402

failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        failures.append(what)


def start_server(work, args):
    log = open(work / "server.log", "w")
    proc = subprocess.Popen([server_bin, "--listen", "127.0.0.1:0", *args], stdout=subprocess.PIPE,
                            stderr=log, text=True)
    for line in proc.stdout:  # ends when the server exits
        if line.startswith("listening on "):
            return proc, line.split()[-1]
    raise SystemExit("shadow-server exited before listening: " + (work / "server.log").read_text())


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
    (the service config), a reply that breaks off after its header is asked for again."""
    from concurrent import futures

    import grpc
    from shadow_client._proto.shadow.v1 import shadow_pb2_grpc as pb_grpc

    calls = []

    class Fake(pb_grpc.ShadowServiceServicer):
        def Render(self, request, context):
            attempts = dict(context.invocation_metadata()).get("grpc-previous-rpc-attempts", "-")
            calls.append(attempts)
            if len(calls) == 1:
                context.abort(grpc.StatusCode.UNAVAILABLE, "going away")
            yield sc.pb.RenderResponse(header=sc.pb.RenderHeader(passes=["fake"]))
            if len(calls) == 2:
                context.abort(grpc.StatusCode.INTERNAL, "reset")

    server = grpc.server(futures.ThreadPoolExecutor(max_workers=2))
    pb_grpc.add_ShadowServiceServicer_to_server(Fake(), server)
    port = server.add_insecure_port("127.0.0.1:0")
    server.start()
    try:
        with sc.Client(f"127.0.0.1:{port}") as client:
            result = client.render(sc.pb.RenderRequest())
            check(list(result.header.passes) == ["fake"] and calls == ["-", "1", "-"]
                  and client.stream_restarts == 1,
                  f"retried before a reply, restarted after one: attempts {calls}, "
                  f"restarts {client.stream_restarts}")
    finally:
        server.stop(None)


def main():
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
