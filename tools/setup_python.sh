#!/usr/bin/env bash
# Creates the project-local Python environment .venv/ for the helpers in
# tools/ and installs the pinned packages of tools/requirements.txt.
# Idempotent: does nothing when everything is already installed.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="$root/.venv"
req="$root/tools/requirements.txt"
py="${PYTHON:-python3}"
if ! command -v "$py" >/dev/null 2>&1; then
  echo "setup_python: $py not found; install Python 3 (e.g. apt-get install python3 python3-venv)" >&2
  exit 1
fi
if [ ! -x "$venv/bin/python" ]; then
  echo "setup_python: creating $venv"
  "$py" -m venv "$venv"
fi
stamp="$venv/.requirements.sha256"
want="$(sha256sum "$req" | cut -d' ' -f1)"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  echo "setup_python: $venv is up to date"
  exit 0
fi
echo "setup_python: installing $(grep -cv '^\s*\(#\|$\)' "$req") pinned packages from tools/requirements.txt"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r "$req"
echo "$want" > "$stamp"
echo "setup_python: done ($("$venv/bin/python" --version))"
