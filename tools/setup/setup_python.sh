#!/usr/bin/env bash
# Creates the project-local Python environment .venv/ for the helpers in
# tools/ (helpers/, check/, bench/, gen/), installs the pinned packages of tools/setup/requirements.txt, then builds
# the Python package `sdrs` (python/, PyO3) with maturin in the release
# profile into .venv (sharing target/ with cargo, so the core is compiled
# once). Idempotent: the pip step is skipped when the requirements are
# installed; the package build is incremental (cargo) and always runs, so
# .venv has the current sources.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
venv="$root/.venv"
req="$root/tools/setup/requirements.txt"
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
  echo "setup_python: $venv packages are up to date"
else
  echo "setup_python: installing $(grep -cv '^\s*\(#\|$\)' "$req") pinned packages from tools/setup/requirements.txt"
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r "$req"
  echo "$want" > "$stamp"
fi
# The `sdrs` Python package: `maturin develop` builds python/ (release
# profile, the workspace's target/) and installs it into .venv.
echo "setup_python: building the sdrs Python package (maturin, release)"
VIRTUAL_ENV="$venv" PATH="$venv/bin:$PATH" "$venv/bin/maturin" develop --release --quiet \
  --manifest-path "$root/python/Cargo.toml"
echo "setup_python: done ($("$venv/bin/python" --version), $("$venv/bin/python" -c 'import sdrs; print(sdrs.__name__, "from", sdrs.__file__)'))"
