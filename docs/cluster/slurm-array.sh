#!/usr/bin/env bash
# A pelage sweep as a Slurm job array, then merged: task I of the array renders shard I of N
# (`pelage sweep --shard auto` reads SLURM_ARRAY_TASK_ID, _MIN and _COUNT), and a job that
# depends on the whole array runs `pelage sweep-merge`. The same results.csv rows, point images,
# contact sheet and plots as one `pelage sweep` (the timings are each task's own).
#
#   docs/cluster/slurm-array.sh N OUT [pelage sweep arguments, without -o, --shard, --threads]
#   docs/cluster/slurm-array.sh 8 sweep/ scenes/thesis-4-1.toml --param number_of_shells=10,20,30,40
#
# Run it where sbatch works (a login node), from a folder every node sees: the shards go to
# OUT.shards/<task id>/ (removed once merged), Slurm's logs to OUT.logs/.
# Environment: PELAGE (the pelage command, default `pelage`, at the same path on every node),
# CPUS_PER_TASK (cores per task, default 1, passed on as --threads), SBATCH_ARGS (more sbatch
# options, split on spaces: "--partition=long --time=02:00:00"), WAIT=1 (wait for the merge and
# exit with its status; otherwise print the two job ids and return at once).
# A task that fails cancels the merge (--kill-on-invalid-dep); its log says why.
set -euo pipefail

# Inside the array: one shard (the script submits itself with --task).
if [ "${1:-}" = --task ]; then
    shards=$2
    shift 2
    exec "${PELAGE:-pelage}" sweep "$@" --shard auto --threads "${SLURM_CPUS_PER_TASK:-1}" \
        -o "$shards/$SLURM_ARRAY_TASK_ID"
fi
# After the array: the merge (the script submits itself with --merge).
if [ "${1:-}" = --merge ]; then
    out=$2
    shards=$3
    "${PELAGE:-pelage}" sweep-merge -o "$out" "$shards"/[0-9]*
    rm -rf "$shards"
    exit 0
fi

if [ $# -lt 3 ]; then
    echo "usage: $0 N OUT SCENE [--param ...]" >&2
    exit 2
fi
n=$1
out=${2%/}
shift 2
case $n in
    '' | *[!0-9]* | 0) echo "$0: N must be a whole number of tasks, at least 1" >&2; exit 2 ;;
esac
shards="$out.shards"
logs="$out.logs"
# The shards' folder is this script's own: an earlier run's shards must not be merged with
# these. Slurm opens the log files before a job starts: their folder must exist.
rm -rf "$shards"
mkdir -p "$shards" "$logs"
read -r -a extra <<< "${SBATCH_ARGS:-}"
array=$(sbatch --parsable --job-name=pelage-sweep --array="1-$n" \
    --cpus-per-task="${CPUS_PER_TASK:-1}" --output="$logs/task-%a.out" "${extra[@]}" \
    "$0" --task "$shards" "$@")
array=${array%%;*} # --parsable prints "id" or "id;cluster"
wait=()
if [ "${WAIT:-0}" = 1 ]; then
    wait=(--wait)
fi
merge=$(sbatch --parsable --job-name=pelage-merge --dependency="afterok:$array" \
    --kill-on-invalid-dep=yes --output="$logs/merge.out" "${extra[@]}" "${wait[@]}" \
    "$0" --merge "$out" "$shards")
echo "array job ${array}, merge job ${merge%%;*} (logs in $logs/)"
# A merge cancelled because a task failed ends with exit code 0 for `sbatch --wait`; only the
# merge removes the shards' folder.
if [ "${WAIT:-0}" = 1 ] && [ -d "$shards" ]; then
    echo "$0: no merge: a task of array job $array failed (its log in $logs/ says why)" >&2
    exit 1
fi
