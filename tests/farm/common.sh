# Helpers of the farm tests (sourced).
fail() { echo "FAIL: $*" >&2; exit 1; }
# same_outputs A B: every EXR of A pixel-identical in B (idiff -fail 0 -warn 0), every PNG and report.html
# byte-identical, report.json equal but for the seconds.
same_outputs() {
  local a=$1 b=$2 n=0 f
  for f in "$a"/*.exr; do
    [ -f "$b/$(basename "$f")" ] || fail "$b/$(basename "$f") missing"
    idiff -fail 0 -warn 0 "$f" "$b/$(basename "$f")" >/dev/null || fail "$b/$(basename "$f") differs from $f"
    n=$((n + 1))
  done
  for f in "$a"/*.png; do
    [ -e "$f" ] || continue
    cmp -s "$f" "$b/$(basename "$f")" || fail "$b/$(basename "$f") differs from $f"
  done
  if [ -f "$a/report.json" ]; then
    python3 - "$a/report.json" "$b/report.json" <<'PY' || fail "$b/report.json differs from $a/report.json"
import json, sys
def strip(x):
    if isinstance(x, dict): return {k: strip(v) for k, v in x.items() if "seconds" not in k}
    if isinstance(x, list): return [strip(v) for v in x]
    return x
a, b = (strip(json.load(open(f))) for f in sys.argv[1:3])
sys.exit(0 if a == b else 1)
PY
  fi
  [ "$n" -gt 0 ] || fail "no EXR in $a"
}
# reseal FILE: a shard file whose header was edited in place gets its header checksum line again (the
# writer's FNV-1a of the header's line: farm/shard_file.hpp), so the edit is read as the header's claim.
reseal() {
  python3 - "$1" <<'PY' || fail "reseal $1"
import sys
p = sys.argv[1]
b = bytearray(open(p, "rb").read())
at = int.from_bytes(b[-8:], "little")
body = b[at:-24]
line = body[: body.rindex(b"\n", 0, len(body) - 1) + 1]
h = 0xcbf29ce484222325
for c in line:
    h = ((h ^ c) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
open(p, "wb").write(b[:at] + line + b"%016x\n" % h + b[-24:])
PY
}
