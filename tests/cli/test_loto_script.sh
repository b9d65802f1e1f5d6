#!/usr/bin/env bash
# scripts/loto.sh's file work on stand-in networks (nothing trained, built or flown): stage copies
# a finished tile without its temperature and never over a staged one; mirror, coarse and ensemble write
# each tile's ensemble.yaml with members that resolve to the networks, and refuse, before writing
# anything, a set with a network missing or without its temperature; partial refuses fewer than two
# networks trained here and a folder it did not write. A few seconds.
#   test_loto_script.sh SOURCE_DIR
set -uo pipefail
source "$(dirname "$0")/cli_common.sh"
loto="$1/scripts/loto.sh"
[ -f "$loto" ] || fail "no $loto"
export PYTHON=true  # no interpreter probe: these subcommands run no Python

# network DIR [TEMPERATURE]: a stand-in network folder (an ONNX file's place, its metadata).
network() {
  mkdir -p "$1"
  echo onnx >"$1/model.onnx"
  { echo "arch: mobilenetv2"; [ -z "${2:-}" ] || echo "temperature: $2"; } >"$1/model.yaml"
}
# set_of DIR [TEMPERATURE]: tile-1 ... tile-6 of a bundled set.
set_of() { for k in 1 2 3 4 5 6; do network "$1/tile-$k" "${2:-}"; done; }
# refused FRAGMENT ARGS...: loto.sh ARGS exits non-zero, saying FRAGMENT on stderr.
refused() {
  local fragment=$1
  shift
  bash "$loto" "$@" >"$work/out" 2>"$work/err" && fail "loto.sh $* succeeded (want a refusal)"
  grep -qF -- "$fragment" "$work/err" || fail "loto.sh $*: stderr lacks '$fragment': $(cat "$work/err")"
  echo "ok: refused: $(head -1 "$work/err")"
}

# --- stage: a trained tile (recipe-cpu's files in LOTO_WORK) into LOTO_BUNDLE ---
w="$work/work" b="$work/bundle"
network "$w/model-2"
for f in train_log.csv val_log.csv val_ema_log.csv; do echo "step" >"$w/model-2/$f"; done
echo '{"fields": {}}' >"$w/eval-2.json"
echo "training done" >"$w/train-2.log"
export LOTO_WORK=$w LOTO_BUNDLE=$b
bash "$loto" stage 2 >"$work/out" 2>&1 || fail "stage 2: $(cat "$work/out")"
for f in model.onnx model.yaml train_log.csv val_log.csv val_ema_log.csv; do
  cmp -s "$w/model-2/$f" "$b/tile-2/$f" || fail "stage 2 did not copy $f"
done
cmp -s "$w/eval-2.json" "$b/tile-2/held_out_eval.json" || fail "stage 2: held_out_eval.json is not eval-2.json"
cmp -s "$w/train-2.log" "$b/tile-2/train.log" || fail "stage 2: train.log is not train-2.log"
grep -q '^temperature:' "$b/tile-2/model.yaml" && fail "stage 2 set a temperature"
echo "ok: stage 2 copied the network, its logs and its held-out scores"
echo "changed" >"$w/model-2/model.onnx"
refused "holds a network already" stage 2
cmp -s "$b/tile-2/model.onnx" <(echo onnx) || fail "a refused stage overwrote tile-2"
refused "no $w/model-3" stage 3
[ -e "$b/tile-3" ] && fail "a refused stage 3 left $b/tile-3"

# --- ensemble: each tile's networks of several sets together ---
set_of "$work/seed0" 1.5
set_of "$work/seed1" 1.25
unset LOTO_WORK LOTO_BUNDLE
bash "$loto" ensemble "$work/ens" "$work/seed0" "$work/seed1" >"$work/out" 2>&1 || fail "ensemble: $(cat "$work/out")"
for k in 1 2 3 4 5 6; do
  e="$work/ens/tile-$k/ensemble.yaml"
  [ -s "$e" ] || fail "ensemble wrote no $e"
  mapfile -t members < <(sed -n 's/^  - model: "\(.*\)"$/\1/p' "$e")
  [ "${#members[@]}" -eq 2 ] || fail "$e: ${#members[@]} members (want 2)"
  for i in 0 1; do
    [ "$(realpath "$work/ens/tile-$k/${members[$i]}")" = "$(realpath "$work/seed$i/tile-$k")" ] ||
      fail "$e: member $i is ${members[$i]}, not seed$i/tile-$k"
  done
  [ "$(grep -c '^    weight: 1$' "$e")" -eq 2 ] || fail "$e: not every member weighted 1"
  # The description holds ": " (a plain YAML scalar may not; yaml-cpp refused the file): quoted.
  grep -qx "description: \"the networks that never saw dubai-tile-$k: .*seed0/tile-$k .*seed1/tile-$k\"" "$e" ||
    fail "$e: description not a double-quoted scalar: $(head -1 "$e")"
done
# Where a YAML parser is at hand, the file parses to the description and two members.
if /usr/bin/python3 -c 'import yaml' 2>/dev/null; then
  /usr/bin/python3 - "$work/ens/tile-3/ensemble.yaml" <<'EOF' || fail "ensemble.yaml does not parse as written"
import sys, yaml
d = yaml.safe_load(open(sys.argv[1]))
assert d["description"].startswith("the networks that never saw dubai-tile-3: "), d
assert [m["weight"] for m in d["members"]] == [1, 1], d
EOF
  echo "ok: ensemble.yaml parses (PyYAML)"
fi
echo "ok: ensemble wrote six ensemble.yaml, two members each, relative to their file"
refused "ensemble: DEST and at least two folders" ensemble "$work/one" "$work/seed0"
# A staged set (no temperature yet) or a missing tile is refused before anything is written.
set_of "$work/staged"
refused "no temperature in $work/staged/tile-1/model.yaml" ensemble "$work/ens2" "$work/seed0" "$work/staged"
rm -r "$work/seed1/tile-6"
refused "no $work/seed1/tile-6/model.onnx" ensemble "$work/ens3" "$work/seed0" "$work/seed1"
[ -e "$work/ens2" ] || [ -e "$work/ens3" ] && fail "a refused ensemble wrote files"

# --- mirror: each network of LOTO_BUNDLE under test-time mirror ---
LOTO_BUNDLE="$work/seed0" bash "$loto" mirror "$work/mir" >"$work/out" 2>&1 || fail "mirror: $(cat "$work/out")"
for k in 1 2 3 4 5 6; do
  e="$work/mir/tile-$k/ensemble.yaml"
  m=$(sed -n 's/^  - model: "\(.*\)"$/\1/p' "$e")
  [ "$(realpath "$work/mir/tile-$k/$m")" = "$(realpath "$work/seed0/tile-$k")" ] || fail "$e: member $m"
  grep -qx '    mirror: true' "$e" || fail "$e: no mirror: true"
done
echo "ok: mirror wrote six ensembles of one mirrored member"
LOTO_BUNDLE="$work/staged" refused "no temperature" mirror "$work/mir2"
[ -e "$work/mir2" ] && fail "a refused mirror wrote files"

# --- coarse: each network of LOTO_BUNDLE with a test-time coarser look (default 10 cm/px) ---
LOTO_BUNDLE="$work/seed0" bash "$loto" coarse "$work/co" >"$work/out" 2>&1 || fail "coarse: $(cat "$work/out")"
LOTO_BUNDLE="$work/seed0" bash "$loto" coarse "$work/co12" 12.5 >"$work/out" 2>&1 || fail "coarse 12.5: $(cat "$work/out")"
for k in 1 2 3 4 5 6; do
  e="$work/co/tile-$k/ensemble.yaml"
  m=$(sed -n 's/^  - model: "\(.*\)"$/\1/p' "$e")
  [ "$(realpath "$work/co/tile-$k/$m")" = "$(realpath "$work/seed0/tile-$k")" ] || fail "$e: member $m"
  grep -qx '    coarse_gsd_cm: 10' "$e" || fail "$e: no coarse_gsd_cm: 10"
  grep -qx '    coarse_gsd_cm: 12.5' "$work/co12/tile-$k/ensemble.yaml" || fail "co12/tile-$k: no coarse_gsd_cm: 12.5"
done
echo "ok: coarse wrote six ensembles of one member with the coarser look"
LOTO_BUNDLE="$work/staged" refused "no temperature" coarse "$work/co2"
[ -e "$work/co2" ] && fail "a refused coarse wrote files"
LOTO_BUNDLE="$work/seed0" refused "G must be a GSD > 0" coarse "$work/co3" 0
LOTO_BUNDLE="$work/seed0" refused "G must be a GSD > 0" coarse "$work/co3" ten
[ -e "$work/co3" ] && fail "a refused coarse wrote files"

# --- partial: needs two networks trained here (each's temperature the others' fits), refused
# before anything is built or written with fewer ---
pw="$work/partial-work"
network "$pw/model-5"
LOTO_WORK=$pw LOTO_BASE="$work/seed0" refused "partial: 1 network(s) in $pw/model-<k>; two are needed" partial "$work/part"
LOTO_WORK=$pw LOTO_BASE="$work/staged" refused "no temperature in $work/staged/tile-1/model.yaml" partial "$work/part"
[ -e "$work/part" ] && fail "a refused partial wrote files"
network "$pw/model-3"
LOTO_WORK=$pw LOTO_BASE="$work/seed0" refused "partial: $work/seed1 holds files that partial did not write" partial "$work/seed1"
[ -s "$work/seed1/tile-3/model.onnx" ] || fail "a refused partial touched $work/seed1"

# --- scores: the held-out table from eval_ensemble's JSON (Python's json module only) ---
# held_out K MIOU5 MIOU15 WATER5: tile K's scores as eval_ensemble --json writes them (two GSDs).
held_out() {
  local iou='"iou": [0.5, 0.6, 0.4, 0.3, '
  printf '{"classes": ["building", "land", "road", "vegetation", "water"], "members": {"loto%s": "m"},\n' "$1"
  printf ' "ensembles": {}, "fields": {"dubai-tile-%s": {\n' "$1"
  printf '  "1.0": {"gsd_cm": 5.0, "images": 9, "loto%s": {"miou": %s, %s%s]}},\n' "$1" "$2" "$iou" "$4"
  printf '  "3.0": {"gsd_cm": 15.0, "images": 1, "loto%s": {"miou": %s, %snull]}}}}}\n' "$1" "$3" "$iou"
}
sw="$work/scores"
mkdir -p "$sw"
held_out 2 0.5 0.4 0.7 >"$sw/eval-2.json"
held_out 5 0.3 0.2 0.5 >"$sw/eval-5.json"
PYTHON=/usr/bin/python3 LOTO_WORK=$sw bash "$loto" scores >"$work/out" 2>&1 || fail "scores: $(cat "$work/out")"
grep -qx '| held-out tile | 5 cm/px | 15 cm/px |' "$work/out" || fail "scores: header: $(cat "$work/out")"
grep -qx '| dubai-tile-5 | 0.300 | 0.200 |' "$work/out" || fail "scores: tile 5's row: $(cat "$work/out")"
grep -qx '| mean | 0.400 | 0.300 |' "$work/out" || fail "scores: the mean row: $(cat "$work/out")"
# water: at 5 cm/px on both tiles (0.7, 0.5), at 15 on neither (null: the class absent there)
grep -qx '  water      5 cm/px 0.600 (n=2)' "$work/out" || fail "scores: water's mean: $(cat "$work/out")"
# each tile's class IoU, finest GSD first; water absent at 15 cm/px
grep -qx '| held-out tile | building | land | road | vegetation | water |' "$work/out" || fail "scores: class header: $(cat "$work/out")"
grep -qx '| dubai-tile-5 | 0.500 / 0.500 | 0.600 / 0.600 | 0.400 / 0.400 | 0.300 / 0.300 | 0.500 / - |' "$work/out" ||
  fail "scores: tile 5's classes: $(cat "$work/out")"
# the FILEs given instead of LOTO_WORK's
PYTHON=/usr/bin/python3 bash "$loto" scores "$sw/eval-5.json" >"$work/out" 2>&1 || fail "scores FILE: $(cat "$work/out")"
grep -qx '| mean | 0.300 | 0.200 |' "$work/out" || fail "scores FILE: the mean row: $(cat "$work/out")"
echo "ok: scores printed each tile's row, the mean, the classes' means and each tile's classes"
refused "no $sw/eval-9.json" scores "$sw/eval-9.json"

# --- LOTO_ARCH: the ERFNet and width-1.4 recipes have no deployment network to calibrate; an
# unknown one is refused; a recipe's missing encoder weights are named ---
LOTO_ARCH=erfnet refused "no erfnet one yet" decision
LOTO_ARCH=mobilenetv2-140 refused "no mobilenetv2-140 one yet" decision
LOTO_ARCH=resnet refused "LOTO_ARCH=resnet: mobilenetv2, mobilenetv2-140 or erfnet" stage 2
(cd "$work" && mkdir -p repo/scripts && cp "$1"/scripts/loto.sh "$1"/scripts/loto_recipe.sh repo/scripts/)
OUT="$work" loto="$work/repo/scripts/loto.sh" LOTO_ARCH=mobilenetv2-140 refused "no .device/mnv2_140_enc.pt" train 1

# --- no subcommand: the usage, exit 2 ---
bash "$loto" >"$work/out" 2>"$work/err"
[ $? -eq 2 ] || fail "loto.sh without a subcommand: exit code not 2"
grep -q "^# Usage\|bash scripts/loto.sh ensemble DEST FOLDER FOLDER" "$work/err" || fail "no usage on stderr"
echo "PASS"
