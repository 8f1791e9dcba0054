#!/usr/bin/env bash
# The Python client's wheel (client/python/make_wheel.py, as scripts/bundle makes it) installs
# with pip into a venv that uses Debian's grpcio, protobuf and numpy (--system-site-packages;
# --no-index: nothing is downloaded), and imports there with its generated stubs, away from the
# build tree.
#   wheel_test.sh SOURCE STAGED_PACKAGE WORK PYTHON
set -euo pipefail
source=$1 package=$2 work=$3 python=$4
rm -rf "$work" && mkdir -p "$work"
version=$(git -C "$source" describe --tags --always --dirty 2> /dev/null || echo 0)
wheel=$("$python" "$source/client/python/make_wheel.py" --package "$package" --version "$version" \
        --out "$work/dist")
echo "wheel test: $wheel"
"$python" -m venv --system-site-packages "$work/venv"
"$work/venv/bin/python" -m pip install --no-index --no-cache-dir --quiet "$wheel"
cd "$work"
env -u PYTHONPATH "$work/venv/bin/python" - <<'PY'
import importlib.metadata
import pathlib
import sys

import shadow_client as sc
from shadow_client._proto.shadow.v1 import shadow_pb2_grpc

where = pathlib.Path(sc.__file__).resolve()
assert where.is_relative_to(pathlib.Path(sys.prefix).resolve()), f"imported from {where}"
request = sc.pb.RenderRequest()
assert request.DESCRIPTOR.full_name == "shadow.v1.RenderRequest"
assert hasattr(shadow_pb2_grpc, "ShadowServiceStub")
assert (where.parent / "service_config.json").is_file()
print("wheel test: shadow-client", importlib.metadata.version("shadow-client"), "from", where.parent)
PY
