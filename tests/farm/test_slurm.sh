#!/bin/bash
# The farm through a real Slurm: a throw-away one-node cluster (slurm_cluster.sh) in the build tree, stopped
# by the PIDs it started whatever happens (trap). Cases:
#   array_merge     a suite of 2 jobs x 3 shards as one array + merge (hfbake slurm --wait): bit-identical to
#                   hfbake bake of the same suite
#   deleted_shard   after hfbake slurm, a deleted shard makes the merge job fail naming it
#   scancel_resume  a task cancelled (scancel) is resubmitted by hfbake slurm --resume: the same bits
#   shared_cache    two bakes of one reference sharing a cache folder, as concurrent Slurm jobs: both
#                   succeed and leave one valid entry (a third bake reads it: a hit, the same bits)
set -u
CASE=$1 H=$2 W=$3
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/common.sh"
rm -rf "$W" && mkdir -p "$W" && cd "$W" || exit 1
trap '"$HERE/slurm_cluster.sh" stop "$W/cluster"' EXIT
eval "$("$HERE/slurm_cluster.sh" start "$W/cluster")" || fail "the Slurm test cluster did not start (see above)"
[ -n "${SLURM_CONF:-}" ] || fail "no SLURM_CONF from slurm_cluster.sh"

job() {  # job NAME SEED SAMPLES: a small p1 + hbao + reference job
  cat >"$1.json" <<J
{"version": 1, "name": "$1",
 "height": {"procedural": {"kind": "fractal", "size": [61, 47], "seed": $2}},
 "environment": {"uniform": [1, 1, 1]},
 "lights": [{"directional": {"direction": [0.3, 0.2, 1.0], "irradiance": 2}}],
 "bake": [{"method": "p1", "directions": 8}, {"method": "hbao", "directions": 8, "radius": 4}],
 "reference": {"samples": $3},
 "output": {"dir": "out-$1", "previews": true}}
J
}
wait_gone() {  # wait_gone JOBID: until Slurm no longer lists it as pending or running
  for _ in $(seq 600); do
    [ -z "$(squeue -h -j "$1" 2>/dev/null)" ] && return 0
    sleep 0.5
  done
  fail "Slurm job $1 still queued after 300 s"
}

case "$CASE" in
array_merge)
  job a 1 16 && job b 2 16
  echo '{"version": 1, "suite": "nightly", "jobs": ["a.json", "b.json"]}' >suite.json
  "$H" bake suite.json --no-cache --quiet --out whole || fail "bake of the suite"
  "$H" slurm suite.json --shards 3 --out farm --no-cache --quiet --wait || fail "hfbake slurm --wait exit $?"
  grep -q -- "--array=0-5" farm/nightly/slurm/bake.sbatch || fail "not one array of 6 tasks"
  grep -q -- "--requeue" farm/nightly/slurm/bake.sbatch || fail "no --requeue"
  same_outputs whole/nightly/a farm/nightly/a
  same_outputs whole/nightly/b farm/nightly/b
  for f in suite.json index.html junit.xml; do [ -f farm/nightly/$f ] || fail "no suite $f"; done
  ;;
deleted_shard)
  job a 1 16
  "$H" slurm a.json --shards 3 --out farm --no-cache --quiet --wait || fail "hfbake slurm --wait"
  rm farm/shards/a.shard-2-of-3.hfshard
  out=$(sbatch --parsable --wait farm/slurm/merge.sbatch 2>&1)
  rc=$?
  [ $rc != 0 ] || fail "the merge job succeeded without shard 2"
  log=$(ls farm/slurm/logs/hfbake-merge-a-"${out%%;*}".out)
  grep -q "a.shard-2-of-3.hfshard: shard 2/3 is missing" "$log" || fail "the merge log does not name the shard: $(cat "$log")"
  echo "ok: $(grep error "$log")"
  ;;
scancel_resume)
  job a 1 256  # slow enough that a task is still running when cancelled
  "$H" bake a.json --no-cache --quiet --out whole || fail "bake"
  "$H" slurm a.json --shards 4 --out farm --no-cache --quiet || fail "hfbake slurm"
  array=$(squeue -h -o %F -n hfbake-a | head -n1)
  [ -n "$array" ] || fail "no array job queued"
  for _ in $(seq 200); do [ -n "$(squeue -h -t R -j "$array" 2>/dev/null)" ] && break; sleep 0.1; done
  scancel "${array}_1" || fail "scancel"
  wait_gone "$array"
  [ -f farm/shards/a.shard-1-of-4.hfshard ] && fail "the cancelled task still wrote its shard"
  ls farm/shards | grep -q tmp && echo "(a cancelled task left its temporary file: never read as a shard)"
  "$H" slurm a.json --shards 4 --out farm --no-cache --resume --wait || fail "hfbake slurm --resume --wait exit $?"
  grep -q -- "--array" farm/slurm/bake.sbatch || fail "no array script"
  same_outputs whole farm
  ;;
shared_cache)
  job a 1 64
  mkdir -p c1 c2 && cp a.json c1/ && cp a.json c2/
  for d in c1 c2; do
    sbatch --parsable -o "$W/$d.log" --chdir "$W/$d" --wrap "'$H' bake a.json --cache '$W/cache' --quiet" >"$d.id" ||
      fail "sbatch"
  done
  wait_gone "$(cat c1.id)" && wait_gone "$(cat c2.id)"
  for d in c1 c2; do
    grep -q "error" "$d.log" && fail "$d: $(cat "$d.log")"
    [ -f "$d/out-a/a.reference.exr" ] || fail "$d did not bake ($(cat "$d.log"))"
  done
  [ "$(ls cache/*.hfref | wc -l)" = 1 ] || fail "not one cache entry: $(ls cache)"
  ls cache | grep -q tmp && fail "a temporary cache file was left: $(ls cache)"
  same_outputs c1/out-a c2/out-a
  "$H" bake a.json --cache "$W/cache" --out c3 --summary c3.json --quiet || fail "third bake"
  grep -q '"cache": "hit"' c3.json || fail "the entry was not valid: $(cat c3.json)"
  same_outputs c1/out-a c3
  ;;
*) fail "unknown case $CASE" ;;
esac
echo "ok: $CASE"
