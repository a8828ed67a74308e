#!/usr/bin/env bash
# Load benchmark: starts the release service on the bundled defaults (photo only: the
# detector finds the ends), then drives it with wrk at concurrency 1, 4 and 16, posting
# dataset photos in turn. Prints throughput and p50/p99 latency per level.
#   scripts/loadtest.sh [SECONDS_PER_LEVEL]     (wrk: `apt-get install wrk`)
set -euo pipefail
cd "$(dirname "$0")/.."
DURATION="${1:-20}"
PORT="${ARIADNE_LOADTEST_PORT:-18080}"
DATASET="${ARIADNE_DATASET:-../shared/datasets/cables}"
command -v wrk >/dev/null || { echo "wrk is not installed (apt-get install wrk)" >&2; exit 1; }
scripts/fetch-onnxruntime.sh .ort
cargo build --release --quiet
target_dir="${CARGO_TARGET_DIR:-target}"
ARIADNE_BIND="127.0.0.1:${PORT}" ARIADNE_LOG_FORMAT=json RUST_LOG=warn \
  "$target_dir/release/ariadne" serve &
server=$!
trap 'kill $server 2>/dev/null || true; wait $server 2>/dev/null || true' EXIT
for _ in $(seq 1 100); do
  curl -fs "http://127.0.0.1:${PORT}/readyz" >/dev/null && break
  sleep 0.2
done
photos=("$DATASET"/simple/*.jpg)
echo "photos: ${#photos[@]} from $DATASET/simple; ${DURATION} s per level; $(nproc) CPUs"
for c in 1 4 16; do
  # wrk ends a level by closing its connections with requests still in flight; those
  # jobs run on (a slot is held until the work really ends), so let them drain before
  # the next level's clients arrive, or its first requests meet a full queue (429).
  sleep 2
  echo "== concurrency $c"
  wrk -t1 -c"$c" -d"${DURATION}s" --timeout 30s -s scripts/loadtest.lua \
    "http://127.0.0.1:${PORT}" -- "${photos[@]}" | grep -E "statuses|summary|Non-2xx|Socket errors"
done
