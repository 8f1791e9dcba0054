#!/usr/bin/env bash
# Runs one of the deploy blocks (the sh block after its marker, `<!-- deploy-NAME:`: tls in
# README.md, nginx in docs/usage.md) as a user would paste it at the repository's root, with the
# built shadow-server and shadowctl on PATH, in a scratch copy of deploy/, and checks what it made.
#   tls:   one replica with TLS and tokens (a free PORT): the render wrote its files, the
#          statistics name the token's tenant, the log is JSON.
#   nginx: three replicas behind deploy/nginx.conf, then the same three with round_robin (free
#          ports swapped for 5006x in the block and the config): both renders wrote the same
#          visibility pixels (idiff), nginx logged the Render call with its replica and scene id.
# Usage: readme_deploy_test.sh README.md|docs/usage.md SERVER_DIR SHADOWCTL_DIR tls|nginx
set -euo pipefail
readme=$1
export PATH="$2:$3:$PATH"
which=$4
repo=$(cd "$(dirname "$readme")" && pwd)
[ -d "$repo/deploy" ] || repo=$(dirname "$repo")  # docs/usage.md
work=$(mktemp -d)
cleanup() {
  for f in "$work/run/tls/server.pid" "$work/run/nginx/pids"; do
    [ -f "$f" ] && kill $(cat "$f") 2>/dev/null || true
  done
  rm -rf "$work"
}
trap cleanup EXIT
block=$(awk -v marker="<!-- deploy-$which:" 'index($0, marker) == 1 {found=1; next}
             found && /^```sh/ {inside=1; next} inside && /^```/ {exit} inside {print}' "$readme")
[ -n "$block" ] || { echo "no deploy-$which block in $readme"; exit 1; }
free_port() {
  python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}
cp -r "$repo/deploy" "$work/deploy"
cd "$work"

case $which in
tls)
  PORT=$(free_port)
  export PORT
  timeout 300 bash -euo pipefail -c "$block" > stdout.txt
  cat stdout.txt
  test -s run/tls/out/visibility.exr
  grep -q '"tenant": "farm"' stdout.txt
  grep -q '"code": "OK"' stdout.txt
  grep -q '^{"event":"render","tenant":"farm"' run/tls/server.log
  ;;
nginx)
  # Four free ports P0..P3 (below the ephemeral range) to stand for 50060..50063.
  prefix=""
  for p in $(shuf -i 2000-3199 -n 50); do
    if python3 -c "
import socket, sys
for i in range(4):
    s = socket.socket(); s.bind(('127.0.0.1', int('$p' + str(i)))); s.close()" 2>/dev/null; then
      prefix=$p
      break
    fi
  done
  [ -n "$prefix" ] || { echo "no four free ports"; exit 1; }
  echo "ports ${prefix}0..${prefix}3 stand for 50060..50063"
  sed -i "s/5006/$prefix/g" deploy/nginx.conf
  block=${block//5006/$prefix}
  timeout 300 bash -euo pipefail -c "$block" > stdout.txt
  cat stdout.txt
  # Same pixels, exactly (the files' headers carry the time they were written).
  idiff -fail 0 -warn 0 run/out-nginx/visibility.exr run/out-round-robin/visibility.exr
  grep -E "/Render .* 200 .*upstream=127\.0\.0\.1:${prefix}[123] scene=[0-9a-f]{64} " \
    run/nginx/logs/access.log
  # Two renders in all (one through nginx, one direct), each logged by the replica that served it.
  test "$(cat run/nginx/replica*.log | grep -c '"event":"render"')" -eq 2
  ;;
*)
  echo "unknown block $which"
  exit 1
  ;;
esac
echo "readme deploy-$which block: passed"
