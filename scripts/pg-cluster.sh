#!/usr/bin/env bash
# A throwaway PostgreSQL cluster on 127.0.0.1, for the tests and the sync benchmark (Debian's
# `postgresql` package: initdb, pg_ctl). Not a way to run a class server: see the README for that.
#
#   pg-cluster.sh start DIR [PORT]   initdb into DIR (once) and start; prints the superuser's URL
#   pg-cluster.sh stop DIR           fast shutdown (open connections are cut)
#   pg-cluster.sh restart DIR        start again a cluster made by `start`, on the same port
#   pg-cluster.sh url DIR            prints the URL again
#
# The superuser is `at` with a random password (scram-sha-256; only loopback TCP is listened on,
# no Unix socket outside DIR). PostgreSQL refuses to run as root: called as root, the cluster is
# made and run as the unprivileged user $AT_PG_USER (default `nobody`). With PORT omitted a free
# port in 20000..39999 is chosen. Durability settings are PostgreSQL's defaults unless
# AT_PG_FAST=1 at `start` (fsync off: for tests only; `restart` keeps the choice). The server takes
# AT_PG_MAX_CONNECTIONS clients at once (default 300; Debian's own default is 100). Exit status 0 on success; on failure one line on
# stderr says why (e.g. no PostgreSQL installed) and the status is 2, so callers can skip.
set -euo pipefail

die() { echo "pg-cluster: $*" >&2; exit 2; }

action=${1:-}
dir=${2:-}
[ -n "$action" ] && [ -n "$dir" ] || die "usage: pg-cluster.sh start|stop|restart|url DIR [PORT]"

bindir=""
for candidate in $(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V -r); do
  if [ -x "$candidate/initdb" ] && [ -x "$candidate/pg_ctl" ]; then bindir=$candidate; break; fi
done
[ -n "$bindir" ] || die "no PostgreSQL server installed (Debian package 'postgresql')"

# Runs a PostgreSQL program as the cluster's owner.
as_owner() {
  if [ "$(id -u)" -eq 0 ]; then
    setpriv --reuid="$owner" --regid="$(id -g "$owner")" --clear-groups -- "$@"
  else
    "$@"
  fi
}
owner=${AT_PG_USER:-nobody}
[ "$(id -u)" -ne 0 ] || id "$owner" > /dev/null 2>&1 || die "user '$owner' does not exist (set AT_PG_USER)"

data="$dir/data"
url_of() { echo "postgresql://at:$(cat "$dir/password")@127.0.0.1:$(cat "$dir/port")/postgres"; }

start_on() {  # start_on PORT: 0 when the server runs
  local port=$1
  local options="-c listen_addresses=127.0.0.1 -p $port -c unix_socket_directories=$dir -c max_connections=$(cat "$dir/max_connections" 2>/dev/null || echo 300)"
  if [ "$(cat "$dir/fast" 2>/dev/null)" = 1 ]; then
    options="$options -c fsync=off -c synchronous_commit=off -c full_page_writes=off"
  fi
  as_owner "$bindir/pg_ctl" -D "$data" -l "$dir/server.log" -w -t 60 -o "$options" start > /dev/null 2>&1
}

case "$action" in
  start)
    mkdir -p "$dir"
    echo "${AT_PG_FAST:-0}" > "$dir/fast"
    echo "${AT_PG_MAX_CONNECTIONS:-300}" > "$dir/max_connections"
    if [ ! -d "$data" ]; then
      head -c 18 /dev/urandom | base64 | tr -dc 'A-Za-z0-9' > "$dir/password"
      if [ "$(id -u)" -eq 0 ]; then chown -R "$owner" "$dir"; fi
      chmod 700 "$dir"
      as_owner "$bindir/initdb" -D "$data" -U at --pwfile="$dir/password" --auth=scram-sha-256 -E UTF8 \
        --locale=C.UTF-8 --no-sync --no-instructions > "$dir/initdb.log" 2>&1 \
        || die "initdb failed: $(tail -n 1 "$dir/initdb.log")"
    fi
    if [ -n "${3:-}" ]; then
      echo "$3" > "$dir/port"
      start_on "$3" || die "the server did not start on port $3: $(tail -n 1 "$dir/server.log" 2>/dev/null)"
    else
      started=0
      for _ in 1 2 3 4 5 6 7 8; do
        port=$((20000 + RANDOM % 20000))
        echo "$port" > "$dir/port"
        if start_on "$port"; then started=1; break; fi
      done
      [ "$started" = 1 ] || die "the server did not start: $(tail -n 1 "$dir/server.log" 2>/dev/null)"
    fi
    url_of
    ;;
  stop)
    as_owner "$bindir/pg_ctl" -D "$data" -m fast -w stop > /dev/null 2>&1 || die "no server running in $dir"
    ;;
  restart)
    [ -f "$dir/port" ] || die "no cluster in $dir"
    start_on "$(cat "$dir/port")" || die "the server did not start again: $(tail -n 1 "$dir/server.log")"
    url_of
    ;;
  url)
    [ -f "$dir/port" ] || die "no cluster in $dir"
    url_of
    ;;
  *) die "unknown action '$action' (start, stop, restart, url)" ;;
esac
