#!/usr/bin/env bash
# The operator console's browser tests: Debian's chromium + chromium-driver with Python selenium,
# and Debian's firefox-esr over WebDriver BiDi with Python websockets (installed quietly when
# missing), against the release binary (ROVERNAV_BIN, default $CARGO_TARGET_DIR/release/rovernav).
# ROVERNAV_SCREENSHOT=docs/images/console.png refreshes the README's screenshot.
set -euo pipefail
cd "$(dirname "$0")/../.."
if ! command -v chromium >/dev/null || ! command -v chromedriver >/dev/null; then
  apt-get update -qq && apt-get install -y -qq chromium chromium-driver >/dev/null
fi
if ! command -v firefox-esr >/dev/null && ! command -v firefox >/dev/null; then
  apt-get update -qq && apt-get install -y -qq firefox-esr >/dev/null
fi
python3 -c "import selenium" 2>/dev/null || pip install -q selenium
python3 -c "import websockets.sync.client" 2>/dev/null || pip install -q websockets
export ROVERNAV_BIN="${ROVERNAV_BIN:-${CARGO_TARGET_DIR:-target}/release/rovernav}"
[ -x "$ROVERNAV_BIN" ] || { echo "no rovernav binary at $ROVERNAV_BIN (cargo build --release -p rovernav)"; exit 1; }
python3 tests/browser/test_console.py
python3 tests/browser/test_console_firefox.py
