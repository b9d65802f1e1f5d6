#!/usr/bin/env bash
# Black-box test of adaptseg_fit_temperature (examples/tools/fit_temperature.cpp) on a copy of the
# bundled MobileNetV2 and a quarter of Dubai tile 4 at two GSD bands: the fitted temperature lowers
# the cross-entropy it minimises, --at evaluates a given one, --write and --set change only the
# copy's `temperature` line, and the command-line mistakes exit 2 with one line.
#   test_fit_temperature_cli.sh FIT_BINARY EXAMPLES_DIR
set -uo pipefail
mission=$1 examples=$2
source "$(dirname "$0")/cli_common.sh"
cp -r "$examples/models/mobilenetv2-dubai" "$work/net"
field=("--field" "$examples/data/dubai-tile-4:0,0,0.5,0.5" --bands 2,3 --pixel-stride 4)

"$mission" --network "$work/net" "${field[@]}" >"$work/fit.out" 2>"$work/fit.err" ||
  fail "the fit: $(cat "$work/fit.err")"
cat "$work/fit.out"
# "temperature: T (cross-entropy A at T = 1, B at T = T; the model file has T = W)"
read -r t a b <<<"$(sed -n 's/^temperature: \([0-9.]*\) (cross-entropy \([0-9.]*\) at T = 1, \([0-9.]*\) at T = .*/\1 \2 \3/p' "$work/fit.out")"
[ -n "${t:-}" ] || fail "no temperature line: $(head -1 "$work/fit.out")"
awk -v t="$t" -v a="$a" -v b="$b" 'BEGIN { exit !(t >= 0.25 && t <= 8.8 && b < a) }' ||
  fail "temperature $t outside [0.25, 8.8], or its cross-entropy $b not below T = 1's $a"
[ "$(grep -c '^| [0-9]' "$work/fit.out")" -eq 2 ] || fail "want one ECE row per band: $(cat "$work/fit.out")"
grep -q "^band 10.00 cm/px: [1-9][0-9]* images" "$work/fit.err" || fail "band 10 cm/px: $(cat "$work/fit.err")"

# --at: the same pixels at a given temperature, nothing fitted, the model untouched.
"$mission" --network "$work/net" "${field[@]}" --at 1 >"$work/at.out" 2>/dev/null || fail "--at 1"
grep -qE "^evaluated at: 1\.0000 \(cross-entropy $a at T = 1, $a at T = 1\.0000;" "$work/at.out" ||
  fail "--at 1: $(head -1 "$work/at.out")"
cmp -s "$examples/models/mobilenetv2-dubai/model.yaml" "$work/net/model.yaml" || fail "--at changed model.yaml"

# --write: the fitted value in the copy's temperature line, every other line as it was.
"$mission" --network "$work/net" "${field[@]}" --write >/dev/null 2>&1 || fail "--write"
grep -qx "temperature: $t" "$work/net/model.yaml" || fail "--write: $(grep temperature "$work/net/model.yaml")"
diff <(grep -v '^temperature:' "$examples/models/mobilenetv2-dubai/model.yaml") \
  <(grep -v '^temperature:' "$work/net/model.yaml") >/dev/null || fail "--write changed more than the temperature"
"$mission" --network "$work/net" --set 1.25 || fail "--set 1.25"
grep -qx "temperature: 1.2500" "$work/net/model.yaml" || fail "--set: $(grep temperature "$work/net/model.yaml")"

expect_error "--field is required" --network "$work/net"
expect_error "--segmenter must be network" --network "$work/net" "${field[@]}" --segmenter oracle
expect_error "no --field, --write or --at with it" --network "$work/net" --set 1.5 "${field[@]}"
expect_error "cannot be combined with --write" --network "$work/net" "${field[@]}" --at 1 --write
expect_error "is an ensemble" --network "$examples/models/ensemble-dubai" "${field[@]}"
expect_error "--set" --network "$work/net" --set 0
grep -qx "temperature: 1.2500" "$work/net/model.yaml" || fail "a refused command changed model.yaml"
echo "PASS: adaptseg_fit_temperature"
