#!/usr/bin/env python3
"""A pelage sweep split into N shards run at once from Python, then merged.

    docs/cluster/sweep_futures.py N OUT [pelage sweep arguments, without -o and --shard]
    docs/cluster/sweep_futures.py 4 sweep/ scenes/thesis-4-1.toml --param number_of_shells=10,20,30,40

Each shard is a `pelage sweep --shard I/N` subprocess submitted to a `concurrent.futures`
executor; `pelage sweep-merge` joins them into OUT: the same results.csv rows, point images,
contact sheet and plots as one `pelage sweep`. Only the standard library and the pelage CLI
are needed (not pelage's Python package). Any `concurrent.futures.Executor` can run the shards:
a `ThreadPoolExecutor` on one machine (here: the work is in the subprocesses), or an executor
that submits to a cluster (submitit's and Dask's have the same `submit` and `result`).

Environment: PELAGE (the pelage command, default `pelage`), JOBS (shards at once, default the
number of cores).
"""

import concurrent.futures
import os
import subprocess
import sys
import tempfile


def run_shard(pelage, args, index, count, folder):
    """Runs shard INDEX of COUNT into FOLDER; raises with pelage's message if it fails."""
    done = subprocess.run(
        [pelage, "sweep", *args, "--shard", f"{index}/{count}", "-o", folder],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    if done.returncode != 0:
        raise RuntimeError(f"shard {index}/{count}: {done.stderr.strip()}")
    return folder


def main(argv):
    if len(argv) < 4 or not argv[1].isdigit() or int(argv[1]) < 1:
        print(f"usage: {argv[0]} N OUT SCENE [--param ...]", file=sys.stderr)
        return 2
    count, out, args = int(argv[1]), argv[2].rstrip("/"), argv[3:]
    pelage = os.environ.get("PELAGE", "pelage")
    jobs = int(os.environ.get("JOBS", os.cpu_count() or 1))
    parent = os.path.dirname(os.path.abspath(out))
    # The shards go beside OUT (on the same disk) and are removed once merged.
    with tempfile.TemporaryDirectory(prefix=os.path.basename(out) + ".shards.", dir=parent) as tmp:
        folders = [os.path.join(tmp, f"shard-{i}") for i in range(1, count + 1)]
        with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
            futures = [
                pool.submit(run_shard, pelage, args, i, count, folder)
                for i, folder in enumerate(folders, start=1)
            ]
            for future in concurrent.futures.as_completed(futures):
                error = future.exception()
                if error is not None:
                    # Shards not started yet are dropped; running ones finish first.
                    pool.shutdown(cancel_futures=True)
                    print(error, file=sys.stderr)
                    return 1
        merged = subprocess.run([pelage, "sweep-merge", "-o", out, *folders])
        return merged.returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv))
