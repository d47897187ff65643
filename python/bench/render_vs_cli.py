"""Benchmark (not a test): the CPU time of a render through Python against `pelage render`
for the same scene, the two interleaved so that both see the same machine.

    python python/bench/render_vs_cli.py [SCENE] [--runs N] [--cli PATH] [--width W --height H]

The command's figure is its process's CPU time (user + system, every thread: start-up, the
bake, the render and writing the PNG); Python's is the CPU time of this process's threads
during `Scene.load(...).render(...)` followed by writing the same PNG (the same work, the
interpreter's start-up aside), and without the PNG. Prints the medians and the ratios, and the
CPU model.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import resource
import statistics
import subprocess
import tempfile
import time

import pelage

ROOT = pathlib.Path(__file__).resolve().parents[2]


def cpu_model() -> str:
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown CPU"


def cli_seconds(cli: str, scene: str, extra: list[str], out: str) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run([cli, "render", scene, "-o", out, *extra], check=True, capture_output=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall


def python_seconds(
    scene: str, width: int | None, height: int | None, png: str | None
) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_SELF)
    started = time.perf_counter()
    image = pelage.Scene.load(scene).render(width=width, height=height)
    if png is not None:
        pelage._pelage.write_png(png, image)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_SELF)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(ROOT / "scenes" / "torus.toml"))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--cli", default=os.environ.get("PELAGE_CLI", str(ROOT / "target" / "release" / "pelage")))
    parser.add_argument("--width", type=int)
    parser.add_argument("--height", type=int)
    args = parser.parse_args()
    extra = []
    if args.width:
        extra += ["--width", str(args.width)]
    if args.height:
        extra += ["--height", str(args.height)]
    with tempfile.TemporaryDirectory() as folder:
        out = os.path.join(folder, "cli.png")
        # One of each first: page cache, lazy loading of the module.
        cli_seconds(args.cli, args.scene, extra, out)
        python_seconds(args.scene, args.width, args.height, None)
        cli_runs, png_runs, py_runs = [], [], []
        for _ in range(args.runs):
            cli_runs.append(cli_seconds(args.cli, args.scene, extra, out))
            png_runs.append(python_seconds(args.scene, args.width, args.height, out))
            py_runs.append(python_seconds(args.scene, args.width, args.height, None))

    def median(runs: list[tuple[float, float]], k: int) -> float:
        return statistics.median(r[k] for r in runs)

    cli_cpu, cli_wall = median(cli_runs, 0), median(cli_runs, 1)
    print(f"machine   {cpu_model()}, {os.cpu_count()} logical CPUs")
    print(f"scene     {args.scene} {' '.join(extra)} ({args.runs} runs each, interleaved, medians)")
    print(f"CLI              CPU {cli_cpu:.3f} s  wall {cli_wall:.3f} s  (pelage render -o x.png)")
    for label, runs in [("Python + PNG", png_runs), ("Python, array", py_runs)]:
        cpu, wall = median(runs, 0), median(runs, 1)
        print(
            f"{label:<16} CPU {cpu:.3f} s  wall {wall:.3f} s  "
            f"(Python / CLI: CPU {cpu / cli_cpu:.3f}, wall {wall / cli_wall:.3f})"
        )


if __name__ == "__main__":
    main()
