#!/usr/bin/env bash
# Reproduces docs/results.md and the measurements of the journal it links to (docs/journal/).
#   bash scripts/results.sh [all|oracle|oracle-default|paper|network|loto|loto-proxy|new-ground-check|ensemble|ensemble-split|cells|curve-check|previous|network-held-out|sigma-prior|sigma-prior-fit|z-choice|z-choice-network|cross-fit|network-variants|proxy-check|vertical-speed|all-tiles] [JOBS]
#   (default: all, one job per core)
#
# oracle: the paper's experiment with the ground-truth oracle, deterministic (fixed 0.1 s per
#   image and 0 s per waypoint), in two configurations: the defaults, and the paper's (utility
#   threshold, I on delta sigma, descents over the whole region). Runs:
#   - WeedMap field 000: decision function initialised on one half, flown on the other, and
#     swapped (L = crop, weed);
#   - Dubai tiles 1-6, leave one tile out: initialised on the other five, flown on the sixth,
#     for each of building, road, vegetation, water.
#   Independent runs in parallel; on 2 cores the defaults take about 7 minutes, the paper's
#   configuration about 19 (its threshold search flies every setting over every training field).
#   oracle-default flies the defaults alone, paper the paper's configuration alone (the defaults'
#   runs, which its table compares with, from an earlier oracle-default). oracle-default takes
#   CONFIG (environment: the folder, default oracle-default) and EXTRA (more flags for every run,
#   e.g. EXTRA="--top-level undominated,hull").
# network: the same with the bundled networks (examples/models/mobilenetv2-dubai, erfnet-dubai,
#   and ensemble-dubai, the mean of the two; measured segmentation times) on the two tiles they
#   never trained on (4 and 6), each initialised on the five other tiles (the networks' training
#   tiles 1, 2, 3, 5 and the other unseen tile), as a user calibrates on every labelled field
#   they have; then every backend's missions against every backend's lawnmower curve
#   (adaptseg_tools.backend_compare: which gives the better map per second). About 26 minutes
#   on 2 cores for the two networks and 26 more for the ensemble (its calibration segments every
#   image with both networks once, into the cache); NETS="..." (environment) flies a subset and
#   keeps the other networks' runs.
#   Calibration keeps each network's segmentations in out/results/segmentation-cache (one folder
#   per network and weights), so a rerun segments only what the missions need.
# loto: the yardstick of decisions on ground nobody tuned for (every decision default is judged
#   here): for each Dubai tile k and each class, the MobileNetV2 of the deployment recipe that
#   never saw tile k (examples/models/mobilenetv2-dubai-loto/tile-k; scripts/loto.sh) flies tile
#   k, its decision function calibrated on the other five tiles, each segmented by the network
#   of the same recipe that never saw it (--calibration-network), as the deployment network's
#   decision model is calibrated for a new site; 24 runs. Declared times as the oracle's (0.1 s per
#   image, about MobileNetV2's median on the VM, the time calibration charges; 0 s per waypoint),
#   so a loaded machine moves no decision (LOTO_TIMES=measured
#   flies the measured times of the rows recorded before 2026-12-01). Printed
#   beside the oracle's runs of the same folds (part oracle-default's Dubai runs, when there;
#   ORACLE_CONFIG names another folder of them). Every network segments its own tile once into
#   the segmentation cache. CONFIG (environment) names the folder (default loto), EXTRA adds
#   flags to every run: CONFIG=loto-hull EXTRA="--top-level hull" ORACLE_CONFIG=oracle-hull.
#   LOTO_NETWORKS names another folder of tile-1 ... tile-6 networks (another seed, say).
#   Then every descent against the real curve and each run's best descents in hindsight
#   (adaptseg_tools.descent_table --curve, --hindsight --gsd 10). Last, the issue's targets
#   (adaptseg_tools.loto_targets; several configurations side by
#   side: loto_targets.py --oracle out/results/oracle-default a=out/results/loto b=...).
# loto-insample: a ceiling on what calibration can give the loto runs, not a deployment: each
#   tile flown by the network that never saw it, as in loto, but calibrated on that tile alone,
#   segmented by the same network: the rule's gain model fitted on the very field it flies, the
#   lawnmower curve it compares descents with that field's own. Where a class's run stays at or
#   below +0.001 here, no calibration of this rule's forecasts could lift it; what would have to
#   change is the candidates (regions, GSDs, durations) or the network. CONFIG (default
#   loto-insample) and EXTRA as for loto (no --gain-ratios or --margin-biases: one training
#   field). About 15 minutes on 2 cores with the segmentation cache warm.
# loto-swap: which half of a calibration transfers badly to new ground (a diagnosis, not a
#   deployment): each loto run flown again at z = 0 with a model put together
#   (adaptseg_tools.compose_model) from its leave-one-tile-out model (LOTO_CONFIG, default
#   loto-pooled-z0) and its model calibrated on the field itself (INSAMPLE_CONFIG, default
#   loto-insample-pooled): the leave-one-tile-out gain model with the field's own reference
#   (lawnmower curve, σ and input priors; config loto-swap-own-reference), the field's own gain
#   model with the leave-one-tile-out reference (loto-swap-own-gain), and both the field's own
#   (loto-swap-own-both). Needs both configurations; about 12 minutes on 2 cores.
# loto-proxy: until the six leave-one-tile-out networks are trained, a stand-in for loto on the
#   tiles that have a network of MobileNetV2 that never saw them: each tile with a bundled
#   mobilenetv2-dubai-loto/tile-k flown by it, tiles 4 and 6 otherwise by mobilenetv2-dubai
#   (trained on 1, 2, 3, 5); each calibrated on the other tiles of the set, each calibration
#   field segmented by a network of these that never saw it (--calibration-network, the first
#   that fits: the leave-one-tile-out networks before mobilenetv2-dubai). With tiles 1 to 4
#   bundled: tiles 1, 2, 3, 4, 6, 20 runs (the first four by their own networks). Every field of
#   each run, calibration and mission, new ground to the network that segments it; but fewer
#   calibration fields than loto, two recipes, the leave-one-tile-out networks untempered, and
#   mobilenetv2-dubai's temperature fitted on tile 4. TILES="1 2 4 6" LOTO_TILES="1 2"
#   (environment) flies the four-tile stand-in of 2026-11-29's second and third sessions (16
#   runs; before them tiles 1, 4 and 6, 12 runs).
#   CONFIG (environment; default loto-proxy) names the configuration and EXTRA adds flags, e.g.
#   CONFIG=loto-proxy-hull EXTRA="--top-level hull". About 13 minutes for five tiles on 2 cores
#   with 2 jobs beside a training (segmentations cached in out/results/segmentation-cache).
#   TILES="1 2 3 4 6" LOTO_TILES="1 2 3 4" keeps flying these five once tile 5's network is bundled.
# new-ground-check: what a network's behaviour on new ground lets the decision forecast, on the
#   stand-in's tiles (adaptseg_tools.new_ground_check): each tile's cell samples, segmented by
#   the network that flies it in loto-proxy (adaptseg_calibrate --cell-samples-csv, into
#   new-ground-check/), each field's descents forecast from the other fields' cells (the cell gain
#   model's normalised gain against the field's own exchange rate of false positives), and the
#   whole-field lawnmower rise against the cells summed and against what each run's model
#   predicted. Needs loto-proxy (CONFIG names another run of it); about 4 minutes on 2 cores.
# ensemble: field mIoU of the bundled networks and of their ensemble (examples/models/ensemble-dubai)
#   on the same whole-field lawnmowers of tiles 4 and 6 at 5, 10 and 15 cm/px
#   (adaptseg_tools.eval_ensemble, PyTorch on the exported weights), each network also with
#   test-time mirror, and the ensembles with MobileNetV2 mirrored (examples/models/
#   ensemble-dubai-mirror) and with both members mirrored; about 5 minutes on 2 cores.
# ensemble-split: the ensemble's runs of part network again, calibration also offered the decision
#   input split (the members split on a class of L) to rank cells by (--cell-input), side by side
#   with the network part's ensemble runs. Needs network; about 26 minutes on 2 cores.
# cells: per network, tile it never trained on (4, 6) and class, how each decision input ranks the
#   5 cm/px cells of every 15 cm/px region by the realised gain of re-mapping each alone, and how
#   much of the achievable gain the input of the network run's model captures with 20 % of the
#   cells (adaptseg_cell_study, adaptseg_tools.cell_study_table). Needs network; about 12
#   minutes on 2 cores for the three backends (NETS as for network).
# curve-check: the field curve's predicted rise from the top level to each lawnmower GSD against
#   the training fields' real curves, from the models oracle-default and network saved
#   (adaptseg_tools.curve_check_table; seconds, nothing flown).
# previous: the oracle and network sweeps flown with the defaults before 2026-11-26's ranked
#   cells (--coverage interest --curve training), side by side with the defaults' runs. Needs
#   oracle-default and network; about 30 minutes on 2 cores.
# network-held-out: ERFNet on tiles 4 and 6 again, each initialised on the other of the two
#   alone (the one scene the network never trained on either) instead of the five other tiles:
#   whether calibrating only where the network is as new to the ground as on the test field makes
#   better decisions (docs/journal/2026-11-networks.md, "Networks": none below -0.002, but fewer
#   gains and a lower mean). About 9 minutes on 2 cores. NETS (environment; default
#   erfnet-dubai) flies other networks: each network's runs go to network-held-out-<network>
#   (ERFNet's to network-held-out), about 6 minutes for MobileNetV2.
# network-variants: part network's runs of NETS (default mobilenetv2-dubai) flown twice more,
#   each with one change a reader might expect to make MobileNetV2's descents pay: the top level at
#   10 cm/px (--lawnmower-factors 1,1.5,2: the descents start where the network's lawnmower
#   curve flattens), and the cells ranked by the expected error about L alone (--cell-input
#   expected_error, the input of the cell study's best mean capture) instead of the input chosen
#   on the training fields; side by side with part network's runs
#   (docs/journal/2026-11-defaults.md, "Three more changes that do not make MobileNetV2's
#   descents pay"). Needs network; about 20 minutes on 2 cores.
# proxy-check: whether what the scene check measures after a descent (each decision input's drop
#   from the top-level image to the finer one over the re-mapped cells) tracks what re-mapping
#   them gained, on the tiles each network (NETS, default erfnet-dubai mobilenetv2-dubai) was
#   trained on (1, 2, 3, 5) and on those it never saw (4, 6): adaptseg_cell_study --csv at 12.5,
#   10 and 5 cm/px, then adaptseg_tools.proxy_table; and, from the same cells, how well the
#   cell gain model's slope fitted on five tiles forecasts the sixth's best cells, and each
#   tile's own slope (adaptseg_tools.slope_transfer). Independent of the other parts; about
#   20 minutes on 2 cores for the two networks. NETS=ensemble-dubai adds the ensemble's tables
#   (with its members' split among the inputs) and keeps the other networks'.
# sigma-prior: the previous defaults' runs (part previous) flown again with the models
#   `oracle-previous` saved, only the front-aware rule's sigma_prior_weight changed (0.01 and 1;
#   the calibrated models have 0.25): how much the prior on the field's share of L holds the
#   forecasts of C and eta back (docs/journal/2026-11-oracle.md, "σ̂, the field's share of L").
#   Needs out/results/oracle-previous; about 8 minutes on 2 cores.
# sigma-prior-fit: the previous defaults' Dubai runs calibrated again with sigma-hat's prior taken
#   from the training fields (--sigma-prior spread and estimated). Needs out/results/oracle-previous
#   for the comparison; about 13 minutes on 2 cores. (With the defaults' field curve sigma-hat
#   scales a descent's gain and the curve's rise alike: neither part applies to them.)
# z-choice: for each of the defaults' runs, the training folds' margins per confidence level z
#   (adaptseg_calibrate) and the test field flown with the run's model at every z: how much any
#   choice of z could buy (docs/results.md, "What any choice of z can buy"). Needs
#   out/results/oracle-default; about 8 minutes on 2 cores.
# z-choice-network: the same for the runs of part network (NETS as there; default the two single
#   networks), their calibrations rerun with the runs' flags (segmentations from the cache),
#   missions with measured segmentation times. Needs network; MobileNetV2's 8 runs took about
#   20 minutes with one job on 2 cores (beside another job); ERFNet's take longer.
# cross-fit: MobileNetV2's runs of part network (tiles 4 and 6, four classes) calibrated on the
#   tiles CROSS_TILES (environment; default "1 2 3") and the other unseen tile, twice: every field
#   segmented by the evaluation network (which trained on tiles 1, 2, 3 and 5), and each of
#   CROSS_TILES by a network of the same recipe that never saw it (--calibration-network
#   out/loto-cpu/model-K, `bash scripts/loto.sh cpu K`, its temperature fitted on tile K as the
#   evaluation network's was on its validation tile): whether calibrating on ground the network
#   knows is what keeps its decision from descending. Needs network; about 20 minutes on 2 cores. With
#   CROSS_TILES="1 2 3 5" only the cross-fitted runs are flown (the others are part network's).
# vertical-speed: the defaults' sweep (calibration included) with climbs and descents limited to
#   1 m/s against 2 m/s level (--vertical-speed 1; the paper's model climbs at the level speed):
#   what the immediate descent, the survey-first tour and staying low along a row are worth
#   when altitude is expensive, as on real multicopters. About 8 minutes on 2 cores.
# all-tiles: calibrated on all six Dubai tiles, as a user with every bundled tile calibrates
#   for new ground (and as acceptance does), per class, with the oracle and the networks NETS
#   (default mobilenetv2-dubai): the training folds of the z choice (each tile flown with the
#   model fitted on the other five) with the cell gain model's slopes pooled over the cells and
#   over the fields, each alone (--slope-pooling), and which the default, trying both, keeps
#   (adaptseg_tools.fold_table). Nothing flown beyond the folds; about 15 minutes on 2 cores
#   for the oracle and MobileNetV2.
# Outputs: out/results/<configuration>/<run>/ (adaptseg_evaluate's files); prints the tables.
set -euo pipefail
part=${1:-all}
jobs=${2:-$(nproc 2>/dev/null || echo 2)}
case "$part" in all | oracle | oracle-default | paper | network | loto | loto-insample | loto-swap | loto-proxy | new-ground-check | ensemble | ensemble-split | cells | curve-check | previous | network-held-out | sigma-prior | sigma-prior-fit | z-choice | z-choice-network | \
  cross-fit | network-variants | proxy-check | vertical-speed | all-tiles) ;;
  *) echo "usage: $0 [all|oracle|oracle-default|paper|network|loto|loto-insample|loto-swap|loto-proxy|new-ground-check|ensemble|ensemble-split|cells|curve-check|previous|network-held-out|sigma-prior|sigma-prior-fit|z-choice|z-choice-network|cross-fit|network-variants|proxy-check|vertical-speed|all-tiles] [JOBS]" >&2
    exit 2 ;;
esac
cd "$(dirname "$0")/.."
# The Python tools run from the source tree (python/README.md).
export PYTHONPATH="$PWD/python${PYTHONPATH:+:$PYTHONPATH}"
bash scripts/deps.sh plots
source scripts/configure.sh
configure_for results build/release >/dev/null
cmake --build build/release -j"$jobs" --target adaptseg_evaluate adaptseg_calibrate adaptseg_cell_study
eval_bin=build/release/examples/adaptseg_evaluate
calibrate_bin=build/release/examples/adaptseg_calibrate
root=out/results
classes="building road vegetation water"
fixed=(--seg-time-s 0.1 --plan-time-s 0)
paper=(--rule utility --gain-inputs delta-sigma --coverage region --no-plots)
# A bundled network (--network examples/models/NET), one thread per run; calibration keeps the
# network's segmentations on disk, so that the runs over the same tiles segment each image once.
network=(--segmenter network --threads 1 --segmentation-cache "out/results/segmentation-cache")
# The networks of part network (environment NETS: a subset, e.g. NETS=ensemble-dubai reruns
# only the ensemble's runs and keeps the others').
nets=${NETS:-erfnet-dubai mobilenetv2-dubai ensemble-dubai}

# One adaptseg_evaluate run: CONFIG RUN ARGS... -> $root/CONFIG/RUN (log: RUN.log beside it).
running=0
# After launching a job in the background: wait for one to end while $jobs are running.
throttle() {
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then
    wait -n || true
    running=$((running - 1))
  fi
}
launched=()
run() {
  local config=$1 name=$2
  shift 2
  mkdir -p "$root/$config"
  launched+=("$config/$name")
  "$eval_bin" "$@" --out "$root/$config/$name" >"$root/$config/$name.log" 2>&1 &
  throttle
}
dubai() { echo examples/data/dubai-tile-$1; }
# The --train arguments of every Dubai tile but tile $1 (leave one out), into the array `train`.
train_except() {
  local k
  train=()
  for k in 1 2 3 4 5 6; do [ "$k" != "$1" ] && train+=(--train "$(dubai "$k")"); done
  return 0
}
# After `wait`: every launched run must have written its results.
check() {
  local bad=0
  for r in "${launched[@]}"; do
    [ -s "$root/$r/results.csv" ] || { echo "FAILED: $r (see $root/$r.log)" >&2; bad=1; }
  done
  [ "$bad" = 0 ] || exit 1
}
# The run directories DIR/ ... given, comma-separated, as sweep_table.py takes them.
dir_list() { ls -d "$@" | sed 's:/$::' | paste -sd, -; }
# Leave-one-tile-out over the Dubai tiles for every class, each run with ARGS...: CONFIG ARGS...
sweep_dubai() {
  local config=$1 cls t k
  local -a train
  shift
  for cls in $classes; do
    for t in 1 2 3 4 5 6; do
      train_except "$t"
      run "$config" "dubai-$cls-tile-$t" "${train[@]}" --test "$(dubai "$t")" --interest "$cls" "$@"
    done
  done
}
# The oracle sweep of one configuration: both WeedMap splits, then sweep_dubai. CONFIG ARGS...
sweep() {
  local config=$1 w=examples/data/weedmap-000
  shift
  run "$config" weedmap-train-left --train "$w:0,0,0.5,1" --test "$w:0.5,0,1,1" "$@"
  run "$config" weedmap-train-right --train "$w:0.5,0,1,1" --test "$w:0,0,0.5,1" "$@"
  sweep_dubai "$config" "$@"
}

if [ "$part" = sigma-prior ]; then
  [ -d "$root/oracle-previous" ] || { echo "run 'bash $0 previous' first" >&2; exit 1; }
  w=examples/data/weedmap-000
  labels=("previous=$(ls -d "$root/oracle-previous"/*/ | sed 's:/$::' | paste -sd, -)")
  for k in 0.01 1; do
    config=oracle-sigma-prior-$k
    rm -rf "${root:?}/$config"
    mkdir -p "$root/$config"
    for d in "$root"/oracle-previous/*/; do
      name=$(basename "$d")
      model="$root/$config/$name.model.yaml"
      sed "s/^\(  *sigma_prior_weight:\) .*/\1 $k/" "$d/model.yaml" >"$model"
      case $name in
        weedmap-train-left) test=(--test "$w:0.5,0,1,1") ;;
        weedmap-train-right) test=(--test "$w:0,0,0.5,1") ;;
        *) cls=${name#dubai-}; cls=${cls%%-*}; test=(--test "$(dubai "${name##*-}")" --interest "$cls") ;;
      esac
      run "$config" "$name" --decision-model "$model" "${test[@]}" "${fixed[@]}" --no-plots
    done
  done
  wait
  check
  for k in 0.01 1; do labels+=("sigma-prior-$k=$(ls -d "$root/oracle-sigma-prior-$k"/*/ | sed 's:/$::' | paste -sd, -)"); done
  /usr/bin/python3 -m adaptseg_tools.sweep_table "${labels[@]}"
  exit 0
fi

if [ "$part" = z-choice ] || [ "$part" = z-choice-network ]; then
  # One run NAME of configuration $src: its training folds' trials (adaptseg_calibrate with the
  # run's flags: train, interest, flags), then its test field at every z (sequential, one core).
  z_run() {
    local name=$1 d=$root/$src/$1
    "$calibrate_bin" "${train[@]}" "${interest[@]}" "${flags[@]}" --out "$out/$name.model.yaml" >"$out/$name.trials.txt" 2>&1
    for z in 0 0.5 1 1.5 2; do
      sed "s/^\(  *confidence:\) .*/\1 $z/" "$d/model.yaml" >"$out/$name.z$z.yaml"
      "$eval_bin" --decision-model "$out/$name.z$z.yaml" "${test[@]}" "${interest[@]}" "${flags[@]}" --no-plots \
        --out "$out/$name.z$z" >"$out/$name.z$z.log" 2>&1
    done
  }
  z_launch() {  # z_run in the background, at most $jobs at a time
    z_run "$1" &
    throttle
  }
  running=0
  if [ "$part" = z-choice ]; then
    src=oracle-default
    flags=("${fixed[@]}")
  else
    src=network
  fi
  [ -d "$root/$src" ] || { echo "run 'bash $0 $src' first" >&2; exit 1; }
  out=$root/$part
  rm -rf "${out:?}"
  mkdir -p "$out"
  w=examples/data/weedmap-000
  if [ "$part" = z-choice ]; then
    for d in "$root"/oracle-default/*/; do
      name=$(basename "$d") interest=()
      case $name in
        weedmap-train-left) train=(--train "$w:0,0,0.5,1") test=(--test "$w:0.5,0,1,1") ;;
        weedmap-train-right) train=(--train "$w:0.5,0,1,1") test=(--test "$w:0,0,0.5,1") ;;
        *)
          cls=${name#dubai-} t=${name##*-}
          cls=${cls%%-*}
          interest=(--interest "$cls")
          train_except "$t"
          test=(--test "$(dubai "$t")")
          ;;
      esac
      z_launch "$name"
    done
  else
    for net in ${NETS:-erfnet-dubai mobilenetv2-dubai}; do
      flags=(--network "examples/models/$net" "${network[@]}")
      for cls in $classes; do
        for t in 4 6; do
          [ -d "$root/network/$net-$cls-fly$t" ] || continue
          train_except "$t"
          interest=(--interest "$cls") test=(--test "$(dubai "$t")")
          z_launch "$net-$cls-fly$t"
        done
      done
    done
  fi
  wait
  /usr/bin/python3 -m adaptseg_tools.z_choice_table "$out"
  exit 0
fi

if [ "$part" = sigma-prior-fit ]; then
  [ -d "$root/oracle-previous" ] || { echo "run 'bash $0 previous' first" >&2; exit 1; }
  labels=("previous=$(ls -d "$root/oracle-previous"/dubai-*/ | sed 's:/$::' | paste -sd, -)")
  for mode in spread estimated; do
    config=oracle-sigma-prior-$mode
    rm -rf "${root:?}/$config"
    sweep_dubai "$config" "${fixed[@]}" --sigma-prior "$mode" --coverage interest --curve training --no-plots
  done
  wait
  check
  for mode in spread estimated; do labels+=("$mode=$(ls -d "$root/oracle-sigma-prior-$mode"/*/ | sed 's:/$::' | paste -sd, -)"); done
  /usr/bin/python3 -m adaptseg_tools.sweep_table "${labels[@]}"
  exit 0
fi

if [ "$part" = vertical-speed ]; then
  config=oracle-vertical-speed
  rm -rf "${root:?}/$config"
  sweep "$config" "${fixed[@]}" --vertical-speed 1 --no-plots
  wait
  check
  /usr/bin/python3 -m adaptseg_tools.sweep_table "vertical 1 m/s=$(ls -d "$root/$config"/*/ | sed 's:/$::' | paste -sd, -)"
  exit 0
fi

if [ "$part" = previous ]; then
  # The defaults before 2026-11-26's (descents over the cells that show L, decided against the
  # training fields' curves: --coverage interest --curve training), flown as the oracle and the
  # network sweeps fly the defaults: what the ranked cells, the top level and the field's own
  # curve changed. Needs oracle-default and network (for the comparison tables).
  [ -d "$root/oracle-default" ] && [ -d "$root/network" ] || { echo "run 'bash $0 oracle-default' and 'network' first" >&2; exit 1; }
  previous=(--coverage interest --curve training --no-plots)
  rm -rf "$root/oracle-previous" "$root/network-previous"
  sweep oracle-previous "${fixed[@]}" "${previous[@]}"
  for net in erfnet-dubai mobilenetv2-dubai; do
    for cls in $classes; do
      for t in 4 6; do
        train_except "$t"
        run network-previous "$net-$cls-fly$t" "${train[@]}" --test "$(dubai "$t")" --interest "$cls" \
          --network "examples/models/$net" "${network[@]}" "${previous[@]}"
      done
    done
  done
  wait
  check
  runs() { ls -d "$root/$1"/*/ | sed 's:/$::' | paste -sd, -; }
  /usr/bin/python3 -m adaptseg_tools.sweep_table "defaults=$(runs oracle-default)" "previous=$(runs oracle-previous)"
  for net in erfnet-dubai mobilenetv2-dubai; do
    echo
    echo "## $net"
    /usr/bin/python3 -m adaptseg_tools.sweep_table "$net=$(ls -d "$root/network/$net"-*/ | sed 's:/$::' | paste -sd, -)" \
      "previous=$(ls -d "$root/network-previous/$net"-*/ | sed 's:/$::' | paste -sd, -)"
  done
  exit 0
fi

if [ "$part" = curve-check ]; then
  [ -d "$root/oracle-default" ] && [ -d "$root/network" ] || { echo "run 'bash $0 oracle-default' and 'network' first" >&2; exit 1; }
  runs() { ls -d "$@" | sed 's:/$::' | paste -sd, -; }
  /usr/bin/python3 -m adaptseg_tools.curve_check_table "oracle=$(runs "$root"/oracle-default/dubai-*/)" \
    "mobilenetv2-dubai=$(runs "$root"/network/mobilenetv2-dubai-*/)" "erfnet-dubai=$(runs "$root"/network/erfnet-dubai-*/)"
  exit 0
fi

if [ "$part" = cells ]; then
  # Per network, tile it never trained on and class: how the decision inputs rank the 5 cm/px
  # cells of every 15 cm/px region by what re-mapping each alone gains, and how much the input
  # of the run's model (bash scripts/results.sh network) captures.
  [ -d "$root/network" ] || { echo "run 'bash $0 network' first" >&2; exit 1; }
  out=$root/cells
  mkdir -p "$out"
  for net in $nets; do
    for t in 4 6; do
      for cls in $classes; do
        build/release/examples/adaptseg_cell_study --field "$(dubai "$t")" --classes "$cls" --gsd 5 \
          --segmenter network --network "examples/models/$net" --threads "$jobs" \
          --decision-model "$root/network/$net-$cls-fly$t/model.yaml" --csv "$out/$net-$cls-$t.csv" >"$out/$net-$cls-$t.md" 2>/dev/null
      done
    done
    echo
    echo "## $net: capture of the achievable gain by the best 20 % of cells (mean over tiles 4, 6 and the four classes)"
    cat "$out/$net"-*.md | /usr/bin/python3 -m adaptseg_tools.cell_study_table
  done
  exit 0
fi

if [ "$part" = ensemble ]; then
  mkdir -p "$root/ensemble"
  /usr/bin/python3 -m adaptseg_tools.eval_ensemble --threads "$jobs" --bands 1,2,3 \
    --members mobilenetv2-dubai=examples/models/mobilenetv2-dubai,erfnet-dubai=examples/models/erfnet-dubai,mobilenetv2-dubai-mirror=examples/models/mobilenetv2-dubai@mirror,erfnet-dubai-mirror=examples/models/erfnet-dubai@mirror \
    --ensembles ensemble-dubai=examples/models/ensemble-dubai,ensemble-dubai-mirror=examples/models/ensemble-dubai-mirror,both-mirrored=mobilenetv2-dubai-mirror+erfnet-dubai-mirror \
    --json "$root/ensemble/ensemble.json"
  exit 0
fi

if [ "$part" = ensemble-split ]; then
  [ -d "$root/network" ] || { echo "run 'bash $0 network' first" >&2; exit 1; }
  config=network-split
  rm -rf "${root:?}/$config"
  for cls in $classes; do
    for t in 4 6; do
      train_except "$t"
      run "$config" "ensemble-dubai-$cls-fly$t" "${train[@]}" --test "$(dubai "$t")" --interest "$cls" \
        --network examples/models/ensemble-dubai "${network[@]}" \
        --cell-input sigma,boundary,ambiguity,expected_error,second_choice,split
    done
  done
  wait
  check
  /usr/bin/python3 -m adaptseg_tools.sweep_table \
    "ensemble-dubai=$(dir_list "$root/network/ensemble-dubai"-*/)" "with-split=$(dir_list "$root/$config"/*/)"
  exit 0
fi

if [ "$part" = loto ] || [ "$part" = loto-insample ]; then
  loto=${LOTO_NETWORKS:-examples/models/mobilenetv2-dubai-loto}
  crossed=()
  for k in 1 2 3 4 5 6; do
    [ -s "$loto/tile-$k/model.onnx" ] || { echo "no $loto/tile-$k: bash scripts/loto.sh recipe-cpu, then bundle" >&2; exit 1; }
    crossed+=(--calibration-network "$loto/tile-$k")
  done
  config=${CONFIG:-$part} oracle=${ORACLE_CONFIG:-oracle-default}
  read -r -a extra <<<"${EXTRA:-}"
  times=("${fixed[@]}")
  [ "${LOTO_TIMES:-declared}" = measured ] && times=()
  rm -rf "${root:?}/$config"
  for cls in $classes; do
    for t in 1 2 3 4 5 6; do
      train_except "$t"
      [ "$part" = loto-insample ] && train=(--train "$(dubai "$t")")
      run "$config" "mobilenetv2-loto-$cls-tile-$t" "${train[@]}" --test "$(dubai "$t")" --interest "$cls" \
        --network "$loto/tile-$t" "${network[@]}" "${crossed[@]}" "${times[@]}" --no-plots "${extra[@]}"
    done
  done
  wait
  check
  labels=("$config=$(dir_list "$root/$config"/*/)")
  [ -d "$root/$oracle" ] && labels+=("oracle=$(dir_list "$root/$oracle"/dubai-*/)")
  /usr/bin/python3 -m adaptseg_tools.sweep_table "${labels[@]}"
  /usr/bin/python3 -m adaptseg_tools.descent_table "$root/$config"/*/
  # Each descent against the real curve, and each run's best descents in hindsight.
  /usr/bin/python3 -m adaptseg_tools.descent_table --curve "$root/$config"/*/
  /usr/bin/python3 -m adaptseg_tools.descent_table --hindsight --gsd 10 "$root/$config"/*/
  targets=("$config=$root/$config")
  [ -d "$root/$oracle" ] && targets=(--oracle "$root/$oracle" "${targets[@]}")
  /usr/bin/python3 -m adaptseg_tools.loto_targets "${targets[@]}"
  exit 0
fi

if [ "$part" = loto-swap ]; then
  loto=${LOTO_NETWORKS:-examples/models/mobilenetv2-dubai-loto}
  lofo=$root/${LOTO_CONFIG:-loto-pooled-z0} own=$root/${INSAMPLE_CONFIG:-loto-insample-pooled}
  for d in "$lofo" "$own"; do
    [ -d "$d" ] || { echo "no $d: bash $0 loto (CONFIG, EXTRA) and loto-insample first" >&2; exit 1; }
  done
  labels=("lofo=$lofo")
  for mix in own-reference own-gain own-both; do
    config=loto-swap-$mix
    rm -rf "${root:?}/$config"
    mkdir -p "$root/$config"
    for cls in $classes; do
      for t in 1 2 3 4 5 6; do
        name=mobilenetv2-loto-$cls-tile-$t
        case $mix in
          own-reference) gain=$lofo/$name/model.yaml reference=$own/$name/model.yaml ;;
          own-gain) gain=$own/$name/model.yaml reference=$lofo/$name/model.yaml ;;
          own-both) gain=$own/$name/model.yaml reference=$own/$name/model.yaml ;;
        esac
        /usr/bin/python3 -m adaptseg_tools.compose_model --gain "$gain" --reference "$reference" --confidence 0 \
          --out "$root/$config/$name.model.yaml"
        run "$config" "$name" --decision-model "$root/$config/$name.model.yaml" --test "$(dubai "$t")" \
          --interest "$cls" --network "$loto/tile-$t" "${network[@]}" "${fixed[@]}" --no-plots
      done
    done
    labels+=("$mix=$root/$config")
  done
  wait
  check
  /usr/bin/python3 -m adaptseg_tools.loto_targets "${labels[@]}"
  exit 0
fi

# The stand-in's networks (loto-proxy, new-ground-check): every tile with a network of the recipe
# that never saw it, its leave-one-tile-out network where one is bundled, else (tiles 4 and 6)
# the evaluation network; into `stand_in` (its tiles), `flier` (the network per tile) and
# `crossed` (the calibration networks, --calibration-network ...). TILES (environment) restricts
# the tiles, LOTO_TILES the leave-one-tile-out networks used: TILES="1 2 4 6" LOTO_TILES="1 2" is
# the four-tile stand-in of before.
stand_in_networks() {
  local loto=examples/models/mobilenetv2-dubai-loto evaluation=examples/models/mobilenetv2-dubai k
  stand_in=() crossed=()
  declare -g -A flier=()
  for k in 1 2 3 4 5 6; do
    if [ -s "$loto/tile-$k/model.onnx" ] && [[ " ${LOTO_TILES:-$k} " == *" $k "* ]]; then
      flier[$k]=$loto/tile-$k
      crossed+=(--calibration-network "$loto/tile-$k")
    elif [ "$k" = 4 ] || [ "$k" = 6 ]; then
      flier[$k]=$evaluation
    else
      continue
    fi
    case " ${TILES:-$k} " in *" $k "*) stand_in+=("$k") ;; esac
  done
  crossed+=(--calibration-network "$evaluation")
}

if [ "$part" = loto-proxy ]; then
  config=${CONFIG:-loto-proxy}
  read -r -a extra <<<"${EXTRA:-}"
  stand_in_networks
  rm -rf "${root:?}/$config"
  for cls in $classes; do
    for t in "${stand_in[@]}"; do
      net=${flier[$t]}
      train=()
      for k in "${stand_in[@]}"; do [ "$k" != "$t" ] && train+=(--train "$(dubai "$k")"); done
      run "$config" "$cls-tile-$t" "${train[@]}" --test "$(dubai "$t")" --interest "$cls" \
        --network "$net" "${crossed[@]}" "${network[@]}" --no-plots "${extra[@]}"
    done
  done
  wait
  check
  /usr/bin/python3 -m adaptseg_tools.sweep_table "$config=$(dir_list "$root/$config"/*/)"
  /usr/bin/python3 -m adaptseg_tools.descent_table "$root/$config"/*/
  exit 0
fi

if [ "$part" = new-ground-check ]; then
  config=${CONFIG:-loto-proxy}
  [ -d "$root/$config" ] || { echo "run 'bash $0 loto-proxy' first" >&2; exit 1; }
  stand_in_networks
  mkdir -p "$root/new-ground-check"
  # Every stand-in tile's cell samples, each tile segmented by the network that flies it there:
  # the first tile's network segments its own tile, and every other tile (one of its training
  # tiles) is segmented by the first calibration network that never saw it, as in the flights.
  for cls in $classes; do
    train=()
    for k in "${stand_in[@]}"; do train+=(--train "$(dubai "$k")"); done
    build/release/examples/adaptseg_calibrate "${train[@]}" --interest "$cls" --network "${flier[${stand_in[0]}]}" \
      "${crossed[@]}" "${network[@]}" --out "$root/new-ground-check/model-$cls.yaml" \
      --cell-samples-csv "$root/new-ground-check/cells-$cls.csv" >"$root/new-ground-check/calibrate-$cls.log" 2>&1 &
    throttle
  done
  wait
  /usr/bin/python3 -m adaptseg_tools.new_ground_check "$root/new-ground-check" "$root/$config"
  exit 0
fi

if [ "$part" = cross-fit ]; then
  [ -d "$root/network" ] || { echo "run 'bash $0 network' first" >&2; exit 1; }
  cross_tiles=${CROSS_TILES:-1 2 3}
  crossed=()
  for k in $cross_tiles; do
    [ -s "out/loto-cpu/model-$k/model.onnx" ] || { echo "no out/loto-cpu/model-$k: bash scripts/loto.sh cpu $k" >&2; exit 1; }
    crossed+=(--calibration-network "out/loto-cpu/model-$k")
  done
  # One pair of configurations per set of tiles (network-fields-123, network-cross-fit-123). With
  # all four tiles the network trained on, the evaluation network's runs are part network's.
  tag=$(printf '%s\n' $cross_tiles | sort | paste -sd '' -)
  fields=network-fields-$tag crossfit=network-cross-fit-$tag
  configs=("$fields" "$crossfit")
  [ "$tag" = 1235 ] && configs=("$crossfit")
  rm -rf "${root:?}/$fields" "${root:?}/$crossfit"
  for cls in $classes; do
    for t in 4 6; do
      train=()
      for k in $cross_tiles $((10 - t)); do train+=(--train "$(dubai "$k")"); done
      for config in "${configs[@]}"; do
        extra=()
        [ "$config" = "$crossfit" ] && extra=("${crossed[@]}")
        run "$config" "mobilenetv2-dubai-$cls-fly$t" "${train[@]}" --test "$(dubai "$t")" --interest "$cls" \
          --network examples/models/mobilenetv2-dubai "${network[@]}" --no-plots "${extra[@]}"
      done
    done
  done
  wait
  check
  same=()
  [ -d "$root/$fields" ] && same=("same-network=$(dir_list "$root/$fields"/*/)")
  /usr/bin/python3 -m adaptseg_tools.sweep_table "five-tiles=$(dir_list "$root/network/mobilenetv2-dubai"-*/)" \
    "${same[@]}" "cross-fit=$(dir_list "$root/$crossfit"/*/)"
  exit 0
fi

if [ "$part" = network-held-out ]; then
  held_out_config() { if [ "$1" = erfnet-dubai ]; then echo network-held-out; else echo "network-held-out-$1"; fi; }
  for net in ${NETS:-erfnet-dubai}; do
    config=$(held_out_config "$net")
    rm -rf "${root:?}/$config"
    for cls in $classes; do
      for t in 4 6; do
        run "$config" "$net-$cls-fly$t" --train "$(dubai $((10 - t)))" --test "$(dubai "$t")" \
          --interest "$cls" --network "examples/models/$net" "${network[@]}" --no-plots
      done
    done
  done
  wait
  check
  labels=()
  for net in ${NETS:-erfnet-dubai}; do labels+=("$net-held-out=$(dir_list "$root/$(held_out_config "$net")"/*/)"); done
  /usr/bin/python3 -m adaptseg_tools.sweep_table "${labels[@]}"
  exit 0
fi

if [ "$part" = all-tiles ]; then
  out=$root/all-tiles
  rm -rf "${out:?}"
  mkdir -p "$out"
  train=()
  for k in 1 2 3 4 5 6; do train+=(--train "$(dubai "$k")"); done
  for net in oracle ${NETS:-mobilenetv2-dubai}; do
    flags=("${fixed[@]}")
    [ "$net" = oracle ] || flags=(--network "examples/models/$net" "${network[@]}")
    for cls in $classes; do
      for pooling in cells fields; do
        "$calibrate_bin" "${train[@]}" --interest "$cls" "${flags[@]}" --slope-pooling "$pooling" \
          --out "$out/$net-$cls.$pooling.yaml" >"$out/$net-$cls.$pooling.txt" 2>&1 &
        throttle
      done
    done
  done
  wait
  for f in "$out"/*.txt; do
    [ -s "${f%.txt}.yaml" ] || { echo "FAILED: $f" >&2; exit 1; }
  done
  /usr/bin/python3 -m adaptseg_tools.fold_table --order cells,fields "$out"
  exit 0
fi

if [ "$part" = proxy-check ]; then
  out=$root/proxy-check
  mkdir -p "$out"
  for net in ${NETS:-erfnet-dubai mobilenetv2-dubai}; do rm -f "$out/$net"-*; done  # other networks' tables stay
  for net in ${NETS:-erfnet-dubai mobilenetv2-dubai}; do
    for set in trained-on never-seen; do
      tiles="1 2 3 5"
      [ "$set" = never-seen ] && tiles="4 6"
      fields=()
      for t in $tiles; do fields+=(--field "$(dubai "$t")"); done
      build/release/examples/adaptseg_cell_study "${fields[@]}" --classes "${classes// /,}" --gsd 12.5,10,5 --segmenter network \
        --network "examples/models/$net" --threads 1 --seg-time-s 0.1 --plan-time-s 0 \
        --csv "$out/$net-$set.csv" >"$out/$net-$set.md" 2>"$out/$net-$set.log" &
      throttle
    done
  done
  wait
  for net in ${NETS:-erfnet-dubai mobilenetv2-dubai}; do
    for set in trained-on never-seen; do
      [ -s "$out/$net-$set.csv" ] || { echo "FAILED: $net $set (see $out/$net-$set.log)" >&2; exit 1; }
    done
    /usr/bin/python3 -m adaptseg_tools.proxy_table "$net, tiles it was trained on=$out/$net-trained-on.csv" \
      "$net, tiles it never saw=$out/$net-never-seen.csv"
  done
  # The cell gain model's slope fitted on five tiles against the sixth's best cells: pooled over
  # the cells (CellGainModel::fit), the mean of the tiles' own slopes, or those pooled as random
  # effects; and each tile's own slope and mean input at the top (--field-slopes).
  transfer=()
  for net in ${NETS:-erfnet-dubai mobilenetv2-dubai}; do transfer+=("$out/$net-trained-on.csv" "$out/$net-never-seen.csv"); done
  /usr/bin/python3 -m adaptseg_tools.slope_transfer --field-slopes "${transfer[@]}"
  exit 0
fi

if [ "$part" = network-variants ]; then
  [ -d "$root/network" ] || { echo "run 'bash $0 network' first" >&2; exit 1; }
  for net in ${NETS:-mobilenetv2-dubai}; do
    ls -d "$root/network/$net"-*/ >/dev/null 2>&1 || { echo "part network has no runs of $net" >&2; exit 1; }
    for variant in top10 expected-error; do
      config=network-$variant
      case $variant in
        top10) extra=(--lawnmower-factors 1,1.5,2) ;;
        expected-error) extra=(--cell-input expected_error) ;;
      esac
      rm -rf "${root:?}/$config/$net"-*
      for cls in $classes; do
        for t in 4 6; do
          train_except "$t"
          run "$config" "$net-$cls-fly$t" "${train[@]}" --test "$(dubai "$t")" --interest "$cls" \
            --network "examples/models/$net" "${network[@]}" --no-plots "${extra[@]}"
        done
      done
    done
  done
  wait
  check
  labels=()
  for net in ${NETS:-mobilenetv2-dubai}; do
    labels+=("$net-five-tiles=$(dir_list "$root/network/$net"-*/)")
    for variant in top10 expected-error; do labels+=("$net-$variant=$(dir_list "$root/network-$variant/$net"-*/)"); done
  done
  /usr/bin/python3 -m adaptseg_tools.sweep_table "${labels[@]}"
  exit 0
fi

if [ "$part" != network ]; then
  configs=(oracle-default oracle-paper)
  [ "$part" = oracle-default ] && configs=("${CONFIG:-oracle-default}")
  if [ "$part" = paper ]; then
    [ -d "$root/oracle-default" ] || { echo "run 'bash $0 oracle-default' first" >&2; exit 1; }
    configs=(oracle-paper)
  fi
  for config in "${configs[@]}"; do rm -rf "${root:?}/$config"; done
  for config in "${configs[@]}"; do
    extra=("${fixed[@]}")
    [ "$config" = oracle-paper ] && extra+=("${paper[@]}")
    [ "$part" = oracle-default ] && read -r -a more <<<"${EXTRA:-}" && extra+=("${more[@]}")
    sweep "$config" "${extra[@]}"
  done
  wait
  check
  runs() { ls -d "$root/$1"/*/ | sed 's:/$::' | paste -sd, -; }
  if [ "$part" = oracle-default ]; then
    /usr/bin/python3 -m adaptseg_tools.sweep_table "defaults=$(runs "${configs[0]}")"
    /usr/bin/python3 -m adaptseg_tools.per_image_table "$root/${configs[0]}/weedmap-train-left" \
      "$root/${configs[0]}/weedmap-train-right"
  elif [ "$part" = paper ]; then
    /usr/bin/python3 -m adaptseg_tools.sweep_table "defaults=$(runs oracle-default)" "paper=$(runs oracle-paper)"
  else
    /usr/bin/python3 -m adaptseg_tools.sweep_table "defaults=$(runs oracle-default)" "paper=$(runs oracle-paper)"
    /usr/bin/python3 -m adaptseg_tools.per_image_table "$root/oracle-default/weedmap-train-left" \
      "$root/oracle-default/weedmap-train-right"
  fi
fi

if [ "$part" = all ] || [ "$part" = network ]; then
  for net in $nets; do rm -rf "$root/network/$net"-*; done
  for net in $nets; do
    for cls in $classes; do
      for t in 4 6; do
        train_except "$t"
        run network "$net-$cls-fly$t" "${train[@]}" --test "$(dubai "$t")" --interest "$cls" \
          --network "examples/models/$net" "${network[@]}"
      done
    done
  done
  wait
  check
  for net in $nets; do
    echo
    echo "## $net"
    /usr/bin/python3 -m adaptseg_tools.sweep_table "$net=$(ls -d "$root/network/$net"-*/ | sed 's:/$::' | paste -sd, -)"
    /usr/bin/python3 -m adaptseg_tools.per_image_table "$root/network/$net-vegetation-fly6" \
      "$root/network/$net-vegetation-fly4"
  done
  # Map per second across backends: every backend's missions against every backend's curve.
  echo
  echo "## The backends against each other"
  /usr/bin/python3 -m adaptseg_tools.backend_compare "$root/network" mobilenetv2-dubai erfnet-dubai ensemble-dubai
fi
