"""Scene.render against `pelage render`: the same bytes, any threads and tiles; bad arguments
refused clearly; Ctrl-C stops a render."""

from __future__ import annotations

import os
import pathlib
import signal
import threading
import time

import numpy as np
import pytest

import pelage
from conftest import SCENES


def test_small_scene_is_the_cli_png(cli, small_scene_file, tmp_path):
    out = tmp_path / "cli.png"
    cli("render", small_scene_file, "-o", out)
    ours = pelage.Scene.load(small_scene_file).render()
    assert ours.dtype == np.uint8 and ours.shape == (48, 64, 4)
    assert ours.flags.c_contiguous
    theirs = pelage.compare(ours, out, tolerance="exact")
    assert theirs.is_exact, str(theirs)
    assert np.array_equal(ours, pelage._pelage.read_image(str(out)))


@pytest.mark.parametrize(
    "scene, args",
    [
        ("torus.toml", ["--width", "160", "--height", "120"]),
        ("wind.toml", ["--width", "120", "--height", "90", "--time", "0.7"]),
        ("spots.toml", ["--width", "96", "--height", "72"]),
    ],
)
def test_repository_scenes_are_the_cli_pngs(cli, tmp_path, scene, args):
    out = tmp_path / "cli.png"
    cli("render", SCENES / scene, "-o", out, *args)
    options = dict(zip(args[::2], args[1::2]))
    ours = pelage.Scene.load(SCENES / scene).render(
        width=int(options["--width"]),
        height=int(options["--height"]),
        time=float(options["--time"]) if "--time" in options else None,
    )
    assert np.array_equal(ours, pelage._pelage.read_image(str(out)))


def test_params_are_the_cli_overrides(cli, tmp_path):
    # scene.with_params(number_of_shells=12) is the point number_of_shells=12 of a sweep: the
    # same scene as the file with that key changed.
    text = (SCENES / "torus.toml").read_text().replace(
        "number_of_shells = 40", "number_of_shells = 12"
    )
    edited = tmp_path / "torus12.toml"
    edited.write_text(text)
    out = tmp_path / "cli.png"
    cli("render", edited, "-o", out, "--width", "96", "--height", "64")
    ours = pelage.Scene.load(SCENES / "torus.toml").with_params(number_of_shells=12)
    assert np.array_equal(ours.render(width=96, height=64), pelage._pelage.read_image(str(out)))


def test_threads_and_tiles_never_change_the_image(small_scene):
    first = small_scene.render(threads=1, tile=16)
    for threads, tile in [(2, 64), (3, 2), (None, 1024)]:
        assert np.array_equal(small_scene.render(threads=threads, tile=tile), first)


def test_float32_is_the_framebuffer_before_rounding(small_scene):
    floats = small_scene.render(dtype="float32")
    assert floats.dtype == np.float32 and floats.shape == (48, 64, 4)
    assert np.all(np.isfinite(floats))
    bytes_ = small_scene.render()
    # Rounding the floats to 8 bits as the framebuffer does gives the 8-bit image.
    assert np.abs(np.clip(floats, 0, 1) * 255 - bytes_.astype(np.float32)).max() <= 0.5 + 1e-3
    assert np.array_equal(small_scene.render(dtype=np.float32), floats)


def test_float32_is_the_cli_exr(cli, small_scene_file, tmp_path):
    out = tmp_path / "cli.exr"
    cli("render", small_scene_file, "-o", out)
    floats = pelage.Scene.load(small_scene_file).render(dtype="float32")
    assert floats.shape == (48, 64, 4)
    assert np.array_equal(floats, pelage._pelage.read_float_image(str(out)))


@pytest.mark.parametrize(
    "kwargs, error",
    [
        ({"width": -1}, ValueError),
        ({"width": 2**40}, ValueError),
        ({"width": 1.5}, TypeError),
        ({"width": "64"}, TypeError),
        ({"height": True}, TypeError),
        ({"threads": 0}, ValueError),
        ({"threads": 1000}, ValueError),
        ({"tile": 3}, ValueError),
        ({"tile": 0}, ValueError),
        ({"time": "noon"}, TypeError),
        ({"time": float("nan")}, pelage.SceneError),
        ({"time": float("inf")}, pelage.SceneError),
        ({"width": 0}, pelage.SceneError),
        ({"dtype": "float64"}, ValueError),
        ({"dtype": "rgb"}, TypeError),
    ],
)
def test_bad_render_arguments_are_refused(small_scene, kwargs, error):
    with pytest.raises(error):
        small_scene.render(**kwargs)


def test_huge_sizes_are_refused_before_memory_is_spent(small_scene):
    started = time.monotonic()
    with pytest.raises((pelage.SceneError, pelage.LimitError)) as caught:
        small_scene.render(width=200_000, height=200_000)
    assert "image" in str(caught.value) or "memory" in str(caught.value)
    assert time.monotonic() - started < 5


def test_ctrl_c_stops_a_render_within_a_second():
    scene = pelage.Scene.load(SCENES / "torus.toml").with_params(number_of_strands=300)
    sent = []

    def interrupt() -> None:
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(1.0, interrupt)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            # Large enough to take several seconds on two cores.
            scene.render(width=2400, height=1800)
            pytest.skip("the render ended before the interrupt")
    finally:
        timer.cancel()
    assert sent and time.monotonic() - sent[0] < 1.0


def test_warnings_become_python_warnings(tmp_path):
    # An OBJ without UVs gets a generated projection, with a warning.
    obj = tmp_path / "quad.obj"
    obj.write_text("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n")
    scene = pelage.Scene.from_toml(
        '[image]\nwidth = 32\nheight = 24\n[mesh]\nkind = "obj"\npath = "quad.obj"\n'
        "[fur]\nnumber_of_strands = 50\nnumber_of_shells = 4\ntexture_resolution = 16\n",
        base_dir=tmp_path,
    )
    with pytest.warns(UserWarning):
        scene.render()
