# Sourced by run-sim.sh, replay.sh and run-drone.sh: the argument checks they share.
#   is_positive VALUE   true when VALUE is a plain decimal number (digits, optional fraction; no
#                       sign or exponent) greater than 0, as their numeric flags expect
is_positive() { [[ "$1" =~ ^[0-9]+([.][0-9]+)?$ ]] && awk -v v="$1" 'BEGIN { exit !(v > 0) }'; }
#   is_port VALUE       true when VALUE is a port number 1-65535 (digits, no leading zero)
is_port() { [[ "$1" =~ ^[1-9][0-9]{0,4}$ ]] && [ "$1" -le 65535 ]; }
