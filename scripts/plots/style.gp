# The look every benchmark plot shares, loaded first by each: one font, plain text (no gnuplot markup, so
# names like kinect_capture0001 keep their underscores), a light grid, and one colour per library.
set encoding utf8
set datafile separator "\t"
set termoption noenhanced
set style fill solid 0.85 border -1
set grid lc rgb "#d8d8d8" lt 1
set key noautotitle box lc rgb "#bbbbbb" opaque
set border lc rgb "#444444"
fot_colour = "#1f6fb4"       # pcl_fot
octomap_colour = "#e8862a"   # OctoMap
nanoflann_colour = "#3a9d3a" # nanoflann
flann_colour = "#8c5bb8"     # FLANN (pcl::KdTreeFLANN)
octree_colour = "#c8413b"    # pcl::octree
grid_colour = "#8a8a8a"      # the dense grid (FastOccMesh)
paper_colour = "#222222"     # the paper's figures
# The line at 1.0 on ratio plots (drawn with lw 2): below or left of it, the other library is faster.
one_colour = "#000000"
