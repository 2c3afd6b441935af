#!/usr/bin/env bash
# `./lab sweep PLAN --shards N --jobs J` (no Slurm; ctest -L lab): the shards run here, J at a time,
# and merge into the data set of one unsharded run, row for row (timing columns aside), with a merge
# record saying how they ran. A shard that did not run leaves the merge without a data set, naming
# that shard and printing the command running just it, which completes the data set. Bad input:
# one `lab: error:` line, exit 2. (A shard killed mid-way: slurm_sweep_test.sh.)
#
# Usage: local_sweep_test.sh RAYLAB_TOOL REPO_DIR WORK_DIR
set -euo pipefail
source "$(dirname "$0")/common.sh"
fail() {
  echo "lab-sweep-test: FAILED: $*" >&2
  exit 1
}
rm -rf "$work"
mkdir -p "$work"
cd "$work"

# 2 scenes x 3 structures x 2 ray sets = 12 cases, well under a second each.
cat >plan.json <<'EOF'
{"scenes": ["sphere:n=300", "walls:n=8,angle=20"], "accels": ["bvh", "kdtree", "grid"],
 "rays": ["primary:1024", "shadow:512"]}
EOF
"$tool" sweep --plan plan.json --out whole.csv 2>/dev/null

err=$("${lab[@]}" sweep plan.json --shards 3 --jobs 0 --out bad.csv 2>&1) && fail "--jobs 0 accepted"
[[ "$err" == "lab: error: "* && "$err" != *$'\n'* ]] || fail "--jobs 0: $err"
err=$("${lab[@]}" sweep plan.json --shards 13 --out bad.csv 2>&1) && fail "more shards than cases accepted"
[[ "$err" == "lab: error: sweep: --shards 13: plan plan.json has only 12 cases" ]] || fail "--shards 13: $err"
[ ! -e bad.csv.shards ] || fail "bad input left bad.csv.shards"

# All shards, two at a time.
"${lab[@]}" sweep plan.json --shards 3 --jobs 2 --out all.csv >all.out 2>&1 || fail "$(cat all.out)"
same_rows whole.csv all.csv || fail "the merged shards differ from the unsharded run"
grep -q '"how": ".* local: shards 0-2 of 3, 2 at a time, on ' all.csv.sweep.json || fail "no record of how it ran"

# Shards 0 and 2 only (as if shard 1 had failed): the merge names shard 1 and writes nothing.
status=0
"${lab[@]}" sweep plan.json --shards 3 --only 0,2 --out partial.csv >partial.out 2>&1 || status=$?
[ "$status" = 2 ] || fail "a missing shard gave exit status $status: $(cat partial.out)"
[ ! -e partial.csv ] || fail "an incomplete merge wrote partial.csv"
grep -q 'in shard 1 of 3' partial.out || fail "the merge does not name shard 1: $(cat partial.out)"
rerun=$(sed -n 's/^  \(.* --only [0-9,]*\)$/\1/p' partial.out)
[[ "$rerun" == *" --only 1" ]] || fail "no command rerunning shard 1: $(cat partial.out)"
bash -c "$rerun" >rerun.out 2>&1 || fail "the printed command failed: $(cat rerun.out)"
same_rows whole.csv partial.csv || fail "the completed data set differs from the unsharded run"
echo "lab-sweep-test: passed"
