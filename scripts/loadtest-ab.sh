#!/usr/bin/env bash
# A/B load benchmark of release binaries on this machine, whose speed drifts: starts
# each binary in turn on the bundled defaults (photo only), drives it with wrk at one
# concurrency level, and repeats the round, so that the binaries are compared at the
# same moments. Prints one line per run.
#   scripts/loadtest-ab.sh SECONDS CONCURRENCY ROUNDS BINARY...
# e.g. build the commit before into another CARGO_TARGET_DIR, copy both binaries aside:
#   scripts/loadtest-ab.sh 8 1 3 /tmp/ariadne-before /tmp/ariadne-after
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 4 ] || { sed -n 2,8p "$0" >&2; exit 2; }
DURATION="$1"; CONCURRENCY="$2"; ROUNDS="$3"; shift 3
PORT="${ARIADNE_LOADTEST_PORT:-18080}"
DATASET="${ARIADNE_DATASET:-../shared/datasets/cables}"
command -v wrk >/dev/null || { echo "wrk is not installed (apt-get install wrk)" >&2; exit 1; }
scripts/fetch-onnxruntime.sh .ort
export ORT_DYLIB_PATH="${ORT_DYLIB_PATH:-$PWD/.ort/libonnxruntime.so.1.31.1}"
photos=("$DATASET"/simple/*.jpg)
server=""
trap '[ -n "$server" ] && kill "$server" 2>/dev/null || true' EXIT
for round in $(seq 1 "$ROUNDS"); do
  for binary in "$@"; do
    ARIADNE_BIND="127.0.0.1:${PORT}" RUST_LOG=error "$binary" serve >/dev/null 2>&1 &
    server=$!
    for _ in $(seq 1 100); do
      curl -fs "http://127.0.0.1:${PORT}/readyz" >/dev/null && break
      sleep 0.2
    done
    result=$(wrk -t1 -c"$CONCURRENCY" -d"${DURATION}s" --timeout 30s -s scripts/loadtest.lua \
      "http://127.0.0.1:${PORT}" -- "${photos[@]}" | grep -E "summary|Non-2xx" | tr '\n' ' ')
    echo "round $round, $binary, concurrency $CONCURRENCY: $result"
    kill "$server"
    wait "$server" 2>/dev/null || true
    server=""
  done
done
