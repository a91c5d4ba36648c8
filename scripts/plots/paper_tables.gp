# The paper's Tables II and III next to ours: FT/GR, FOT's time over the dense grid's (the paper's S),
# per scan, with the paper's own figures as dashed lines. Only S compares across machines: the paper's
# absolute times come from 2007 hardware.
#   gnuplot -c paper_tables.gp <out.png> <table2.tsv: scan, FT/GR repeated, FT/GR first insertion>
#           <paper2.tsv: value, words> <table3.tsv: scan, FT/GR> <paper3.tsv: value, words>
# A linear axis from 0, so that a bar's length is the ratio itself; the same axis in both panels.
load "style.gp"  # found through GNUPLOT_LIB, which make_pictures.sh sets
set terminal pngcairo size 1300,620 font "DejaVu Sans,11" noenhanced
set output ARG1
max(a, b) = a > b ? a : b
stats ARG2 using 2:3 nooutput
n2 = STATS_records
top = max(STATS_max_x, STATS_max_y)
stats ARG4 using 2 nooutput
n3 = STATS_records
top = max(top, STATS_max)
stats ARG3 using 1 nooutput
top = max(top, STATS_max)
stats ARG5 using 1 nooutput
top = max(top, STATS_max)
set yrange [0 : top * 1.45]
set grid noxtics ytics
set xtics rotate by 25 right nomirror
set ytics nomirror
set style fill solid 0.85 border -1
set boxwidth 0.36
set multiplot layout 1, 2 margins 0.08, 0.98, 0.2, 0.84 spacing 0.06 \
    title "The paper's Tables II and III beside ours: FT/GR, FOT's time over the dense grid's " . \
          "(lower is better for FOT)"
set key top left
set ylabel "FT/GR = FOT time / grid time"
set title "Table II: cell access, raw points (medians of one run)"
set xrange [0.4 : n2 + 0.6]
set arrow 1 from graph 0, first 1 to graph 1, first 1 nohead lc rgb one_colour lw 2
plot ARG2 using ($0 + 1 - 0.19):2:xtic(1) with boxes lc rgb fot_colour \
       title "ours, repeated insertion (the paper's protocol)", \
     '' using ($0 + 1 + 0.19):3 with boxes lc rgb "#86b9e3" title "ours, first insertion", \
     ARG3 using (0.4):1:(n2 + 0.2):(0) with vectors nohead lc rgb paper_colour dt 2 lw 2 title "the paper", \
     '' using (n2 + 0.55):1:2 with labels right offset 0, 0.6, \
     NaN with lines lc rgb one_colour lw 2 title "1.0: FOT as fast as the grid"
unset ylabel
set title "Table III: ray-traced mapping (medians of one run)"
set xrange [0.4 : n3 + 0.6]
set boxwidth 0.6
plot ARG4 using ($0 + 1):2:xtic(1) with boxes lc rgb fot_colour title "ours", \
     ARG5 using (0.4):1:(n3 + 0.2):(0) with vectors nohead lc rgb paper_colour dt 2 lw 2 title "the paper", \
     '' using (n3 + 0.55):1:2 with labels right offset 0, 0.6, \
     NaN with lines lc rgb one_colour lw 2 title "1.0: FOT as fast as the grid"
unset multiplot
