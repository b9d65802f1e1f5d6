#!/usr/bin/env bash
# scripts/device_travel.sh in a scratch git repository: size counts the tracked and the
# untracked-not-ignored files and the carried paths, not the ignored ones, and fails over 64 MiB;
# aside takes a folder out of what travels, refuses a second aside and a path outside the
# repository; restore brings every file back as it was and refuses to overwrite one that
# reappeared with other content. Sparse files stand in for large ones. A second or two.
#   test_device_travel.sh SOURCE_DIR
set -uo pipefail
source "$(dirname "$0")/cli_common.sh"
src="$1/scripts/device_travel.sh"
[ -f "$src" ] || fail "no $src"
repo="$work/repo"
mkdir -p "$repo/scripts" "$repo/models/big" "$repo/data" "$repo/carried"
cp "$src" "$repo/scripts/"
cd "$repo" || fail "no $repo"
git init -q . && git config user.email t@t && git config user.name t
echo "/ignored/" >.gitignore
printf 'abc' >data/small.txt                 # 3 bytes, tracked
truncate -s 40M models/big/a.onnx            # tracked
truncate -s 20M models/big/b.pt              # tracked
truncate -s 3M data/untracked.bin            # untracked, not ignored: travels
mkdir ignored && truncate -s 100M ignored/x  # ignored: stays home
truncate -s 2M carried/enc.pt                # ignored? no: carried explicitly below
echo "/carried/" >>.gitignore
git add .gitignore scripts data/small.txt models && git commit -qm init
travel=(bash scripts/device_travel.sh)
sha256sum models/big/a.onnx models/big/b.pt >"$work/before"

# 40 + 20 + 3 MiB and the small files travel; 65 MiB with the 2 MiB carried: over.
"${travel[@]}" size >"$work/out" 2>&1 || fail "size without carry failed (63 MiB and some bytes): $(cat "$work/out")"
grep -q "^travels: [0-9]* bytes (63.0 MiB)" "$work/out" || fail "size: $(cat "$work/out")"
"${travel[@]}" size carried >"$work/out" 2>&1 && fail "size with 2 MiB carried passed (65 MiB): $(cat "$work/out")"
grep -q "over the limit" "$work/out" || fail "size over: $(cat "$work/out")"
grep -q "carry carried: 2097152 bytes" "$work/out" || fail "carried bytes: $(cat "$work/out")"
echo "ok: size counts tracked, untracked and carried files, not ignored ones"

"${travel[@]}" aside /etc >"$work/out" 2>&1 && fail "aside /etc succeeded"
"${travel[@]}" aside models/../.. >"$work/out" 2>&1 && fail "aside models/../.. succeeded"
"${travel[@]}" aside nothing-here >"$work/out" 2>&1 && fail "aside of a missing path succeeded"
[ ! -e .device-aside/.paths ] || fail "a refused aside left a record"
"${travel[@]}" aside models/big >"$work/out" 2>&1 || fail "aside: $(cat "$work/out")"
[ ! -e models/big ] || fail "models/big still in the work tree"
[ -z "$(git status --porcelain --ignored=no -- .device-aside)" ] || fail ".device-aside is not excluded"
"${travel[@]}" size carried >"$work/out" 2>&1 || fail "size after aside: $(cat "$work/out")"
grep -q "(5.0 MiB)" "$work/out" || fail "size after aside: $(cat "$work/out")"
"${travel[@]}" aside data >"$work/out" 2>&1 && fail "a second aside succeeded"
grep -q "restore first" "$work/out" || fail "second aside: $(cat "$work/out")"
echo "ok: aside takes the folder out of what travels and refuses a second one"

# A file that reappeared with other content is not overwritten.
mkdir -p models/big && echo other >models/big/a.onnx
"${travel[@]}" restore >"$work/out" 2>&1 && fail "restore overwrote a changed file"
grep -q "models/big/a.onnx exists and differs" "$work/out" || fail "restore clash: $(cat "$work/out")"
rm -r models/big
"${travel[@]}" restore >"$work/out" 2>&1 || fail "restore: $(cat "$work/out")"
grep -q "restored 2 files" "$work/out" || fail "restore: $(cat "$work/out")"
sha256sum models/big/a.onnx models/big/b.pt >"$work/after"
cmp -s "$work/before" "$work/after" || fail "restored files differ"
[ -z "$(git status --porcelain -- models)" ] || fail "git sees changes after restore: $(git status --porcelain)"
[ ! -e .device-aside ] || fail ".device-aside left behind"
"${travel[@]}" restore >"$work/out" 2>&1 || fail "a restore with nothing aside failed"
echo "ok: restore brings every file back and refuses to overwrite a changed one"
