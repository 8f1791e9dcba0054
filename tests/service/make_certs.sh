#!/usr/bin/env bash
# Makes throw-away certificates for the TLS tests in directory $1 with openssl: a CA, a server
# certificate for localhost / 127.0.0.1 and a client certificate signed by it, and a second CA
# with a client certificate of its own (the "wrong CA").
set -euo pipefail
dir=$1
mkdir -p "$dir"
cd "$dir"
quiet() { "$@" >/dev/null 2>&1 || { echo "make_certs: failed: $*" >&2; exit 1; }; }
for ca in ca other_ca; do
  quiet openssl req -x509 -newkey rsa:2048 -nodes -days 2 -subj "/CN=shadow test $ca" \
    -keyout "$ca.key" -out "$ca.pem"
done
# name, signing CA, extensions
sign() {
  quiet openssl req -newkey rsa:2048 -nodes -subj "/CN=$1" -keyout "$1.key" -out "$1.csr"
  printf '%s\n' "$3" >"$1.ext"
  quiet openssl x509 -req -in "$1.csr" -CA "$2.pem" -CAkey "$2.key" -CAcreateserial -days 2 \
    -extfile "$1.ext" -out "$1.pem"
}
sign server ca "subjectAltName=DNS:localhost,IP:127.0.0.1"
sign client ca "extendedKeyUsage=clientAuth"
sign other_client other_ca "extendedKeyUsage=clientAuth"
