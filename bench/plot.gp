# plot.gp - the benchmark figures; bench/plot.sh sets
#   term, mode ("wp", "inv" or "iters"), out, and
#   wp, inv:  prob, files, titles, colors, dts, pts, lws (space-separated lists)
#             (inv also has_g: 1 when the problem has constraints)
#   iters:    probs, and files_P, titles_P, ..., lws_P for each problem P
# Data files: h seconds err_q err_H err_g (wp, inv) or h iters_per_step.
eval "set terminal ".term
set output out
set logscale xy
set format x "10^{%L}"
set format y "10^{%L}"
set grid
set key outside right top samplen 2 spacing 1.1


if (mode eq "wp") {
  set title prob.": CPU time to reach an error at the final time (lower left is better)" noenhanced
  set xlabel "err_q = max-norm error of (q, p) at T"
  set ylabel "CPU seconds (median of 5)"
  plot for [i=1:words(files)] word(files, i) using 3:2 with linespoints lw real(word(lws, i)) ps 0.9 \
       lc rgb word(colors, i) dt int(word(dts, i)) pt int(word(pts, i)) title word(titles, i)
}

if (mode eq "inv") {
  cols = has_g ? 2 : 1
  set multiplot layout 1, cols title prob.": invariants over the run against CPU time" noenhanced
  set xlabel "CPU seconds"
  set ylabel "max |H - H0|"
  set key inside top right font ",8" samplen 1 spacing 0.9
  plot for [i=1:words(files)] word(files, i) using 2:4 with linespoints lw 0.8 * real(word(lws, i)) ps 0.7 \
       lc rgb word(colors, i) dt int(word(dts, i)) pt int(word(pts, i)) title word(titles, i)
  if (has_g) {
    set ylabel "max |g|"
    plot for [i=1:words(files)] word(files, i) using 2:5 with linespoints lw 0.8 * real(word(lws, i)) ps 0.7 \
         lc rgb word(colors, i) dt int(word(dts, i)) pt int(word(pts, i)) title word(titles, i)
  }
  unset multiplot
}

if (mode eq "iters") {
  # three panels a row, as many rows as needed (problem names may hold "_",
  # hence noenhanced titles)
  set multiplot layout (words(probs) + 2) / 3, 3 title "mean fixed-point iterations per step against h (const solid, generic dashed, poly thick with triangles)"
  unset logscale y
  set format y "%g"
  set xlabel "h"
  set ylabel "iterations per step"
  set key inside top left font ",8" samplen 1 spacing 0.9
  do for [p in probs] {
    files = value("files_".p)
    titles = value("titles_".p)
    colors = value("colors_".p)
    dts = value("dts_".p)
    pts = value("pts_".p)
    lws = value("lws_".p)
    set title p noenhanced
    plot for [i=1:words(files)] word(files, i) using 1:2 with linespoints lw 0.8 * real(word(lws, i)) ps 0.6 \
         lc rgb word(colors, i) dt int(word(dts, i)) pt int(word(pts, i)) title word(titles, i)
  }
  unset multiplot
}
