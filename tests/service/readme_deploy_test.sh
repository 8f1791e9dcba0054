#!/usr/bin/env bash
# Runs the README's "Deploying" block (the sh block after the deploy-tls marker) as a user would
# paste it, with the built shadow-server and shadowctl on PATH and a free port, then checks that
# the render wrote its files, the statistics name the token's tenant, and the log is JSON.
# Usage: readme_deploy_test.sh README.md SERVER_DIR SHADOWCTL_DIR
set -euo pipefail
readme=$1
export PATH="$2:$3:$PATH"
work=$(mktemp -d)
cleanup() {
  [ -f "$work/deploy/server.pid" ] && kill "$(cat "$work/deploy/server.pid")" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
block=$(awk '/<!-- deploy-tls:/ {found=1; next} found && /^```sh/ {inside=1; next}
             inside && /^```/ {exit} inside {print}' "$readme")
[ -n "$block" ] || { echo "no deploy block in $readme"; exit 1; }
PORT=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export PORT
cd "$work"
timeout 300 bash -euo pipefail -c "$block" > stdout.txt
cat stdout.txt
test -s deploy/out/visibility.exr
grep -q '"tenant": "farm"' stdout.txt
grep -q '"code": "OK"' stdout.txt
grep -q '^{"event":"render","tenant":"farm"' deploy/server.log
echo "readme deploy block: passed"
