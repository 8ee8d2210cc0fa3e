#!/usr/bin/env bash
# 200 lab machines on one class server: class_server_bench against a throwaway PostgreSQL server
# with Debian's default max_connections (100) and PostgreSQL's default durability (fsync on,
# synchronous commit), first directly (machines beyond the server's slots are refused), then
# through PgBouncer in transaction mode (scripts/pgbouncer.sh; 20 server connections).
#
#   bench/lab_machines_bench.sh [BUILD_DIR] [MACHINES] [THINK_MS] [PARTICIPANTS_PER_MACHINE]
#                                               (defaults: build 200 2000 1)
# THINK_MS: each machine commits after a random 0.5–1.5 × THINK_MS, as a person rating items does.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
machines=${2:-200}
think=${3:-2000}
participants=${4:-1}
bench="$build/bench/class_server_bench"
[ -x "$bench" ] || { echo "class_server_bench: build it first (ninja -C $build class_server_bench)" >&2; exit 2; }

cluster=$(mktemp -d /tmp/at-pg-lab-XXXXXX)
bouncer=$(mktemp -d /tmp/at-pgbouncer-lab-XXXXXX)
cleanup() {
  "$here/scripts/pgbouncer.sh" stop "$bouncer" 2>/dev/null || true
  "$here/scripts/pg-cluster.sh" stop "$cluster" 2>/dev/null || true
  rm -rf "$cluster" "$bouncer"
}
trap cleanup EXIT
url=$(AT_PG_MAX_CONNECTIONS=100 "$here/scripts/pg-cluster.sh" start "$cluster")
pooled=$(AT_PGB_POOL_SIZE=20 "$here/scripts/pgbouncer.sh" start "$bouncer" "$url")
ulimit -n 4096 2>/dev/null || true
echo "# directly to PostgreSQL (max_connections = 100)"
"$bench" --db "$url" --clients "$machines" --participants-per-client "$participants" --think-ms "$think" || true
echo "# through PgBouncer (transaction mode, 20 server connections)"
"$bench" --db "$pooled" --clients "$machines" --participants-per-client "$participants" --think-ms "$think"
