#!/usr/bin/env bash
# Serves a render from inside a root filesystem that holds nothing of the project but what was
# unpacked into it: chroots there, starts SERVER, renders builtin:demo through the shadowctl beside
# it and checks the files it wrote.
#
#   serve_in_root.sh ROOT POCL_CACHE [VAR=VALUE ...] -- SERVER [ARGS...]
#
# SERVER is a path inside ROOT; VAR=VALUE are set in its environment (which starts empty);
# POCL_CACHE, a folder outside, keeps PoCL's compiled kernels between runs (copied in and out).
# ROOT must have its /dev nodes (mmdebstrap's tarball has them). Only fresh proc (the loader
# reads /proc/self/exe for $ORIGIN) and sysfs (PoCL's hwloc) instances are mounted, in a mount
# namespace of their own: private, so they go with it, where the machine's root allows; inside a
# chroot (CI runs in one) it cannot be made private, and they are unmounted on exit. Nothing
# bound from the machine is mounted, so even a mount left behind by a killed run holds nothing
# that a later `rm -r` could harm.
set -euo pipefail
if [ "${SERVE_IN_ROOT_NAMESPACE:-}" != 1 ]; then
  propagation=private
  unshare --mount --propagation private true 2> /dev/null || propagation=unchanged
  exec unshare --mount --propagation $propagation env SERVE_IN_ROOT_NAMESPACE=1 bash "$0" "$@"
fi
root=$1 cache=$2
shift 2
vars=()
while [ "$1" != -- ]; do vars+=("$1"); shift; done
shift
[ -c "$root/dev/null" ] || { echo "serve: $root/dev has no device nodes" >&2; exit 1; }
mkdir -p "$cache" "$root/var/cache/pocl"
cp -a "$cache/." "$root/var/cache/pocl/"
cleanup() {
  umount -l "$root/proc" "$root/sys" 2> /dev/null || true
  cp -a "$root/var/cache/pocl/." "$cache/" 2> /dev/null || true
}
trap cleanup EXIT
mount -t proc proc "$root/proc"
mount -t sysfs sysfs "$root/sys"

chroot "$root" /usr/bin/env -i HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
  POCL_CACHE_DIR=/var/cache/pocl "${vars[@]}" /bin/sh -s "$@" <<'SCRIPT'
set -eu
shadowctl=$(dirname "$1")/shadowctl
rm -rf /tmp/serve && mkdir -p /tmp/serve && cd /tmp/serve
echo "serve: $*"
: > server.out  # read below before the server may have opened it
"$@" < /dev/null > server.out 2> server.log &
server=$!
address=
i=0
# Up to 5 minutes: a cold start compiles every OpenCL kernel.
while [ $i -lt 3000 ] && [ -z "$address" ]; do
  address=$(sed -n 's/^listening on //p' server.out)
  kill -0 $server 2> /dev/null || { echo "serve: the server exited"; cat server.out server.log; exit 1; }
  [ -n "$address" ] || sleep 0.1
  i=$((i + 1))
done
cat server.out server.log
[ -n "$address" ] || { echo "serve: no 'listening on' line"; kill $server; exit 1; }
"$shadowctl" render --server "$address" --scene builtin:demo --size 640x360 --out out/ < /dev/null
status=0
for f in shadowmap.exr visibility.exr position.exr shadowmap.png visibility.png position.png; do
  if [ -s "out/$f" ]; then echo "serve: out/$f: $(wc -c < "out/$f") bytes"
  else echo "serve: out/$f is missing"; status=1; fi
done
kill $server
wait $server || { echo "serve: the server exited $? on SIGTERM"; status=1; }
exit $status
SCRIPT
