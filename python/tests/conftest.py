"""Shared fixtures: the repository's scenes, a small fast scene, and the `pelage` command
(the CLI whose output the package must match byte for byte)."""

from __future__ import annotations

import os
import pathlib
import shutil
import subprocess
from typing import Callable, List

import pytest

import pelage

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"

#: A scene that bakes and renders in a fraction of a second.
SMALL_SCENE = """\
seed = 7

[image]
width = 64
height = 48

[camera]
eye = [0.0, 1.0, 4.0]

[mesh]
kind = "sphere"

[fur]
number_of_strands = 200
number_of_shells = 8
texture_resolution = 32
"""


def _find_cli() -> pathlib.Path | None:
    named = os.environ.get("PELAGE_CLI")
    if named:
        return pathlib.Path(named)
    candidates = []
    if os.environ.get("CARGO_TARGET_DIR"):
        candidates.append(pathlib.Path(os.environ["CARGO_TARGET_DIR"]) / "release" / "pelage")
    candidates.append(ROOT / "target" / "release" / "pelage")
    on_path = shutil.which("pelage")
    if on_path:
        candidates.append(pathlib.Path(on_path))
    for candidate in candidates:
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return candidate
    return None


@pytest.fixture(scope="session")
def cli() -> Callable[..., subprocess.CompletedProcess[str]]:
    """Runs the `pelage` command (PELAGE_CLI, $CARGO_TARGET_DIR/release/pelage,
    target/release/pelage or `pelage` on PATH); skips without one, fails instead when
    PELAGE_REQUIRE_CLI=1 (as CI sets)."""
    binary = _find_cli()
    if binary is None:
        message = "needs the pelage command: cargo build --release (or set PELAGE_CLI)"
        if os.environ.get("PELAGE_REQUIRE_CLI") == "1":
            pytest.fail(message)
        pytest.skip(message)

    def run(*args: str | os.PathLike[str], check: bool = True) -> subprocess.CompletedProcess[str]:
        command: List[str] = [str(binary)] + [os.fspath(a) for a in args]
        done = subprocess.run(command, capture_output=True, text=True, cwd=ROOT)
        if check and done.returncode != 0:
            raise AssertionError(f"{command} failed ({done.returncode}): {done.stderr}")
        return done

    return run


@pytest.fixture()
def small_scene_file(tmp_path: pathlib.Path) -> pathlib.Path:
    path = tmp_path / "small.toml"
    path.write_text(SMALL_SCENE)
    return path


@pytest.fixture()
def small_scene() -> pelage.Scene:
    return pelage.Scene.from_toml(SMALL_SCENE, name="small.toml")
