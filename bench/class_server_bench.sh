#!/usr/bin/env bash
# Several lab machines writing one study at once: class_server_bench against a throwaway PostgreSQL
# server with PostgreSQL's default durability (fsync on, synchronous commit; scripts/pg-cluster.sh,
# as `nobody` when run as root), then the same clients on one SQLite file for comparison.
#
#   bench/class_server_bench.sh [BUILD_DIR] [CLIENTS]      (defaults: build, 1,3,10)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
clients=${2:-1,3,10}
bench="$build/bench/class_server_bench"
[ -x "$bench" ] || { echo "class_server_bench: build it first (ninja -C $build class_server_bench)" >&2; exit 2; }

cluster=$(mktemp -d /tmp/at-pg-bench-XXXXXX)
sqlite=$(mktemp -d /tmp/at-sqlite-bench-XXXXXX)
cleanup() {
  "$here/scripts/pg-cluster.sh" stop "$cluster" 2>/dev/null || true
  rm -rf "$cluster" "$sqlite"
}
trap cleanup EXIT
url=$("$here/scripts/pg-cluster.sh" start "$cluster")
"$bench" --db "$url" --clients "$clients"
"$bench" --db "$sqlite/class.db" --clients "$clients"
