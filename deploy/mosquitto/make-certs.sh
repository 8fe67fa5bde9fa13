#!/usr/bin/env bash
# Makes the certificates of the broker's TLS listener: a certificate authority (ca.crt, ca.key) and a server
# certificate signed by it for the broker's host names (server.crt, server.key), in DIR.
#   make-certs.sh DIR [NAME...]      NAME: the host names and IP addresses clients use to reach the broker
#                                    (default: this host's name); localhost and 127.0.0.1 are always added.
# Clients trust ca.crt (`--ca ca.crt`, BrokerOptions.trustedCertificates). An existing CA in DIR is kept, so that
# clients need not be given a new one when the server certificate is made again for other names.
set -euo pipefail

if [ $# -lt 1 ]; then
  echo "usage: $0 DIR [NAME...]" >&2
  exit 2
fi
dir=$1; shift
names=("$@")
[ ${#names[@]} -gt 0 ] || names=("$(hostname -f 2>/dev/null || hostname)")
names+=(localhost 127.0.0.1)

san=""
for n in "${names[@]}"; do
  if [[ $n =~ ^[0-9.]+$ || $n == *:* ]]; then san+="IP:$n,"; else san+="DNS:$n,"; fi
done
san=${san%,}

mkdir -p "$dir"
cd "$dir"
umask 077
# EC keys: small, and quick to make and to handshake with.
if [ ! -f ca.key ] || [ ! -f ca.crt ]; then
  openssl req -x509 -new -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -keyout ca.key -out ca.crt \
    -days 3650 -subj "/CN=PocketBot broker CA" -addext "basicConstraints=critical,CA:TRUE" \
    -addext "keyUsage=critical,keyCertSign,cRLSign" 2>/dev/null
fi
openssl req -new -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -keyout server.key -out server.csr \
  -subj "/CN=${names[0]}" 2>/dev/null
printf 'subjectAltName=%s\nbasicConstraints=CA:FALSE\nkeyUsage=digitalSignature,keyEncipherment\nextendedKeyUsage=serverAuth\n' \
  "$san" > server.ext
openssl x509 -req -in server.csr -CA ca.crt -CAkey ca.key -CAcreateserial -out server.crt -days 825 \
  -extfile server.ext 2>/dev/null
rm -f server.csr server.ext ca.srl
# The broker reads the key; clients need only ca.crt.
chmod 644 ca.crt server.crt
chmod 600 ca.key server.key
echo "made $dir/ca.crt and $dir/server.crt for ${names[*]}"
