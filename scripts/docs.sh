#!/usr/bin/env bash
# Builds the API reference from the headers' doc comments and the pages of docs/ with doxygen
# (docs/Doxyfile) into build/docs/html/index.html; fails on any doxygen warning.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh docs
exec bash tests/docs/run_doxygen.sh "$PWD" "$PWD/build/docs"
