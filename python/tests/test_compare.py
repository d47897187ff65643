"""pelage.compare against `pelage compare`: the same metrics and verdicts; arrays and paths;
wrong shapes and dtypes refused clearly."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import pelage


@pytest.fixture()
def pair(small_scene, tmp_path):
    reference = small_scene.render()
    capture = reference.copy()
    capture[10:20, 10:30, :3] = np.clip(capture[10:20, 10:30, :3].astype(int) + 40, 0, 255)
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    pelage._pelage.write_png(str(a), reference)
    pelage._pelage.write_png(str(b), capture)
    return reference, capture, a, b


@pytest.mark.parametrize("tolerance", ["gpu", "exact", "threshold=2,over=0.5", "gpu,psnr=10"])
def test_metrics_are_the_cli_metrics(cli, pair, tolerance):
    reference, capture, a, b = pair
    result = pelage.compare(reference, capture, tolerance=tolerance)
    done = cli("compare", a, b, "--tolerance", tolerance, check=False)
    assert done.stdout.rstrip("\n") == str(result)
    assert done.returncode == (0 if result else 1)
    as_json = json.loads(cli("compare", a, b, "--tolerance", tolerance, "--json", check=False).stdout)
    assert as_json == result.as_dict()


def test_result_fields(pair):
    reference, capture, a, b = pair
    result = pelage.compare(a, b)
    assert not result and result.passed is False
    assert (result.width, result.height, result.pixels) == (64, 48, 64 * 48)
    assert result.exact_pixels < result.pixels and not result.is_exact
    assert max(result.max_abs_error[:3]) == 40 and result.max_abs_error[3] == 0
    assert 0 < result.flip_mean <= result.flip_max
    assert result.failures and result.checked
    assert result.heatmap.shape == (48, 64, 4) and result.heatmap.dtype == np.uint8
    same = pelage.compare(reference, reference, tolerance="exact")
    assert same and same.is_exact and math.isinf(same.psnr)
    assert "within tolerance" in str(same)
    assert repr(same).startswith("<pelage.CompareResult passed")


def test_conversions(pair):
    reference, capture, _, _ = pair
    # Non-contiguous views, other integer dtypes and RGB are converted.
    wide = np.zeros((48, 128, 4), dtype=np.uint8)
    wide[:, ::2] = reference
    assert pelage.compare(reference, wide[:, ::2], tolerance="exact")
    assert pelage.compare(reference, reference.astype(np.int64), tolerance="exact")
    rgb = reference[..., :3]
    opaque = np.concatenate([rgb, np.full((48, 64, 1), 255, np.uint8)], axis=2)
    assert pelage.compare(opaque, rgb, tolerance="exact")
    assert pelage.compare(reference.tolist(), reference, tolerance="exact")


@pytest.mark.parametrize(
    "capture, error",
    [
        (np.zeros((48, 64, 4), np.float32), TypeError),
        (np.full((48, 64, 4), np.nan), TypeError),
        (np.zeros((48, 64, 4), bool), TypeError),
        (np.zeros((48, 64, 4), np.int32) - 1, ValueError),
        (np.zeros((48, 64, 5), np.uint8), ValueError),
        (np.zeros((48, 64, 4, 1), np.uint8), ValueError),
        (np.zeros((0, 64, 4), np.uint8), ValueError),
        (np.zeros((47, 64, 4), np.uint8), ValueError),
        ("no-such-file.png", FileNotFoundError),
        (object(), TypeError),
    ],
)
def test_bad_images_are_refused(pair, capture, error):
    with pytest.raises(error):
        pelage.compare(pair[0], capture)


def test_bad_tolerances_are_refused(pair):
    for bad in ["loose", "threshold=300", "flip-p200=0.1", "psnr=x"]:
        with pytest.raises(ValueError):
            pelage.compare(pair[0], pair[1], tolerance=bad)
    with pytest.raises(TypeError):
        pelage.compare(pair[0], pair[1], tolerance=8)  # type: ignore[arg-type]


def test_a_file_that_is_not_an_image(tmp_path, pair):
    junk = tmp_path / "junk.png"
    junk.write_bytes(b"not a png")
    with pytest.raises(ValueError):
        pelage.compare(pair[0], junk)
