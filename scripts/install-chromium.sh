#!/usr/bin/env bash
# Headless Chromium for the viewer's picture tests (tests/test_viewer.py): Debian's package,
# installed when it is missing and we are root (CI); otherwise those tests skip, saying why.
set -euo pipefail
if command -v chromium >/dev/null 2>&1; then
    exit 0
fi
if [ "$(id -u)" != "0" ] || ! command -v apt-get >/dev/null 2>&1; then
    echo "note: chromium is not installed and cannot be installed here (needs root and apt-get);" \
         "the browser tests of the viewer will be skipped" >&2
    exit 0
fi
echo "installing chromium (apt-get) for the viewer's browser tests" >&2
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq chromium >/dev/null
