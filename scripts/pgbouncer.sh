#!/usr/bin/env bash
# PgBouncer (Debian's `pgbouncer`) in front of a class server, in transaction mode: hundreds of lab
# machines keep a connection each to the pooler, which runs their transactions on a few server
# connections (PostgreSQL's max_connections, 100 on Debian, is never reached).
#
#   pgbouncer.sh start DIR PG_URL [PORT]   write DIR/pgbouncer.ini (once) and start; prints the pooled URL
#   pgbouncer.sh stop DIR                  stop it (clients' connections are cut)
#   pgbouncer.sh url DIR                   prints the pooled URL again
#
# PG_URL is postgresql://USER:PASSWORD@HOST:PORT/DB of a login allowed to read pg_authid (the
# server's superuser, or a role given that right): PgBouncer logs in as it only to look up the
# password of whoever connects (auth_query), so every person's own login works through the pooler
# with the same password as on the server. The pooled URL is PG_URL with PgBouncer's address; give
# the lab machines that URL with their own login instead of USER.
#
# Settings (environment, read at the first `start`): AT_PGB_POOL_SIZE server connections per
# database and login (default 20), AT_PGB_MAX_CLIENTS client connections (default 1000; the process
# needs that many file descriptors: `ulimit -n` is raised to match). Listens on 127.0.0.1 unless
# AT_PGB_LISTEN says otherwise (e.g. 0.0.0.0 on a class server). With PORT omitted a free port in
# 40000..59999 is chosen. PgBouncer refuses to run as root: called as root, it runs as the
# unprivileged user $AT_PG_USER (default `nobody`), as scripts/pg-cluster.sh does. Exit status 0
# on success; on failure one line on stderr says why and the status is 2, so callers can skip.
set -euo pipefail

die() { echo "pgbouncer: $*" >&2; exit 2; }

action=${1:-}
dir=${2:-}
[ -n "$action" ] && [ -n "$dir" ] || die "usage: pgbouncer.sh start DIR PG_URL [PORT] | stop DIR | url DIR"

binary=$(command -v pgbouncer || true)
[ -n "$binary" ] || [ ! -x /usr/sbin/pgbouncer ] || binary=/usr/sbin/pgbouncer
[ -n "$binary" ] || die "PgBouncer is not installed (Debian package 'pgbouncer'; scripts/install-deps.sh installs it)"

owner=${AT_PG_USER:-nobody}
as_owner() {
  if [ "$(id -u)" -eq 0 ]; then
    setpriv --reuid="$owner" --regid="$(id -g "$owner")" --clear-groups -- "$@"
  else
    "$@"
  fi
}
[ "$(id -u)" -ne 0 ] || id "$owner" > /dev/null 2>&1 || die "user '$owner' does not exist (set AT_PG_USER)"

# postgresql://USER:PASSWORD@HOST:PORT/DB → the parts (no URL escapes in the password: the tests'
# and the README's passwords are letters and digits).
parse_url() {
  local rest=${1#postgresql://}
  [ "$rest" != "$1" ] || rest=${1#postgres://}
  [ "$rest" != "$1" ] || die "PG_URL must start with postgresql:// (got '${1%%:*}…')"
  local auth=${rest%%@*} hostpart=${rest#*@}
  [ "$auth" != "$rest" ] || die "PG_URL must name a login and its password (postgresql://USER:PASSWORD@HOST:PORT/DB)"
  pg_user=${auth%%:*}
  pg_password=${auth#*:}
  [ "$pg_password" != "$auth" ] || die "PG_URL must carry the login's password (postgresql://USER:PASSWORD@…)"
  local hostport=${hostpart%%/*}
  pg_db=${hostpart#*/}
  [ "$pg_db" != "$hostpart" ] && [ -n "$pg_db" ] || die "PG_URL must name a database (…/DB)"
  pg_db=${pg_db%%\?*}
  pg_host=${hostport%%:*}
  pg_port=${hostport#*:}
  [ "$pg_port" != "$hostport" ] || pg_port=5432
}

pooled_url() {
  parse_url "$(cat "$dir/server_url")"
  local host=${AT_PGB_LISTEN:-127.0.0.1}
  [ "$host" != 0.0.0.0 ] || host=$(hostname -f 2>/dev/null || hostname)
  echo "postgresql://$pg_user:$pg_password@$host:$(cat "$dir/port")/$pg_db"
}

write_config() {  # write_config PORT
  parse_url "$(cat "$dir/server_url")"
  local max_clients=${AT_PGB_MAX_CLIENTS:-1000}
  # The login PgBouncer looks passwords up with is the one line of its auth file.
  printf '"%s" "%s"\n' "$pg_user" "$pg_password" > "$dir/userlist.txt"
  cat > "$dir/pgbouncer.ini" <<EOF
;; written by scripts/pgbouncer.sh
[databases]
* = host=$pg_host port=$pg_port auth_user=$pg_user

[pgbouncer]
listen_addr = ${AT_PGB_LISTEN:-127.0.0.1}
listen_port = $1
unix_socket_dir =
pool_mode = transaction
auth_type = scram-sha-256
auth_file = $dir/userlist.txt
auth_user = $pg_user
auth_query = SELECT rolname, CASE WHEN rolvaliduntil < now() THEN NULL ELSE rolpassword END FROM pg_authid WHERE rolname = \$1 AND rolcanlogin
max_client_conn = $max_clients
default_pool_size = ${AT_PGB_POOL_SIZE:-20}
max_db_connections = 0
server_reset_query =
ignore_startup_parameters = extra_float_digits
logfile = $dir/pgbouncer.log
pidfile = $dir/pgbouncer.pid
EOF
}

start_on() {  # start_on PORT: 0 when PgBouncer answers
  local port=$1
  write_config "$port"
  echo "$port" > "$dir/port"
  rm -f "$dir/pgbouncer.pid"
  if [ "$(id -u)" -eq 0 ]; then chown -R "$owner" "$dir"; fi
  local max_clients=${AT_PGB_MAX_CLIENTS:-1000}
  ulimit -n $((max_clients + 100)) 2> /dev/null || ulimit -n "$(ulimit -Hn)"
  as_owner "$binary" -d -q "$dir/pgbouncer.ini" > /dev/null 2>&1 || return 1
  for _ in $(seq 50); do
    if [ -s "$dir/pgbouncer.pid" ] && kill -0 "$(cat "$dir/pgbouncer.pid")" 2> /dev/null &&
       (exec 3<> "/dev/tcp/127.0.0.1/$port") 2> /dev/null; then
      return 0
    fi
    sleep 0.1
  done
  return 1
}

case "$action" in
  start)
    url=${3:-}
    [ -n "$url" ] || [ -f "$dir/server_url" ] || die "usage: pgbouncer.sh start DIR PG_URL [PORT]"
    mkdir -p "$dir"
    chmod 700 "$dir"
    [ -z "$url" ] || (umask 077 && echo "$url" > "$dir/server_url")
    parse_url "$(cat "$dir/server_url")"
    if [ -n "${4:-}" ]; then
      start_on "$4" || die "PgBouncer did not start on port $4: $(tail -n 1 "$dir/pgbouncer.log" 2>/dev/null)"
    else
      started=0
      for _ in 1 2 3 4 5 6 7 8; do
        if start_on $((40000 + RANDOM % 20000)); then started=1; break; fi
      done
      [ "$started" = 1 ] || die "PgBouncer did not start: $(tail -n 1 "$dir/pgbouncer.log" 2>/dev/null)"
    fi
    pooled_url
    ;;
  stop)
    [ -s "$dir/pgbouncer.pid" ] || die "no PgBouncer running in $dir"
    pid=$(cat "$dir/pgbouncer.pid")
    kill -INT "$pid" 2> /dev/null || die "no PgBouncer running in $dir (pid $pid)"
    for _ in $(seq 50); do kill -0 "$pid" 2> /dev/null || break; sleep 0.1; done
    ! kill -0 "$pid" 2> /dev/null || kill -KILL "$pid"
    rm -f "$dir/pgbouncer.pid"
    ;;
  url)
    [ -f "$dir/port" ] || die "no PgBouncer set up in $dir"
    pooled_url
    ;;
  *) die "unknown action '$action' (start, stop, url)" ;;
esac
