#!/usr/bin/env bash
# Black-box test of adaptseg_cell_study, adaptseg_tools.cell_study_table and proxy_table on the bundled
# WeedMap field with the oracle: every decision input ranks the cells, the oracle's purity ranks
# them as well as the truth allows (rank correlation near 1 for σ), and an input the backend
# cannot give (the ensemble members' split, from a single backend) is unknown (nan), not ranked
# by the order the cells come in, and left out of the table.
#   test_cell_study_cli.sh CELL_STUDY_BINARY EXAMPLES_DIR [PYTHON]
set -uo pipefail
study=$1 examples=$2 python=${3:-}
# The Python tools run from the source tree (python/README.md).
export PYTHONPATH="$examples/../python${PYTHONPATH:+:$PYTHONPATH}"
source "$(dirname "$0")/cli_common.sh"
"$study" --field "$examples/data/weedmap-000:0,0,0.5,1" --top-gsd 3 --gsd 1 --segmenter oracle \
  --csv "$work/cells.csv" >"$work/table.md" 2>"$work/log" || fail "cell study failed: $(tail -3 "$work/log")"
# One row per class of interest (crop, weed), then their mean.
rows=$(grep -c '^| weedmap-rededge-000\[0,0,0.5,1\] |' "$work/table.md")
[ "$rows" = 2 ] || fail "want 2 class rows, got $rows: $(cat "$work/table.md")"
# Column 8 is σ (rho / 10 % / 20 %), the last is split.
awk -F'|' '/^\| weedmap/ { split($9, s, "/"); if (!(s[1] + 0 > 0.8)) bad++; if ($(NF-1) !~ /nan \/ nan \/ nan/) bad++ }
  END {exit bad}' "$work/table.md" || fail "σ's rank correlation not > 0.8, or split not unknown: $(cat "$work/table.md")"
echo "ok: σ ranks the oracle's cells, split is unknown from one backend"
# --csv: every cell of both classes, with the top-level inputs.
[ "$(($(wc -l <"$work/cells.csv") - 1))" -gt 50 ] || fail "cells.csv holds $(($(wc -l <"$work/cells.csv") - 1)) cells"
head -1 "$work/cells.csv" | grep -q '^field,class,region,gsd_cm,field_px,field_share,field_sigma,relabelled,gain,top_sigma,' ||
  fail "cells.csv header: $(head -1 "$work/cells.csv")"
if [ -n "$python" ]; then
  "$python" -m adaptseg_tools.cell_study_table <"$work/table.md" >"$work/summary.md" || fail "cell_study_table.py failed"
  grep -q '^| sigma | +' "$work/summary.md" || fail "no sigma row: $(cat "$work/summary.md")"
  ! grep -q '^| split |' "$work/summary.md" || fail "the unknown input split has a row: $(cat "$work/summary.md")"
  echo "ok: the table lists the inputs the backend gives, and only those"
  # The region's name holds commas: quoted, every row has the header's columns.
  "$python" -c 'import csv, sys; r = list(csv.reader(open(sys.argv[1]))); sys.exit(any(len(x) != len(r[0]) for x in r))' \
    "$work/cells.csv" || fail "cells.csv rows differ from its header in columns: $(sed -n 2p "$work/cells.csv")"
  # proxy_table.py: the oracle's finer look at the field's GSD is exact, so the drop of its
  # expected error over a cell is the top level's error there, which the cell's gain follows.
  "$python" -m adaptseg_tools.proxy_table "oracle=$work/cells.csv" >"$work/proxy.md" || fail "proxy_table.py failed"
  awk -F'|' 'NR == 1 || !/^\| (crop|weed|all classes) \|/ { next } { n++; if (!($8 + 0 > 0.9)) bad++ }
    END { exit !(n == 3 && bad == 0) }' "$work/proxy.md" ||
    fail "want 3 rows with the expected error's drop ranking the gain (rho > 0.9): $(cat "$work/proxy.md")"
  ! grep -q 'split drop' "$work/proxy.md" || fail "the unknown input split has a column: $(cat "$work/proxy.md")"
  echo "ok: proxy_table.py ranks the oracle's gains by the drop of its expected error"
  # slope_transfer.py --field-slopes on two fields (the field's halves): each field's own slope of
  # the oracle's gain on its expected error is positive (its doubt is real error), and each field's
  # mean input is the field-pixel weighted mean of its cells' input, recomputed here.
  "$study" --field "$examples/data/weedmap-000:0,0,0.5,1" --field "$examples/data/weedmap-000:0.5,0,1,1" \
    --top-gsd 3 --gsd 1 --segmenter oracle --csv "$work/halves.csv" >/dev/null 2>"$work/log" ||
    fail "cell study of two fields failed: $(tail -3 "$work/log")"
  "$python" -m adaptseg_tools.slope_transfer --field-slopes "$work/halves.csv" >"$work/slopes.md" ||
    fail "slope_transfer.py failed"
  grep -E '^\| halves \((crop|weed)\) \| expected_error \| 0 -> 1 \| \+0\.[0-9]+ \| \+0\.[0-9]+ \|$' "$work/slopes.md" |
    wc -l | grep -qx 2 || fail "want both classes' own slopes on expected_error positive on both fields: $(cat "$work/slopes.md")"
  "$python" - "$work/halves.csv" "$work/slopes.md" <<'PY' || fail "a field's mean input differs from its cells': $(cat "$work/slopes.md")"
import csv, sys
cells = [r for r in csv.DictReader(open(sys.argv[1])) if r["class"] == "weed"]
fields = sorted({r["field"] for r in cells})
want = [sum(float(r["field_px"]) * float(r["top_expected_error"]) for r in cells if r["field"] == f)
        / sum(float(r["field_px"]) for r in cells if r["field"] == f) for f in fields]
rows = [l for l in open(sys.argv[2]) if l.startswith("| halves (weed) | expected_error | ") and l.count("|") == 5]
got = [float(v) for v in rows[0].strip().strip("|").split("|")[2:]]
sys.exit(not (len(rows) == 1 and all(abs(g - w) < 6e-4 for g, w in zip(got, want)) and len(got) == 2))
PY
  echo "ok: slope_transfer.py prints each field's own slope and mean input"
fi
