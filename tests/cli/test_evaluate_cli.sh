#!/usr/bin/env bash
# Black-box test of adaptseg_evaluate, the paper's experiment on a scene the decision function
# never saw: initialised on Dubai tile 3, flown on tile 6 with the oracle, L = {road} (0.8 % of
# tile 6's pixels: a spatially localised class). Checks results.csv's and decisions.csv's
# columns, the figures (and the tour strategy's rows), a positive front margin for the adaptive strategy, and that a budget is
# never exceeded.
#   test_evaluate_cli.sh EVALUATE_BINARY EXAMPLES_DIR
set -uo pipefail
evaluate=$1 examples=$2
source "$(dirname "$0")/cli_common.sh"
fixed=(--seg-time-s 0.1 --plan-time-s 0)
"$evaluate" --train "$examples/data/dubai-tile-3" --test "$examples/data/dubai-tile-6" --interest road \
  "${fixed[@]}" --out "$work/e" >"$work/log" 2>&1 || fail "evaluate failed: $(tail -5 "$work/log")"
for f in results.csv per_image.csv decisions.csv strategies.csv model.yaml miou_vs_time.png per_image_miou.png decisions.png paths.png \
  maps.png; do
  [ -s "$work/e/$f" ] || fail "missing $f"
done
# strategies.csv: the table of strategies the figures read (examples/common/strategies.hpp), in
# the order results.csv has them on the test field, each with its legend label.
[ "$(head -1 "$work/e/strategies.csv")" = "name,policy,schedule,online,label" ] ||
  fail "strategies.csv header: $(head -1 "$work/e/strategies.csv")"
[ "$(awk -F, 'NR > 1 {print $1}' "$work/e/strategies.csv" | paste -sd,)" = \
  "$(awk -F, 'NR > 1 && !seen[$2]++ {print $2}' "$work/e/results.csv" | paste -sd,)" ] ||
  fail "strategies.csv does not list results.csv's strategies in their order"
grep -qx 'adaptive,decision_function,immediate,true,"adaptive"' "$work/e/strategies.csv" &&
  grep -qx 'nonadaptive,decision_function,immediate,false,"non-adaptive"' "$work/e/strategies.csv" &&
  grep -qx 'tour,decision_function,tour,true,.*' "$work/e/strategies.csv" ||
  fail "strategies.csv rows: $(cat "$work/e/strategies.csv")"
echo "ok: strategies.csv lists the strategies flown"
header=$(head -1 "$work/e/results.csv")
want="field,strategy,gsd_cm,miou_interest,miou_all,time_total,time_flight,time_segmentation,time_planning,images,front_margin"
[ "${header#"$want"}" != "$header" ] || fail "results.csv header: $header"
# adaptive's row: front margin (column 11) > 0
margin=$(awk -F, '$2 == "adaptive" {print $11}' "$work/e/results.csv")
[ -n "$margin" ] || fail "no adaptive row"
awk -v m="$margin" 'BEGIN {exit !(m > 0)}' || fail "adaptive front margin $margin is not positive"
echo "ok: adaptive front margin on dubai-tile-6 (road) = $margin"
# decisions.csv: one row per top-level decision of each model-based strategy; every descent of
# adaptive carries its forecast, what it relabelled (no truth needed) and what it realised.
want="field,strategy,decision,image,sigma,action,gsd_cm,images,extra_time_s,forecast_delta_sigma,forecast_delta_miou,"
want+="forecast_delta_miou_std,forecast_relabelled_interest,forecast_field_gain,forecast_front_margin,observed_sigma_sub,"
want+="observed_relabelled,observed_relabelled_interest,realised_region_delta_miou,realised_field_gain,flown,"
want+="observed_top_input,observed_fine_input,realised_delta_tp,realised_delta_fp,realised_delta_fn,forecast_curve_rise,"
want+="forecast_end_s,realised_field_gain_region"
[ "$(head -1 "$work/e/decisions.csv")" = "$want" ] || fail "decisions.csv header: $(head -1 "$work/e/decisions.csv")"
# Every realised descent's pixel counts: present, whole numbers, and a class's true positives and
# false negatives (its pixels, whatever the map says) moving by opposite amounts.
awk -F, '$2 == "adaptive" && $6 == "descend" { n++
    if ($24 !~ /^-?[0-9]+$/ || $25 !~ /^-?[0-9]+$/ || $26 !~ /^-?[0-9]+$/) bad++
    if ($24 + $26 != 0) bad++ }
  END {exit !(n > 0 && bad == 0)}' "$work/e/decisions.csv" ||
  fail "decisions.csv: realised_delta_tp / fp / fn missing, not whole, or TP and FN not moving together"
descents=$(awk -F, '$2 == "adaptive" {print $12}' "$work/e/results.csv")
awk -F, -v n="$descents" '$2 == "adaptive" {rows++} $2 == "adaptive" && $6 == "descend" {
    d++; if ($13 == "" || $14 == "" || $18 == "" || $20 == "" || $14 <= 0 || $20 <= 0 || $29 !~ /^-?[0-9]+\.[0-9]+$/) bad++ }
  END {exit !(rows > 0 && d == n && d > 0 && bad == 0)}' "$work/e/decisions.csv" ||
  fail "decisions.csv: adaptive's $descents descents not all recorded with forecast, observation and realised gain"
echo "ok: decisions.csv records adaptive's $descents descents"
# How each descent was flown: adaptive always at once; tour and row at once or in a tour.
# Adaptive's altitude changes (results.csv column 13): one or two per descent.
awk -F, '$6 == "descend" && !((($2 == "tour" || $2 == "row") && ($21 == "now" || $21 == "tour")) ||
                              ($2 != "tour" && $2 != "row" && $21 == "now")) {bad++}
  $2 == "tour" {tour++} $2 == "row" {row++} END {exit !(bad == 0 && tour > 0 && row > 0)}' "$work/e/decisions.csv" ||
  fail "decisions.csv: column flown is not now/tour as the strategy allows, or no tour or row rows"
awk -F, -v n="$descents" '$2 == "adaptive" {exit !($13 >= n && $13 <= 2 * n)}' "$work/e/results.csv" ||
  fail "results.csv: adaptive's altitude_changes is not between its descents and twice them"
echo "ok: decisions.csv says how each descent was flown"
# per_image.csv: every image has the truth's share of L, in [0, 1]; road is in some of them
want="field,strategy,gsd_cm,image,level,image_gsd_cm,sigma,image_miou_interest,image_miou_all,truth_sigma"
[ "$(head -1 "$work/e/per_image.csv")" = "$want" ] || fail "per_image.csv header: $(head -1 "$work/e/per_image.csv")"
awk -F, 'NR > 1 {n++; if ($10 == "" || $10 < 0 || $10 > 1) bad++; if ($10 > 0) some++}
  END {exit !(n > 0 && bad == 0 && some > 0)}' "$work/e/per_image.csv" || fail "per_image.csv truth_sigma out of [0, 1] or never > 0"

# With a budget between the top-level coverage and what adaptive took without one, no mission
# exceeds it (and the top level is still covered: evaluate fails otherwise).
total=$(awk -F, '$2 == "adaptive" {print $6}' "$work/e/results.csv")
budget=$(awk -F, '$2 == "lawnmower" && $3 == "15.000" {print $6}' "$work/e/results.csv")
[ -n "$total" ] && [ -n "$budget" ] || fail "missing adaptive or 15 cm/px lawnmower row"
budget=$(awk -v a="$total" -v b="$budget" 'BEGIN {printf "%.1f", (a + b) / 2}')
"$evaluate" --decision-model "$work/e/model.yaml" --test "$examples/data/dubai-tile-6" --interest road "${fixed[@]}" \
  --budget-s "$budget" --no-plots --out "$work/b" >"$work/log" 2>&1 || fail "evaluate with budget failed"
awk -F, -v b="$budget" 'NR > 1 && $2 != "lawnmower" && $6 > b + 1e-6 {bad = 1; print "over budget: " $0}
  END {exit bad}' "$work/b/results.csv" || fail "a mission exceeded the budget $budget s"
echo "ok: budget $budget s kept"

# A calibration flag next to --decision-model (which fixes the calibration) is refused, not ignored.
if "$evaluate" --decision-model "$work/e/model.yaml" --test "$examples/data/dubai-tile-6" --coverage region \
  --out "$work/x" >"$work/log" 2>&1; then
  fail "--coverage with --decision-model was accepted"
fi
grep -q "excludes" "$work/log" || fail "no clear error for --coverage with --model: $(tail -3 "$work/log")"
# The old spellings (--model, --calibration-model-file) inherit the exclusions stated for the new.
for flags in "--model $work/e/model.yaml --coverage region" \
  "--model $work/e/model.yaml --segmenter network --network $examples/models/mobilenetv2-dubai --calibration-network $examples/models/mobilenetv2-dubai-loto/tile-1" \
  "--decision-model $work/e/model.yaml --segmenter network --network $examples/models/mobilenetv2-dubai --calibration-model-file $examples/models/mobilenetv2-dubai-loto/tile-1"; do
  # shellcheck disable=SC2086  # the flags split at spaces
  if "$evaluate" $flags --test "$examples/data/dubai-tile-6" --out "$work/x" >"$work/log" 2>&1; then
    fail "accepted: $flags"
  fi
  grep -q "excludes" "$work/log" || fail "no clear error for $flags: $(tail -3 "$work/log")"
done
[ ! -e "$work/x" ] || fail "a refused command line wrote $work/x"
echo "ok: calibration flags with --decision-model refused, in the old spellings too"
