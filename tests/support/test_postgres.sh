#!/usr/bin/env bash
# The PostgreSQL cluster CTest's tests share (the `postgres` fixture):
#   test_postgres.sh start FILE  a fresh cluster (fsync off) with the database `attest` in a new
#                                folder under $TMPDIR (the server's user, not root, must reach
#                                it), whose path is written to FILE
#   test_postgres.sh stop FILE   stops that cluster and removes its folder and FILE
# Without PostgreSQL installed, `start` prints "SKIPPED: …" and exits 0: the tests that need the
# server then report their own skips.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
cluster="$here/../../scripts/pg-cluster.sh"
action=${1:?start|stop}
file=${2:?FILE}
stop_listed() {
  if [ -f "$file" ]; then
    dir=$(cat "$file")
    if [ -d "$dir" ]; then bash "$cluster" stop "$dir" >/dev/null 2>&1 || true; rm -rf "$dir"; fi
    rm -f "$file"
  fi
}
case "$action" in
  start)
    stop_listed
    dir=$(mktemp -d "${TMPDIR:-/tmp}/at-pg-tests-XXXXXX")
    status=0
    url=$(AT_PG_FAST=1 bash "$cluster" start "$dir" 2>&1) || status=$?
    if [ "$status" -eq 2 ]; then
      rm -rf "$dir"
      echo "SKIPPED: no test PostgreSQL server: $url"
      exit 0
    fi
    [ "$status" -eq 0 ] || { echo "test_postgres: $url" >&2; exit 1; }
    psql -q -X "$url" -c "CREATE DATABASE attest" >/dev/null
    echo "$dir" > "$file"
    echo "test_postgres: server for the tests at ${url%/*}/attest"
    ;;
  stop)
    stop_listed
    ;;
  *) echo "test_postgres: unknown action '$action'" >&2; exit 2 ;;
esac
