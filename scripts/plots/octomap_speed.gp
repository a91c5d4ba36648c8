# Mapping speed against OctoMap: one bar per scan or sequence, the ratio of the medians in the tables.
#   gnuplot -c octomap_speed.gp <out.png> <ray-traced.tsv: scan, OctoMap / FOT>
#           <multi-scan.tsv: sequence, speed-up> [<goal, e.g. 25> <goal's words>]
# A linear axis from 0: the ratios are of one order, so a bar's length is the speed-up itself.
load "style.gp"  # found through GNUPLOT_LIB, which make_pictures.sh sets
set terminal pngcairo size 1100,640 font "DejaVu Sans,11" noenhanced
set output ARG1
stats ARG2 using 2 nooutput
n1 = STATS_records
top = STATS_max
stats ARG3 using 2 nooutput
n2 = STATS_records
top = STATS_max > top ? STATS_max : top
goal = ARGC >= 4 ? real(ARG4) : NaN
goal_words = ARGC >= 5 ? ARG5 : "goal"
top = goal > top ? goal : top
gap = 1  # an empty slot between the two groups
set lmargin 10
set rmargin 3
set bmargin 8
set xrange [0.4 : n1 + gap + n2 + 0.6]
set yrange [0 : top * 1.45]
set xtics rotate by 25 right nomirror
set ytics nomirror
set grid noxtics ytics
set ylabel "OctoMap time / pcl_fot time (higher: pcl_fot faster)"
set title "Mapping speed against OctoMap (medians of one run, measured side by side)"
set key top left
set boxwidth 0.7
# The goal is the multi-scan table's: its line spans that group only.
if (goal == goal) set arrow from n1 + gap + 0.5, goal to n1 + gap + n2 + 0.5, goal nohead \
                    lc rgb paper_colour dt 2 lw 1.5
plot ARG2 using ($0 + 1):2:xtic(1) with boxes lc rgb fot_colour \
       title "one scan, ray-traced, binary rule (paper Table III): the same cells as OctoMap", \
     ARG3 using ($0 + 1 + n1 + gap):2:xtic(1) with boxes lc rgb "#86b9e3" \
       title "several scans, log-odds: OctoMap's values bit for bit", \
     ARG2 using ($0 + 1):2:(sprintf("%.1f×", $2)) with labels offset 0, 0.7, \
     ARG3 using ($0 + 1 + n1 + gap):2:(sprintf("%.1f×", $2)) with labels offset 0, 0.7, \
     NaN with lines lc rgb paper_colour dt 2 lw 1.5 \
       title (goal == goal ? sprintf("%s (%g×)", goal_words, goal) : ""), \
     1 with lines lc rgb one_colour lw 2 title "1.0: as fast as OctoMap"
