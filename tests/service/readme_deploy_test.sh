#!/usr/bin/env bash
# Runs one of the deploy blocks (the sh block after its marker, `<!-- deploy-NAME:`: tls in
# README.md, nginx in docs/usage.md) as a user would paste it at the repository's root, with the
# built shadow-server and shadowctl on PATH, in a scratch copy of deploy/, and checks what it made.
#   tls:   one replica with TLS and tokens (a free PORT): the render wrote its files, the
#          statistics name the token's tenant, the log is JSON.
#   nginx: three replicas behind deploy/nginx.conf, then the same three with round_robin (free
#          ports swapped for 5006x in the block and the config): both renders wrote the same
#          visibility pixels (idiff), nginx logged the Render call with its replica and scene id.
# And their failure paths (issue 54), in the shell a user pastes them into, with the server's
# port taken: the block gives up with the server's log instead of waiting for ever, and leaves
# the shell running in the directory it started in.
#   try-it-taken: README's "Try it" block (marker `<!-- try-it:`).
#   tls-taken:    the tls block.
# Usage: readme_deploy_test.sh README.md|docs/usage.md SERVER_DIR SHADOWCTL_DIR
#        tls|nginx|try-it-taken|tls-taken
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
marker="<!-- deploy-${which%-taken}:"
[ "$which" = try-it-taken ] && marker="<!-- try-it:"
block=$(awk -v marker="$marker" 'index($0, marker) == 1 {found=1; next}
             found && /^```sh/ {inside=1; next} inside && /^```/ {exit} inside {print}' "$readme")
[ -n "$block" ] || { echo "no '$marker' block in $readme"; exit 1; }
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
  grep -qE '^  farm +[0-9]+ requests' stdout.txt
  grep -qE '^requests: (.*, )?OK [0-9]' stdout.txt
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
try-it-taken | tls-taken)
  # A port that something else holds (bound, not listening: calls to it are refused at once):
  # the server cannot listen and exits.
  PORT=$(free_port)
  export PORT
  python3 -c "import socket, time
s = socket.socket(); s.bind(('127.0.0.1', $PORT)); time.sleep(300)" &
  holder=$!
  trap 'kill $holder 2>/dev/null || true; cleanup' EXIT
  sleep 0.5
  block=${block//50051/$PORT}
  # As pasted into an interactive shell: no -e, and what follows the block still runs.
  start=$SECONDS
  set +e
  timeout 200 bash -c "$block
echo \"still in the shell, in \$PWD\"" > stdout.txt 2>&1
  rc=$?
  set -e
  cat stdout.txt
  [ $rc -ne 124 ] || { echo "the block waited for a server that had exited"; exit 1; }
  grep -q "cannot listen on 127.0.0.1:$PORT" stdout.txt
  grep -qx "still in the shell, in $work" stdout.txt
  echo "gave up in $((SECONDS - start)) s"
  ;;
*)
  echo "unknown block $which"
  exit 1
  ;;
esac
echo "readme deploy-$which block: passed"
