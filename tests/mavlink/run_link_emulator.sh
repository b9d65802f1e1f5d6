#!/usr/bin/env bash
# CTest mavlink:emulator: adaptseg::mavlink's VehicleLink (tests/mavlink/link_flight.cpp) flies
# against an emulated autopilot written with node-mavlink (tests/mavlink/emulator.mjs), over UDP
# on 127.0.0.1, once per firmware and once per fault:
#   px4, ardupilot   5 waypoints, camera, RTL and landing: exit 0; the emulator saw no bad
#                    checksum and the commands of its firmware (ArduPilot: GUIDED set first)
#   drop             10 % of the datagrams dropped both ways (ArduPilot): the mission completes
#   link_lost        the link lost mid-mission: LinkLost, exit 2, what it flew reported
#   refused          DO_REPOSITION answered DENIED: fails at once (sent once), exit 2
#   stop_short_fail  the vehicle stops 2 m short, tolerance 0.5 m: stopped ~2 m short, exit 2
#   stop_short_pass  the same with a 3 m tolerance: completes
#   no_fix           no GPS fix: connect refuses, nothing commanded, exit 2
#   geofence         a waypoint outside the site: refused, never sent, exit 2
# The scenarios run side by side (each link binds its own port); about 35 s in all.
#   tests/mavlink/run_link_emulator.sh FLIGHT_BINARY WORK_DIR
# Exit 77 (CTest's SKIP_RETURN_CODE) if node or the pinned node-mavlink is not installed:
#   (cd tests/mavlink && npm ci)     # scripts/test.sh does it where npm exists
set -uo pipefail
flight=$1 work=$2
here=$(cd "$(dirname "$0")" && pwd)
source "$here/require_node_mavlink.sh" "the emulated autopilot"
mkdir -p "$work"

# The emulator's flight: 5 m/s, 3 m/s^2, landing at 4 m/s, so that 5 legs of ~11 m and the
# return fit in ~30 s (emulator.mjs flies at the timing model's 2 m/s by default).
physics="--speed 5 --accel 3 --land-speed 4"

# scenario NAME "EMULATOR OPTIONS" "FLIGHT OPTIONS": both sides' output, exit code and report in WORK_DIR/NAME.
scenario() {
  local name=$1 emulator_options=$2 flight_options=$3 dir="$work/$1"
  rm -rf "$dir" && mkdir -p "$dir"
  # shellcheck disable=SC2086  # the options are words
  timeout 90 "$flight" --connect udpin:127.0.0.1:0 --port-file "$dir/port" $flight_options \
    >"$dir/flight.out" 2>"$dir/flight.err" &
  local flight_pid=$!
  for _ in $(seq 200); do [ -s "$dir/port" ] && break; sleep 0.05; done
  if [ ! -s "$dir/port" ]; then
    echo "no port written" >"$dir/flight.err"
    kill "$flight_pid" 2>/dev/null
    echo 1 >"$dir/rc"
    return
  fi
  # shellcheck disable=SC2086
  node "$here/emulator.mjs" --port "$(cat "$dir/port")" --report "$dir/report.json" --max-time 100 \
    $physics $emulator_options >"$dir/emulator.out" 2>&1 &
  local emulator_pid=$!
  wait "$flight_pid"
  echo $? >"$dir/rc"
  kill -TERM "$emulator_pid" 2>/dev/null
  wait "$emulator_pid"
}

scenario px4 "--firmware px4" "" &
scenario ardupilot "--firmware ardupilot" "" &
scenario drop "--firmware ardupilot --drop 0.1 --seed 7" "--attempts 8 --mode-timeout-s 5" &
scenario link_lost "--firmware px4 --lose-link-after 7" "--link-timeout-s 2" &
scenario refused "--firmware px4 --refuse 192" "" &
scenario stop_short_fail "--firmware px4 --stop-short 2" "--tolerance-m 0.5 --stall-s 2" &
scenario stop_short_pass "--firmware px4 --stop-short 2" "--tolerance-m 3 --stall-s 2 --land-timeout-s 0" &
scenario no_fix "--firmware px4 --no-fix" "--fix-timeout-s 3" &
scenario geofence "--firmware px4" "--outside-after 2 --site-m 15" &
wait

failures=0
fail() {
  echo "FAIL $1: $2"
  echo "  flight stdout: $(tr '\n' '|' <"$work/$1/flight.out")"
  echo "  flight stderr: $(tr '\n' '|' <"$work/$1/flight.err")"
  failures=$((failures + 1))
}
# expect NAME RC: the flight's exit code
expect_rc() {
  local got
  got=$(cat "$work/$1/rc" 2>/dev/null || echo none)
  [ "$got" = "$2" ] || fail "$1" "exit code $got, expected $2"
}
# expect_err NAME REGEX: the one line on stderr
expect_err() {
  grep -Eq -- "$2" "$work/$1/flight.err" || fail "$1" "stderr does not match /$2/"
  [ "$(wc -l <"$work/$1/flight.err")" -le 1 ] || fail "$1" "more than one line on stderr"
}
expect_out() {
  grep -Eq -- "$2" "$work/$1/flight.out" || fail "$1" "stdout does not match /$2/"
}
# expect_report NAME JS-EXPRESSION: true of the emulator's report r (every scenario: no bad checksum)
expect_report() {
  if [ ! -s "$work/$1/report.json" ]; then
    fail "$1" "the emulator wrote no report"
    return
  fi
  local js='const r = JSON.parse(require("fs").readFileSync(process.argv[1], "utf8"));
    const c = (id) => r.commands[id] || 0;
    process.exit(r.bad_crc === 0 && r.frames_received > 0 && ('"$2"') ? 0 : 1);'
  node -e "$js" "$work/$1/report.json" || fail "$1" "emulator report: not ($2) or bad checksums: $(tr -d '\n' <"$work/$1/report.json" | head -c 600)"
}

expect_rc px4 0
expect_out px4 "flew 5 of 5 waypoints, returned and landed"
expect_report px4 'c(192) === 5 && c(2000) === 5 && c(203) === 0 && c(176) === 0 && c(20) === 1 && c(511) === 2 &&
  r.captures === 5 && r.landed && r.gcs.sysid === 255 && r.gcs.sequence_gaps === 0 && r.repositions.every((p) => Math.abs(p[2] - 20) < 0.01 || Math.abs(p[2] - 25) < 0.01)'

expect_rc ardupilot 0
expect_out ardupilot "flew 5 of 5 waypoints, returned and landed"
expect_report ardupilot 'c(176) === 1 && c(192) === 5 && c(203) === 5 && c(2000) === 0 && r.captures === 5 && r.landed &&
  r.modes[0] === 4 && r.repositions.every((p) => Math.abs(p[2] - 20) < 0.01 || Math.abs(p[2] - 25) < 0.01)'

expect_rc drop 0
expect_out drop "flew 5 of 5 waypoints, returned and landed"
expect_report drop 'r.dropped_in > 0 && r.dropped_out > 0 && c(192) >= 5 && r.landed'

expect_rc link_lost 2
expect_err link_lost "^link_flight: (go_to|wait_arrival|trigger_camera): no frame from the vehicle \(system 1\) for 2\.[0-9] s on udpin:127\.0\.0\.1:[0-9]+: the link is lost; the vehicle is left to its own failsafe$"
expect_out link_lost "^flew [0-4] of 5 waypoints; stopped: link_lost$"
expect_report link_lost 'r.lost_link && c(192) >= 1 && c(192) <= 4 && c(20) === 0'

expect_rc refused 2
expect_err refused "^link_flight: go_to: the vehicle refused DO_REPOSITION \(192\): MAV_RESULT_DENIED \(the vehicle says: \"Reposition command rejected\"\)$"
expect_out refused "^flew 0 of 5 waypoints; stopped: refused$"
expect_report refused 'c(192) === 1 && c(20) === 0'

expect_rc stop_short_fail 2
expect_err stop_short_fail "^link_flight: wait_arrival: the vehicle stopped (1\.9|2\.0|2\.1) m short of \("
expect_out stop_short_fail "^flew 0 of 5 waypoints; stopped: stopped_short$"
expect_report stop_short_fail 'c(192) === 1'

expect_rc stop_short_pass 0
expect_out stop_short_pass "waypoint 5/5 .*: arrived [0-3]\.[0-9]+ m off"
expect_out stop_short_pass "flew 5 of 5 waypoints, returned"
expect_report stop_short_pass 'c(192) === 5 && c(20) === 1'

expect_rc no_fix 2
expect_err no_fix "^link_flight: connect: no 3-D GPS fix within 3\.0 s: GPS_RAW_INT says fix_type 1 \(no fix\), 0 satellites; refusing to start without one$"
expect_report no_fix 'c(192) === 0 && c(511) === 2'

expect_rc geofence 2
expect_err geofence "^link_flight: go_to: refused to send the vehicle to \([0-9., m-]+\): outside the site polygon$"
expect_out geofence "^flew 2 of 5 waypoints; stopped: outside_site$"
expect_report geofence 'c(192) === 2'

if [ "$failures" -gt 0 ]; then
  echo "mavlink:emulator: $failures check(s) failed (outputs in $work)"
  exit 1
fi
echo "mavlink:emulator: 9 scenarios as expected against the node-mavlink autopilot (outputs in $work)"
for s in px4 ardupilot drop link_lost refused stop_short_fail stop_short_pass no_fix geofence; do
  line=$(head -n 1 "$work/$s/flight.err")
  [ -n "$line" ] || line=$(tail -n 1 "$work/$s/flight.out")
  printf '  %-16s %s\n' "$s" "$(echo "$line" | head -c 200)"
done
