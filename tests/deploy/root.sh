#!/usr/bin/env bash
# Makes (once) the minimal Debian bookworm root the bundle and image tests serve from: minbase
# and an OpenCL driver, PoCL, with its kernel compiler; no build packages, nothing of the
# project. Cached as a tarball (delete it to refresh the packages).
#   root.sh ROOT.tar
set -euo pipefail
tarball=$1
[ "$(id -u)" -eq 0 ] || { echo "root: needs root (mmdebstrap, chroot): skipped"; exit 77; }
if [ -s "$tarball" ]; then echo "root: cached $tarball"; exit 0; fi
mkdir -p "$(dirname "$tarball")"
rm -f "$tarball.part"
start=$SECONDS
mmdebstrap --format=tar --variant=minbase --include=pocl-opencl-icd bookworm "$tarball.part" 2>&1 | tail -n 20
mv "$tarball.part" "$tarball"
echo "root: made $tarball in $((SECONDS - start)) s"
