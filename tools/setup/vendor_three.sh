#!/usr/bin/env bash
# Refreshes the vendored three.js used by `sdrs view` (cli/assets/three/):
# the minified ES module, OrbitControls and the licence, from the npm
# package `three@VERSION` (default: the version in cli/assets/three/VERSION).
# The build never needs npm: the files are committed and embedded with
# include_str!. Usage: bash tools/setup/vendor_three.sh [VERSION]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
dest="$root/cli/assets/three"
ver="${1:-$(sed -n 's/^version //p' "$dest/VERSION")}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && npm pack --silent "three@$ver" >/dev/null && tar xzf "three-$ver.tgz")
cp "$tmp/package/build/three.module.min.js" "$dest/three.module.min.js"
cp "$tmp/package/examples/jsm/controls/OrbitControls.js" "$dest/OrbitControls.js"
cp "$tmp/package/LICENSE" "$dest/LICENSE"
{
  echo "version $ver"
  echo "source npm package three@$ver (build/three.module.min.js, examples/jsm/controls/OrbitControls.js, LICENSE)"
  (cd "$dest" && sha256sum three.module.min.js OrbitControls.js LICENSE)
} >"$dest/VERSION"
echo "vendored three@$ver into $dest"
