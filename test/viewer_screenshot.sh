#!/usr/bin/env bash
# Opens a file in the real pcl_viewer on a virtual X server, takes screenshots until the view shows the
# data, and fails if it never does. Usage: viewer_screenshot.sh <file> <screenshot.png>
set -euo pipefail
file=$1 shot=$2
xvfb-run -a -s "-screen 0 800x600x24" bash -c '
  file=$0 shot=$1
  pcl_viewer "$file" >"$shot.log" 2>&1 &
  viewer=$!
  lit=0
  for _ in $(seq 1 60); do
    sleep 1
    xwd -root -silent | convert xwd:- "$shot"
    # The share of pixels brighter than the black background (brightness: the largest channel); the
    # file-name caption alone is far below 1 %.
    lit=$(convert "$shot" -colorspace HSB -channel B -separate -threshold 4% -format "%[fx:mean]" info:)
    if awk -v lit="$lit" "BEGIN { exit !(lit > 0.01) }"; then
      kill "$viewer"
      echo "pcl_viewer shows $file: $lit of the screen lit ($shot)"
      exit 0
    fi
  done
  kill "$viewer" || true
  echo "pcl_viewer showed nothing of $file: only $lit of the screen lit ($shot, log $shot.log)" >&2
  exit 1' "$file" "$shot"
