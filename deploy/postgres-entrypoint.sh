#!/bin/sh
# fleet-postgres: the entry point of localhost/fleet-postgres (deploy/postgres.Containerfile). On
# the first start (an empty /var/lib/postgresql/data) makes the database cluster with the user
# `fleet`, whose password is FLEET_PG_PASSWORD (required then), reachable over the network with
# scram-sha-256; then runs the server in the foreground (SIGTERM: a fast shutdown). The fleet's
# services create their own tables (docs/operator-guide.md#standby-managers-on-postgresql).
set -eu
PGDATA=/var/lib/postgresql/data
BIN=/usr/lib/postgresql/15/bin
if [ ! -s "$PGDATA/PG_VERSION" ]; then
  if [ -z "${FLEET_PG_PASSWORD:-}" ]; then
    echo "fleet-postgres: set FLEET_PG_PASSWORD (the password of the database user fleet) for the first start" >&2
    exit 2
  fi
  pw=$(mktemp)
  printf '%s\n' "$FLEET_PG_PASSWORD" >"$pw"
  "$BIN/initdb" -D "$PGDATA" -U fleet --pwfile="$pw" --auth-local=trust --auth-host=scram-sha-256 \
    --no-locale -E UTF8 >/dev/null
  rm -f "$pw"
  printf 'host all all 0.0.0.0/0 scram-sha-256\nhost all all ::/0 scram-sha-256\n' >>"$PGDATA/pg_hba.conf"
  echo "fleet-postgres: made the database cluster in $PGDATA"
fi
exec "$BIN/postgres" -D "$PGDATA" -c listen_addresses='*' -c unix_socket_directories=/tmp
