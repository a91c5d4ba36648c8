# Prints one Markdown table of doc/benchmarks.md as tab-separated rows, for gnuplot.
#   awk -f md_table.awk -v anchor='## Ray-traced mapping' -v cols='scan|FT/GR' benchmarks.md
# The table is the first one after the first line that starts with `anchor` whose header names every
# column in `cols` ('|'-separated); the columns come out in that order. A name the header holds twice means
# its first column. Bold marks and a trailing "×" or "%" are dropped, so that ratios and shares read as
# numbers. Exits 1 if there is no such table: the caller skips the plot and says why.
BEGIN {
  FS = "|"
  nwant = split(cols, want, "|")
}
function trim(s) { gsub(/^[ \t]+|[ \t]+$/, "", s); return s }
function clean(s) {
  s = trim(s)
  gsub(/\*\*/, "", s)
  sub(/(×|%)$/, "", s)
  return s
}
!after && index($0, anchor) == 1 { after = 1; next }
!/^\|/ { if (rows) exit; table_line = 0; next }
# A table line: its first is the header, its second the | --- | line, the rest rows.
{ ++table_line }
after && !taken && table_line == 1 {
  delete at
  for (i = 2; i < NF; ++i) {
    name = trim($i)
    if (!(name in at)) at[name] = i
  }
  taken = 1
  for (w = 1; w <= nwant; ++w) if (!(want[w] in at)) taken = 0
  next
}
taken && table_line > 2 {
  line = ""
  for (w = 1; w <= nwant; ++w) line = line (w > 1 ? "\t" : "") clean($(at[want[w]]))
  print line
  ++rows
}
END { exit rows > 0 ? 0 : 1 }
