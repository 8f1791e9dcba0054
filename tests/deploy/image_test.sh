#!/usr/bin/env bash
# scripts/image on the bundle and the tests' bookworm root (root.sh), then the image's root
# filesystem, unpacked by umoci as a container runtime would, serves a render (serve_in_root.sh)
# with the image's own entrypoint and environment, its --listen moved to loopback (as
# Kubernetes' args replace the command).
#   image_test.sh SOURCE DIST ROOT.tar WORK PYTHON
set -euo pipefail
source=$1 dist=$2 tarball=$3 work=$4 python=$5
here=$(cd "$(dirname "$0")" && pwd)
[ "$(id -u)" -eq 0 ] || { echo "image test: needs root (umoci, chroot): skipped"; exit 77; }
bundles=("$dist"/shadow-service-*-linux-x86_64.tar.xz)
[ ${#bundles[@]} -eq 1 ] && [ -f "${bundles[0]}" ] || { echo "no single bundle in $dist" >&2; exit 1; }
start=$SECONDS
rootfs=$work/image-unpacked/rootfs
umount -l "$rootfs/proc" "$rootfs/sys" 2> /dev/null || true  # left by a killed run
rm -rf --one-file-system "$work/image" "$work/image-unpacked"
"$source/scripts/image" --bundle "${bundles[0]}" --base "$tarball" --out "$work/image"
echo "image test: image built in $((SECONDS - start)) s"
layouts=("$work"/image/shadow-service-*-oci)
umoci unpack --image "${layouts[0]}:latest" "$work/image-unpacked" > /dev/null
echo "image test: unpacked in $((SECONDS - start)) s"

# The runtime spec umoci wrote from the image's config: entrypoint + command, environment.
mapfile -t args < <("$python" -c 'import json, sys
print("\n".join(json.load(open(sys.argv[1]))["process"]["args"]))' "$work/image-unpacked/config.json")
mapfile -t vars < <("$python" -c 'import json, sys
print("\n".join(json.load(open(sys.argv[1]))["process"]["env"]))' "$work/image-unpacked/config.json")
echo "image test: args ${args[*]}; env ${vars[*]}"
[ "${args[*]}" = "/opt/shadow-service/bin/shadow-server --listen 0.0.0.0:50051" ] ||
  { echo "the entrypoint is not the server on 0.0.0.0:50051" >&2; exit 1; }
[ "$(cat "$rootfs/etc/OpenCL/vendors/nvidia.icd")" = libnvidia-opencl.so.1 ] ||
  { echo "NVIDIA's ICD is not registered" >&2; exit 1; }
printf '%s\n' "${vars[@]}" | grep -q '^PATH=/opt/shadow-service/bin:' ||
  { echo "the bundle's bin/ is not on PATH" >&2; exit 1; }

# The device nodes a container runtime makes: the image's /dev is empty.
for node in "null 1 3" "zero 1 5" "full 1 7" "random 1 8" "urandom 1 9" "tty 5 0"; do
  read -r name major minor <<< "$node"
  mknod -m 666 "$rootfs/dev/$name" c "$major" "$minor"
done
bash "$here/serve_in_root.sh" "$rootfs" "$work/pocl-cache" "${vars[@]}" -- \
  "${args[0]}" --listen 127.0.0.1:0
rm -rf --one-file-system "$work/image-unpacked" "$work/image"
echo "image test: passed in $((SECONDS - start)) s"
