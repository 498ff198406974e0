#!/bin/sh
# Test certificates for Modbus/TCP Security, made with Debian's openssl the way docs/security.md
# tells an integrator to: a CA, the gateway's server certificate, and client certificates whose
# role travels in the extension 1.3.6.1.4.1.50316.802.1 (an ASN.1 UTF8String).
#
# Usage: tests/support/make_certs.sh DIR
# Writes into DIR (keys mode 0600):
#   ca.pem ca.key                 the plant's CA
#   server.pem server.key         CN=localhost, SAN DNS:localhost, IP:127.0.0.1, IP:::1
#   otherhost.pem otherhost.key   CN=other.example, SAN DNS:other.example: from the CA, but for
#                                 another host than this one
#   viewer / operator / engineer  .pem .key: client certificates with those roles
#   norole.pem norole.key         a client certificate from the CA without the role extension
#   otherca.pem otherca.key       role "operator", signed by another CA (other-ca.pem)
#   expired.pem expired.key       role "operator", from the CA, valid only in 2020
set -eu
dir=$1
mkdir -p "$dir"
cd "$dir"
umask 077

key() { openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$1.key" 2>/dev/null; }

ca() {  # name subject
  key "$1"
  openssl req -x509 -new -key "$1.key" -subj "$2" -days 3650 -out "$1.pem" \
    -addext basicConstraints=critical,CA:TRUE -addext keyUsage=critical,keyCertSign,cRLSign
}

# issue NAME CA ROLE [startdate enddate]: a client certificate; ROLE "-" for none.
issue() {
  name=$1 signer=$2 role=$3
  key "$name"
  {
    echo "basicConstraints = CA:FALSE"
    echo "keyUsage = critical, digitalSignature"
    echo "extendedKeyUsage = clientAuth"
    [ "$role" = "-" ] || echo "1.3.6.1.4.1.50316.802.1 = ASN1:UTF8String:$role"
  } > "$name.ext"
  openssl req -new -key "$name.key" -subj "/O=drivegate test/CN=$name" -out "$name.csr"
  if [ $# -ge 5 ]; then
    # openssl x509 cannot backdate; openssl ca can (-startdate / -enddate).
    mkdir -p "ca-db"
    : > ca-db/index.txt
    echo 01 > ca-db/serial
    cat > ca-db/ca.cnf <<CNF
[ca]
default_ca = test
[test]
database = ca-db/index.txt
serial = ca-db/serial
new_certs_dir = ca-db
default_md = sha256
policy = any
[any]
commonName = supplied
organizationName = optional
CNF
    openssl ca -batch -config ca-db/ca.cnf -cert "$signer.pem" -keyfile "$signer.key" \
      -in "$name.csr" -out "$name.pem" -startdate "$4" -enddate "$5" -extfile "$name.ext" \
      -notext 2>/dev/null
  else
    openssl x509 -req -in "$name.csr" -CA "$signer.pem" -CAkey "$signer.key" -CAcreateserial \
      -days 825 -extfile "$name.ext" -out "$name.pem" 2>/dev/null
  fi
  rm -f "$name.csr" "$name.ext"
}

ca ca "/O=drivegate test/CN=test plant CA"
ca other-ca "/O=somebody else/CN=other CA"

# issue_server NAME CN SAN: a server certificate from the CA.
issue_server() {
  name=$1
  key "$name"
  openssl req -new -key "$name.key" -subj "/O=drivegate test/CN=$2" -out "$name.csr"
  printf '%s\n' "basicConstraints = CA:FALSE" "keyUsage = critical, digitalSignature" \
    "extendedKeyUsage = serverAuth" "subjectAltName = $3" > "$name.ext"
  openssl x509 -req -in "$name.csr" -CA ca.pem -CAkey ca.key -CAcreateserial -days 825 \
    -extfile "$name.ext" -out "$name.pem" 2>/dev/null
  rm -f "$name.csr" "$name.ext"
}

issue_server server localhost "DNS:localhost, IP:127.0.0.1, IP:::1"
issue_server otherhost other.example "DNS:other.example"

issue viewer ca viewer
issue operator ca operator
issue engineer ca engineer
issue norole ca -
issue otherca other-ca operator
issue expired ca operator 20200101000000Z 20201231000000Z
rm -rf ca-db ca.srl other-ca.srl
chmod 0644 ./*.pem
