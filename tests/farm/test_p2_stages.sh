#!/bin/bash
# p2 with 2 bounces as staged shards (stage 0 its direct light, stage b its bounce b, each from the whole
# field's previous stage) merges to the bits of a single-machine bake, for 1 and 2 shards, with a second p2
# entry of 1 bounce (fewer stages) and a direction-dividing method beside them; a stage whose previous stage
# is missing is refused naming that file, before anything is baked.
set -u
H=$1 W=$2
. "$(dirname "$0")/common.sh"
rm -rf "$W" && mkdir -p "$W" && cd "$W" || exit 1
cat >job.json <<'J'
{"version": 1, "name": "p2farm",
 "height": {"procedural": {"kind": "fractal", "size": [61, 47], "seed": 3}},
 "environment": {"sky": {"sun": {"elevation_deg": 35}}},
 "lights": [{"directional": {"direction": [0.3, 0.2, 1.0], "irradiance": 2}}],
 "bounces": 2,
 "bake": [{"method": "p2", "directions": 12,
           "layers": ["indirect", "total", "direct", "indirect_b1", "indirect_b2"]},
          {"method": "hbao", "directions": 10, "radius": 5},
          {"method": "p2", "directions": 8, "bounces": 1, "senders": "texels"}],
 "output": {"dir": "out", "previews": true}}
J
"$H" validate job.json --quiet || fail "test job invalid"
"$H" bake job.json --no-cache --quiet --out whole || fail "bake"
for N in 1 2; do
  for s in 0 1 2; do
    for ((i = 0; i < N; i++)); do
      "$H" bake job.json --no-cache --quiet --out "s$N" --shard "$i/$N" --stage $s || fail "--shard $i/$N --stage $s"
    done
  done
  ls "s$N"/shards/p2farm.p2-0.stage-2.hfshard >/dev/null || fail "no last stage file"
  "$H" merge job.json --no-cache --quiet --out "s$N" || fail "merge of $N shards"
  same_outputs whole "s$N"
  echo "ok: $N shards, 3 stages: the bake's bits"
done
# Stage 2 without stage 1: refused, naming stage 1's file.
rm -rf s2/shards/p2farm.p2-0.stage-[12].hfshard
err=$("$H" bake job.json --no-cache --quiet --out s2 --shard 0/2 --stage 2 2>&1)
rc=$?
[ $rc = 2 ] || fail "stage 2 without stage 1: exit $rc, expected 2 ($err)"
echo "$err" | grep -q "p2farm.p2-0.stage-1.hfshard.*missing" || fail "the error does not name stage 1: $err"
[ ! -e s2/shards/p2farm.p2-0.stage-2.hfshard ] || fail "stage 2 written without stage 1"
# The merge without the last stage names it.
err=$("$H" merge job.json --no-cache --quiet --out s2 2>&1)
[ $? = 2 ] && echo "$err" | grep -q "p2farm.p2-0.stage-2.hfshard" || fail "merge without the last stage: $err"
echo "ok: all"
