#!/usr/bin/env bash
# Black-box tests of adaptseg_mission: bad input gives one clear error line and exit code 2
# (never a crash); good input writes result.json with the documented keys and the figures;
# on the bundled WeedMap field the GSD sweep behaves as docs/results.md describes; adaptseg_calibrate
# (5th argument) is deterministic and cross-fits its calibration fields.
#   test_mission_cli.sh MISSION_BINARY EXAMPLES_DIR PYTHON CASE [CALIBRATE_BINARY]
set -uo pipefail
mission=$1 examples=$2 python=$3 case=$4 calibrate=${5:-}
# The Python tools run from the source tree (python/README.md).
export PYTHONPATH="$examples/../python${PYTHONPATH:+:$PYTHONPATH}"
source "$(dirname "$0")/cli_common.sh"
field="$examples/data/weedmap-000"

case "$case" in
bad_inputs)
  mkdir -p "$work/broken" "$work/nolabels"
  printf 'name: [unclosed\n' >"$work/broken/field.yaml"
  printf 'name: x\ngsd_cm: 1\nlabels: labels.png\nclasses: [{name: a, color: [0,0,0]}]\n' >"$work/nolabels/field.yaml"
  expect_error "field directory not found" --field "$work/none" --gsd 3 --out "$work/o"
  expect_error "missing" --field "$work" --gsd 3 --out "$work/o"
  expect_error "YAML error" --field "$work/broken" --gsd 3 --out "$work/o"
  expect_error "file not found" --field "$work/nolabels" --gsd 3 --out "$work/o"
  expect_error "unknown class 'tree'" --field "$field" --gsd 3 --interest crop,tree --out "$work/o"
  expect_error "finer than field" --field "$field" --gsd 0.5 --out "$work/o"
  expect_error "needs --gsd" --field "$field" --out "$work/o"
  expect_error "focal_length_mm" --field "$field" --gsd 3 --focal-mm 0 --out "$work/o"
  expect_error "image_width_px" --field "$field" --gsd 3 --image-width -480 --out "$work/o"
  expect_error "sensor_width_mm" --field "$field" --gsd 3 --sensor-width-mm -1 --out "$work/o"
  expect_error "max_speed_mps" --field "$field" --gsd 3 --speed 0 --out "$work/o"
  expect_error "max_vertical_speed_mps must be finite and >= 0" --field "$field" --gsd 3 --vertical-speed -0.5 \
    --out "$work/o"
  expect_error "fixed_segmentation_time_s" --field "$field" --gsd 3 --seg-time-s -1 --out "$work/o"
  expect_error "needs --network" --field "$field" --gsd 3 --segmenter network --out "$work/o"
  expect_error "applies to --segmenter network only" --field "$field" --gsd 3 --network "$work" --out "$work/o"
  expect_error "not found" --field "$field" --gsd 3 --segmenter network --network "$work/none" --out "$work/o"
  # The bundled ERFNet knows the Dubai classes, not WeedMap's.
  expect_error "classes" --field "$field" --gsd 3 --segmenter network --network "$examples/models/erfnet-dubai" \
    --out "$work/o"
  # A decision model of another class set (WeedMap's, flown on Dubai).
  expect_error "decision model was calibrated for classes [soil, crop, weed] but field 'dubai-tile-1' has" \
    --field "$examples/data/dubai-tile-1" --strategy adaptive \
    --decision-model "$examples/../tests/data/decision_model/weedmap_utility.yaml" --out "$work/o"
  # A model calibrated with one backend flown with another: refused, naming both (a network by its
  # folder and the hash of its weights and metadata).
  expect_error "decision model was calibrated with segmenter 'oracle' but the mission uses 'erfnet:erfnet-dubai-" \
    --field "$examples/data/dubai-tile-1" --strategy adaptive --segmenter network \
    --network "$examples/models/erfnet-dubai" \
    --decision-model "$examples/../tests/data/decision_model/dubai_road_front_aware.yaml" --out "$work/o"
  sed 's/^  segmenter: oracle/  segmenter: "erfnet:mobilenetv2-dubai-0123456789abcdef"/' \
    "$examples/../tests/data/decision_model/dubai_road_front_aware.yaml" >"$work/mobilenet-model.yaml"
  expect_error "calibrated with segmenter 'erfnet:mobilenetv2-dubai-0123456789abcdef' but the mission uses 'erfnet:erfnet-dubai-" \
    --field "$examples/data/dubai-tile-1" --strategy adaptive --segmenter network \
    --network "$examples/models/erfnet-dubai" --decision-model "$work/mobilenet-model.yaml" --out "$work/o"
  expect_error "'0.5,0,1' is not a region x0,y0,x1,y1 (fractions 0..1); write DIR:x0,y0,x1,y1" \
    --field "$field:0.5,0,1" --gsd 3 --out "$work/o"
  # Command-line syntax errors (CLI11's): the same one line and exit code 2.
  expect_error "Could not convert: --gsd = abc" --field "$field" --gsd abc --out "$work/o"
  expect_error "unknown option --bogus" --field "$field" --gsd 3 --out "$work/o" --bogus
  expect_error "unknown option --gds; did you mean --gsd?" --field "$field" --gds 3 --out "$work/o"
  # A misspelt required flag is named as unknown, not as the required one missing.
  expect_error "unknown option --feild; did you mean --field?" --feild "$field" --gsd 3 --out "$work/o"
  expect_error "--out is required" --field "$field" --gsd 3
  expect_error "--gsd must be a finite positive GSD in cm/px (got nan)" --field "$field" --gsd nan --out "$work/o"
  expect_error "--speed 1e+308 m/s is beyond any UAV the timing model describes" --field "$field" --gsd 3 \
    --speed 1e308 --out "$work/o"
  expect_error "--threads: Value 100000 not in range 0 to 256" --field "$field" --gsd 3 --threads 100000 --out "$work/o"
  expect_error "is not OVERLAP or ALONG,ACROSS with fractions in [0, 0.9]" --field "$field" --gsd 3 --overlap 0.95 --out "$work/o"
  expect_error "is not OVERLAP or ALONG,ACROSS" --field "$field" --gsd 3 --overlap 0.2,x --out "$work/o"
  expect_error "--overlap applies to --strategy lawnmower only" --field "$field" --strategy adaptive --overlap 0.2 \
    --out "$work/o"
  # The old spellings (--model, --model-file) and the new given together: refused.
  expect_error "excludes" --field "$examples/data/dubai-tile-1" --strategy adaptive \
    --model "$work/mobilenet-model.yaml" --decision-model "$work/mobilenet-model.yaml" --out "$work/o"
  expect_error "excludes" --field "$field" --gsd 3 --segmenter network --network "$work" --model-file "$work" \
    --out "$work/o"
  [ ! -e "$work/o" ] || fail "an error must be reported before the mission writes anything"
  # The old spellings still fly, until adaptseg 0.4, with one line each on stderr naming the new.
  "$mission" --field "$examples/data/dubai-tile-1:0,0,0.5,0.5" --strategy adaptive --segmenter erfnet \
    --model-file "$examples/models/erfnet-dubai" --model "$work/mobilenet-model.yaml" --threads 1 \
    --out "$work/old" >"$work/old.out" 2>"$work/old.err"
  grep -q "calibrated with segmenter 'erfnet:mobilenetv2-dubai-0123456789abcdef'" "$work/old.err" ||
    fail "the old spellings did not reach the mission: $(cat "$work/old.err")"
  [ "$(grep -c -- "--model is deprecated and goes in adaptseg 0.4: use --decision-model" "$work/old.err")" = 1 ] ||
    fail "want one notice for --model: $(cat "$work/old.err")"
  [ "$(grep -c -- "--model-file is deprecated and goes in adaptseg 0.4: use --network" "$work/old.err")" = 1 ] ||
    fail "want one notice for --model-file: $(cat "$work/old.err")"
  [ "$(grep -c -- "--segmenter erfnet is deprecated and goes in adaptseg 0.4: use --segmenter network" \
    "$work/old.err")" = 1 ] || fail "want one notice for --segmenter erfnet: $(cat "$work/old.err")"
  echo "ok: the old spellings --model, --model-file and --segmenter erfnet, each with one notice"
  rm -rf "$work/old"
  # With overlap the lawnmower takes more images over the same field and says so in result.json.
  for o in 0 0.5,0.25; do
    "$mission" --field "$field" --gsd 3 --seg-time-s 0.1 --plan-time-s 0 --overlap "$o" \
      --out "$work/overlap-$o" >/dev/null || fail "mission with --overlap $o failed"
  done
  "$python" - "$work/overlap-0/result.json" "$work/overlap-0.5,0.25/result.json" <<'PY' || fail "--overlap checks"
import json, math, sys
plain, over = (json.load(open(f)) for f in sys.argv[1:])
assert plain["overlap"] == {"along": 0.0, "across": 0.0} and over["overlap"] == {"along": 0.5, "across": 0.25}
xs = sorted({round(w["x"], 6) for w in over["waypoints"]})
ys = sorted({round(w["y"], 6) for w in over["waypoints"]})
fp_w, fp_h = 14.4, 10.8  # the default camera at 3 cm/px
assert len(xs) == 3 and len(ys) == 9, (xs, ys)  # 27.33 x 68.08 m: 1 + ceil(12.93 / 7.2), 1 + ceil(57.28 / 8.1)
assert all(math.isclose(b - a, fp_w * 0.5) for a, b in zip(xs, xs[1:])), xs
assert all(math.isclose(b - a, fp_h * 0.75) for a, b in zip(ys, ys[1:])), ys
assert over["images"] > plain["images"], (over["images"], plain["images"])
assert over["coverage"] >= plain["coverage"] - 1e-12, (over["coverage"], plain["coverage"])
print(f"ok: {plain['images']} images without overlap, {over['images']} with 0.5 along and 0.25 across")
PY
  ;;
weedmap_sweep)
  for gsd in 1.0 1.5 2.0 2.5 3.0; do
    "$mission" --field "$field" --strategy lawnmower --gsd "$gsd" --segmenter oracle \
      --seg-time-s 0.1 --plan-time-s 0 --out "$work/lm-$gsd" >/dev/null || fail "mission at $gsd failed"
    for f in result.json path.png map.png; do [ -s "$work/lm-$gsd/$f" ] || fail "missing $f at $gsd"; done
  done
  "$python" - "$work" <<'PY' || fail "result.json checks"
import json, sys
work = sys.argv[1]
gsds = ["1.0", "1.5", "2.0", "2.5", "3.0"]
res = [json.load(open(f"{work}/lm-{g}/result.json")) for g in gsds]
keys = ["field", "strategy", "segmenter", "miou_interest", "miou_all", "iou_per_class", "images",
        "time_s", "waypoints"]
for r in res:
    for k in keys:
        assert k in r, f"missing key {k}"
    assert set(r["time_s"]) >= {"total", "flight", "segmentation", "planning"}
    assert set(r["iou_per_class"]) == {"soil", "crop", "weed"}
    assert r["images"] == len(r["waypoints"]) > 0
    for w in r["waypoints"]:
        assert set(w) >= {"x", "y", "z", "gsd_cm"}
    assert r["coverage"] == 1.0, f"coverage {r['coverage']}"
assert res[0]["miou_all"] == 1.0, res[0]["miou_all"]
mi = [r["miou_interest"] for r in res]
tt = [r["time_s"]["total"] for r in res]
print("miou_interest", mi)
print("time_s.total", tt)
assert all(a > b for a, b in zip(mi, mi[1:])), "miou_interest must fall with GSD"
assert all(a > b for a, b in zip(tt, tt[1:])), "total time must fall with GSD"
PY
  ;;
erfnet_sweep)
  # Each bundled network and the bundled ensemble of the two on the held-out Dubai tile 6
  # (MobileNetV2: a 512x384 input for the 480x360 camera, logits at stride 4): the mission
  # records the backend, and the field mIoU (all classes) is higher at the finest GSD than at the
  # coarsest.
  tile="$examples/data/dubai-tile-6"
  for net in erfnet-dubai mobilenetv2-dubai ensemble-dubai; do
    for gsd in 5 15; do
      "$mission" --field "$tile" --strategy lawnmower --gsd "$gsd" --segmenter network \
        --network "$examples/models/$net" --seg-time-s 0.1 --plan-time-s 0 \
        --out "$work/$net-$gsd" >/dev/null || fail "$net mission at $gsd failed"
    done
  done
  "$python" - "$work" <<'PY' || fail "result.json checks"
import json, sys
work = sys.argv[1]
runs = {}
for net in ("erfnet-dubai", "mobilenetv2-dubai", "ensemble-dubai"):
    fine, coarse = runs[net] = [json.load(open(f"{work}/{net}-{g}/result.json")) for g in (5, 15)]
    kind = "ensemble" if net.startswith("ensemble") else "erfnet"
    for r in (fine, coarse):
        # The network's name: erfnet:<its folder>-<the hash of its weights and metadata>
        # (ensemble:<its folder>-<the hash of ensemble.yaml and its members' files>).
        assert r["segmenter"].startswith(f"{kind}:{net}-") and len(r["segmenter"]) == len(f"{kind}:{net}-") + 16, r["segmenter"]
        # Exactly black orthomosaic pixels carry no RGB: the backend leaves them unlabelled.
        assert r["coverage"] > 0.999, r["coverage"]
    print(net, "miou_all 5 cm/px", fine["miou_all"], "15 cm/px", coarse["miou_all"])
    # Measured: ERFNet 0.649 vs 0.562, MobileNetV2 0.611 vs 0.571.
    assert fine["miou_all"] > coarse["miou_all"] + 0.02, f"{net}: finer GSD must segment better"
    assert 0.3 < fine["miou_all"] < 1.0, f"{net} is not the oracle, and not useless"
    # Every image has its per-image mIoU and the truth's share of L. (Their mean per GSD is not
    # asserted: on this tile it does not rise as GSD falls; docs/journal/2026-11-networks.md,
    # "Networks".)
    for name, r in (("fine", fine), ("coarse", coarse)):
        assert all(w["image_miou_all"] is not None for w in r["waypoints"]), name
        assert all(w["truth_ratio"] is not None and 0.0 <= w["truth_ratio"] <= 1.0 for w in r["waypoints"]), name
# The ensemble maps the tile better than either member at both GSDs (eval_ensemble.py: 0.662
# and 0.601 against 0.649 / 0.611 and 0.571 / 0.562).
for k, g in enumerate((5, 15)):
    members = max(runs[n][k]["miou_all"] for n in ("erfnet-dubai", "mobilenetv2-dubai"))
    assert runs["ensemble-dubai"][k]["miou_all"] > members + 0.005, (g, runs["ensemble-dubai"][k]["miou_all"], members)
PY
  ;;
cross_fit)
  # A calibration field the missions' network was trained on (the deployment MobileNetV2 saw every
  # tile) is segmented by the first --calibration-network that never saw it: not the deployment
  # network given again, the evaluation MobileNetV2 (tiles 1, 2, 3, 5). The model names the
  # missions' network and, per field, the one that segmented it; without the flag no field_segmenters.
  [ -x "$calibrate" ] || fail "cross_fit needs the adaptseg_calibrate binary as 5th argument"
  opts=(--segmenter network --threads 1 --network "$examples/models/mobilenetv2-dubai-all" --seg-time-s 0.1
        --plan-time-s 0 --confidence 1 --interest water --top-factor 3 --candidate-factors 1 --lawnmower-factors 1,3)
  common=(--field "$examples/data/dubai-tile-4" --region 0,0,0.5,0.5 "${opts[@]}")
  "$calibrate" "${common[@]}" --calibration-network "$examples/models/mobilenetv2-dubai-all" \
    --calibration-network "$examples/models/mobilenetv2-dubai" --out "$work/cross.yaml" 2>"$work/cross.log" ||
    fail "cross-fitted calibration failed: $(tail -3 "$work/cross.log")"
  grep -q '^  segmenter: erfnet:mobilenetv2-dubai-all-' "$work/cross.yaml" || fail "the model names another segmenter"
  grep -q '^  field_segmenters: \[erfnet:mobilenetv2-dubai-[0-9a-f]*\]$' "$work/cross.yaml" ||
    fail "tile 4 not segmented by mobilenetv2-dubai: $(grep segmenter "$work/cross.yaml")"
  grep -q 'calibration field dubai-tile-4\[0,0,0.5,0.5\] segmented by erfnet:mobilenetv2-dubai-' "$work/cross.log" ||
    fail "no line names the field's network: $(cat "$work/cross.log")"
  "$calibrate" "${common[@]}" --out "$work/plain.yaml" 2>"$work/plain.log" || fail "calibration failed"
  ! grep -q field_segmenters "$work/plain.yaml" || fail "a model of one network names field_segmenters"
  # The same network for the missions and the field: other segmentations, another model.
  ! cmp -s "$work/cross.yaml" "$work/plain.yaml" || fail "cross-fitting changed nothing"
  echo "ok: cross-fitted calibration"
  # With --calibration-network-each every network that never saw a field segments it, one
  # calibration field each: tile 4 by mobilenetv2-dubai (tiles 1, 2, 3, 5) and the leave-one-tile-
  # out network of tile 4, tile 6 by mobilenetv2-dubai and that of tile 6; four fields, two grounds.
  "$calibrate" --train "$examples/data/dubai-tile-4:0,0,0.5,0.5" --train "$examples/data/dubai-tile-6:0,0,0.5,0.5" \
    "${opts[@]}" --calibration-network-each \
    --calibration-network "$examples/models/mobilenetv2-dubai" \
    --calibration-network "$examples/models/mobilenetv2-dubai-loto/tile-4" \
    --calibration-network "$examples/models/mobilenetv2-dubai-loto/tile-6" --out "$work/each.yaml" 2>"$work/each.log" ||
    fail "calibration with --calibration-network-each failed: $(tail -3 "$work/each.log")"
  grep -q '^  field_segmenters: \[erfnet:mobilenetv2-dubai-[0-9a-f]*, erfnet:tile-4-[0-9a-f]*, erfnet:mobilenetv2-dubai-[0-9a-f]*, erfnet:tile-6-[0-9a-f]*\]$' "$work/each.yaml" ||
    fail "not each field by each network that never saw it: $(grep -A1 calibration_fields "$work/each.yaml")"
  [ "$(grep -c 'calibration field dubai-tile-[46]\[0,0,0.5,0.5\] segmented by' "$work/each.log")" = 4 ] ||
    fail "not four calibration fields: $(grep 'calibration field' "$work/each.log")"
  # Looks of one ground alone leave the folds nothing to fit: refused before any segmentation.
  if "$calibrate" "${common[@]}" --calibration-network-each --calibration-network "$examples/models/mobilenetv2-dubai" \
    --calibration-network "$examples/models/mobilenetv2-dubai-loto/tile-4" --out "$work/one.yaml" >"$work/one.log" 2>&1; then
    fail "looks of one ground alone accepted"
  fi
  grep -q "every training field is of one ground" "$work/one.log" || fail "no clear error: $(tail -3 "$work/one.log")"
  # The flag means nothing without --calibration-network.
  if "$calibrate" "${common[@]}" --calibration-network-each --out "$work/one.yaml" >"$work/one.log" 2>&1; then
    fail "--calibration-network-each without --calibration-network accepted"
  fi
  grep -q "requires" "$work/one.log" || fail "no clear error: $(tail -3 "$work/one.log")"
  echo "ok: each calibration field segmented by every network that never saw it"
  # The model knows its network by the bytes of its weights and metadata, not by the folder's
  # name: in the same folder, changed weights or a changed temperature are another network, and
  # the mission refuses the model.
  mkdir -p "$work/net"
  cp "$examples/models/mobilenetv2-dubai-all/model.onnx" "$examples/models/mobilenetv2-dubai-all/model.yaml" "$work/net/"
  net_common=("${common[@]}")
  for i in "${!net_common[@]}"; do
    [ "${net_common[i]}" = "$examples/models/mobilenetv2-dubai-all" ] && net_common[i]="$work/net"
  done
  "$calibrate" "${net_common[@]}" --out "$work/net.yaml" 2>"$work/net.log" || fail "calibration with the copy failed"
  fly() {
    "$mission" --field "$examples/data/dubai-tile-4:0,0,0.5,0.5" --strategy adaptive --decision-model "$work/net.yaml" \
      --segmenter network --network "$work/net" --threads 1 --seg-time-s 0.1 --plan-time-s 0 --out "$work/fly" \
      >"$work/fly.log" 2>&1
  }
  fly || fail "the model refused its own network: $(tail -2 "$work/fly.log")"
  cp "$work/net/model.yaml" "$work/model.yaml.orig"
  sed -i 's/^temperature: .*/temperature: 1.5/' "$work/net/model.yaml"
  grep -q '^temperature: 1.5$' "$work/net/model.yaml" || echo "temperature: 1.5" >>"$work/net/model.yaml"
  fly && fail "a changed temperature in the same folder was flown with the old model"
  grep -q "calibrated with segmenter" "$work/fly.log" || fail "no message naming the segmenters: $(tail -2 "$work/fly.log")"
  cp "$work/model.yaml.orig" "$work/net/model.yaml"
  fly || fail "the folder restored was refused: $(tail -2 "$work/fly.log")"
  # One weight changed: a byte in the middle of the file (inside the weights' raw data).
  size=$(stat -c %s "$work/net/model.onnx")
  "$python" - "$work/net/model.onnx" "$((size / 2))" <<'PY' || fail "cannot change a byte"
import sys
path, at = sys.argv[1], int(sys.argv[2])
data = bytearray(open(path, "rb").read())
data[at] ^= 0x01
open(path, "wb").write(data)
PY
  fly && fail "changed weights in the same folder were flown with the old model"
  grep -q "calibrated with segmenter" "$work/fly.log" || fail "no message naming the segmenters: $(tail -2 "$work/fly.log")"
  echo "ok: a model refuses its network's folder with other weights or another temperature"
  # A pooled map (--map-fusion pooled): the model records it, and a mission flown with the model
  # pools its maps without being told and says so in result.json.
  "$calibrate" "${common[@]}" --map-fusion pooled --out "$work/pooled.yaml" 2>"$work/pooled.log" ||
    fail "pooled calibration failed: $(tail -3 "$work/pooled.log")"
  grep -qx 'map_fusion: pooled' "$work/pooled.yaml" || fail "the pooled model does not say so"
  ! grep -q map_fusion "$work/plain.yaml" || fail "a model of the paper's fusion names map_fusion"
  "$mission" --field "$examples/data/dubai-tile-4:0,0,0.5,0.5" --strategy adaptive --decision-model "$work/pooled.yaml" \
    --segmenter network --network "$examples/models/mobilenetv2-dubai-all" --threads 1 --seg-time-s 0.1 \
    --plan-time-s 0 --out "$work/pooled-fly" >"$work/pooled-fly.log" 2>&1 ||
    fail "the pooled model did not fly: $(tail -2 "$work/pooled-fly.log")"
  grep -q '"map_fusion": "pooled"' "$work/pooled-fly/result.json" || fail "result.json does not say the map was pooled"
  echo "ok: a pooled model is recorded and flown pooled"
  ;;
determinism)
  # The same inputs and seed give byte-identical outputs (times fixed by
  # --seg-time-s and --plan-time-s): the calibrated model, result.json and the figures, for a
  # lawnmower, an adaptive and a linear mission, each flown twice into its own directory.
  [ -x "$calibrate" ] || fail "determinism needs the adaptseg_calibrate binary as 5th argument"
  test="$field:0.5,0,1,0.2"
  fixed=(--seg-time-s 0.1 --plan-time-s 0.01)
  for run in a b; do
    mkdir -p "$work/$run"
    "$calibrate" --field "$field" --region 0,0,0.5,0.2 --segmenter oracle --threshold-steps 2 "${fixed[@]}" \
      --out "$work/$run/model.yaml" --cell-samples-csv "$work/$run/cells.csv" --frame-check \
      >"$work/$run/calibrate.log" 2>&1 || fail "calibration $run failed"
    "$mission" --field "$test" --strategy lawnmower --gsd 2 --segmenter oracle "${fixed[@]}" \
      --out "$work/$run/lawnmower" >/dev/null || fail "lawnmower $run failed"
    for s in adaptive linear; do
      "$mission" --field "$test" --strategy "$s" --decision-model "$work/$run/model.yaml" --segmenter oracle "${fixed[@]}" \
        --out "$work/$run/$s" >/dev/null || fail "$s $run failed"
    done
  done
  cmp "$work/a/model.yaml" "$work/b/model.yaml" || fail "model.yaml differs between two calibrations"
  cmp "$work/a/cells.csv" "$work/b/cells.csv" || fail "the cell samples differ between two calibrations"
  # --frame-check only adds the cell samples' *_reframed columns: the model is the same without.
  "$calibrate" --field "$field" --region 0,0,0.5,0.2 --segmenter oracle --threshold-steps 2 "${fixed[@]}" \
    --out "$work/plain.yaml" >/dev/null 2>&1 || fail "calibration without --frame-check failed"
  cmp "$work/a/model.yaml" "$work/plain.yaml" || fail "--frame-check changed the model"
  # --cell-samples-csv: one row per cell sample the calibration reports, every decision input
  # of the top-level and the finer image as columns.
  cells=$(sed -n 's/^\([0-9]*\) cell samples$/\1/p' "$work/a/calibrate.log")
  [ -n "$cells" ] && [ "$cells" -gt 0 ] && [ "$(($(wc -l <"$work/a/cells.csv") - 1))" = "$cells" ] ||
    fail "cells.csv does not hold the $cells cell samples reported"
  head -1 "$work/a/cells.csv" | grep -q '^field,region,top_gsd_cm,sub_gsd_cm,field_px,field_share,field_sigma,relabelled,field_gain,delta_tp,delta_fp,field_tp,field_fp,field_fn,added,removed,added_right,removed_right,added_confirmed,removed_confirmed,added_confirmed_right,removed_confirmed_right,added_reframed,removed_reframed,added_reframed_right,removed_reframed_right,top_sigma,.*,fine_expected_error,' ||
    fail "cells.csv header: $(head -1 "$work/a/cells.csv")"
  # The checks of a closer look's changes: the right ones and the confirmed ones are parts of the
  # changes, the confirmed right ones of both; confirmed where twice the cell's GSD is a
  # candidate (the default factors 1 and 2), nan where not (1.5: 3 is none); the frames shifted
  # half a footprint (--frame-check) check every cell.
  "$python" - "$work/a/cells.csv" <<'PY' || fail "cells.csv change checks out of order"
import csv, math, sys
confirmed = unconfirmed = 0
for r in csv.DictReader(open(sys.argv[1], newline="")):
    for side in ("added", "removed"):
        n, right, conf, both = (float(r[side + k]) for k in ("", "_right", "_confirmed", "_confirmed_right"))
        assert right <= n + 1e-12, r
        if math.isnan(conf):
            unconfirmed += 1
            continue
        confirmed += 1
        assert conf <= n + 1e-12 and both <= min(conf, right) + 1e-12, r
    for side in ("added", "removed"):
        n, right, shifted, both = (float(r[side + k]) for k in ("", "_right", "_reframed", "_reframed_right"))
        assert shifted <= n + 1e-12 and both <= min(shifted, right) + 1e-12, r
assert confirmed > 0 and unconfirmed > 0, (confirmed, unconfirmed)
PY
  # The scene check's slopes: proxy_slopes.py refits from cells.csv the gain slope, the proxy
  # slope and its spread between the fields that the calibration printed (CellGainModel::fit).
  input=$(sed -n 's/^cell gain model of \([a-z_]*\) per pair.*/\1/p' "$work/a/calibrate.log")
  [ -n "$input" ] || fail "the calibration printed no cell gain model"
  "$python" -m adaptseg_tools.proxy_slopes "$work/a/cells.csv" "$input" >"$work/slopes.md" ||
    fail "proxy_slopes.py failed"
  "$python" - "$work/a/calibrate.log" "$work/slopes.md" <<'EOF' || fail "proxy_slopes.py disagrees with the calibration"
import re, sys
printed = {}
for line in open(sys.argv[1]):
    m = re.match(r"\s*([\d.]+) -> +([\d.]+) cm/px  beta (\S+)  gamma (\S+)  tau (\S+)", line)
    if m:
        printed[(float(m[1]), float(m[2]))] = [float(v) for v in m.groups()[2:]]
tool = {}
for line in open(sys.argv[2]):
    m = re.match(r"\| ([\d.]+) -> ([\d.]+) \| (\S+) \| (\S+) \| (\S+) \|", line)
    if m:
        tool[(float(m[1]), float(m[2]))] = [float(v) for v in m.groups()[2:]]
assert printed and printed.keys() == tool.keys(), (printed, tool)
for k in printed:
    assert all(abs(a - b) <= 0.0015 for a, b in zip(printed[k], tool[k])), (k, printed[k], tool[k])
EOF
  for s in lawnmower adaptive linear; do
    for f in result.json path.png map.png; do
      cmp "$work/a/$s/$f" "$work/b/$s/$f" || fail "$s/$f differs between two runs"
    done
  done
  # The adaptive result holds the GPs' predictions for every candidate; the linear mission
  # descends, so sub-lawnmowers and map fusion are covered too.
  grep -q '"predicted_delta_miou"' "$work/a/adaptive/result.json" || fail "the adaptive mission scored no candidate"
  grep -q '"action": "descend"' "$work/a/linear/result.json" || fail "the linear mission never descended"
  echo "identical: model.yaml, cells.csv, {lawnmower,adaptive,linear}/{result.json,path.png,map.png}"
  ;;
*) fail "unknown case $case" ;;
esac
echo "PASS: $case"
