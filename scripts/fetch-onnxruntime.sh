#!/usr/bin/env bash
# Fetches ONNX Runtime's CPU shared library from the PyPI `onnxruntime` wheel (the
# official build; no other download site is needed) into DEST (default .ort/).
# Idempotent: does nothing when the library is already there.
set -euo pipefail
VERSION="${ORT_VERSION:-1.31.1}"
DEST="${1:-.ort}"
LIB="libonnxruntime.so.${VERSION}"
if [ -f "${DEST}/${LIB}" ]; then
  exit 0
fi
PYTHON="${PYTHON:-python3}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$PYTHON" -m pip download --quiet --no-deps --only-binary=:all: \
  --dest "$tmp" "onnxruntime==${VERSION}"
wheel="$(ls "$tmp"/onnxruntime-*.whl)"
"$PYTHON" - "$wheel" "$DEST" "$LIB" <<'PY'
import sys, zipfile, pathlib
wheel, dest, lib = sys.argv[1:]
dest = pathlib.Path(dest)
dest.mkdir(parents=True, exist_ok=True)
with zipfile.ZipFile(wheel) as z:
    member = f"onnxruntime/capi/{lib}"
    (dest / lib).write_bytes(z.read(member))
PY
echo "ONNX Runtime ${VERSION}: ${DEST}/${LIB}"
