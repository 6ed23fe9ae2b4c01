#!/usr/bin/env bash
# The reports' 3D view with a map of a million surfels (viewer/README.md): a page built as a
# report builds it (500,000 of the surfels, evenly spread; the full count stated), drawn in
# headless Chromium within 5 s of opening it. A second try where the first was slow: this shared
# 2-core VM has taken 4.3 s one time and 5.8 s the next on the same page.
# Usage: viewer_million.sh SOURCE_DIR WORK_DIR
set -euo pipefail
source_dir=$1
work=$2
rm -rf "$work"
node "$source_dir/viewer/test/make_big_view.mjs" "$work" 1000000 --page-cap 500000
for try in 1 2; do
  if node "$source_dir/viewer/test/viewer_test.mjs" "$work/report.html" --max-load-ms 5000; then
    rm -rf "$work"
    exit 0
  fi
  echo "try $try failed"
done
exit 1
