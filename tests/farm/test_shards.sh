#!/bin/bash
# Shards + merge give the bits of a single-machine bake, for shard counts below, at and above the direction
# blocks, and with shards on SSE2, AVX2 and this machine's kernels and math functions; missing, truncated and
# foreign shards are refused naming the shard (exit 2); a re-run shard is kept.
set -u
H=$1 W=$2
. "$(dirname "$0")/common.sh"
rm -rf "$W" && mkdir -p "$W" && cd "$W" || exit 1
# p1 with every layer, a non-uniform environment (the built-in sky) and two suns, and again with a far
# field (its certified bound the same in the merge's EXR as in the bake's); hbao with bent
# normals; lsao, farfield and hsao with bent normals and more directions than blocks (block partial sums);
# vo (runs whole in one shard); a reference of every layer the methods are scored against.
cat >job.json <<'J'
{"version": 1, "name": "farm",
 "height": {"procedural": {"kind": "fractal", "size": [67, 53], "seed": 5}},
 "environment": {"sky": {"sun": {"elevation_deg": 40}}},
 "lights": [{"directional": {"direction": [0.3, 0.2, 1.0], "irradiance": 2}},
            {"directional": {"direction": [-0.5, 0.1, 0.6], "irradiance": [1, 0.5, 0.2]}}],
 "bake": [{"method": "p1", "directions": 12,
           "layers": ["ao", "vsky", "direct", "horizon", "horizon_distance", "bent_normal"]},
          {"method": "p1", "directions": 12, "far_field": {"beyond": 6, "cell": 4}, "layers": ["ao", "horizon"]},
          {"method": "hbao", "directions": 10, "radius": 5, "falloff": "smooth"},
          {"method": "lsao", "directions": 12, "radius": 5, "layers": ["obscurance", "bent_normal"]},
          {"method": "farfield", "directions": 10, "radius": 8, "layers": ["obscurance", "bent_normal"]},
          {"method": "hsao", "directions": 9, "radius": 4, "layers": ["obscurance", "bent_normal"]},
          {"method": "vo", "radius": 4}],
 "reference": {"samples": 16},
 "output": {"dir": "out", "previews": true}}
J
"$H" validate job.json --quiet || fail "test job invalid"
"$H" bake job.json --no-cache --quiet --out whole || fail "bake"
for N in 1 3 11; do
  for ((i = 0; i < N; i++)); do
    "$H" bake job.json --no-cache --quiet --out "s$N" --shard "$i/$N" || fail "bake --shard $i/$N"
  done
  "$H" merge job.json --no-cache --quiet --out "s$N" || fail "merge of $N shards"
  same_outputs whole "s$N"
  bound() { oiiotool --info -v "$1" | grep "hfbake:p1:far_field_bound"; }
  [ -n "$(bound whole/farm.p1-1.exr)" ] || fail "whole/farm.p1-1.exr has no far-field bound"
  [ "$(bound whole/farm.p1-1.exr)" = "$(bound "s$N/farm.p1-1.exr")" ] || fail "s$N's far-field bound differs"
  echo "ok: $N shards merge to the bake's bits"
done

# A farm of mixed machines: glibc picks its math functions' variants by CPU, and its double ones (sin, exp,
# pow, atan2, ...) give other last bits with FMA than without in 1 input in 1400 to 3700, so a farm's tasks
# take the SSE2 ones everywhere (GLIBC_TUNABLES, as hfbake slurm's scripts set it; docs/cluster.md); p1's
# lane search runs each machine's widest kernel (AVX-512F, AVX2 or SSE2). One shard baked as on an SSE2-only
# machine (glibc's variants forced by its tunable, the lane search's by HFBAKE_ISA), one with the lane
# search on AVX2, one with this machine's best: the merge must be the bits of a bake under the same tunable.
SSE2_MATH="glibc.cpu.hwcaps=-AVX2_Usable,-FMA_Usable,-AVX512F_Usable,-AVX2,-FMA,-AVX512F"
FARM_MATH="glibc.cpu.hwcaps=-FMA,-FMA4"
GLIBC_TUNABLES=$FARM_MATH "$H" bake job.json --no-cache --quiet --out wholem || fail "bake with the farm's math"
GLIBC_TUNABLES=$SSE2_MATH HFBAKE_ISA=sse2 "$H" bake job.json --no-cache --quiet --out mixed --shard 0/3 ||
  fail "SSE2 shard"
GLIBC_TUNABLES=$FARM_MATH HFBAKE_ISA=avx2 "$H" bake job.json --no-cache --quiet --out mixed --shard 1/3 ||
  fail "AVX2 shard"
GLIBC_TUNABLES=$FARM_MATH "$H" bake job.json --no-cache --quiet --out mixed --shard 2/3 || fail "bake --shard 2/3"
GLIBC_TUNABLES=$FARM_MATH "$H" merge job.json --no-cache --quiet --out mixed || fail "merge of mixed-machine shards"
same_outputs wholem mixed
echo "ok: shards baked with SSE2, AVX2 and this machine's kernels and math merge to the bake's bits"
# Any other HFBAKE_ISA is refused before anything runs, naming the variable.
msg=$(HFBAKE_ISA=neon "$H" validate job.json 2>&1)
[ $? -eq 2 ] && echo "$msg" | grep -q "HFBAKE_ISA=neon" || fail "HFBAKE_ISA=neon: $msg"

# A re-run of a complete shard keeps it (idempotent), and the merge is the same again.
before=$(stat -c %Y%N s3/shards/farm.shard-1-of-3.hfshard)
sleep 1
"$H" bake job.json --no-cache --quiet --out s3 --shard 1/3 || fail "re-run shard"
[ "$(stat -c %Y%N s3/shards/farm.shard-1-of-3.hfshard)" = "$before" ] || fail "a complete shard was baked again"

# Names like a shard's that are not one of this count (a count past int's range, not digits) are not
# shards: the merge reads the three and gives the bake's bits.
touch s3/shards/farm.shard-1-of-99999999999.hfshard s3/shards/farm.shard-x-of-3.hfshard \
  s3/shards/farm.shard--1-of-3.hfshard
"$H" merge job.json --no-cache --quiet --out s3 || fail "merge beside names that are not shards"
same_outputs whole s3
rm s3/shards/farm.shard-1-of-99999999999.hfshard s3/shards/farm.shard-x-of-3.hfshard \
  s3/shards/farm.shard--1-of-3.hfshard
echo "ok: names that are not shards are passed over"

expect_refusal() {  # expect_refusal WHAT PATTERN: the merge of s3 exits 2 naming the shard
  local err
  err=$("$H" merge job.json --no-cache --quiet --out s3 2>&1 >/dev/null)
  local rc=$?
  [ $rc = 2 ] || fail "$1: merge exit $rc, expected 2"
  [ "$(echo "$err" | grep -c 'hfbake: error:')" = 1 ] || fail "$1: not one error line: $err"
  echo "$err" | grep -q "farm.shard-1-of-3.hfshard" || fail "$1: the error does not name the shard: $err"
  echo "$err" | grep -q "$2" || fail "$1: the error does not say '$2': $err"
  echo "ok: $1 refused: $err"
}
cp s3/shards/farm.shard-1-of-3.hfshard keep
rm s3/shards/farm.shard-1-of-3.hfshard
expect_refusal "a deleted shard" "missing"
head -c $(($(stat -c %s keep) - 100)) keep >s3/shards/farm.shard-1-of-3.hfshard
expect_refusal "a truncated shard" "truncated"
cp keep s3/shards/farm.shard-1-of-3.hfshard
printf '\x01' | dd of=s3/shards/farm.shard-1-of-3.hfshard bs=1 seek=100 conv=notrunc 2>/dev/null
expect_refusal "a damaged shard" "damaged"
sed 's/"seed": 5/"seed": 6/' job.json >other.json
mkdir -p other && cp other.json other/job.json
"$H" bake other/job.json --no-cache --quiet --out o --shard 1/3 || fail "other shard"
cp o/shards/farm.shard-1-of-3.hfshard s3/shards/
expect_refusal "a shard of another job" "another job"
# The version a shard records carries the binary's GNU build id (readelf's), so a rebuilt hfbake's shards
# are refused; a shard whose header names another build (same length, edited in place) is refused.
build=$(readelf -n "$H" | sed -n 's/.*Build ID: \([0-9a-f]*\).*/\1/p')
[ -n "$build" ] || fail "no build id in $H"
cp keep s3/shards/farm.shard-1-of-3.hfshard
grep -aq "+build.${build:0:16}" s3/shards/farm.shard-1-of-3.hfshard || fail "the shard's version lacks the build id ${build:0:16}"
sed -i "s/+build.${build:0:16}/+build.0000000000000000/" s3/shards/farm.shard-1-of-3.hfshard
expect_refusal "a shard whose header was edited" "header checksum"
reseal s3/shards/farm.shard-1-of-3.hfshard
expect_refusal "a shard of another build" "0000000000000000"
# A layer's channel named otherwise in the header, edited in place: damage, not a layer of other channels.
cp keep s3/shards/farm.shard-1-of-3.hfshard
sed -i 's/"channels":\["Y"\]/"channels":["Z"]/' s3/shards/farm.shard-1-of-3.hfshard
cmp -s keep s3/shards/farm.shard-1-of-3.hfshard && fail "no channel Y in the shard's header"
expect_refusal "a shard whose header names other channels" "header checksum"
# Temporary shard files of writers that no longer run are removed by the next bake of a shard there;
# those of a live process (this shell: its pid and start time) and of another host are kept.
cp keep s3/shards/farm.shard-1-of-3.hfshard
start=$(awk '{print $22}' /proc/$$/stat)
host=$(hostname)
touch "s3/shards/farm.shard-0-of-3.hfshard.tmp-999999999+1@$host" "s3/shards/farm.shard-0-of-3.hfshard.tmp-$$+$start@$host" \
  "s3/shards/farm.shard-0-of-3.hfshard.tmp-999999999+1@elsewhere" "s3/shards/farm.shard-2-of-3.hfshard.tmp-999999998@$host"
msg=$("$H" bake job.json --no-cache --out s3 --shard 1/3 2>&1) || fail "re-run shard: $msg"
[ ! -e "s3/shards/farm.shard-0-of-3.hfshard.tmp-999999999+1@$host" ] || fail "a dead writer's file was kept"
[ ! -e "s3/shards/farm.shard-2-of-3.hfshard.tmp-999999998@$host" ] || fail "a dead writer's file (no start time) was kept"
echo "$msg" | grep -q "removed .*tmp-999999999+1@$host" || fail "the removal was not told: $msg"
[ -e "s3/shards/farm.shard-0-of-3.hfshard.tmp-$$+$start@$host" ] || fail "a live writer's file was removed"
[ -e "s3/shards/farm.shard-0-of-3.hfshard.tmp-999999999+1@elsewhere" ] || fail "another host's file was removed"
rm -f s3/shards/*.tmp-*
echo "ok: stale temporary shard files removed, live and foreign ones kept"
# Nothing was written by the refused merges: the outputs are those of the first merge.
cp keep s3/shards/farm.shard-1-of-3.hfshard
same_outputs whole s3
"$H" bake job.json --quiet --shard 3/3 >/dev/null 2>&1 && fail "--shard 3/3 accepted"
echo "ok: all"
