#!/usr/bin/env bash
# A pelage sweep split into N shards run by GNU parallel (Debian: apt-get install parallel), then
# merged: the same results.csv rows, point images, contact sheet and plots as one `pelage sweep`
# (the timings are those of each shard's machine and moment).
#
#   docs/cluster/sweep-parallel.sh N OUT [pelage sweep arguments, without -o and --shard]
#   docs/cluster/sweep-parallel.sh 4 sweep/ scenes/thesis-4-1.toml --param number_of_shells=10,20,30,40
#
# Environment: PELAGE (the pelage command, default `pelage`), JOBS (shards at once, default
# one per core: GNU parallel's 100%), SSH_HOSTS (optional: comma-separated ssh logins, e.g.
# "8/node1,8/node2", to spread the shards over machines with parallel's --sshlogin; pelage and
# the scene must be at the same paths there, and OUT's folder shared).
set -euo pipefail
if [ $# -lt 3 ]; then
    echo "usage: $0 N OUT SCENE [--param ...]" >&2
    exit 2
fi
n=$1
out=${2%/}
shift 2
pelage=${PELAGE:-pelage}
shards=$(mktemp -d "$out.shards.XXXXXX")
trap 'rm -rf "$shards"' EXIT
remote=()
if [ -n "${SSH_HOSTS:-}" ]; then
    remote=(--sshlogin "$SSH_HOSTS")
fi
# -q quotes the command's words as given; --halt stops every shard as soon as one fails.
seq 1 "$n" | parallel --will-cite -q --halt now,fail=1 --jobs "${JOBS:-100%}" "${remote[@]}" \
    "$pelage" sweep "$@" --shard "{}/$n" -o "$shards/shard-{}"
"$pelage" sweep-merge -o "$out" "$shards"/shard-*
