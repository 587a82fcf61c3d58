#!/usr/bin/env bash
# Creates the project-local Python environment .venv/ for the helpers in
# tools/ (helpers/, check/, bench/, gen/), installs the pinned packages of
# tools/setup/requirements.txt (with uv, itself pinned), then builds
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
uv_version=0.13.9
want="$(sha256sum "$req" | cut -d' ' -f1) uv $uv_version"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  echo "setup_python: $venv packages are up to date"
else
  echo "setup_python: installing $(grep -cv '^\s*\(#\|$\)' "$req") pinned packages from tools/setup/requirements.txt"
  # uv (pinned) installs the same pinned set as `pip install -r` would, with
  # parallel downloads: 26 s instead of pip's 133 s on a fresh 2-core machine
  # (2026-11-29; same `pip freeze` either way).
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "uv==$uv_version"
  # uv reads no pip configuration: pass on the machine's pip settings.
  [ -n "${PIP_INDEX_URL:-}" ] && export UV_INDEX_URL="$PIP_INDEX_URL"
  [ -n "${PIP_EXTRA_INDEX_URL:-}" ] && export UV_EXTRA_INDEX_URL="$PIP_EXTRA_INDEX_URL"
  [ -n "${PIP_FIND_LINKS:-}" ] && export UV_FIND_LINKS="$PIP_FIND_LINKS"
  [ -n "${PIP_CERT:-}" ] && export SSL_CERT_FILE="$PIP_CERT"
  "$venv/bin/uv" pip install --quiet --python "$venv/bin/python" -r "$req"
  echo "$want" > "$stamp"
fi
# The `sdrs` Python package: `maturin develop` builds python/ (release
# profile, the workspace's target/) and installs it into .venv.
echo "setup_python: building the sdrs Python package (maturin, release)"
VIRTUAL_ENV="$venv" PATH="$venv/bin:$PATH" "$venv/bin/maturin" develop --release --quiet \
  --manifest-path "$root/python/Cargo.toml"
echo "setup_python: done ($("$venv/bin/python" --version), $("$venv/bin/python" -c 'import sdrs; print(sdrs.__name__, "from", sdrs.__file__)'))"
