# The end-to-end benchmark's plot: success rate and certified-wrong count per swarm size (left),
# simulated time to the certified result, median and p90, and CPU per drone (right). Usage:
#   gnuplot -e "dir='bench/results'" bench/plots/e2e.gp
if (!exists("dir")) dir = "bench/results"
set terminal pngcairo size 1200,450 noenhanced font ",10"
set output dir."/e2e.png"
set datafile separator ","
set multiplot layout 1,2 title "fact-bench-e2e: simulated swarms initializing end to end (run-sim.sh --fast, obstacles)"
set xlabel "drones"
set grid
set key bottom left
set ylabel "% of runs"
set yrange [0:105]
plot dir."/e2e.csv" using 1:3 with linespoints lw 2 pt 7 title "certified and correct", \
     "" using 1:4 with impulses lw 4 title "certified but wrong (count)"
set yrange [0:*]
set ylabel "simulated s / % of one core"
set key top left
plot dir."/e2e.csv" using 1:5 with linespoints lw 2 pt 7 title "time to certified, median (s)", \
     "" using 1:6 with linespoints lw 2 pt 5 title "time to certified, p90 (s)", \
     "" using 1:10 with linespoints lw 2 pt 9 title "CPU per drone, all apps (% core at real time)"
unset multiplot
