#!/usr/bin/env bash
# Builds the GlassFusion report viewer into OUTDIR/gf_viewer.js: one minified plain script
# (an IIFE defining the global GFViewer) that a report loads from file:// with a <script> tag.
# Usage: viewer/build.sh OUTDIR   (works from any directory; installs node_modules if missing)
set -euo pipefail
if [ $# -ne 1 ]; then
  echo "usage: $0 OUTDIR" >&2
  exit 2
fi
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
mkdir -p "$1"
out="$(cd "$1" && pwd)/gf_viewer.js"
cd "$here"
if [ ! -d node_modules ]; then
  npm ci --no-audit --no-fund --loglevel=error >&2
fi
./node_modules/.bin/esbuild src/main.js --bundle --minify --format=iife --global-name=GFViewer \
  --target=es2020 --log-level=warning --outfile="$out"
echo "gf_viewer.js: $(wc -c <"$out") bytes -> $out"
