# Sourced by the tests that need the emulated autopilot or the node-mavlink cross-check:
#   source tests/mavlink/require_node_mavlink.sh "WHAT FOR"
# exits 77 (CTest's SKIP_RETURN_CODE), saying why, when node or the pinned node-mavlink is not
# installed: (cd tests/mavlink && npm ci), which scripts/test.sh does where npm exists.
if ! command -v node >/dev/null; then
  echo "SKIP: node not installed (needed for $1)"
  exit 77
fi
if [ ! -f "$(dirname "${BASH_SOURCE[0]}")/node_modules/node-mavlink/package.json" ]; then
  echo "SKIP: node-mavlink not installed in tests/mavlink/node_modules; run: (cd tests/mavlink && npm ci)"
  exit 77
fi
