# Search against nanoflann and FLANN: one pair of bars per row of the table "Search against nanoflann,
# PCL's next default", each the other method's build-plus-query time over pcl_fot's.
#   gnuplot -c search_nanoflann.gp <out.png> <rows.tsv>
# rows.tsv (make_pictures.sh writes it): y, query, nanoflann / FOT, FLANN / FOT, and a heading row
# (y, "", NaN, NaN, "<queries> into <target>") above each pair of clouds.
# Bars start at 1.0 on a log axis, so 2× faster and 2× slower are equally long, to either side.
load "style.gp"  # found through GNUPLOT_LIB, which make_pictures.sh sets
stats ARG2 using 1 nooutput
n = STATS_max
stats ARG2 using 3 nooutput
lo = STATS_min
hi = STATS_max
stats ARG2 using 4 nooutput
lo = STATS_min < lo ? STATS_min : lo
hi = STATS_max > hi ? STATS_max : hi
set terminal pngcairo size 1000, 200 + 26 * n font "DejaVu Sans,11" noenhanced
set output ARG1
set logscale x 2
xmin = (lo < 0.5 ? lo : 0.5) / 1.25
set xrange [xmin : (hi > 2 ? hi : 2) * 1.25]
set format x "%g×"
set yrange [n + 0.6 : 0.4]  # the table's first row at the top
set ytics nomirror scale 0
set grid xtics mxtics noytics
set mxtics 2
set lmargin 14
set bmargin 6
set xlabel "the other method's time / pcl_fot's time (log scale): right of 1.0, pcl_fot is faster"
set title "Search against nanoflann (set up as PCL 1.15's KdTreeNanoflann) and pcl::KdTreeFLANN:\n" . \
          "build plus queries, medians of one run, measured side by side"
set key outside bottom center horizontal
h = 0.4  # height of one bar; a row holds two
min(a, b) = a < b ? a : b
max(a, b) = a > b ? a : b
set arrow from 1, graph 0 to 1, graph 1 nohead lc rgb one_colour lw 2 front
# Each value is printed at its bar's outer end: right of bars above 1.0, left of those below.
right_of(r) = r >= 1 ? r : NaN
left_of(r) = r < 1 ? r : NaN
plot ARG2 using (1):1:(min(1, $3)):(max(1, $3)):($1 - h):1:ytic(2) with boxxyerror \
       lc rgb nanoflann_colour title "nanoflann / pcl_fot", \
     ARG2 using (1):1:(min(1, $4)):(max(1, $4)):1:($1 + h) with boxxyerror \
       lc rgb flann_colour title "KdTreeFLANN / pcl_fot", \
     for [c = 3 : 4] ARG2 using (right_of(column(c))):($1 + (c - 3.5) * h):(sprintf(" %.2f", column(c))) \
       with labels left font ",9", \
     for [c = 3 : 4] ARG2 using (left_of(column(c))):($1 + (c - 3.5) * h):(sprintf("%.2f ", column(c))) \
       with labels right font ",9", \
     ARG2 using (xmin):1:5 with labels left offset 0.5, 0 font "DejaVu Sans Bold,10", \
     NaN with lines lc rgb one_colour lw 2 title "1.0: as fast as pcl_fot"
