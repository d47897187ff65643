"""Scenes: loading, parameters and their checks, errors with the CLI's messages, pickling."""

from __future__ import annotations

import pickle

import pytest

import pelage
from conftest import SCENES, SMALL_SCENE


def test_load_from_toml_and_default_agree():
    loaded = pelage.Scene.load(SCENES / "torus.toml")
    assert (loaded.width, loaded.height) == (640, 480)
    parsed = pelage.Scene.from_toml((SCENES / "torus.toml").read_text(), base_dir=SCENES)
    assert parsed.to_toml() == loaded.to_toml()
    assert pelage.Scene.default().to_toml() == loaded.to_toml()


def test_missing_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError):
        pelage.Scene.load(tmp_path / "nothing.toml")


def test_unknown_key_has_the_cli_message(cli, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(SMALL_SCENE.replace("number_of_shells = 8", "number_of_shell = 8"))
    with pytest.raises(pelage.SceneError) as caught:
        pelage.Scene.load(bad)
    error = caught.value
    assert isinstance(error, ValueError)
    assert error.file == str(bad)
    assert error.line == SMALL_SCENE.splitlines().index("number_of_shells = 8") + 1
    assert "number_of_shells" in error.message  # the suggestion
    done = cli("render", bad, "-o", tmp_path / "x.png", check=False)
    assert done.returncode == 2
    assert done.stderr.strip() == f"error: {error}"


def test_from_toml_errors_name_the_given_name():
    with pytest.raises(pelage.SceneError) as caught:
        pelage.Scene.from_toml("[fur]\nnumber_of_shells = -3\n", name="mine.toml")
    assert str(caught.value).startswith("mine.toml:2: ")
    assert caught.value.line == 2
    with pytest.raises(TypeError):
        pelage.Scene.from_toml(b"seed = 1")  # type: ignore[arg-type]


def test_with_params_checks_values_as_scene_files_do(small_scene):
    changed = small_scene.with_params(number_of_shells=12, model_difference=0.5)
    assert changed.params == {"number_of_shells": 12, "model_difference": 0.5}
    assert "number_of_shells = 12" in changed.to_toml()
    assert small_scene.params == {}
    for bad in [
        {"number_of_shells": -3},
        {"number_of_shells": "many"},
        {"number_of_shells": float("nan")},
        {"no_such_parameter": 1},
        {"fur.": 1},
        {"time": 1.0, "burn_time": 2.0},
    ]:
        with pytest.raises(pelage.SceneError) as caught:
            small_scene.with_params(**bad)
        assert str(caught.value).startswith("small.toml")
    with pytest.raises(TypeError):
        small_scene.with_params(number_of_shells=object())  # type: ignore[arg-type]


def test_dotted_keys_vectors_and_strings(small_scene):
    scene = small_scene.with_params(
        **{"light.direction": [1, 0, 0], "shading.debug_view": "tangents", "seed": 9}
    )
    text = scene.to_toml()
    assert 'debug_view = "tangents"' in text and "seed = 9" in text


def test_scenes_pickle_and_compare_equal(small_scene):
    changed = small_scene.with_params(number_of_shells=6)
    again = pickle.loads(pickle.dumps(changed))
    assert again == changed and hash(again) == hash(changed)
    assert again.to_toml() == changed.to_toml()
    assert repr(changed).startswith("<pelage.Scene small.toml 64×48")


def test_sweep_points(small_scene):
    points = small_scene.sweep(number_of_shells=[4, 8], seed=[1, 2, 3])
    assert [p.params for p in points][:4] == [
        {"number_of_shells": 4, "seed": 1},
        {"number_of_shells": 4, "seed": 2},
        {"number_of_shells": 4, "seed": 3},
        {"number_of_shells": 8, "seed": 1},
    ]
    assert [p.index for p in points] == list(range(6))
    assert points[0].label == "number_of_shells=4 seed=1"
    with pytest.raises(ValueError):
        small_scene.sweep()
    with pytest.raises(ValueError):
        small_scene.sweep(number_of_shells=[])
    with pytest.raises(TypeError):
        small_scene.sweep(number_of_shells=10)  # type: ignore[arg-type]
    with pytest.raises(pelage.SceneError):
        small_scene.sweep(number_of_shells=[4, -1])


def _render_point(point: pelage.SweepPoint) -> bytes:
    return bytes(point.render().tobytes())


def test_sweep_points_run_in_other_processes(small_scene):
    from concurrent.futures import ProcessPoolExecutor

    points = small_scene.sweep(number_of_shells=[4, 6])
    with ProcessPoolExecutor(max_workers=2) as pool:
        rendered = list(pool.map(_render_point, points))
    assert rendered == [_render_point(p) for p in points]
    assert pickle.loads(pickle.dumps(points[1])) == points[1]


def test_export_writes_the_cli_files(cli, small_scene_file, tmp_path):
    ours = pelage.export(pelage.Scene.load(small_scene_file), tmp_path / "ours")
    names = {p.relative_to(tmp_path / "ours").as_posix() for p in ours}
    assert {"scene.json", "oracle.png"} <= names
    assert all(p.is_file() for p in ours)
    cli("export", small_scene_file, "-o", tmp_path / "theirs")
    for name in ["scene.json", "oracle.png", "textures/shell_00_colour.png"]:
        assert (tmp_path / "ours" / name).read_bytes() == (tmp_path / "theirs" / name).read_bytes()
    oracle = pelage._pelage.read_image(str(tmp_path / "ours" / "oracle.png"))
    assert (oracle == pelage.Scene.load(small_scene_file).render()).all()
    with pytest.raises(FileNotFoundError):
        pelage.export(tmp_path / "missing.toml", tmp_path / "x")
