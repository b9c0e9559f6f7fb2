#!/usr/bin/env bash
# Rebuild src/amble/viz/_vendor/ from the npm registry.
#
# The viewer must be one offline HTML file, so three.js and its OrbitControls
# addon are bundled into a single minified classic script that defines the
# global `THREE` (with `THREE.OrbitControls`). A classic script can be inlined
# in a <script> tag as-is: no import maps, blob URLs or module loading needed.
#
# Usage: scripts/vendor_three.sh [THREE_VERSION] [ESBUILD_VERSION]
set -euo pipefail

THREE_VERSION="${1:-0.187.0}"
ESBUILD_VERSION="${2:-0.28.2}"

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="$root/src/amble/viz/_vendor"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

cd "$work"
npm init -y >/dev/null
npm install --no-audit --no-fund --save-exact \
    "three@$THREE_VERSION" "esbuild@$ESBUILD_VERSION" >/dev/null

cat > entry.js <<'JS'
export * from 'three';
export { OrbitControls } from 'three/addons/controls/OrbitControls.js';
JS

npx --no-install esbuild entry.js --bundle --minify --format=iife \
    --global-name=THREE --target=es2020 --legal-comments=none \
    --banner:js="/* three.js ${THREE_VERSION} + OrbitControls, MIT License, see LICENSE */" \
    --outfile=three.min.js

mkdir -p "$out"
cp three.min.js "$out/three.min.js"
cp node_modules/three/LICENSE "$out/LICENSE"
printf 'three %s\nesbuild %s\n' "$THREE_VERSION" "$ESBUILD_VERSION" > "$out/VERSION"

ls -l "$out"
