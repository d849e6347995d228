# The detector benchmark's plot: recall and precision against range (left), median range error
# (% of range) and bearing error (degrees) against range (right). Usage:
#   gnuplot -e "dir='bench/results'" bench/plots/detector.gp
if (!exists("dir")) dir = "bench/results"
set terminal pngcairo size 1200,450 noenhanced font ",10"
set output dir."/detector.png"
set datafile separator ","
set key autotitle columnhead bottom left
set multiplot layout 1,2 title "fact-bench-detector: depth segmentation + tracker on fact-sim frames (640x480)"
set xlabel "range (m, bin centre)"
set ylabel "fraction"
set yrange [0:1.05]
set grid
plot dir."/detector.csv" using (($1+$2)/2):5 with linespoints lw 2 title "recall (unoccluded)", \
     "" using (($1+$2)/2):8 with linespoints lw 2 title "precision"
set ylabel "error"
set yrange [0:*]
set key top left
plot dir."/detector.csv" using (($1+$2)/2):9 with linespoints lw 2 title "median range error (% of range)", \
     "" using (($1+$2)/2):10 with linespoints lw 2 title "median bearing error (deg)"
unset multiplot
