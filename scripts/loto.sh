#!/usr/bin/env bash
# Leave-one-tile-out estimate of the deployment MobileNetV2's accuracy on new ground: six
# trainings of examples/models/mobilenetv2-dubai-all's recipe, each on five of the
# six bundled Dubai tiles, each scored on the tile it never saw (field mIoU of whole-field
# lawnmowers at 5, 10 and 15 cm/px, adaptseg_tools.eval_ensemble).
#
#   bash scripts/loto.sh weights
#       here (npm and node needed): the ImageNet encoder weights into .device/mnv2_enc.pt and
#       .device/mnv2_140_enc.pt (LOTO_ARCH=mobilenetv2-140), the folder a device call carries (it
#       reaches no network).
#   bash scripts/loto.sh train MINUTES [TILES] [STEPS]
#       on a CUDA machine (the `device` tool: carry .device; a call carries 64 MiB, so first here
#       `bash scripts/device_travel.sh size .device`, and where it is over, `bash
#       scripts/device_travel.sh aside` (examples/models, which train reads none of) before the
#       call and `bash scripts/device_travel.sh restore` after): the trainings side by side on its
#       one GPU, each fitting its learning-rate cycle into MINUTES (train_segnet.py --minutes) but
#       at most LOTO_STEP_CAP steps (environment; default the recipe's: 1784 for the MobileNetV2,
#       1563 for the ERFNet), batches made on the GPU (--sampler device, PREFETCH batches ahead, default 2),
#       each network's exported weights (train_segnet --slim-checkpoint: no optimiser state) to
#       $OUT/loto-<k>.pt and the logs to $OUT/loto-logs.tar.gz, seed LOTO_SEED (environment;
#       default 0, the bundled networks').
#       TILES: the held-out tiles (default 1,2,3,4,5,6). STEPS > 0
#       trains that many steps instead of fitting MINUTES, on the CPU if there is no GPU (a
#       rehearsal of the call here).
#   bash scripts/loto.sh eval DIR
#       here: exports every DIR/loto-<k>.pt (PyTorch 1.13 and OpenCV 4.6 check it loads and
#       matches) to out/loto/model-<k>/ and prints its field mIoU on tile k.
#   bash scripts/loto.sh scores [FILE...]
#       here: the table eval ends with (each held-out tile's field mIoU per GSD, their mean, the
#       classes' mean IoU, each tile's class IoU per GSD) from LOTO_WORK's eval-<k>.json, or from
#       the FILEs given (one network's eval_ensemble --json on its held-out tile), e.g. a bundled
#       set's tile-*/held_out_eval.json.
#   bash scripts/loto.sh recipe-cpu TILES
#       here, no accelerator: the deployment recipe itself (1784 steps of 32 crops, seed 0; the
#       GPU run's schedule without --minutes) on the CPU, one held-out tile after another (TILES
#       comma-separated, default 1,2,3,4,5,6), checkpoints every 100 steps into
#       out/loto/work-<k> (an interrupted call resumes where it stopped), exported to
#       out/loto/model-<k> and scored on tile k as `eval` does. About an hour a tile on the
#       2-core VM with nothing else running (2026-12-03: about 15 images a second, the freed
#       memory kept; about five hours before, when glibc unmapped and faulted in each step's
#       activations again: benchmarks/train_cpu.sh, docs/benchmarks.md). What
#       rebuilds the bundled leave-one-tile-out networks (examples/models/mobilenetv2-dubai-loto)
#       when their checkpoints are gone. LOTO_STEP_CAP=N (environment): the recipe's cycle in N
#       steps instead (its warm-up as it is), to compare two recipes on the CPU in less time, e.g.
#       LOTO_STEP_CAP=300 LOTO_WORK=out/ab-100 bash scripts/loto.sh recipe-cpu 4 beside
#       LOTO_ARCH=mobilenetv2-140 LOTO_STEP_CAP=300 LOTO_WORK=out/ab-140 ... (held-out mIoU in
#       LOTO_WORK/eval-<k>.json; never bundle such networks).
#   bash scripts/loto.sh bundle
#       here, once out/loto/model-<k> exist for k = 1..6 (recipe-cpu, or eval after a device
#       call; a tile bundled already, examples/models/mobilenetv2-dubai-loto/tile-<k>, is taken
#       from there): each network's temperature fitted on the tile it never saw (adaptseg_fit_temperature,
#       out/loto/temperature-<k>.log), then each bundled with the median of the other five's
#       (never a temperature fitted on the tile it is tested on) into
#       examples/models/mobilenetv2-dubai-loto/tile-<k> (model.onnx, model.yaml, its logs and
#       held-out scores), the six fits in its temperatures.csv, and the deployment network
#       (mobilenetv2-dubai-all) given the median of all six.
#   bash scripts/loto.sh stage TILES
#       here: each network of TILES (comma-separated) trained by recipe-cpu (or eval) copied into
#       LOTO_BUNDLE/tile-<k> as bundle would copy it, without a temperature (bundle fits and sets
#       those once all six are there, taking staged tiles from LOTO_BUNDLE): a set trained over
#       several sessions on the CPU kept tile by tile (committed) where the checkpoints are lost
#       with the machine. Never over a network already there.
#   bash scripts/loto.sh decision [CLASSES]
#       here, after bundle: the deployment network's decision model per class of interest
#       (CLASSES space-separated, default "building road vegetation water"), calibrated on the six
#       tiles with each tile segmented by the network that never saw it (adaptseg_calibrate
#       --network examples/models/mobilenetv2-dubai-all --calibration-network
#       examples/models/mobilenetv2-dubai-loto/tile-k, k = 1..6; the model file names each
#       field's network) into examples/models/mobilenetv2-dubai-all/decision-<class>.yaml, logs in
#       out/loto/decision-<class>.log, with pooled maps (--map-fusion pooled; LOTO_MAP_FUSION=finest
#       for the paper's fusion): the models record it and the missions flown with them pool;
#       and β a line in the field's entropy tried first, then the slopes pooled over the fields
#       (--slope-pooling field-entropy,fields; LOTO_SLOPE_POOLING another list; `cells` dropped
#       in the forty-sixth session: it weighs the fields by their cells, not as draws of a new
#       field), what did best on the leave-one-tile-out folds with pooled maps (docs/results.md);
#       and the top level chosen by the folds (--top-level undominated,hull; LOTO_TOP_LEVEL
#       another list), since the forty-second session (docs/results.md). What a user flies a
#       new site with (docs/programs.md, "A new site"). Segmentations are cached in
#       out/results/segmentation-cache.
#   LOTO_SEED=1 LOTO_WORK=out/loto-seed1 LOTO_BUNDLE=out/loto-seed1/bundle bash scripts/loto.sh ...
#       another seed of the six: train and recipe-cpu train with LOTO_SEED; eval, recipe-cpu and
#       bundle work in LOTO_WORK (default out/loto); bundle fills LOTO_BUNDLE (default
#       examples/models/mobilenetv2-dubai-loto) and sets the deployment network's temperature
#       only from the default folder; decision reads LOTO_BUNDLE and writes into LOTO_WORK unless
#       it is the default. scripts/results.sh loto flies such a folder with LOTO_NETWORKS.
#   LOTO_ARCH=mobilenetv2-140 bash scripts/loto.sh train|eval|recipe-cpu|bundle|stage ...
#       the deployment's recipe on the width-1.4 MobileNetV2 with every block (scripts/loto_recipe.sh,
#       adaptseg_tools.mobilenet_v2_140), in out/loto-mnv2-140 into
#       examples/models/mobilenetv2-140-dubai-loto unless LOTO_WORK and LOTO_BUNDLE say otherwise;
#       decision refuses it. 15 MB of ONNX a network: bring the six back as train does and keep
#       them out of the repository until they earn their place.
#   LOTO_ARCH=erfnet bash scripts/loto.sh train|eval|recipe-cpu|bundle|stage ...
#       the six with the bundled ERFNet's recipe instead (scripts/loto_recipe.sh: its first
#       learning-rate cycle, at most 1563 steps), in out/loto-erfnet into
#       examples/models/erfnet-dubai-loto unless LOTO_WORK and LOTO_BUNDLE say otherwise; decision
#       refuses it (the deployment network is a MobileNetV2). train brings back each network's
#       exported weights alone (train_segnet --slim-checkpoint, 8 MB), which eval exports.
#   bash scripts/loto.sh mirror [DEST]
#       here: DEST/tile-<k>/ensemble.yaml (default out/loto-mirror) for k = 1..6, each network of
#       LOTO_BUNDLE under test-time mirror (an ensemble of one member, mirror: true: its
#       probabilities the mean over the image and its left-right mirror, its temperature as
#       bundled; two passes per image). Flown with LOTO_NETWORKS=DEST bash scripts/results.sh loto.
#   bash scripts/loto.sh coarse [DEST] [G]
#       here: DEST/tile-<k>/ensemble.yaml (default out/loto-coarse) for k = 1..6, each network of
#       LOTO_BUNDLE with a test-time coarser look (OnnxParams::test_time_coarse_gsd_cm G, default
#       10: an image finer than G cm/px also segmented shrunk to min(G, 2 x its GSD), the
#       probabilities the mean of the two passes; its temperature as bundled). Flown with
#       LOTO_NETWORKS=DEST bash scripts/results.sh loto.
#   LOTO_ARCH=mobilenetv2-140 bash scripts/loto.sh partial [DEST]
#       here, while a set is trained tile by tile on the CPU over several sessions: DEST/tile-<k>
#       (default out/loto-partial) for k = 1..6, the network trained here (LOTO_WORK/model-k,
#       recipe-cpu) where there is one, each at the median of the temperatures the other networks
#       trained here fit on their own held-out tiles (at least two needed; never its own tile's;
#       the fits in DEST/temperatures.csv), and LOTO_BASE/tile-k (default
#       examples/models/mobilenetv2-dubai-loto, a link) for the rest. Flown with
#       LOTO_NETWORKS=DEST bash scripts/results.sh loto, or only the trained tiles' runs: a mixed
#       set, so its runs say what the new networks change on their tiles, not what the six would.
#   bash scripts/loto.sh ensemble DEST FOLDER FOLDER...
#       here: DEST/tile-<k>/ensemble.yaml for k = 1..6, the ensemble of FOLDER/tile-<k> over the
#       FOLDERs given (each a bundled set of six, e.g. examples/models/mobilenetv2-dubai-loto and
#       its seed-1 twin), weighted alike, each at its temperature as bundled: every tile's members
#       never saw it. Flown with LOTO_NETWORKS=DEST bash scripts/results.sh loto.
#   bash scripts/loto.sh cpu TILE [--resume]
#       here, no accelerator: one training of examples/models/mobilenetv2-dubai's CPU recipe
#       (2000 steps of 8 crops) on the five tiles but TILE, exported to out/loto-cpu/model-TILE
#       (work folder out/loto-cpu/work-TILE, checkpoints every 100 steps: --resume continues),
#       its temperature then fitted on TILE (adaptseg_fit_temperature --write, as the evaluation
#       network's on its validation tile: the decision inputs come from its probabilities).
#       About 26 minutes on the 2-core VM with nothing else running (twice that and more when
#       it shares the cores). The calibration networks of `scripts/results.sh cross-fit`.
set -euo pipefail
cd "$(dirname "$0")/.."
# The Python tools run from the source tree (python/README.md).
export PYTHONPATH="$PWD/python${PYTHONPATH:+:$PYTHONPATH}"
# The interpreter with PyTorch: a device machine's plain python3, else Debian's (this machine's).
py=${PYTHON:-$(python3 -c 'import torch, cv2' 2>/dev/null && echo python3 || echo /usr/bin/python3)}
# The recipe's train_segnet arguments (LOTO_ARCH): loto_net, loto_arch, loto_encoder, loto_recipe,
# loto_batch, loto_steps.
source scripts/loto_recipe.sh
tiles_all=(1 2 3 4 5 6)
# Where recipe-cpu, eval and bundle work (LOTO_WORK), and the folder bundle fills and decision
# reads (LOTO_BUNDLE): another seed's networks go beside the bundled ones, never over them.
case "$loto_net" in
erfnet)
  wroot=${LOTO_WORK:-out/loto-erfnet}
  dest=${LOTO_BUNDLE:-examples/models/erfnet-dubai-loto}
  ;;
mobilenetv2-140)
  wroot=${LOTO_WORK:-out/loto-mnv2-140}
  dest=${LOTO_BUNDLE:-examples/models/mobilenetv2-140-dubai-loto}
  ;;
*)
  wroot=${LOTO_WORK:-out/loto}
  dest=${LOTO_BUNDLE:-examples/models/mobilenetv2-dubai-loto}
  ;;
esac
# The MobileNetV2 recipes start from ImageNet weights that a device machine cannot download.
need_encoder() {
  [ -z "$loto_encoder" ] || [ -s "$loto_encoder" ] ||
    { echo "no $loto_encoder: run 'bash $0 weights' here first" >&2; exit 2; }
}
train_fields() {  # every bundled tile but $1, comma-separated
  local k=$1 out=""
  for t in "${tiles_all[@]}"; do [ "$t" = "$k" ] || out+="${out:+,}dubai-tile-$t"; done
  echo "$out"
}

# The estimate from held-out scores (eval_ensemble --json of one network on its tile, as eval and
# recipe-cpu write them): each held-out tile's field mIoU per GSD, their mean, per class, and each
# tile's class IoU per GSD.
print_scores() {
  local f
  for f in "$@"; do [ -s "$f" ] || { echo "no $f: bash $0 eval DIR or recipe-cpu first" >&2; exit 2; }; done
  "$py" - "$@" <<'PY'
import json, sys
rows, classes = [], None
for path in sys.argv[1:]:
    d = json.load(open(path))
    classes = d["classes"]
    (name, bands), = d["fields"].items()
    (member,) = d["members"]
    rows.append((name, {b["gsd_cm"]: b[member] for b in bands.values()}))
gsds = sorted({g for _, r in rows for g in r})
print("| held-out tile | " + " | ".join(f"{g:g} cm/px" for g in gsds) + " |")
print("| --- |" + " ---: |" * len(gsds))
for name, r in rows:
    print(f"| {name} | " + " | ".join(f"{r[g]['miou']:.3f}" for g in gsds) + " |")
print("| mean | " + " | ".join(f"{sum(r[g]['miou'] for _, r in rows) / len(rows):.3f}" for g in gsds) + " |")
print("\nclass IoU, mean over the held-out tiles (tiles where the class occurs):")
for c, cls in enumerate(classes):
    vals = {g: [r[g]["iou"][c] for _, r in rows if r[g]["iou"][c] is not None] for g in gsds}
    print(f"  {cls:<11}" + "  ".join(f"{g:g} cm/px {sum(v) / len(v):.3f} (n={len(v)})" for g, v in vals.items() if v))
print("\nclass IoU per held-out tile, " + " / ".join(f"{g:g}" for g in gsds) + " cm/px (- where the class is absent):")
print("| held-out tile | " + " | ".join(classes) + " |")
print("| --- |" + " ---: |" * len(classes))
for name, r in rows:
    cell = lambda c: " / ".join("-" if r[g]["iou"][c] is None else f"{r[g]['iou'][c]:.3f}" for g in gsds)
    print(f"| {name} | " + " | ".join(cell(c) for c in range(len(classes))) + " |")
PY
}

# Tile $1's network trained here ($wroot/model-k, its training and held-out scores) into
# $dest/tile-k, as it was exported (bundle then sets its temperature).
stage_tile() {
  local k=$1
  mkdir -p "$dest/tile-$k"
  for f in model.onnx model.yaml train_log.csv val_log.csv val_ema_log.csv; do cp "$wroot/model-$k/$f" "$dest/tile-$k/"; done
  cp "$wroot/eval-$k.json" "$dest/tile-$k/held_out_eval.json"
  [ ! -f "$wroot/train-$k.log" ] || cp "$wroot/train-$k.log" "$dest/tile-$k/train.log"
}

# Exits unless every folder given holds a network with its temperature (a staged tile has none
# until bundle sets it: flown so, it would be at 1): checked before anything is written.
need_networks() {
  local net
  for net in "$@"; do
    [ -s "$net/model.onnx" ] || { echo "no $net/model.onnx: bundle its set first (bash $0 bundle)" >&2; exit 2; }
    grep -q '^temperature:' "$net/model.yaml" 2>/dev/null ||
      { echo "no temperature in $net/model.yaml: bundle its set first (bash $0 bundle)" >&2; exit 2; }
  done
}

# The median of the numbers given (the mean of the middle two for an even count).
median() { printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2) }'; }

# adaptseg_fit_temperature built in build/release, its path in $fit (bundle, partial).
build_fitter() {
  source scripts/configure.sh
  configure_for results build/release >/dev/null
  cmake --build build/release -j2 --target adaptseg_fit_temperature >/dev/null
  fit=build/release/examples/adaptseg_fit_temperature
}

# fit_own_tile K NET LOG: fitted[K] (an associative array the caller declares), the temperature
# network NET fits on dubai-tile-K, the tile it never saw; the fit's output in LOG.
fit_own_tile() {
  "$fit" --network "$2" --field "examples/data/dubai-tile-$1" --threads 2 >"$3"
  fitted[$1]=$(sed -n 's/^temperature: \([0-9.]*\).*/\1/p' "$3")
  [ -n "${fitted[$1]}" ] || { echo "no temperature in $3" >&2; exit 1; }
}

# The median of fitted[] over every tile but $1: a network's temperature, never fitted on its own tile.
median_of_others() {
  local j others=()
  for j in "${!fitted[@]}"; do [ "$j" = "$1" ] || others+=("${fitted[$j]}"); done
  median "${others[@]}"
}

# $1 as a double-quoted YAML scalar: a description or a folder's name may hold ": " or " #",
# which a plain scalar may not (yaml-cpp refuses the file).
yaml_string() {
  local text=${1//\\/\\\\}
  printf '"%s"' "${text//\"/\\\"}"
}

# $1/ensemble.yaml: description $2, the networks $4... as members (found relative to the file), each
# with the line $3 below its model line.
write_ensemble() {
  local to=$1 description=$2 line=$3 net
  mkdir -p "$to"
  {
    printf '%s\n' "description: $(yaml_string "$description")" "members:"
    for net in "${@:4}"; do
      printf '%s\n' "  - model: $(yaml_string "$(realpath --relative-to="$to" "$net")")" "$line"
    done
  } >"$to/ensemble.yaml"
}

case "${1:-}" in
weights)
  mkdir -p .device
  exclude=$(git rev-parse --git-path info/exclude)
  mkdir -p "$(dirname "$exclude")"
  grep -qx '/.device/' "$exclude" 2>/dev/null || echo '/.device/' >>"$exclude"
  "$py" -m adaptseg_tools.mobilenet_v2 --out .device/mnv2_enc.pt
  "$py" -m adaptseg_tools.mobilenet_v2_140 --out .device/mnv2_140_enc.pt
  ;;
train)
  minutes=${2:?minutes}
  IFS=, read -r -a tiles <<<"${3:-1,2,3,4,5,6}"
  steps=${4:-0}
  out=${OUT:?set OUT (the device tool sets it)}
  need_encoder
  if [ "$steps" -gt 0 ]; then
    crop=150  # ERFNet's crops map to whole multiples of 8 network pixels
    [ "$loto_arch" = mobilenetv2 ] || crop=160
    schedule=(--steps "$steps" --warmup 1 --batch 2 --crop "$crop" --val-max-images 2)
    device=$("$py" -c 'import torch; print("cuda" if torch.cuda.is_available() else "cpu")')
  else
    schedule=(--steps "${LOTO_STEP_CAP:-$loto_steps}" --minutes "$minutes" --max-minutes "$(awk -v m="$minutes" 'BEGIN { print m * 1.08 }')"
              "${loto_batch[@]}")
    device=cuda
  fi
  sampler=cpu
  [ "$device" = cuda ] && sampler=device
  work=$(mktemp -d)
  pids=()
  for k in "${tiles[@]}"; do
    "$py" -m adaptseg_tools.train_segnet "${loto_recipe[@]}" --seed "${LOTO_SEED:-0}" \
      --sampler "$sampler" --prefetch "${PREFETCH:-2}" --device "$device" --train-fields "$(train_fields "$k")" --val-field "dubai-tile-$k" \
      --test-field none --threads 1 --val-every 0 --ckpt-every 100 --log-every 50 --no-export \
      "${schedule[@]}" --work-dir "$work/loto-$k" --model-dir "$work/unused-$k" >"$work/loto-$k.log" 2>&1 &
    pids+=($!)
  done
  status=0
  for p in "${pids[@]}"; do wait "$p" || status=1; done
  for k in "${tiles[@]}"; do
    # The exported weights alone: an ERFNet checkpoint (33 MB) is over what a device call brings back.
    [ ! -s "$work/loto-$k/checkpoint.pt" ] ||
      "$py" -m adaptseg_tools.train_segnet --work-dir "$work/loto-$k" --model-dir "$work/unused-$k" \
        --slim-checkpoint "$out/loto-$k.pt" || status=1
    tail -n 3 "$work/loto-$k.log"
  done
  tar czf "$out/loto-logs.tar.gz" -C "$work" --exclude='*.pt' .
  exit "$status"
  ;;
eval)
  dir=${2:?directory with loto-<k>.pt}
  mkdir -p "$wroot"
  for ckpt in "$dir"/loto-*.pt; do
    k=${ckpt##*/loto-}
    k=${k%.pt}
    work=$wroot/work-$k
    mkdir -p "$work"
    cp "$ckpt" "$work/checkpoint.pt"
    "$py" -m adaptseg_tools.train_segnet --arch "$loto_arch" --work-dir "$work" --model-dir "$wroot/model-$k" \
      --export-only --train-fields "$(train_fields "$k")" --val-field "dubai-tile-$k" --test-field none \
      >"$wroot/export-$k.log" 2>&1 || { echo "export of $ckpt failed: $wroot/export-$k.log" >&2; exit 1; }
    # The device call's training logs beside the network, as recipe-cpu leaves them.
    if [ -s "$dir/loto-logs.tar.gz" ]; then
      tar xzf "$dir/loto-logs.tar.gz" -C "$wroot/model-$k" --strip-components 2 "./loto-$k/"
      tar xzf "$dir/loto-logs.tar.gz" -O "./loto-$k.log" >"$wroot/train-$k.log"
    fi
    echo "== held out dubai-tile-$k (trained on $(train_fields "$k"))"
    "$py" -m adaptseg_tools.eval_ensemble --members "loto$k=$wroot/model-$k" \
      --fields "examples/data/dubai-tile-$k" --bands 1,2,3 --json "$wroot/eval-$k.json"
  done
  print_scores "$wroot"/eval-*.json
  ;;
scores)
  shift
  if [ $# -gt 0 ]; then print_scores "$@"; else print_scores "$wroot"/eval-*.json; fi
  ;;
recipe-cpu)
  IFS=, read -r -a tiles <<<"${2:-1,2,3,4,5,6}"
  need_encoder
  mkdir -p "$wroot"
  for k in "${tiles[@]}"; do
    work=$wroot/work-$k
    if [ ! -s "$work/done" ]; then
      resume=()
      [ -s "$work/checkpoint.pt" ] && resume=(--resume)
      "$py" -m adaptseg_tools.train_segnet "${loto_recipe[@]}" --seed "${LOTO_SEED:-0}" \
        --sampler cpu --device cpu --workers 1 --threads "${LOTO_THREADS:-2}" --train-fields "$(train_fields "$k")" \
        --val-field "dubai-tile-$k" --test-field none --val-every 0 --ckpt-every 100 --log-every 50 --no-export \
        --steps "${LOTO_STEP_CAP:-$loto_steps}" "${loto_batch[@]}" --work-dir "$work" --model-dir "$wroot/unused-$k" \
        "${resume[@]}" >>"$wroot/train-$k.log" 2>&1 || { echo "training $k failed: $wroot/train-$k.log" >&2; exit 1; }
      date -u +%FT%TZ >"$work/done"
    fi
    "$py" -m adaptseg_tools.train_segnet --arch "$loto_arch" --work-dir "$work" --model-dir "$wroot/model-$k" \
      --export-only --train-fields "$(train_fields "$k")" --val-field "dubai-tile-$k" --test-field none \
      >"$wroot/export-$k.log" 2>&1 || { echo "export of tile $k failed: $wroot/export-$k.log" >&2; exit 1; }
    "$py" -m adaptseg_tools.eval_ensemble --members "loto$k=$wroot/model-$k" \
      --fields "examples/data/dubai-tile-$k" --bands 1,2,3 --json "$wroot/eval-$k.json"
  done
  ;;
bundle)
  build_fitter
  declare -A fitted src
  mkdir -p "$wroot"
  for k in "${tiles_all[@]}"; do
    # The network trained here ($wroot/model-k), else the one bundled already (committed).
    src[$k]=$wroot/model-$k
    [ -s "${src[$k]}/model.onnx" ] || src[$k]=$dest/tile-$k
    [ -s "${src[$k]}/model.onnx" ] || { echo "no $wroot/model-$k nor $dest/tile-$k: bash $0 recipe-cpu $k (or eval)" >&2; exit 1; }
    fit_own_tile "$k" "${src[$k]}" "$wroot/temperature-$k.log"
  done
  mkdir -p "$dest"
  echo "held_out_tile,fitted_on_held_out_tile,bundled_median_of_the_other_five" >"$dest/temperatures.csv"
  for k in "${tiles_all[@]}"; do
    t=$(median_of_others "$k")
    [ "${src[$k]}" = "$dest/tile-$k" ] || stage_tile "$k"
    "$fit" --network "$dest/tile-$k" --set "$t" >/dev/null
    echo "dubai-tile-$k,${fitted[$k]},$t" >>"$dest/temperatures.csv"
  done
  # The deployment network's temperature comes from the bundled networks' fits alone.
  [ "$dest" != examples/models/mobilenetv2-dubai-loto ] ||
    "$fit" --network examples/models/mobilenetv2-dubai-all --set "$(median "${fitted[@]}")"
  cat "$dest/temperatures.csv"
  ;;
stage)
  IFS=, read -r -a tiles <<<"${2:?tiles, comma-separated}"
  for k in "${tiles[@]}"; do
    [ -s "$wroot/model-$k/model.onnx" ] && [ -s "$wroot/eval-$k.json" ] ||
      { echo "no $wroot/model-$k with its eval-$k.json: bash $0 recipe-cpu $k (or eval)" >&2; exit 1; }
    [ ! -e "$dest/tile-$k/model.onnx" ] || { echo "$dest/tile-$k holds a network already; not overwritten" >&2; exit 1; }
    stage_tile "$k"
    echo "$dest/tile-$k (no temperature yet: bundle sets it once all six are here)"
  done
  ;;
decision)
  read -r -a classes <<<"${2:-building road vegetation water}"
  [ "$loto_net" = mobilenetv2 ] ||
    { echo "decision: the deployment network is the width-1.0 MobileNetV2 trained on all six tiles (no $loto_net one yet)" >&2; exit 2; }
  deploy=examples/models/mobilenetv2-dubai-all
  trains=() crossed=()
  for k in "${tiles_all[@]}"; do
    grep -q '^temperature:' "$dest/tile-$k/model.yaml" 2>/dev/null ||
      { echo "$dest/tile-$k has no network with its temperature yet: bash $0 recipe-cpu $k, then bundle" >&2; exit 1; }
    trains+=(--train "examples/data/dubai-tile-$k")
    crossed+=(--calibration-network "$dest/tile-$k")
  done
  grep -q '^temperature:' "$deploy/model.yaml" || { echo "$deploy has no temperature yet: bash $0 bundle" >&2; exit 1; }
  source scripts/configure.sh
  configure_for results build/release >/dev/null
  cmake --build build/release -j2 --target adaptseg_calibrate >/dev/null
  # The bundled decision models come from the bundled networks; another folder's go to LOTO_WORK.
  models=$deploy
  [ "$dest" = examples/models/mobilenetv2-dubai-loto ] || models=$wroot
  mkdir -p "$wroot"
  for cls in "${classes[@]}"; do
    build/release/examples/adaptseg_calibrate "${trains[@]}" --interest "$cls" --segmenter network --network "$deploy" \
      "${crossed[@]}" --threads "${LOTO_THREADS:-2}" --segmentation-cache out/results/segmentation-cache \
      --map-fusion "${LOTO_MAP_FUSION:-pooled}" --slope-pooling "${LOTO_SLOPE_POOLING:-field-entropy,fields}" \
      --top-level "${LOTO_TOP_LEVEL:-undominated,hull}" --out "$models/decision-$cls.yaml" >"$wroot/decision-$cls.log" 2>&1 ||
      { echo "calibration for $cls failed: $wroot/decision-$cls.log" >&2; exit 1; }
    echo "$models/decision-$cls.yaml"
  done
  ;;
cpu)
  k=${2:?held-out tile}
  shift 2
  [ -s .device/mnv2_enc.pt ] || { echo "no .device/mnv2_enc.pt: run 'bash $0 weights' here first" >&2; exit 2; }
  mkdir -p out/loto-cpu
  "$py" -m adaptseg_tools.train_segnet --arch mobilenetv2 --encoder-weights .device/mnv2_enc.pt \
    --work-dir "out/loto-cpu/work-$k" --model-dir "out/loto-cpu/model-$k" \
    --steps 2000 --crop 300 --frozen-blocks 4 --no-image-pooling --lr 1e-3 --warmup 100 \
    --weight-decay 0.01 --val-every 0 --ckpt-every 100 --threads 2 --ema 0.998 --seed 0 \
    --train-fields "$(train_fields "$k")" --val-field "dubai-tile-$k" --test-field none "$@"
  source scripts/configure.sh
  configure_for results build/release >/dev/null
  cmake --build build/release -j2 --target adaptseg_fit_temperature >/dev/null
  build/release/examples/adaptseg_fit_temperature --network "out/loto-cpu/model-$k" \
    --field "examples/data/dubai-tile-$k" --threads 2 --write
  ;;
mirror)
  to=${2:-out/loto-mirror}
  need_networks "${tiles_all[@]/#/$dest/tile-}"
  for k in "${tiles_all[@]}"; do
    write_ensemble "$to/tile-$k" \
      "$dest/tile-$k under test-time mirror (its probabilities the mean over the image and its left-right mirror)" \
      "    mirror: true" "$dest/tile-$k"
  done
  echo "wrote $to/tile-{1..6}/ensemble.yaml"
  ;;
coarse)
  to=${2:-out/loto-coarse}
  g=${3:-10}
  [[ $g =~ ^[0-9]*\.?[0-9]+$ && ! $g =~ ^[0.]+$ ]] || { echo "coarse: G must be a GSD > 0 in cm/px (got '$g')" >&2; exit 2; }
  need_networks "${tiles_all[@]/#/$dest/tile-}"
  for k in "${tiles_all[@]}"; do
    write_ensemble "$to/tile-$k" \
      "$dest/tile-$k with a test-time coarser look (images finer than $g cm/px also segmented at min($g, 2 x their GSD), the probabilities the mean)" \
      "    coarse_gsd_cm: $g" "$dest/tile-$k"
  done
  echo "wrote $to/tile-{1..6}/ensemble.yaml"
  ;;
partial)
  to=${2:-out/loto-partial}
  base=${LOTO_BASE:-examples/models/mobilenetv2-dubai-loto}
  need_networks "${tiles_all[@]/#/$base/tile-}"
  trained=()
  for k in "${tiles_all[@]}"; do [ ! -s "$wroot/model-$k/model.onnx" ] || trained+=("$k"); done
  [ "${#trained[@]}" -ge 2 ] ||
    { echo "partial: ${#trained[@]} network(s) in $wroot/model-<k>; two are needed (bash $0 recipe-cpu K)" >&2; exit 2; }
  # DEST's tiles are replaced: only a folder partial wrote, or a new or empty one.
  header="tile,network,fitted_on_held_out_tile,set"
  [ ! -d "$to" ] || [ -z "$(ls -A "$to")" ] || [ "$(head -n 1 "$to/temperatures.csv" 2>/dev/null)" = "$header" ] ||
    { echo "partial: $to holds files that partial did not write; not overwritten" >&2; exit 2; }
  build_fitter
  declare -A fitted
  mkdir -p "$to"
  for k in "${trained[@]}"; do fit_own_tile "$k" "$wroot/model-$k" "$to/temperature-$k.log"; done
  echo "$header" >"$to/temperatures.csv"
  for k in "${tiles_all[@]}"; do
    rm -rf "$to/tile-$k"
    if [ -n "${fitted[$k]:-}" ]; then
      t=$(median_of_others "$k")
      mkdir -p "$to/tile-$k"
      cp "$wroot/model-$k/model.onnx" "$wroot/model-$k/model.yaml" "$to/tile-$k/"
      "$fit" --network "$to/tile-$k" --set "$t" >/dev/null
      echo "$k,$wroot/model-$k,${fitted[$k]},$t" >>"$to/temperatures.csv"
    else
      ln -s "$(realpath --relative-to="$to" "$base/tile-$k")" "$to/tile-$k"
      echo "$k,$base/tile-$k,,as bundled" >>"$to/temperatures.csv"
    fi
  done
  cat "$to/temperatures.csv"
  ;;
ensemble)
  to=${2:?destination folder}
  folders=("${@:3}")
  [ "${#folders[@]}" -ge 2 ] || { echo "ensemble: DEST and at least two folders of tile-1 ... tile-6" >&2; exit 2; }
  for f in "${folders[@]}"; do need_networks "${tiles_all[@]/#/$f/tile-}"; done
  for k in "${tiles_all[@]}"; do
    write_ensemble "$to/tile-$k" "the networks that never saw dubai-tile-$k: ${folders[*]/%//tile-$k}" \
      "    weight: 1" "${folders[@]/%//tile-$k}"
  done
  echo "wrote $to/tile-{1..6}/ensemble.yaml"
  ;;
*)
  sed -n '2,/^set -euo pipefail/{/^set -euo pipefail/!p}' "$0" >&2  # the comment above, whatever its length
  exit 2
  ;;
esac
