#!/usr/bin/env bash
# Regenerates every picture of the docs into doc/img/ (or <out_dir>):
#   plots  the benchmark plots, drawn by gnuplot from doc/benchmarks.md's tables (scripts/plots/*.gp);
#   map    the main job's map as pcl_viewer renders it, on a virtual X server with software GL.
# Usage: make_pictures.sh [plots|map|all] [--bench <benchmarks.md>] [--map <mesh.vtk>] [<out_dir>]
# Defaults: all, doc/benchmarks.md, output/fot_map_mesh.vtk (bash scripts/run_main.sh writes it), doc/img.
# fot_bench runs the plots part on the report it has just written.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
plots_dir="$repo/scripts/plots"
what=all bench="$repo/doc/benchmarks.md" map="$repo/output/fot_map_mesh.vtk" out="$repo/doc/img"
while [ $# -gt 0 ]; do
  case $1 in
    plots | map | all) what=$1 ;;
    --bench) bench=${2:?--bench needs a file}; shift ;;
    --map) map=${2:?--map needs a file}; shift ;;
    -h | --help) sed -n '2,7s/^# \{0,1\}//p' "$0"; exit 0 ;;
    -*) echo "make_pictures.sh: unknown option $1 (see -h)" >&2; exit 1 ;;
    *) out=$1 ;;
  esac
  shift
done
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# ---- Benchmark plots -----------------------------------------------------------------------------------

# table <anchor> <columns>: the first table after the line starting with <anchor> that has these columns,
# tab-separated (scripts/plots/md_table.awk); fails if there is none.
table() { awk -f "$plots_dir/md_table.awk" -v anchor="$1" -v cols="$2" "$bench"; }

# paper <anchor>: the paper's figures the section quotes as "FT/GR ... (paper: 1.70 stereo, 2.47 TOF)",
# one "value<TAB>paper: words" line each; fails if there are none.
paper() {
  awk -v anchor="$1" '
    index($0, anchor) == 1 { on = 1; next }
    on && /^## / { exit }
    on && /FT\/GR/ && match($0, /\(paper: [^)]*\)/) {
      n = split(substr($0, RSTART + 8, RLENGTH - 9), items, ", ")
      for (i = 1; i <= n; ++i)
        if (match(items[i], /[0-9]+(\.[0-9]+)?/)) {
          printf "%s\tpaper: %s\n", substr(items[i], RSTART, RLENGTH), items[i]
          ++found
        }
    }
    END { exit found ? 0 : 1 }' "$bench"
}

# plot <name.png> <script.gp> <args>: gnuplot writes beside the picture, which is then replaced whole.
plot() {
  local name=$1 script=$2
  shift 2
  GNUPLOT_LIB="$plots_dir" gnuplot -c "$plots_dir/$script" "$out/.$name.tmp" "$@"
  mv "$out/.$name.tmp" "$out/$name"
  echo "Wrote $out/$name"
}

# skip <name.png> <what is missing>: fot_bench -sections writes only some tables; the rest are skipped.
skip() { echo "Skipped $1: $bench has no $2" >&2; }

make_plots() {
  if ! command -v gnuplot >/dev/null; then
    echo "make_pictures.sh: no gnuplot for the plots (apt-get install gnuplot-nox)" >&2
    exit 2
  fi
  [ -r "$bench" ] || { echo "make_pictures.sh: cannot read $bench" >&2; exit 2; }

  # Mapping speed: OctoMap's time over ours, per scan (ray-traced, Table III) and per sequence (log-odds).
  if table '## Ray-traced mapping' 'scan|OctoMap / FOT' >"$tmp/rays.tsv" &&
    table '## Multi-scan mapping' 'sequence|speed-up' >"$tmp/multi.tsv"; then
    # The multi-scan section states its goal as "Goal: 30× OctoMap's speed".
    goal=$(awk '/^## Multi-scan mapping/ { on = 1 } on && match($0, /Goal: [0-9.]+× OctoMap.s speed/) {
             print substr($0, RSTART + 6, RLENGTH - 6) + 0; exit }' "$bench")
    plot bench_octomap_speed.png octomap_speed.gp "$tmp/rays.tsv" "$tmp/multi.tsv" \
      ${goal:+"$goal" "goal of the multi-scan table"}
  else
    skip bench_octomap_speed.png "ray-traced or multi-scan mapping table"
  fi

  # Search: one row per query kind, under a heading row for each pair of clouds ("<queries> into <target>").
  if table '## Search against nanoflann' 'target|queries|query|nanoflann / FOT|FLANN / FOT' \
    >"$tmp/search.tsv"; then
    awk -F '\t' -v OFS='\t' '{
      pair = $2 " into " $1
      if (pair != last) print ++y, "", "NaN", "NaN", pair
      last = pair
      print ++y, $3, $4, $5, ""
    }' "$tmp/search.tsv" >"$tmp/search_rows.tsv"
    plot bench_search_nanoflann.png search_nanoflann.gp "$tmp/search_rows.tsv"
  else
    skip bench_search_nanoflann.png "\"Search against nanoflann\" table"
  fi

  # Memory per map, from the three tables that measure it.
  if table '## Cell access' 'scan|FOT bytes|pcl::octree bytes|OctoMap bytes|grid bytes' \
    >"$tmp/mem_cells.tsv" &&
    table '## Ray-traced mapping' 'scan|ray-traced: FOT KB|ray-traced: OctoMap KB' >"$tmp/mem_rays.tsv" &&
    table '## Multi-scan mapping' 'sequence|log-odds bytes as inserted|OctoMap bytes' >"$tmp/mem_multi.tsv"; then
    plot bench_memory.png memory.gp "$tmp/mem_cells.tsv" "$tmp/mem_rays.tsv" "$tmp/mem_multi.tsv"
  else
    skip bench_memory.png "memory table of the cell access, ray-traced or multi-scan mapping section"
  fi

  # The paper's Tables II and III beside ours: FT/GR per scan, and the paper's figures as quoted.
  if table '**Repeated insertion**' 'scan|FT/GR' >"$tmp/repeated.tsv" &&
    table '**First insertion**' 'scan|FT/GR' >"$tmp/first.tsv" &&
    table '## Ray-traced mapping' 'scan|FT/GR' >"$tmp/table3.tsv" &&
    paper '## Cell access' >"$tmp/paper2.tsv" && paper '## Ray-traced mapping' >"$tmp/paper3.tsv"; then
    # One row per scan: repeated insertion, then first insertion (matched by name).
    awk -F '\t' -v OFS='\t' 'NR == FNR { first[$1] = $2; next }
      { print $1, $2, ($1 in first ? first[$1] : "NaN") }' "$tmp/first.tsv" "$tmp/repeated.tsv" \
      >"$tmp/table2.tsv"
    plot bench_paper_tables.png paper_tables.gp \
      "$tmp/table2.tsv" "$tmp/paper2.tsv" "$tmp/table3.tsv" "$tmp/paper3.tsv"
  else
    skip bench_paper_tables.png "FT/GR tables (cell access, ray-traced) or the paper's figures in them"
  fi
}

# ---- The map, as pcl_viewer shows it -------------------------------------------------------------------

# bounds <mesh.vtk>: "xmin xmax ymin ymax zmin zmax" of its points. fot_map writes binary legacy VTK: five
# header lines, the last "POINTS <n> float", then the points as big-endian floats.
bounds() {
  local header points
  header=$(head -n 5 "$1" | wc -c)
  points=$(head -n 5 "$1" | awk '$1 == "POINTS" && $3 == "float" { print $2 }')
  if [ -z "$points" ] || [ "$points" -eq 0 ]; then
    echo "make_pictures.sh: $1 is no mesh of fot_map's, or an empty one (no POINTS <n> float)" >&2
    exit 2
  fi
  od -A n -v -w12 -t f4 --endian=big -j "$header" -N $((points * 12)) "$1" | awk '
    NR == 1 { x0 = x1 = $1; y0 = y1 = $2; z0 = z1 = $3 }
    { if ($1 < x0) x0 = $1; if ($1 > x1) x1 = $1; if ($2 < y0) y0 = $2; if ($2 > y1) y1 = $2
      if ($3 < z0) z0 = $3; if ($3 > z1) z1 = $3 }
    END { print x0, x1, y0, y1, z0, z1 }'
}

# camera <bounds> <width> <height>: pcl_viewer's -cam value (clip/focal/position/view up/fovy/window size/
# window position) for a view from above at an angle: from the -x, -y side, 54° above the horizon, z up,
# as close as lets the bounding box fit the window, with a margin; trimmed afterwards.
camera() {
  awk -v b="$1" -v w="$2" -v h="$3" 'BEGIN {
    split(b, v, " ")
    for (a = 0; a < 3; ++a) { lo[a] = v[2 * a + 1]; hi[a] = v[2 * a + 2]; c[a] = (lo[a] + hi[a]) / 2 }
    fovy = 0.5236; ty = sin(fovy / 2) / cos(fovy / 2); tx = ty * w / h  # 30° high, in radians
    d[0] = -0.45; d[1] = -1; d[2] = 1.5  # from the focal point towards the camera
    n = sqrt(d[0] ^ 2 + d[1] ^ 2 + d[2] ^ 2); for (a = 0; a < 3; ++a) d[a] /= n
    # The screen axes: up is z made square to the view, right is up × d.
    for (a = 0; a < 3; ++a) up[a] = (a == 2) - d[2] * d[a]
    n = sqrt(up[0] ^ 2 + up[1] ^ 2 + up[2] ^ 2); for (a = 0; a < 3; ++a) up[a] /= n
    r[0] = up[1] * d[2] - up[2] * d[1]; r[1] = up[2] * d[0] - up[0] * d[2]; r[2] = up[0] * d[1] - up[1] * d[0]
    # Each corner of the box must lie inside the view cone: the distance is the largest any corner needs.
    dist = 0
    for (i = 0; i < 8; ++i) {
      pd = pu = pr = 0
      for (a = 0; a < 3; ++a) {
        p = (int(i / 2 ^ a) % 2 ? hi[a] : lo[a]) - c[a]
        pd += p * d[a]; pu += p * up[a]; pr += p * r[a]
      }
      need = pd + (pu < 0 ? -pu : pu) / ty; if (need > dist) dist = need
      need = pd + (pr < 0 ? -pr : pr) / tx; if (need > dist) dist = need
    }
    dist *= 1.08
    span = sqrt((hi[0] - lo[0]) ^ 2 + (hi[1] - lo[1]) ^ 2 + (hi[2] - lo[2]) ^ 2)
    near = dist > span ? dist - span : dist / 10
    printf "%g,%g/%g,%g,%g/%g,%g,%g/0,0,1/%g/%d,%d/0,0\n", near, dist + span,
      c[0], c[1], c[2], c[0] + dist * d[0], c[1] + dist * d[1], c[2] + dist * d[2], fovy, w, h
  }'
}

make_map() {
  if [ ! -r "$map" ]; then
    echo "make_pictures.sh: no map at $map; make it with: bash scripts/run_main.sh" >&2
    exit 2
  fi
  local tool
  for tool in pcl_viewer xvfb-run xwd convert identify od; do
    if ! command -v "$tool" >/dev/null; then
      echo "make_pictures.sh: $tool is missing (bash scripts/install_deps.sh installs it)" >&2
      exit 2
    fi
  done
  # Drawn at twice the size and shrunk by half: smoother edges than the software renderer's own.
  local width=2400 height=1800 box cam name=fot_map_room.png
  box=$(bounds "$map")
  cam=$(camera "$box" $width $height)
  # pcl_viewer runs in the scratch directory, where no camera file of an earlier run can steer it.
  # shellcheck disable=SC2016 # the quoted script expands its own arguments, on the virtual display
  (cd "$tmp" && LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -s "-screen 0 ${width}x${height}x24" bash -c '
    map=$0 cam=$1 shot=$2
    pcl_viewer "$map" -cam "$cam" >viewer.log 2>&1 &
    viewer=$!
    # The picture is done when the screen holds the map (far more colours than the caption) and stays
    # the same from one grab to the next.
    last=
    for _ in $(seq 1 120); do
      sleep 0.5
      xwd -root -silent | convert xwd:- "$shot"
      now=$(identify -format "%k %#" "$shot")
      if [ "${now%% *}" -gt 256 ] && [ "$now" = "$last" ]; then
        kill "$viewer"
        exit 0
      fi
      last=$now
    done
    kill "$viewer" || true
    echo "make_pictures.sh: pcl_viewer showed no map of $map in 60 s:" >&2
    cat viewer.log >&2
    exit 1' "$(realpath "$map")" "$cam" "$tmp/screen.png")
  # The bottom rows hold pcl_viewer's caption (the file name); then black is cut off all round.
  convert "$tmp/screen.png" -crop "${width}x$((height - 40))+0+0" +repage -resize 50% -trim +repage \
    -bordercolor black -border 12 -strip "$out/.$name.tmp"  # -strip: no dates, so a rerun gives the same bytes
  mv "$out/.$name.tmp" "$out/$name"
  echo "Wrote $out/$name"
}

case $what in
  plots) make_plots ;;
  map) make_map ;;
  all) make_plots; make_map ;;
esac
