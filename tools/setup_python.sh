#!/usr/bin/env bash
# Creates the project-local virtual environment .venv/ with the packages in
# tools/requirements.txt (idempotent: does nothing when they are installed).
set -euo pipefail
cd "$(dirname "$0")/.."
req=tools/requirements.txt
stamp=.venv/.requirements.sha256
if ! command -v python3 >/dev/null 2>&1; then
  echo "setup_python: python3 is required (Debian: apt-get install python3 python3-venv)" >&2
  exit 1
fi
if [ ! -x .venv/bin/python ]; then
  echo "setup_python: creating .venv"
  python3 -m venv .venv
fi
want=$(sha256sum "$req" | cut -d' ' -f1)
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  exit 0
fi
echo "setup_python: installing $(grep -cv '^\s*\(#\|$\)' "$req") packages from $req into .venv"
.venv/bin/python -m pip install --quiet --disable-pip-version-check -r "$req"
echo "$want" > "$stamp"
