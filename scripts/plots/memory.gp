# Memory per map, in three panels for the three tables that measure it, on one log axis in MiB.
#   gnuplot -c memory.gp <out.png> <raw.tsv: scan, FOT, pcl::octree, OctoMap, grid bytes>
#           <ray.tsv: scan, FOT KB, OctoMap KB> <multi.tsv: sequence, pcl_fot bytes, OctoMap bytes>
# Points, not bars: the sizes span three orders of magnitude, and a bar's length on a log axis means
# nothing. The same axis in every panel, so that the panels compare; each library is a little to one
# side of its map, so that equal sizes (pcl::octree and OctoMap) stay visible.
load "style.gp"  # found through GNUPLOT_LIB, which make_pictures.sh sets
set terminal pngcairo size 1300,640 font "DejaVu Sans,11" noenhanced
set output ARG1
mib(bytes) = bytes / 1048576.0
stats ARG2 using (mib($2)) nooutput
lo = STATS_min
stats ARG2 using (mib($5)) nooutput
hi = STATS_max
stats ARG3 using ($2 / 1024.0) nooutput
lo = STATS_min < lo ? STATS_min : lo
stats ARG4 using (mib($2)) nooutput
lo = STATS_min < lo ? STATS_min : lo
stats ARG4 using (mib($3)) nooutput
hi = STATS_max > hi ? STATS_max : hi
set logscale y
set yrange [10 ** floor(log10(lo)) : 10 ** ceil(log10(hi))]
set format y "%g"
set grid ytics mytics noxtics
set xtics rotate by 30 right nomirror
set ytics nomirror
set offsets 0.6, 0.6, 0, 0
fot = -0.18; octree = 0.0; octomap = 0.18; grid = 0.0  # where each library sits beside its map
set multiplot layout 1, 3 margins 0.08, 0.98, 0.27, 0.80 spacing 0.05 \
    title "Memory per map, measured in one run (KB and MiB: 1024 and 1024² bytes)"
# A legend of its own in one row: a key at screen position keeps to a panel's width.
unset key
set label 1 "pcl_fot" at screen 0.25, 0.905 point pt 7 ps 1.8 lc rgb fot_colour offset 1.2, 0
set label 2 "pcl::octree" at screen 0.38, 0.905 point pt 5 ps 1.5 lc rgb octree_colour offset 1.2, 0
set label 3 "OctoMap" at screen 0.53, 0.905 point pt 9 ps 1.8 lc rgb octomap_colour offset 1.2, 0
set label 4 "dense grid (FastOccMesh)" at screen 0.66, 0.905 point pt 13 ps 1.8 lc rgb grid_colour offset 1.2, 0
set ylabel "MiB (log scale)"
set title "Raw points, no ray tracing\n(the cell access section's memory table)"
plot ARG2 using ($0 + grid):(mib($5)):xtic(1) with points pt 13 ps 1.8 lc rgb grid_colour, \
     '' using ($0 + octree):(mib($3)) with points pt 5 ps 1.5 lc rgb octree_colour, \
     '' using ($0 + octomap):(mib($4)) with points pt 9 ps 1.8 lc rgb octomap_colour, \
     '' using ($0 + fot):(mib($2)) with points pt 7 ps 1.8 lc rgb fot_colour
unset label
unset ylabel
set title "Ray-traced, one scan\n(paper Table IV)"
plot ARG3 using ($0 + octomap):($3 / 1024.0):xtic(1) with points pt 9 ps 1.8 lc rgb octomap_colour, \
     '' using ($0 + fot):($2 / 1024.0) with points pt 7 ps 1.8 lc rgb fot_colour
set title "Log-odds, several scans (the multi-scan\nmapping table; pcl_fot as inserted)"
plot ARG4 using ($0 + octomap):(mib($3)):xtic(1) with points pt 9 ps 1.8 lc rgb octomap_colour, \
     '' using ($0 + fot):(mib($2)) with points pt 7 ps 1.8 lc rgb fot_colour
unset multiplot
