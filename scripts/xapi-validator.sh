#!/usr/bin/env bash
# The xAPI validator the tests run: npm's @learninglocker/xapi-validation (the version pinned by
# scripts/xapi-validator/package-lock.json) under Node.js (Debian's nodejs and npm, installed by
# scripts/install-deps.sh), plus validate.js's RFC 4122 check of ids and registrations.
#
#   xapi-validator.sh install          npm ci into $AT_XAPI_VALIDATOR_DIR (default .cache/xapi-validator,
#                                      ignored by git); nothing to do when the lockfile's packages are there
#   xapi-validator.sh validate FILE…   validate statements (JSON arrays); exit 1 with one line per problem
#
# Exit status 2 with one line on stderr when Node.js or npm is missing, or the install fails.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
dir=${AT_XAPI_VALIDATOR_DIR:-$here/../.cache/xapi-validator}
die() { echo "xapi-validator: $*" >&2; exit 2; }
command -v node > /dev/null 2>&1 || die "Node.js is not installed (Debian package 'nodejs'; scripts/install-deps.sh)"

install() {
  command -v npm > /dev/null 2>&1 || die "npm is not installed (Debian package 'npm'; scripts/install-deps.sh)"
  mkdir -p "$dir"
  if [ -f "$dir/installed.lock" ] && cmp -s "$dir/installed.lock" "$here/xapi-validator/package-lock.json" &&
     [ -d "$dir/node_modules/@learninglocker/xapi-validation" ]; then
    return 0
  fi
  cp "$here/xapi-validator/package.json" "$here/xapi-validator/package-lock.json" "$dir/"
  (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error > "$dir/npm.log" 2>&1) ||
    die "npm ci failed in $dir: $(tail -n 1 "$dir/npm.log")"
  cp "$here/xapi-validator/package-lock.json" "$dir/installed.lock"
}

case "${1:-}" in
  install) install ;;
  validate)
    shift
    [ $# -gt 0 ] || die "usage: xapi-validator.sh validate FILE.json..."
    install
    NODE_PATH="$dir/node_modules" node "$here/xapi-validator/validate.js" "$@"
    ;;
  *) die "usage: xapi-validator.sh install | validate FILE.json..." ;;
esac
