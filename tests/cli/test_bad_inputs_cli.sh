#!/usr/bin/env bash
# Black-box tests of the command-line mistakes of adaptseg_calibrate, adaptseg_evaluate and
# adaptseg_live: each gives exit code 2 and one stderr line naming the flag or the file and
# the fix (adaptseg_mission's are in test_mission_cli.sh). CLI11's own parse errors (unknown
# or misspelt flags, missing values) included.
#   test_bad_inputs_cli.sh PROGRAM_BINARY EXAMPLES_DIR PROGRAM
set -uo pipefail
mission=$1 examples=$2 program=$3
source "$(dirname "$0")/cli_common.sh"
weedmap="$examples/data/weedmap-000"
dubai="$examples/data/dubai-tile-1"
weedmap_model="$examples/../tests/data/decision_model/weedmap_utility.yaml"

# An unknown flag named as such, in one line with the pointer to --help (each program's case
# adds a misspelt flag, for which the likely one is named; calibrate a flag without its value,
# live a missing required option).
common_parse_errors() {
  expect_error "unknown option --bogus" "$@" --bogus
  expect_error "run $program --help for the options" "$@" --bogus
}

case "$program" in
adaptseg_calibrate)
  common_parse_errors --field "$weedmap" --out "$work/m.yaml"
  expect_error "did you mean --candidate-factors?" --field "$weedmap" --out "$work/m.yaml" --candidate-factor 1
  expect_error "--top-factor" --field "$weedmap" --out "$work/m.yaml" --top-factor
  expect_error "give a training field" --out "$work/m.yaml"
  expect_error "--frame-check requires --cell-samples-csv" --field "$weedmap" --out "$work/m.yaml" --frame-check
  expect_error "--lawnmower-factors 0.500 is finer than the field" --field "$weedmap" --out "$work/m.yaml" \
    --lawnmower-factors 0.5,1
  expect_error "--candidate-factors 0.500 is finer than the field" --field "$weedmap" --out "$work/m.yaml" \
    --candidate-factors 0.5,1
  expect_error "--top-factor 0.500 is finer than the field" --field "$weedmap" --out "$work/m.yaml" --top-factor 0.5
  expect_error "--candidate-factors 3.000 is not finer than --top-factor 3.000" --field "$weedmap" \
    --out "$work/m.yaml" --candidate-factors 1,3
  expect_error "is not a region x0,y0,x1,y1 (fractions 0..1); write DIR:x0,y0,x1,y1" --train "$weedmap:0.5,0,1" \
    --out "$work/m.yaml"
  expect_error "field directory not found" --train "$work/none" --out "$work/m.yaml"
  # A setting's choices are its table's names (decision inputs, input scores, slope poolings, top-level
  # choices).
  expect_error "--cell-input: confusion not in {sigma,boundary,ambiguity,expected_error,second_choice," \
    --field "$weedmap" --out "$work/m.yaml" --cell-input sigma,confusion
  expect_error "--slope-pooling: field not in {cells,fields,field-entropy}" --field "$weedmap" \
    --out "$work/m.yaml" --slope-pooling field
  expect_error "--cell-input-score: capture not in {ranking,transfer}" --field "$weedmap" \
    --out "$work/m.yaml" --cell-input-score capture
  expect_error "--top-level: convex not in {undominated,hull}" --field "$weedmap" \
    --out "$work/m.yaml" --top-level convex
  expect_error "--top-level: convex not in {undominated,hull}" --field "$weedmap" \
    --out "$work/m.yaml" --top-level hull,convex
  expect_error "top_levels names a choice twice: (got hull)" --field "$weedmap" --out "$work/m.yaml" \
    --top-level hull,hull
  expect_error "--finest-descent names the factor 2.000 twice: give each limit once (0: no limit)" \
    --field "$weedmap" --out "$work/m.yaml" --finest-descent 0,2,2
  expect_error "--finest-descent -1.000 is not a GSD factor: give multiples of the field's GSD, 0 for no limit" \
    --field "$weedmap" --out "$work/m.yaml" --finest-descent 0,-1
  expect_error "--longest-descent names 30.000 s twice: give each limit once (0: no limit)" \
    --field "$weedmap" --out "$work/m.yaml" --longest-descent 0,30,30
  expect_error "--longest-descent -1.000 is not a number of seconds: give seconds >= 0, 0 for no limit" \
    --field "$weedmap" --out "$work/m.yaml" --longest-descent 0,-1
  expect_error "max_vertical_speed_mps must be finite and >= 0" --field "$weedmap" --out "$work/m.yaml" \
    --vertical-speed -1
  expect_error "--map-fusion: mean not in {finest,pooled,pooled-interest,pooled-guarded}" --field "$weedmap" --out "$work/m.yaml" \
    --map-fusion mean
  # Cross-fitting: a field every network given was trained on, a flag the oracle has no use for.
  expect_error "every network given was trained on calibration field 'dubai-tile-1' (as --network" \
    --train "$dubai" --out "$work/m.yaml" --segmenter network --network "$examples/models/mobilenetv2-dubai" \
    --calibration-network "$examples/models/erfnet-dubai"
  expect_error "--calibration-network applies to --segmenter network only" --field "$weedmap" --out "$work/m.yaml" \
    --calibration-network "$examples/models/erfnet-dubai"
  # A network whose model.yaml names no training fields: whether it saw a field cannot be told.
  mkdir -p "$work/unnamed"
  cp "$examples/models/mobilenetv2-dubai/model.onnx" "$work/unnamed/"
  awk '/^training:/ { skip = 1; next } skip && /^[^ ]/ { skip = 0 } !skip' \
    "$examples/models/mobilenetv2-dubai/model.yaml" >"$work/unnamed/model.yaml"
  expect_error "--calibration-network: --network $work/unnamed names no training fields" --train "$dubai" \
    --out "$work/m.yaml" --segmenter network --network "$work/unnamed" \
    --calibration-network "$examples/models/erfnet-dubai"
  # None of them wrote a model.
  [ ! -e "$work/m.yaml" ] || fail "a refused calibration wrote $work/m.yaml"
  ;;
adaptseg_evaluate)
  common_parse_errors --test "$dubai" --decision-model "$weedmap_model" --out "$work/o" --no-plots
  expect_error "did you mean --no-plots?" --test "$dubai" --decision-model "$weedmap_model" --out "$work/o" --no-plot
  expect_error "decision model was calibrated for classes [soil, crop, weed] but field 'dubai-tile-1' has" \
    --test "$dubai" --decision-model "$weedmap_model" --out "$work/o" --no-plots
  expect_error "--lawnmower-factors needs at least two factors in increasing order" --test "$weedmap" \
    --decision-model "$weedmap_model" --out "$work/o" --no-plots --lawnmower-factors 3,1
  expect_error "--lawnmower-factors 0.500 is finer than the field" --test "$weedmap" --decision-model "$weedmap_model" \
    --out "$work/o" --no-plots --lawnmower-factors 0.5,1
  expect_error "write DIR:x0,y0,x1,y1" --test "$weedmap:0,0,1" --decision-model "$weedmap_model" --out "$work/o" --no-plots
  expect_error "give exactly one of --train (calibrate) and --decision-model (load)" --test "$weedmap" --out "$work/o"
  expect_error "--decision-model excludes --calibration-network" --test "$dubai" --decision-model "$weedmap_model" --out "$work/o" \
    --calibration-network "$examples/models/erfnet-dubai"
  expect_error "every network given was trained on calibration field 'dubai-tile-1[0,0,0.5,1]'" \
    --train "$dubai:0,0,0.5,1" --test "$dubai" --out "$work/o" --no-plots --segmenter network \
    --network "$examples/models/mobilenetv2-dubai" --calibration-network "$examples/models/erfnet-dubai"
  # The lawnmowers fly the model's camera and speed limits too: explicit ones must agree.
  expect_error "--vertical-speed 1.0000 differs from the decision model's 0.0000" --test "$weedmap" \
    --decision-model "$weedmap_model" --out "$work/o" --no-plots --vertical-speed 1
  expect_error "--speed 3.0000 differs from the decision model's 2.0000" --test "$weedmap" --decision-model "$weedmap_model" \
    --out "$work/o" --no-plots --speed 3
  expect_error "--map-fusion pooled differs from the decision model's finest" --test "$weedmap" \
    --decision-model "$weedmap_model" --out "$work/o" --no-plots --map-fusion pooled
  expect_error "--camera dji-phantom4-rtk (5472x3648 px, 13.20 mm sensor, 8.80 mm focal) differs from the decision model's camera (480x360 px, 4.80 mm sensor, 5.50 mm focal)" \
    --test "$weedmap" --decision-model "$weedmap_model" --out "$work/o" --no-plots --camera dji-phantom4-rtk
  ;;
adaptseg_live)
  common_parse_errors --images "$work/images" --decision-model "$weedmap_model" --record-from "$weedmap"
  expect_error "did you mean --record-from?" --images "$work/images" --decision-model "$weedmap_model" --record-for "$weedmap"
  expect_error "--decision-model is required" --images "$work/images"
  expect_error "decision model was calibrated for classes [soil, crop, weed] but field 'dubai-tile-1' has" \
    --images "$work/images" --decision-model "$weedmap_model" --record-from "$dubai"
  expect_error "area.yaml" --images "$work/none" --decision-model "$weedmap_model"
  expect_error "--record-yaw requires --record-from" --images "$work/images" --decision-model "$weedmap_model" --record-yaw 30
  expect_error "--record-yaw: Value 400 not in range" --images "$work/images" --decision-model "$weedmap_model" \
    --record-from "$weedmap" --record-yaw 400
  # GNSS poses: they need a geo-reference, to record and to fly.
  expect_error "--record-gnss requires --record-from" --images "$work/images" --decision-model "$weedmap_model" --record-gnss
  expect_error "--record-gnss needs the field's geo-reference" --images "$work/images" --decision-model "$weedmap_model" \
    --record-from "$weedmap:0.5,0,1,0.5" --record-gnss
  "$mission" --images "$work/images" --decision-model "$weedmap_model" --record-from "$weedmap:0.5,0,1,0.5" >/dev/null ||
    fail "recording"
  expect_error "--geo-origin is for --record-from" --images "$work/images" --decision-model "$weedmap_model" \
    --geo-origin 47.4,8.5,500,30
  printf 'file,latitude_deg,longitude_deg,relative_altitude_m\n00000.png,47.4,8.5,16.5\n' >"$work/images/poses.csv"
  expect_error "GNSS poses need the area's geo-reference" --images "$work/images" --decision-model "$weedmap_model"
  printf 'file,lat,lon\n' >"$work/images/poses.csv"
  expect_error "the header must be one of file,x,y,z[,yaw_deg]" --images "$work/images" --decision-model "$weedmap_model"
  # area.yaml is read as field.yaml is: a misspelt key or a bad class colour is named.
  cp "$work/images/area.yaml" "$work/area.yaml.orig"
  echo "colour_map: x" >>"$work/images/area.yaml"
  expect_error "area.yaml: unknown key 'colour_map' (known: format, name," --images "$work/images" \
    --decision-model "$weedmap_model"
  sed 's/color: \[0, 255, 0\]/color: [0, 256, 0]/' "$work/area.yaml.orig" >"$work/images/area.yaml"
  expect_error "'classes[1].color[1]' must be an integer in [0, 255] (got '256')" --images "$work/images" \
    --decision-model "$weedmap_model"
  # Flying a vehicle: the camera sources need it, it needs a georeferenced area, the
  # connection string is checked, and a fence that leaves out waypoints is refused before
  # anything is sent.
  quarter="$weedmap:0.5,0,1,0.5"
  expect_error "give the area to map: --images DIR" --decision-model "$weedmap_model"
  expect_error "--simulate-camera requires --mavlink" --decision-model "$weedmap_model" --simulate-camera "$quarter"
  expect_error "--mavlink needs a georeferenced area" --decision-model "$weedmap_model" --mavlink udpin:0 \
    --simulate-camera "$quarter"
  expect_error "--camera-folder gives camera images without labels" --decision-model "$weedmap_model" --mavlink udpin:0 \
    --camera-folder "$work" --images "$work/images"
  expect_error "--camera-folder requires --mavlink" --decision-model "$weedmap_model" --camera-folder "$work" \
    --images "$work/images"
  expect_error "connection 'tcp:5760': unknown scheme 'tcp'; use udpin:[HOST:]PORT" --decision-model "$weedmap_model" \
    --mavlink tcp:5760 --simulate-camera "$quarter" --geo-origin 47.4,8.5,500,30 --fence-margin-m 10
  expect_error "waypoints the planner may fly are outside the site's fence" --decision-model "$weedmap_model" \
    --mavlink udpin:0 --simulate-camera "$quarter" --geo-origin 47.4,8.5,500,30
  expect_error "the mission would fly 16.5 m above home at 3.00 cm/px, above --max-altitude-m 10.0" \
    --decision-model "$weedmap_model" --mavlink udpin:0 --simulate-camera "$quarter" --geo-origin 47.4,8.5,500,30 \
    --max-altitude-m 10
  ;;
*)
  fail "unknown program $program"
  ;;
esac
echo "ok: $program bad inputs"
