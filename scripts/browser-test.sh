#!/usr/bin/env bash
# The page at GET / in a real headless browser: tests/browser/page_test.py drives
# Debian's Chromium through Selenium against the release binary (built by
# `cargo test --release`). Installs what is missing: chromium and chromium-driver from
# apt (needs root or sudo), selenium from PyPI into the cached tools environment.
set -euo pipefail
cd "$(dirname "$0")/.."
BINARY="${1:-${CARGO_TARGET_DIR:-target}/release/ariadne}"
VENV="${ARIADNE_TOOLS_VENV:-$HOME/.cache/ariadne-tools-venv}"
PYTHON="${PYTHON:-python3}"

if ! command -v chromium >/dev/null 2>&1 || ! command -v chromedriver >/dev/null 2>&1; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  echo "browser test: installing chromium and chromium-driver from apt"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    chromium chromium-driver >/dev/null
fi
if [ ! -d "$VENV" ]; then
  "$PYTHON" -m venv "$VENV"
fi
"$VENV/bin/python" -c "import selenium" 2>/dev/null \
  || "$VENV/bin/pip" install --quiet "selenium==4.*"
# The page is served from the binary: nothing here may reach beyond the loopback.
"$VENV/bin/python" tests/browser/page_test.py "$BINARY"
