#!/usr/bin/env bash
# CTest mavlink:node_peer: adaptseg::mavlink against node-mavlink, both ways.
#   tests/mavlink/run_node_peer.sh PEER_BINARY WORK_DIR
# 1. adaptseg writes random frames of every message; node-mavlink decodes them (checksum, header,
#    every field) and encodes the same values: the bytes must be the same.
# 2. node-mavlink writes random frames (signed and MAVLink 1 ones too); adaptseg decodes them as
#    one stream in random chunks, checks every field and encodes them again: the same bytes.
# 3. adaptseg's named constants equal node-mavlink's enums.
# Exit 77 (CTest's SKIP_RETURN_CODE) if node or the pinned node-mavlink is not installed:
#   (cd tests/mavlink && npm ci)     # scripts/test.sh does it where npm exists
set -euo pipefail
peer=$1 work=$2
here=$(cd "$(dirname "$0")" && pwd)
source "$here/require_node_mavlink.sh" "the node-mavlink cross-check"
mkdir -p "$work"
"$peer" write "$work/adaptseg_frames.txt" 200
node "$here/node_peer.mjs" check "$work/adaptseg_frames.txt"
node "$here/node_peer.mjs" write "$work/node_frames.txt" 200
"$peer" check "$work/node_frames.txt"
"$peer" constants "$work/constants.txt"
node "$here/node_peer.mjs" constants "$work/constants.txt"
