#!/bin/sh
# bench/plot.sh RESULTS WORKDIR - the figures of bench/results from its CSVs:
#   wp_PROBLEM.png    CPU seconds against err_q (work-precision), one line
#                     per method and per (k,s) for HBVM: const(k,s) the
#                     paper's method (hbvm), the generic HBVM dashed in its
#                     colour, poly(k,s) (hbvm-poly, order 2s) thick, with
#                     triangles, in a palette of its own
#   inv_PROBLEM.png   max |H - H0| and max |g| against CPU seconds
#                     (hbvm-adaptive, hbvm-poly-adaptive: NAME_step_adaptive over
#                     tolerances, thick red with diamonds)
#   iterations.png    mean fixed-point iterations per step against h
# The series are split out of the CSVs into WORKDIR/*.dat, then drawn by
# bench/plot.gp.
set -eu
R=$1
W=$2
mkdir -p "$W"
rm -f "$W"/*.dat

. "$(dirname "$0")/common.sh"
term=$(png_terminal 1100,750)
KS_COLORS="#1f77b4 #ff7f0e #2ca02c #d62728 #17becf #e377c2 #8c564b #bcbd22 #aec7e8"
POLY_COLORS="#000080 #b22222 #006400 #ff00ff #8b4513"

# Split csv ($1) into WORKDIR/PROBLEM__SERIES.dat (h, seconds, err_q, err_H,
# err_g or, for iterations.csv, h, iters_per_step) and list the series as
# "problem series" lines in order of appearance.
split() {
  awk -F, -v w="$W" -v kind="$2" 'NR > 1 && !(kind == "it" && $2 ~ /adaptive/) {
    key = $2 ($3 != "" ? "(" $3 "," $4 ")" : "")
    f = w "/" $1 "__" key "." kind ".dat"
    if (!(f in seen)) { seen[f] = 1; print $1, key }
    if (kind == "wp") print $5, $7, $8, $9, ($10 == "" ? "NaN" : $10) > f
    else print $5, $7 > f
  }' "$1"
}

# The gnuplot lists (files, titles, colours, dash types, point types) of a
# problem's series, from "problem series" lines on stdin.
lists() {
  awk -v prob="$1" -v w="$W" -v kind="$2" -v palette="$KS_COLORS" -v ppalette="$POLY_COLORS" '
    BEGIN { np = split(palette, pal, " "); npp = split(ppalette, ppal, " ")
            other["rattle"] = "#000000"; other["ida"] = "#9467bd"
            other["gsl-rk8pd"] = "#7f7f7f"; other["gsl-rk4imp"] = "#aa6600" }
    $1 == prob {
      key = $2; method = key; ks = ""
      if (i = index(key, "(")) { method = substr(key, 1, i - 1); ks = substr(key, i) }
      if (method ~ /-adaptive$/) {
        c = "#e41a1c"; d = 1; t = (method == "hbvm-poly-adaptive" ? "adaptive poly" : "adaptive") ks
        pt = 13; lw = 3
      } else if (method == "hbvm-poly") {
        if (!(ks in pcol)) pcol[ks] = ppal[++npk > npp ? npp : npk]
        c = pcol[ks]; d = 1; t = "poly" ks; pt = 9; lw = 2.5
      } else if (ks != "") {
        if (!(ks in col)) col[ks] = pal[++nks > np ? np : nks]
        c = col[ks]; d = method == "hbvm" ? 1 : 2; t = method == "hbvm" ? "const" ks : "generic" ks
        pt = method == "hbvm" ? 7 : 6; lw = 1.5
      } else { c = other[method]; d = 1; t = method; pt = 5; lw = 1.5 }
      files = files " " w "/" prob "__" key "." kind ".dat"; titles = titles " " t
      colors = colors " " c; dts = dts " " d; pts = pts " " pt; lws = lws " " lw
    }
    END { printf "files=\"%s\"; titles=\"%s\"; colors=\"%s\"; dts=\"%s\"; pts=\"%s\"; lws=\"%s\"\n", files, titles, colors, dts, pts, lws }'
}

split "$R/work_precision.csv" wp >"$W/series.wp"
split "$R/iterations.csv" it >"$W/series.it"
for p in $(cut -d' ' -f1 "$W/series.wp" | uniq); do
  vars=$(lists "$p" wp <"$W/series.wp")
  has_g=$(awk -F, -v p="$p" '$1 == p && $10 != "" { print 1; exit }' "$R/work_precision.csv")
  gnuplot -e "term=\"$term\"; mode=\"wp\"; prob=\"$p\"; out=\"$R/wp_$p.png\"; $vars" bench/plot.gp
  gnuplot -e "term=\"$term\"; mode=\"inv\"; prob=\"$p\"; out=\"$R/inv_$p.png\"; has_g=${has_g:-0}; $vars" bench/plot.gp
done
probs=$(cut -d' ' -f1 "$W/series.it" | uniq | tr '\n' ' ')
{
  for p in $probs; do
    lists "$p" it <"$W/series.it" | sed "s/^files=/files_$p=/; s/; titles=/; titles_$p=/;
      s/; colors=/; colors_$p=/; s/; dts=/; dts_$p=/; s/; pts=/; pts_$p=/; s/; lws=/; lws_$p=/"
  done
} >"$W/iterations.gp"
gnuplot -e "term=\"$term\"; mode=\"iters\"; probs=\"$probs\"; out=\"$R/iterations.png\"" \
  -e "load \"$W/iterations.gp\"" bench/plot.gp
