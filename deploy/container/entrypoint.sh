#!/bin/sh
# Container entrypoint of luxeld (deploy/container/Containerfile, deploy/k8s/).
# Turns environment variables into luxeld's flags and then exec's luxeld, so
# luxeld is PID 1's replacement and receives SIGTERM itself (checkpoint, stop).
#
#   LUXELD_LISTEN          gRPC address            (default 0.0.0.0:50051)
#   LUXELD_DATA_DIR        the data dir, a volume  (default /var/lib/luxel)
#   LUXELD_TOKEN_FILE      bearer token file       (default /run/secrets/luxel-token
#                          when it exists); or LUXELD_TOKEN, read by luxeld itself
#   LUXELD_ALLOW_NO_TOKEN  1: start without a token (refused otherwise, since the
#                          container listens beyond loopback)
#   LUXELD_METRICS_LISTEN  Prometheus address, e.g. 0.0.0.0:9464 (empty: off);
#                          passed as --metrics-listen when this luxeld has it
#   LUXELD_EXTRA_ARGS      more flags, split on spaces; arguments of the
#                          container command are appended as well
#   LUXEL_CACHE_DIR, POCL_CACHE_DIR  compiled OpenCL programs (default
#                          /var/cache/luxel[/pocl]; must be writable)
set -eu

luxeld="${LUXELD_BIN:-luxeld}"
listen="${LUXELD_LISTEN:-0.0.0.0:50051}"
data_dir="${LUXELD_DATA_DIR:-/var/lib/luxel}"
export LUXEL_CACHE_DIR="${LUXEL_CACHE_DIR:-/var/cache/luxel}"
export POCL_CACHE_DIR="${POCL_CACHE_DIR:-$LUXEL_CACHE_DIR/pocl}"
mkdir -p "$LUXEL_CACHE_DIR" "$POCL_CACHE_DIR"

say() { echo "luxeld-entrypoint: $*" >&2; }

set -- --listen "$listen" --data-dir "$data_dir" "$@"

token_file="${LUXELD_TOKEN_FILE:-}"
if [ -z "$token_file" ] && [ -f /run/secrets/luxel-token ]; then
  token_file=/run/secrets/luxel-token
fi
if [ -n "$token_file" ]; then
  if [ ! -r "$token_file" ]; then
    say "LUXELD_TOKEN_FILE=$token_file cannot be read"
    exit 2
  fi
  set -- "$@" --token-file "$token_file"
  # luxeld refuses a token file its group or others can read; a secret
  # mounted root-owned and group-readable (Kubernetes defaultMode 0440 with
  # fsGroup) needs this.
  if [ "${LUXELD_ALLOW_READABLE_TOKEN_FILE:-0}" = 1 ]; then
    set -- "$@" --allow-readable-token-file
  fi
elif [ -z "${LUXELD_TOKEN:-}" ] && [ "${LUXELD_ALLOW_NO_TOKEN:-0}" != 1 ]; then
  say "no token: mount one at /run/secrets/luxel-token, set LUXELD_TOKEN_FILE or" \
    "LUXELD_TOKEN, or set LUXELD_ALLOW_NO_TOKEN=1 to serve without authentication"
  exit 2
fi

if [ -n "${LUXELD_METRICS_LISTEN:-}" ]; then
  if "$luxeld" --help 2>/dev/null | grep -q -- '--metrics-listen'; then
    set -- "$@" --metrics-listen "$LUXELD_METRICS_LISTEN"
  else
    say "this luxeld has no --metrics-listen; LUXELD_METRICS_LISTEN ignored"
  fi
fi

# shellcheck disable=SC2086  # split on purpose: several flags in one variable
exec "$luxeld" "$@" ${LUXELD_EXTRA_ARGS:-}
