# Sourced by run-sim.sh, replay.sh and run-drone.sh: the argument checks they share.
#   is_positive VALUE   true when VALUE is a plain decimal number (digits, optional fraction; no
#                       sign or exponent) greater than 0, as their numeric flags expect
is_positive() { [[ "$1" =~ ^[0-9]+([.][0-9]+)?$ ]] && awk -v v="$1" 'BEGIN { exit !(v > 0) }'; }
