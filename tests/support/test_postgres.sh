#!/usr/bin/env bash
# The PostgreSQL cluster CTest's tests share (the `postgres` fixture):
#   test_postgres.sh start FILE  a fresh cluster (fsync off) with the database `attest` in a new
#                                folder under $TMPDIR (the server's user, not root, must reach
#                                it), whose path is written to FILE
#   test_postgres.sh stop FILE   stops that cluster and removes its folder and FILE
# A CTest run that is killed or interrupted never runs the stop: `start` also leaves a watcher (in
# a session of its own, so a kill of CTest's process group spares it) that polls the process that
# ran it — CTest — and, once that is gone, stops the cluster if FILE still names it.
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
# watch FILE DIR OWNER: the watcher (see above).
watch_owner() {
  local dir=$1 owner=$2
  while kill -0 "$owner" 2>/dev/null; do
    # Stopped by the fixture, or FILE taken over by another run's cluster: nothing left to do.
    [ "$(cat "$file" 2>/dev/null)" = "$dir" ] || exit 0
    sleep 2
  done
  [ "$(cat "$file" 2>/dev/null)" = "$dir" ] && stop_listed
  exit 0
}
case "$action" in
  watch)
    watch_owner "${3:?DIR}" "${4:?OWNER}"
    ;;
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
    setsid bash "$0" watch "$file" "$dir" "$PPID" </dev/null >/dev/null 2>&1 &
    echo "test_postgres: server for the tests at ${url%/*}/attest"
    ;;
  stop)
    stop_listed
    ;;
  *) echo "test_postgres: unknown action '$action'" >&2; exit 2 ;;
esac
