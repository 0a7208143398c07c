#!/bin/bash
# p2 with 2 bounces as staged shards (stage 0 its direct light, stage b its bounce b, each divided by
# direction blocks across the shards, a bounce's blocks from the whole field's previous stage) merges to the (float) bits
# of a single-machine bake, for 1, 2, 3 and 5 shards (K = 16: 8 blocks of 2 directions, so 3 and 5 shards
# take unequal runs of blocks), with a second p2 entry of 1 bounce (fewer stages, K = 8: blocks of one
# direction, texel senders), a third subdivided on its triangulation (its stages hold the fine field's
# state) and a direction-dividing method beside them. A stage whose previous stage is
# missing is refused naming a missing file, before anything is baked; so is a merge without a block. A lost
# or damaged stage file is made again by following its refusal's advice as printed (the merge then gives the
# bake's bits), and slurm --resume submits the stage that makes it.
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
 "bake": [{"method": "p2", "directions": 16,
           "layers": ["indirect", "total", "direct", "indirect_b1", "indirect_b2"]},
          {"method": "hbao", "directions": 10, "radius": 5},
          {"method": "p2", "directions": 8, "bounces": 1, "senders": "texels"},
          {"method": "p2", "directions": 8, "subdivide": 2, "layers": ["indirect", "indirect_b2"]}],
 "output": {"dir": "out", "previews": true, "pixel_type": "float"}}
J
"$H" validate job.json --quiet || fail "test job invalid"
"$H" bake job.json --no-cache --quiet --out whole || fail "bake"
for N in 1 2 3 5; do
  for s in 0 1 2; do
    for ((i = 0; i < N; i++)); do
      "$H" bake job.json --no-cache --quiet --out "s$N" --shard "$i/$N" --stage $s || fail "--shard $i/$N --stage $s"
    done
  done
  for b in 0 1 2 3 4 5 6 7; do
    for s in 0 2; do
      ls "s$N"/shards/p2farm.p2-0.stage-$s.block-$b.hfshard >/dev/null || fail "no block $b of stage $s"
    done
  done
  ls "s$N"/shards/p2farm.p2-0.stage-0.hfshard >/dev/null || fail "stage 0 not merged into its file by stage 1"
  ls "s$N"/shards/p2farm.p2-0.stage-1.hfshard >/dev/null || fail "stage 1 not merged into its file by stage 2"
  "$H" merge job.json --no-cache --quiet --out "s$N" || fail "merge of $N shards"
  same_outputs whole "s$N"
  echo "ok: $N shards, 3 stages, each by 8 direction blocks: the bake's bits"
done
# A lost or damaged stage file is made again from its blocks by the command the refusal names: the advice,
# followed as printed, ends in the bake's bits, and slurm --resume submits the stage whose tasks make it.
# run_advised N CMD...: runs CMD; while it is refused with "bake stage S again, --stage S with every
# --shard I/N", runs that (each refused the same way followed in turn), then CMD again.
run_advised() {
  local n=$1 err stage i k=0
  shift
  while ! err=$("$@" 2>&1); do
    k=$((k + 1))
    [ $k -le 3 ] || fail "$* still refused after following its advice: $err"
    [ "$(printf '%s\n' "$err" | wc -l)" = 1 ] && printf '%s' "$err" | grep -q '^hfbake: error: .*\.hfshard: ' ||
      fail "$* refused not in one line naming the file: $err"
    stage=$(printf '%s' "$err" | sed -n 's/.*bake stage \([0-9]*\) again, --stage \1 with every --shard I\/N.*/\1/p')
    [ -n "$stage" ] || fail "$* refused without a stage to bake again: $err"
    for ((i = 0; i < n; i++)); do
      run_advised "$n" "$H" bake job.json --no-cache --quiet --out "s$n" --shard "$i/$n" --stage "$stage"
    done
  done
}
head -c 5000 s2/shards/p2farm.p2-0.stage-1.hfshard >cut && mv cut s2/shards/p2farm.p2-0.stage-1.hfshard
run_advised 2 "$H" merge job.json --no-cache --quiet --out s2
same_outputs whole s2
echo "ok: a truncated stage file is made again by the stage the merge names"
# One byte of a layer changed (the middle of the file: layer data; the header is at its end): the checksum
# finds it, and the advice is the same.
f=s2/shards/p2farm.p2-0.stage-1.hfshard
off=$(($(stat -c %s "$f") / 2))
byte=$(od -An -tu1 -j "$off" -N1 "$f" | tr -d ' ')
printf "\\$(printf %03o $((255 - byte)))" | dd of="$f" bs=1 seek="$off" conv=notrunc 2>/dev/null
run_advised 2 "$H" merge job.json --no-cache --quiet --out s2
same_outputs whole s2
echo "ok: a stage file whose layer's checksum fails is made again by the stage the merge names"
rm s3/shards/p2farm.p2-0.stage-[01].hfshard s3/shards/p2farm.p2-2.stage-0.hfshard
run_advised 3 "$H" merge job.json --no-cache --quiet --out s3
same_outputs whole s3
echo "ok: lost stage files are made again, each by the stage its refusal names"
resume() { "$H" slurm job.json --shards 5 --no-cache --quiet --out s5 --resume --dry-run | grep '^sbatch --parsable --array='; }
[ -z "$(resume)" ] || fail "slurm --resume of a complete bake submits tasks: $(resume)"
head -c 5000 s5/shards/p2farm.p2-0.stage-1.hfshard >cut && mv cut s5/shards/p2farm.p2-0.stage-1.hfshard
[ "$(resume)" = "sbatch --parsable --array=0-4 '$PWD/s5/slurm/bake.sbatch' 2" ] ||
  fail "slurm --resume with stage 1's file damaged submits other than stage 2: $(resume)"
echo "ok: slurm --resume submits the stage that makes a damaged stage file again"
# Stage 2 without stage 1 (neither its file nor one of its blocks): refused, naming the missing block.
rm -f s2/shards/p2farm.p2-0.stage-[12].hfshard s2/shards/p2farm.p2-0.stage-[12].block-*.hfshard
rm -f s2/shards/p2farm.p2-0.stage-1.block-3.hfshard
cp s3/shards/p2farm.p2-0.stage-1.block-[0-2].hfshard s2/shards/
err=$("$H" bake job.json --no-cache --quiet --out s2 --shard 0/2 --stage 2 2>&1)
rc=$?
[ $rc = 2 ] || fail "stage 2 without stage 1: exit $rc, expected 2 ($err)"
echo "$err" | grep -q "p2farm.p2-0.stage-1.block-3.hfshard.*missing" || fail "the error does not name block 3 of stage 1: $err"
ls s2/shards/p2farm.p2-0.stage-2.block-*.hfshard >/dev/null 2>&1 && fail "stage 2 written without stage 1"
# The merge without the last stage names its first missing block.
err=$("$H" merge job.json --no-cache --quiet --out s2 2>&1)
[ $? = 2 ] && echo "$err" | grep -q "p2farm.p2-0.stage-2.block-0.hfshard" || fail "merge without the last stage: $err"
# A stage file of another entry of the same shape (stage count, field) in an entry's place: refused naming
# the file, never merged as that entry's state.
mkdir -p two && cd two || fail "mkdir two"
cat >job.json <<'J'
{"version": 1, "name": "two",
 "height": {"procedural": {"kind": "fractal", "size": [33, 29], "seed": 4}},
 "bounces": 1,
 "bake": [{"method": "p2", "directions": 8}, {"method": "p2", "directions": 4}],
 "output": {"dir": "out", "pixel_type": "float"}}
J
for s in 0 1; do "$H" bake job.json --no-cache --quiet --shard 0/1 --stage $s || fail "two: --stage $s"; done
"$H" merge job.json --no-cache --quiet || fail "two: merge"
# A block of stage 0 at a stage 1 block's name (the same block of the same entry): refused naming the file.
cp out/shards/two.p2-0.stage-1.block-0.hfshard keep
cp out/shards/two.p2-0.stage-0.block-0.hfshard out/shards/two.p2-0.stage-1.block-0.hfshard
err=$("$H" merge job.json --no-cache --quiet 2>&1)
rc=$?
[ $rc = 2 ] || fail "a stage 0 block as stage 1's: merge exit $rc, expected 2 ($err)"
echo "$err" | grep -q "two.p2-0.stage-1.block-0.hfshard: direction block 0 of stage 1 of p2-0 holds another piece (stage-block 0 of stage 0 of bake entry 0)" ||
  fail "a stage 0 block as stage 1's: $err"
mv keep out/shards/two.p2-0.stage-1.block-0.hfshard
cp out/shards/two.p2-1.stage-0.hfshard out/shards/two.p2-0.stage-0.hfshard
err=$("$H" merge job.json --no-cache --quiet 2>&1)
rc=$?
[ $rc = 2 ] || fail "another entry's stage file: merge exit $rc, expected 2 ($err)"
echo "$err" | grep -q "two.p2-0.stage-0.hfshard: stage 0 of p2-0 holds another piece (stage 0 of bake entry 1)" ||
  fail "another entry's stage file: $err"
cd .. || exit 1
echo "ok: a stage file of another entry is refused"
echo "ok: all"
