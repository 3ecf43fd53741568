#!/usr/bin/env bash
# A throwaway PostgreSQL server for the fleet tests (ctest label postgres) and benchmarks: made in a temporary directory,
# listening on its socket there and on 127.0.0.1 at a free port, gone when stopped. Nothing outside that
# directory is touched (no cluster of /etc/postgresql, no systemd). PostgreSQL refuses to run as root:
# as root the server runs as the `postgres` user.
#
#   scripts/pg_throwaway.sh start          prints DIR PORT on success (the socket is in DIR)
#   scripts/pg_throwaway.sh crash DIR      an immediate stop and a start: the server crashes, recovers
#   scripts/pg_throwaway.sh stop DIR       stops it and removes DIR
#
# Authentication: the superuser `postgres` without a password on the socket; every other role with its
# password (scram-sha-256), on the socket and on TCP.
set -euo pipefail
bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1)
[ -x "$bin/pg_ctl" ] || { echo "PostgreSQL's server is not installed (Debian: apt-get install postgresql)" >&2; exit 77; }

owner() { if [ "$(id -u)" = 0 ]; then (cd / && runuser -u postgres -- "$@"); else "$@"; fi; }

options() { # DIR PORT
  echo "-c listen_addresses=127.0.0.1 -p $2 -k $1 -c fsync=off -c full_page_writes=off -c max_connections=40"
}

case "${1:-}" in
start)
  dir=$(mktemp -d /tmp/ballbar-pg-XXXXXX)
  chmod 755 "$dir"
  [ "$(id -u)" = 0 ] && chown postgres:postgres "$dir"
  trap 'rm -rf "$dir"' ERR
  owner "$bin/initdb" -D "$dir/data" -U postgres -A trust -E UTF8 --locale=C.UTF-8 --no-sync >"$dir/initdb.log" 2>&1 ||
    { cat "$dir/initdb.log" >&2; exit 1; }
  printf '%s\n' 'local all postgres trust' 'local all all scram-sha-256' 'host all all 127.0.0.1/32 scram-sha-256' |
    owner tee "$dir/data/pg_hba.conf" >/dev/null
  for try in 1 2 3 4 5 6 7 8; do
    port=$((20000 + RANDOM % 40000))
    if owner "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -t 60 -o "$(options "$dir" "$port")" start >/dev/null; then
      echo "$dir $port" >"$dir/where"
      echo "$dir $port"
      exit 0
    fi
    grep -q "Address already in use\|could not bind" "$dir/server.log" 2>/dev/null || { cat "$dir/server.log" >&2; exit 1; }
  done
  echo "no free port for PostgreSQL after 8 tries" >&2
  exit 1
  ;;
crash)
  dir=${2:?DIR}
  read -r _ port <"$dir/where"
  owner "$bin/pg_ctl" -D "$dir/data" -m immediate -w -t 30 stop >/dev/null
  owner "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -t 60 -o "$(options "$dir" "$port")" start >/dev/null
  ;;
stop)
  dir=${2:?DIR}
  case "$dir" in /tmp/ballbar-pg-*) ;; *) echo "refusing to remove $dir: not a throwaway server's" >&2; exit 2 ;; esac
  [ -f "$dir/data/postmaster.pid" ] && owner "$bin/pg_ctl" -D "$dir/data" -m immediate -w -t 30 stop >/dev/null || true
  rm -rf "$dir"
  ;;
*)
  echo "usage: pg_throwaway.sh start | crash DIR | stop DIR" >&2
  exit 2
  ;;
esac
