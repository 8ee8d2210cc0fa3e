#!/usr/bin/env bash
# A class's answers through the offline-first outbox to a class server that is stopped and started
# again in the middle: outbox_sync_bench against a throwaway PostgreSQL server with PostgreSQL's
# default durability (fsync on, synchronous commit; scripts/pg-cluster.sh, as `nobody` when root).
#
#   bench/outbox_sync_bench.sh [BUILD_DIR] [STUDENTS] [ANSWERS] [WORKERS]   (defaults: build 200 50 16)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
students=${2:-200}
answers=${3:-50}
workers=${4:-16}
bench="$build/bench/outbox_sync_bench"
[ -x "$bench" ] || { echo "outbox_sync_bench: build it first (ninja -C $build outbox_sync_bench)" >&2; exit 2; }

cluster=$(mktemp -d /tmp/at-pg-sync-XXXXXX)
clients=$(mktemp -d /tmp/at-sync-clients-XXXXXX)
cleanup() {
  "$here/scripts/pg-cluster.sh" stop "$cluster" 2>/dev/null || true
  rm -rf "$cluster" "$clients"
}
trap cleanup EXIT
url=$("$here/scripts/pg-cluster.sh" start "$cluster")
"$bench" --server "$url" --dir "$clients" --students "$students" --answers "$answers" --workers "$workers" \
  --stop-command "$here/scripts/pg-cluster.sh stop $cluster" \
  --start-command "$here/scripts/pg-cluster.sh restart $cluster > /dev/null" --down-seconds 3
