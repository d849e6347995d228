# Plots of fact-bench-estimator's CSV files (PNG, 900 x 600), written next to them.
# Usage: gnuplot -e "dir='bench/results'" bench/plots/estimator.gp
# The png terminal draws no dash patterns, so the paper's numbers and the reference series are
# told apart by open symbols and thin lines. Rows are picked with awk (rows whose column c equals v), so every series is one unbroken line.
if (!exists("dir")) dir = "bench/results"
set datafile separator ","
set terminal png size 900,600 font ",11"
set grid
set key below horizontal maxcols 3 spacing 1.1 width 2
set pointsize 1.2

rows(file, c, v) = sprintf("< awk -F, -v c=%d -v v='%s' '$1 !~ /^#/ && $c == v' '%s/%s'", c, v, dir, file)
rows2(file, c1, v1, c2, v2) = sprintf("< awk -F, -v c1=%d -v v1='%s' -v c2=%d -v v2='%s' '$1 !~ /^#/ && $c1 == v1 && $c2 == v2' '%s/%s'", c1, v1, c2, v2, dir, file)

# --- 1. Table I: rotation solve time against N, ours and the paper's (log y)
set output dir."/estimator_table1_time.png"
set title "Table I: time of one rotation solve, median over scenarios\n(paper noise 0.05 x range, K = N+1 rounds, all-to-all)"
set xlabel "drones N"
set ylabel "time per solve (µs, log scale)"
set logscale y
set format y "10^{%T}"
set xrange [1.8:8.2]
set xtics 1
plot rows("estimator_table1.csv", 2, "sdp_plain")   using 1:4 with linespoints lw 2 pt 7 lc rgb "#1f77b4" title "SDP plain (ours)", \
     rows("estimator_table1.csv", 2, "sdp_complex") using 1:4 with linespoints lw 2 pt 5 lc rgb "#2ca02c" title "SDP complex form (ours)", \
     rows("estimator_table1.csv", 2, "gn_zero")     using 1:4 with linespoints lw 2 pt 9 lc rgb "#d62728" title "GN from 0 (ours)", \
     rows("estimator_table1.csv", 2, "lm_zero")     using 1:4 with linespoints lw 2 pt 11 lc rgb "#ff7f0e" title "LM from 0 (ours)", \
     rows("estimator_table1.csv", 2, "gn_multi")    using 1:4 with linespoints lw 2 pt 8 lc rgb "#9467bd" title "GN 20 starts (ours)", \
     rows("estimator_table1.csv", 2, "lm_multi")    using 1:4 with linespoints lw 2 pt 10 lc rgb "#8c564b" title "LM 20 starts (ours)", \
     rows("estimator_table1.csv", 2, "sdp_plain")   using 1:($11*1e6) with linespoints lw 1 pt 6 lc rgb "#1f77b4" title "paper: SDP (MOSEK)", \
     rows("estimator_table1.csv", 2, "lm_zero")     using 1:($11*1e6) with linespoints lw 1 pt 12 lc rgb "#ff7f0e" title "paper: LM", \
     rows("estimator_table1.csv", 2, "gn_zero")     using 1:($11*1e6) with linespoints lw 1 pt 10 lc rgb "#d62728" title "paper: GN"
unset logscale y
set format y "% g"

# --- 2. Yaw MAE against N (paper noise 0.05)
set output dir."/estimator_mae_vs_n.png"
set title "Yaw error vs N (paper noise 0.05 x range, K = N+1 rounds, all-to-all)\nmodes scored whatever their status; open symbols: SDP rounded directly"
set xlabel "drones N"
set ylabel "yaw MAE (rad, log scale)"
set logscale y
set yrange [0.001:4]
plot rows("estimator_mae_vs_n.csv", 3, "paper")                using 1:5 with linespoints lw 2 pt 7 lc rgb "#1f77b4" title "mode paper", \
     rows("estimator_mae_vs_n.csv", 3, "complex")              using 1:5 with linespoints lw 2 pt 5 lc rgb "#2ca02c" title "mode complex", \
     rows("estimator_mae_vs_n.csv", 3, "associated")           using 1:5 with linespoints lw 2 pt 9 lc rgb "#d62728" title "mode associated", \
     rows("estimator_mae_vs_n.csv", 3, "associated")           using 1:7 with points pt 8 ps 2 lc rgb "#d62728" title "associated, certified only", \
     rows("estimator_mae_vs_n.csv", 3, "sdp_plain_rounding")   using 1:5 with linespoints lw 1 pt 6 lc rgb "#1f77b4" title "SDP plain, rounded", \
     rows("estimator_mae_vs_n.csv", 3, "sdp_complex_rounding") using 1:5 with linespoints lw 1 pt 4 lc rgb "#2ca02c" title "SDP complex, rounded", \
     0.085 with lines lw 1 lc rgb "gray40" title "paper's data: 0.085-0.19 rad", \
     0.19 with lines lw 1 lc rgb "gray40" notitle
unset logscale y
set yrange [*:*]

# --- 3. Yaw MAE against the paper's noise level, N = 4 (solid) and 8 (dashed)
set output dir."/estimator_mae_vs_noise.png"
set title "Yaw error vs noise (per-axis σ = paper sigma x range, K = N+1 rounds, all-to-all)\nall results whatever their status; thick: N = 4, thin with open symbols: N = 8"
set xlabel "paper noise σ per metre of range"
set ylabel "yaw MAE (rad, log scale)"
set logscale y
set yrange [0.001:4]
set xrange [0:0.32]
set xtics 0.05
plot rows2("estimator_mae_vs_noise.csv", 1, "4", 3, "paper")                using 2:5 with linespoints lw 2 pt 7 lc rgb "#1f77b4" title "paper, N=4", \
     rows2("estimator_mae_vs_noise.csv", 1, "8", 3, "paper")                using 2:5 with linespoints lw 1 pt 6 lc rgb "#1f77b4" title "paper, N=8", \
     rows2("estimator_mae_vs_noise.csv", 1, "4", 3, "complex")              using 2:5 with linespoints lw 2 pt 5 lc rgb "#2ca02c" title "complex, N=4", \
     rows2("estimator_mae_vs_noise.csv", 1, "8", 3, "complex")              using 2:5 with linespoints lw 1 pt 4 lc rgb "#2ca02c" title "complex, N=8", \
     rows2("estimator_mae_vs_noise.csv", 1, "4", 3, "associated")           using 2:5 with linespoints lw 2 pt 9 lc rgb "#d62728" title "associated, N=4", \
     rows2("estimator_mae_vs_noise.csv", 1, "8", 3, "associated")           using 2:5 with linespoints lw 1 pt 8 lc rgb "#d62728" title "associated, N=8", \
     rows2("estimator_mae_vs_noise.csv", 1, "4", 3, "sdp_plain_rounding")   using 2:5 with linespoints lw 2 pt 11 lc rgb "#9467bd" title "SDP plain rounded, N=4", \
     rows2("estimator_mae_vs_noise.csv", 1, "8", 3, "sdp_plain_rounding")   using 2:5 with linespoints lw 1 pt 10 lc rgb "#9467bd" title "SDP plain rounded, N=8", \
     rows2("estimator_mae_vs_noise.csv", 1, "4", 3, "sdp_complex_rounding") using 2:5 with linespoints lw 2 pt 13 lc rgb "#8c564b" title "SDP complex rounded, N=4", \
     rows2("estimator_mae_vs_noise.csv", 1, "8", 3, "sdp_complex_rounding") using 2:5 with linespoints lw 1 pt 12 lc rgb "#8c564b" title "SDP complex rounded, N=8"
unset logscale y
set yrange [*:*]
set xrange [*:*]
set xtics autofreq

# --- 4. Rounds to certified against N, per mode (depth noise, 6 m range)
set output dir."/estimator_rounds_vs_n.png"
set title "Rounds until certified, mean over the certified scenarios\n(depth noise, 6 m range, room max(4, 2.5 sqrt N) m, K_{max} = N+3)"
set xlabel "drones N (log scale)"
set ylabel "rounds to certified"
set logscale x 2
set xrange [1.8:36]
set xtics (2, 3, 4, 6, 8, 12, 16, 24, 32)
set yrange [0:14]
plot rows("estimator_modes.csv", 1, "paper")      using 2:7 with linespoints lw 2 pt 7 lc rgb "#1f77b4" title "paper", \
     rows("estimator_modes.csv", 1, "complex")    using 2:7 with linespoints lw 2 pt 5 lc rgb "#2ca02c" title "complex", \
     rows("estimator_modes.csv", 1, "associated") using 2:7 with linespoints lw 2 pt 9 lc rgb "#d62728" title "associated", \
     rows("estimator_modes.csv", 1, "auto")       using 2:7 with linespoints lw 1 pt 12 ps 1.8 lc rgb "black" title "auto", \
     x + 1 with lines lc rgb "gray40" title "N+1 (paper, noise-free)", \
     x - 1 with lines lc rgb "#bcbd22" title "N-1 (complex, noise-free)"

# --- 5. Success rate against N, per mode
set output dir."/estimator_success_vs_n.png"
set title "Scenarios certified within K_{max} = N+3 rounds (thick) and within 2 rounds (thin, open)\n(depth noise, 6 m range, room max(4, 2.5 sqrt N) m)"
set ylabel "scenarios certified (%)"
set yrange [-5:105]
plot rows("estimator_modes.csv", 1, "paper")      using 2:($5*100) with linespoints lw 2 pt 7 lc rgb "#1f77b4" title "paper", \
     rows("estimator_modes.csv", 1, "complex")    using 2:($5*100) with linespoints lw 2 pt 5 lc rgb "#2ca02c" title "complex", \
     rows("estimator_modes.csv", 1, "associated") using 2:($5*100) with linespoints lw 2 pt 9 lc rgb "#d62728" title "associated", \
     rows("estimator_modes.csv", 1, "auto")       using 2:($5*100) with linespoints lw 2 pt 13 lc rgb "black" title "auto", \
     rows("estimator_modes.csv", 1, "paper")      using 2:($6*100) with linespoints lw 1 pt 6 lc rgb "#1f77b4" title "paper, ≤ 2 rounds", \
     rows("estimator_modes.csv", 1, "complex")    using 2:($6*100) with linespoints lw 1 pt 4 lc rgb "#2ca02c" title "complex, ≤ 2 rounds", \
     rows("estimator_modes.csv", 1, "associated") using 2:($6*100) with linespoints lw 1 pt 8 lc rgb "#d62728" title "associated, ≤ 2 rounds", \
     rows("estimator_modes.csv", 1, "auto")       using 2:($6*100) with linespoints lw 1 pt 12 lc rgb "black" title "auto, ≤ 2 rounds"
