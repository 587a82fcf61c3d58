#!/usr/bin/env bash
# Installs the Debian packages the tests need (the report's browser test
# renders `sdrs compare` output in headless Chromium). Idempotent: does
# nothing when everything is there. Needs root or sudo the first time.
set -euo pipefail
need=()
command -v chromium >/dev/null 2>&1 || need+=(chromium)
if [ ${#need[@]} -eq 0 ]; then
  echo "setup_system: Debian packages present (chromium)"
  exit 0
fi
if ! command -v apt-get >/dev/null 2>&1; then
  echo "setup_system: ${need[*]} missing and no apt-get here; install it with your package manager" >&2
  exit 1
fi
sudo=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then sudo="sudo"; else
    echo "setup_system: ${need[*]} missing; run as root or install it: apt-get install ${need[*]}" >&2
    exit 1
  fi
fi
echo "setup_system: installing ${need[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
echo "setup_system: done ($(chromium --version))"
