#!/usr/bin/env bash
# What each package set of scripts/deps.sh brings onto a bare Debian system: the packages apt
# would install and their download size, simulated (apt-get -s, nothing installed) against a
# dpkg status that holds only this machine's Priority: required and Essential packages, apt, and
# what they depend on (about what a debian:bookworm image holds). Sizes from this machine's apt
# lists; a stand-in for timing apt on a fresh machine, which this one is not.
#   bash scripts/apt_footprint.sh [SET...]   (default: demo plots build test)
set -euo pipefail
cd "$(dirname "$0")/.."
sets=("$@")
[ ${#sets[@]} -eq 0 ] && sets=(demo plots build test)
base=$(mktemp)
trap 'rm -f "$base"' EXIT
/usr/bin/python3 - "$base" <<'PY'
import re, sys
entries = [e for e in open("/var/lib/dpkg/status").read().split("\n\n") if "install ok installed" in e]
by = {re.search(r"^Package: (\S+)", e, re.M).group(1): e for e in entries}
def depends(e):
    out = []
    for field in ("Pre-Depends", "Depends"):
        m = re.search(r"^" + field + r": (.*)$", e, re.M)
        for group in (m.group(1).split(",") if m else []):
            for alt in (a.strip().split()[0].split(":")[0] for a in group.split("|")):
                if alt in by:
                    out.append(alt)
                    break
    return out
keep = {p for p, e in by.items() if re.search(r"^(Priority: required|Essential: yes)$", e, re.M) or p == "apt"}
stack = list(keep)
while stack:
    for d in depends(by[stack.pop()]):
        if d not in keep:
            keep.add(d)
            stack.append(d)
open(sys.argv[1], "w").write("\n\n".join(by[p] for p in sorted(keep)) + "\n\n")
PY
for set in "${sets[@]}"; do
  mapfile -t want < <(bash scripts/deps.sh "$set" --list)
  mapfile -t inst < <(apt-get -s -o Dir::State::status="$base" install --no-install-recommends "${want[@]}" 2>/dev/null |
    awk '/^Inst /{print $2}')
  mb=$(apt-cache show --no-all-versions "${inst[@]}" 2>/dev/null | awk '/^Size:/{s+=$2} END{printf "%.0f", s/1e6}')
  printf '%-6s %4d packages, %4s MB to download\n' "$set" "${#inst[@]}" "$mb"
done
