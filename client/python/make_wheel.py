#!/usr/bin/env python3
"""Packs the staged shadow_client package (build/client/python/shadow_client: the sources and
the stubs CMake generated with Debian's protoc and grpc_python_plugin) into a pure-Python wheel
that `pip install` takes, with the standard library alone: a wheel is a zip with a .dist-info
folder (PEP 427), and this package has nothing to compile, so no build backend is needed.

    make_wheel.py --package build/client/python/shadow_client --version "$(git describe ...)" \
        --out dist/

--version takes `git describe --tags --always --dirty` output and writes it as a PEP 440
version: v1.2.3 -> 1.2.3, v1.2.3-4-gabc1234 -> 1.2.3.post4+gabc1234, abc1234 (no tag yet) ->
0+gabc1234; -dirty adds a .dirty local part. Prints the wheel's path.
"""

import argparse
import base64
import hashlib
import pathlib
import re
import zipfile

NAME = "shadow_client"
# What the generated stubs import: protoc 3.21's builder API (protobuf >= 3.20) and grpcio.
REQUIRES = ["grpcio>=1.51", "protobuf>=3.20", "numpy"]


def pep440(describe: str) -> str:
    m = re.fullmatch(r"v?(\d+(?:\.\d+)*)(?:-(\d+)-g([0-9a-f]+))?(-dirty)?", describe)
    if m:
        version, distance, commit, dirty = m.groups()
        local = [f"g{commit}"] if commit else []
        if distance:
            version += f".post{distance}"
    else:
        m = re.fullmatch(r"([0-9a-f]+)(-dirty)?", describe)
        if not m:
            raise SystemExit(f"make_wheel: cannot read a version from '{describe}'")
        version, local, dirty = "0", [f"g{m.group(1)}"], m.group(2)
    if dirty:
        local.append("dirty")
    return version + ("+" + ".".join(local) if local else "")


def record_hash(data: bytes) -> str:
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=")
    return "sha256=" + digest.decode()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--package", required=True, type=pathlib.Path)
    parser.add_argument("--version", required=True)
    parser.add_argument("--out", required=True, type=pathlib.Path)
    args = parser.parse_args()

    stubs = args.package / "_proto/shadow/v1"
    if not (stubs / "shadow_pb2.py").is_file() or not (stubs / "shadow_pb2_grpc.py").is_file():
        raise SystemExit(f"make_wheel: {stubs} lacks the generated stubs (build the "
                         "shadow_python target first)")
    version = pep440(args.version)
    dist_info = f"{NAME}-{version}.dist-info"
    files = {}
    for path in sorted(args.package.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts and path.suffix != ".pyc":
            files[f"{NAME}/{path.relative_to(args.package).as_posix()}"] = path.read_bytes()
    metadata = [
        "Metadata-Version: 2.1",
        "Name: shadow-client",
        f"Version: {version}",
        "Summary: Python client for shadow-server (gRPC shadow.v1.ShadowService)",
        "Requires-Python: >=3.9",
        *[f"Requires-Dist: {r}" for r in REQUIRES],
    ]
    files[f"{dist_info}/METADATA"] = ("\n".join(metadata) + "\n").encode()
    files[f"{dist_info}/WHEEL"] = ("Wheel-Version: 1.0\nGenerator: make_wheel.py\n"
                                   "Root-Is-Purelib: true\nTag: py3-none-any\n").encode()
    files[f"{dist_info}/top_level.txt"] = f"{NAME}\n".encode()
    record = "".join(f"{name},{record_hash(data)},{len(data)}\n" for name, data in files.items())
    files[f"{dist_info}/RECORD"] = (record + f"{dist_info}/RECORD,,\n").encode()

    args.out.mkdir(parents=True, exist_ok=True)
    wheel = args.out / f"{NAME}-{version}-py3-none-any.whl"
    with zipfile.ZipFile(wheel, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in files.items():
            # Fixed timestamps: the same sources make the same wheel.
            info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
            info.external_attr = 0o644 << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(info, data)
    print(wheel)


if __name__ == "__main__":
    main()
