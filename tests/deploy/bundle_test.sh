#!/usr/bin/env bash
# The bundle in a minimal bookworm root that has only PoCL (root.sh): unpacked in
# /opt/shadow-service, its server serves builtin:demo to its shadowctl (serve_in_root.sh). The
# launchers keep the root's own C++ runtime, which has every version the bundle needs; told of a
# version the root lacks, they take the bundle's fallback copies, and those serve as well.
#   bundle_test.sh DIST ROOT.tar WORK
set -euo pipefail
dist=$1 tarball=$2 work=$3
here=$(cd "$(dirname "$0")" && pwd)
[ "$(id -u)" -eq 0 ] || { echo "bundle test: needs root (chroot): skipped"; exit 77; }
bundles=("$dist"/shadow-service-*-linux-x86_64.tar.xz)
[ ${#bundles[@]} -eq 1 ] && [ -f "${bundles[0]}" ] || { echo "no single bundle in $dist" >&2; exit 1; }
root=$work/bundle-root
prefix=$root/opt/shadow-service
start=$SECONDS
umount -l "$root/proc" "$root/sys" 2> /dev/null || true  # left by a killed run
rm -rf --one-file-system "$root"
mkdir -p "$prefix"
tar -C "$root" -xf "$tarball"
tar -C "$prefix" --strip-components=1 -xJf "${bundles[0]}"
echo "bundle test: root and bundle unpacked in $((SECONDS - start)) s"
# The root has no library of the project's but what the bundle brings.
for lib in libgrpc++.so libOpenImageIO.so libprotobuf.so libembree3.so; do
  ! ls "$root"/usr/lib/x86_64-linux-gnu/$lib* 2> /dev/null || { echo "the root has $lib" >&2; exit 1; }
done

log=$work/bundle-serve.log
bash "$here/serve_in_root.sh" "$root" "$work/pocl-cache" SHADOW_BUNDLE_VERBOSE=1 -- \
  /opt/shadow-service/bin/shadow-server --listen 127.0.0.1:0 2>&1 | tee "$log"
grep -q "C++ runtime: system" "$log" || { echo "the launcher did not keep the root's C++ runtime" >&2; exit 1; }

echo "libstdc++.so.6 GLIBCXX_3.4.99" >> "$prefix/lib/fallback/needs"
bash "$here/serve_in_root.sh" "$root" "$work/pocl-cache" SHADOW_BUNDLE_VERBOSE=1 -- \
  /opt/shadow-service/bin/shadow-server --listen 127.0.0.1:0 2>&1 | tee "$log"
grep -q "C++ runtime: bundled" "$log" || { echo "the launcher did not fall back" >&2; exit 1; }
rm -rf --one-file-system "$root"
echo "bundle test: passed in $((SECONDS - start)) s"
