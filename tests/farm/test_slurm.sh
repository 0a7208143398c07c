#!/bin/bash
# The farm through a real Slurm: a throw-away one-node cluster (slurm_cluster.sh) in the build tree, stopped
# by the PIDs it started whatever happens (trap). Cases:
#   array_merge     a suite of 6 jobs (p1, hbao, lsao, farfield, hsao, vo, nlp, references) x 2 shards as one
#                   array of 12 tasks + merge (hfbake slurm --wait): bit-identical to hfbake bake of the suite
#   big_job         one 256^2 job with p1, hbao and a reference as 4 shards + merge: bit-identical (the 2048^2
#                   job of the same kind is measured by farm-bench, not tested: see docs/cluster.md)
#   p2_stages       p2 with 2 bounces, K = 16, as 3 staged shards (3 stage arrays chained by afterok, each
#                   stage's 8 direction blocks across the 3 tasks, then the merge): bit-identical to hfbake bake
#   deleted_shard   after hfbake slurm, a deleted shard makes the merge job fail naming it
#   scancel_resume  a task cancelled (scancel) is resubmitted by hfbake slurm --resume: the same bits
#   failed_task     the height file removed while the tasks wait to begin: every task fails, Slurm cancels the
#                   merge, and hfbake slurm --wait exits 2 naming the shards no task wrote
#   tiles           a 150 x 97 georeferenced raster (an ASCII grid) baked in tiles of 40 (relief, hbao) as 3
#                   tile tasks + merge --tiles (hfbake slurm --tiles --wait): the COGs of bake --tiles, byte
#                   for byte
#   shared_cache    two bakes of one reference sharing a cache folder, as concurrent Slurm jobs: both
#                   succeed and leave one valid entry (a third bake reads it: a hit, the same bits)
set -u
CASE=$1 H=$2 W=$3
# The farm's tasks take glibc's SSE2 math (hfbake slurm's scripts set this tunable; docs/cluster.md): the
# single bakes they are compared with take it too.
export GLIBC_TUNABLES="glibc.cpu.hwcaps=-FMA,-FMA4"
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/common.sh"
# A failure says what Slurm saw: the queue, the daemons' log tails and the task logs.
fail() {
  echo "FAIL: $*" >&2
  {
    echo "--- squeue"
    squeue -a -o "%i %j %T %r %M" 2>&1
    for f in "$W"/cluster/log/*.log $(find "$W" -path '*/slurm/logs/*' -type f 2>/dev/null); do
      [ -f "$f" ] && echo "--- $f" && tail -n 25 "$f"
    done
  } >&2
  exit 1
}
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
  # Four more jobs: the other direction-dividing methods, vo and nlp (whole), one without a reference.
  obsc() {  # obsc NAME SEED BAKE REFERENCE
    cat >"$1.json" <<J
{"version": 1, "name": "$1",
 "height": {"procedural": {"kind": "fractal", "size": [53, 41], "seed": $2}},
 "environment": {"uniform": [1, 1, 1]},
 "bake": [$3]$4,
 "output": {"dir": "out-$1"}}
J
  }
  obsc c 3 '{"method": "lsao", "directions": 12, "radius": 5, "layers": ["obscurance", "bent_normal"]}' ', "reference": {"samples": 8}'
  obsc d 4 '{"method": "farfield", "directions": 10, "radius": 8}, {"method": "vo", "radius": 4}' ''
  obsc e 5 '{"method": "hsao", "directions": 9, "radius": 4, "layers": ["obscurance", "bent_normal"]}' ''
  obsc f 6 '{"method": "nlp"}, {"method": "hbao", "directions": 12, "radius": 4}' ', "reference": {"samples": 8}'
  echo '{"version": 1, "suite": "nightly", "jobs": ["a.json", "b.json", "c.json", "d.json", "e.json", "f.json"]}' >suite.json
  "$H" bake suite.json --no-cache --quiet --out whole || fail "bake of the suite"
  "$H" slurm suite.json --shards 2 --out farm --no-cache --quiet --wait || fail "hfbake slurm --wait exit $?"
  grep -q -- "--array=0-11" farm/nightly/slurm/bake.sbatch || fail "not one array of 12 tasks"
  grep -q -- "--requeue" farm/nightly/slurm/bake.sbatch || fail "no --requeue"
  for j in a b c d e f; do same_outputs whole/nightly/$j farm/nightly/$j; done
  for f in suite.json index.html junit.xml; do [ -f farm/nightly/$f ] || fail "no suite $f"; done
  ;;
big_job)
  cat >big.json <<J
{"version": 1, "name": "big",
 "height": {"procedural": {"kind": "fractal", "size": [256, 256], "seed": 7}},
 "environment": {"uniform": [1, 1, 1]},
 "lights": [{"directional": {"direction": [0.3, 0.2, 1.0], "irradiance": 2}}],
 "bake": [{"method": "p1", "directions": 16}, {"method": "hbao", "directions": 16, "radius": 6}],
 "reference": {"samples": 8},
 "output": {"dir": "out-big"}}
J
  "$H" bake big.json --no-cache --quiet --out whole || fail "bake"
  "$H" slurm big.json --shards 4 --out farm --no-cache --quiet --wait || fail "hfbake slurm --wait exit $?"
  [ "$(ls farm/shards/big.shard-*-of-4.hfshard | wc -l)" = 4 ] || fail "not 4 shards: $(ls farm/shards)"
  same_outputs whole farm
  ;;
p2_stages)
  cat >p2.json <<J
{"version": 1, "name": "p2",
 "height": {"procedural": {"kind": "fractal", "size": [61, 47], "seed": 3}},
 "environment": {"sky": {"sun": {"elevation_deg": 35}}},
 "bounces": 2,
 "bake": [{"method": "p2", "directions": 16, "layers": ["indirect", "total", "direct", "indirect_b1", "indirect_b2"]},
          {"method": "hbao", "directions": 10, "radius": 5}],
 "reference": {"samples": 8},
 "output": {"dir": "out-p2"}}
J
  "$H" bake p2.json --no-cache --quiet --out whole || fail "bake"
  "$H" slurm p2.json --shards 3 --out farm --no-cache --wait 2>slurm.err || fail "hfbake slurm --wait exit $? ($(cat slurm.err))"
  cat slurm.err
  grep -q "3 tasks of stage 0 as array job" slurm.err || fail "stage 0 was not submitted as 3 tasks"
  for st in 1 2; do grep -q "3 tasks of stage $st as array job" slurm.err || fail "stage $st was not divided over the 3 tasks"; done
  for st in 0 1; do [ -f farm/shards/p2.p2.stage-$st.hfshard ] || fail "no stage $st file: $(ls farm/shards)"; done
  for st in 0 1 2; do
    for b in 0 1 2 3 4 5 6 7; do
      [ -f farm/shards/p2.p2.stage-$st.block-$b.hfshard ] || fail "no block $b of stage $st: $(ls farm/shards)"
    done
  done
  same_outputs whole farm
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
  # 4096 reference samples: a shard task runs for seconds (a whole bake, 2 threads: about 4 s), so task 1 is
  # still running when it is cancelled.
  job a 1 4096
  "$H" bake a.json --no-cache --quiet --out whole || fail "bake"
  "$H" slurm a.json --shards 4 --out farm --no-cache --quiet || fail "hfbake slurm"
  array=$(squeue -h -o %F -n hfbake-a | head -n1)
  [ -n "$array" ] || fail "no array job queued"
  running=
  for _ in $(seq 600); do
    [ -n "$(squeue -h -t R -j "${array}_1" 2>/dev/null)" ] && running=1 && break
    sleep 0.05
  done
  [ -n "$running" ] || fail "task 1 never ran"
  # Slurm lists a task as running while its batch step is still being launched, and a cancel that arrives
  # then can miss the step's processes: cancelled once its hfbake runs.
  started=
  for _ in $(seq 600); do
    pgrep -f -- "--shard 1/4 .*--out farm" >/dev/null && started=1 && break
    sleep 0.05
  done
  [ -n "$started" ] || fail "task 1's hfbake never started"
  scancel "${array}_1" || fail "scancel"
  wait_gone "$array"
  [ -f farm/shards/a.shard-1-of-4.hfshard ] && fail "the cancelled task still wrote its shard"
  ls farm/shards | grep -q tmp && echo "(a cancelled task left its temporary file: never read as a shard)"
  "$H" slurm a.json --shards 4 --out farm --no-cache --resume --wait || fail "hfbake slurm --resume --wait exit $?"
  grep -q -- "--array" farm/slurm/bake.sbatch || fail "no array script"
  same_outputs whole farm
  ;;
failed_task)
  awk 'BEGIN { print "ncols 40\nnrows 30\nxllcorner 0\nyllcorner 0\ncellsize 1";
               for (j = 0; j < 30; j++) { r = ""; for (i = 0; i < 40; i++) r = r sprintf(" %.3f", sin(0.3 * i) * cos(0.2 * j)); print r } }' >dem.asc
  cat >f.json <<J
{"version": 1, "name": "f", "height": {"image": "dem.asc"},
 "bake": [{"method": "hbao", "directions": 8, "radius": 3}], "output": {"dir": "out-f"}}
J
  "$H" slurm f.json --shards 2 --out farm --no-cache --quiet --wait --sbatch-arg=--begin=now+5 2>slurm.err &
  pid=$!
  for _ in $(seq 300); do [ -n "$(squeue -h -n hfbake-f 2>/dev/null)" ] && break; sleep 0.1; done
  [ -n "$(squeue -h -n hfbake-f)" ] || fail "no array job queued"
  rm dem.asc
  wait $pid
  rc=$?
  cat slurm.err
  [ $rc = 2 ] || fail "hfbake slurm --wait exited $rc with every task failed"
  grep -q "f.shard-0-of-2.hfshard: shard 0/2 is missing" slurm.err || fail "shard 0 not named"
  grep -q "f.shard-1-of-2.hfshard: shard 1/2 is missing" slurm.err || fail "shard 1 not named"
  grep -q "never ran" slurm.err || fail "the merge's fate not said"
  [ -e farm/f.hbao.exr ] && fail "an output was written"
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
tiles)
  awk 'BEGIN { print "ncols 150\nnrows 97\nxllcorner 400000\nyllcorner 100000\ncellsize 0.5";
               for (j = 0; j < 97; j++) { r = ""; for (i = 0; i < 150; i++) r = r sprintf(" %.4f", 3 * sin(0.21 * i) * cos(0.13 * j) + 0.02 * i); print r } }' >dem.asc
  cat >tiles.json <<J
{"version": 1, "name": "tiles", "height": {"image": "dem.asc"},
 "bake": [{"method": "relief", "directions": 8, "search_radius": 4.5, "layers": ["svf", "horizon_deg"]},
          {"method": "hbao", "directions": 8, "radius": 3, "falloff": "smooth"}],
 "output": {"dir": "out-tiles", "geotiff": true}}
J
  "$H" bake tiles.json --tiles --tile-size 40 --quiet --out whole || fail "bake --tiles"
  "$H" slurm tiles.json --tiles --tile-size 40 --shards 3 --out farm --quiet --wait || fail "hfbake slurm --tiles --wait exit $?"
  grep -q -- "--tile-task" farm/slurm/bake.sbatch || fail "the tasks are not tile tasks"
  grep -q -- "merge .* --tiles --tile-size 40" farm/slurm/merge.sbatch || fail "the merge is not merge --tiles"
  n=0
  for f in whole/*.tif; do
    cmp -s "$f" "farm/$(basename "$f")" || fail "farm/$(basename "$f") differs from $f"
    n=$((n + 1))
  done
  [ "$n" = 4 ] || fail "$n COGs, not 4"
  ;;
*) fail "unknown case $CASE" ;;
esac
echo "ok: $CASE"
