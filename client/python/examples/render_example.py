#!/usr/bin/env python3
"""Renders a small scene (a ground plane and a box) twice with shadow_client: under a sun with the
CSM filter (shadow map, its float64 SAT, visibility, world positions, the CSM basis), then under a
point light (a cube shadow map). Saves each result as NAME.npz in --out, prints a summary.

    PYTHONPATH=build/client/python python3 client/python/examples/render_example.py \
        --server 127.0.0.1:50051 --out out/
"""

import argparse
import pathlib

import numpy as np

import shadow_client as sc


def box(center, half):
    """A closed box: 8 corners, 12 triangles."""
    c = np.array(center, dtype=np.float64)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half + c
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = [t for a, b, c_, d in quads for t in ((a, b, c_), (a, c_, d))]
    return corners, np.array(tris)


def scene() -> sc.pb.Scene:
    ground = sc.mesh([[-10, 0, -10], [-10, 0, 10], [10, 0, 10], [10, 0, -10]],
                     [[0, 1, 2], [0, 2, 3]])
    cube = sc.mesh(*box([0, 1, 0], 1.0))
    return sc.pb.Scene(meshes=[ground, cube],
                       instances=[sc.pb.Instance(mesh=0), sc.pb.Instance(mesh=1)])


def camera() -> sc.pb.Camera:
    return sc.pb.Camera(eye=sc.pb.Vec3(x=0, y=6, z=12), target=sc.pb.Vec3(x=0, y=0, z=0),
                        width=320, height=180, fov_deg=50)


def requests() -> dict:
    P = sc.pb
    sun = P.RenderRequest(
        scene=scene(), camera=camera(),
        lights=[P.Light(directional=P.DirectionalLight(direction=P.Vec3(x=-1, y=-2, z=-0.5)))],
        shadow_map=P.ShadowMapSettings(size=512),
        filter=P.Filter(csm=P.CsmSettings(terms=4)),
        products=[P.PRODUCT_SHADOW_MAP, P.PRODUCT_SHADOW_MAP_SAT, P.PRODUCT_VISIBILITY,
                  P.PRODUCT_POSITION, P.PRODUCT_CSM_BASIS])
    point = P.RenderRequest(
        scene=scene(), camera=camera(),
        lights=[P.Light(point=P.PointLight(position=P.Vec3(x=2, y=4, z=1)))],
        shadow_map=P.ShadowMapSettings(size=256),
        products=[P.PRODUCT_SHADOW_MAP, P.PRODUCT_VISIBILITY])
    return {"sun": sun, "point": point}


def save(path: pathlib.Path, result: sc.RenderResult) -> None:
    arrays = {}
    for t in result.textures:
        arrays[t.name] = t.data
        arrays[t.name + ".world_to_ndc"] = t.world_to_ndc
        arrays[t.name + ".world_to_camera"] = t.world_to_camera
        for i, f in enumerate(t.cube_faces):
            arrays[f"{t.name}.face{i}.world_to_ndc"] = f.world_to_ndc
        if t.cube_faces:
            arrays[t.name + ".faces"] = np.array([f.name for f in t.cube_faces])
        if t.channel_names:
            arrays[t.name + ".channels"] = np.array(t.channel_names)
    np.savez(path, **arrays)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--server", default="127.0.0.1:50051",
                    help="HOST:PORT, several separated by commas, or dns:///NAME:PORT")
    ap.add_argument("--tls-ca")
    ap.add_argument("--tls-cert")
    ap.add_argument("--tls-key")
    ap.add_argument("--token")
    ap.add_argument("--out", default="out", type=pathlib.Path)
    ap.add_argument("--save-requests", action="store_true",
                    help="also write each request as NAME.request.pb (binary protobuf)")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    with sc.Client(args.server, tls_ca=args.tls_ca, tls_cert=args.tls_cert, tls_key=args.tls_key,
                   token=args.token) as client:
        for name, request in requests().items():
            result = client.render(request)
            save(args.out / f"{name}.npz", result)
            if args.save_requests:
                (args.out / f"{name}.request.pb").write_bytes(request.SerializeToString())
            vis = result["visibility"].data
            seen = ~np.isnan(vis)
            print(f"{name}: {result.header.light_fits[0].light_case}; "
                  f"{100 * np.mean(vis[seen] < 0.5):.1f}% of {seen.sum()} seen pixels in shadow")
            for t in result.textures:
                extra = f" faces {[f.name for f in t.cube_faces]}" if t.cube_faces else ""
                print(f"  {t.name}: {t.data.shape} {t.data.dtype}{extra}")


if __name__ == "__main__":
    main()
