#!/usr/bin/env bash
# Reproduces docs/results.md and the measurements of the journal it links to (docs/journal/).
#   bash scripts/results.sh [PART] [JOBS]   (default: all, one job per core)
#   bash scripts/results.sh --help          the parts: what each flies, needs and takes
# Installs the plotting dependencies, builds the programs in build/release, then hands over to
# adaptseg_tools.experiments, which flies the part's runs as scripts/results.toml lists them
# (at most JOBS at a time) and prints its tables. The knobs (CONFIG, EXTRA, NETS, ...) are
# environment variables; each part's description names those it reads. Every command a part
# runs, without running it:
#   PYTHONPATH=python /usr/bin/python3 -m adaptseg_tools.experiments --dry-run PART
# Outputs: out/results/<configuration>/<run>/ (adaptseg_evaluate's files), each run's log beside it.
set -euo pipefail
cd "$(dirname "$0")/.."
# The Python tools run from the source tree (python/README.md).
export PYTHONPATH="$PWD/python${PYTHONPATH:+:$PYTHONPATH}"
experiments=(/usr/bin/python3 -m adaptseg_tools.experiments)
case "${1:-}" in -h | --help) exec "${experiments[@]}" --help ;; esac
part=${1:-all}
jobs=${2:-$(nproc 2>/dev/null || echo 2)}
bash scripts/deps.sh plots
# An unknown part, or one whose prerequisites are missing, fails here, before the build.
"${experiments[@]}" --check "$part" "$jobs"
source scripts/configure.sh
configure_for results build/release >/dev/null
cmake --build build/release -j"$jobs" --target adaptseg_evaluate adaptseg_calibrate adaptseg_cell_study
exec "${experiments[@]}" "$part" "$jobs"
