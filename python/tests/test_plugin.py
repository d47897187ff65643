"""The pytest plugin, in pytest sessions of their own (pytester)."""

from __future__ import annotations

import pytest

pytest_plugins = ["pytester"]

TEST_FILE = '''
import numpy as np
import pelage
from pelage.testing import assert_matches_oracle

SCENE = pelage.Scene.from_toml(
    "[image]\\nwidth = 48\\nheight = 32\\n[mesh]\\nkind = \\"sphere\\"\\n"
    "[camera]\\neye = [0.0, 1.0, 4.0]\\n"
    "[fur]\\nnumber_of_strands = 100\\nnumber_of_shells = 4\\ntexture_resolution = 16\\n",
    name="tiny.toml",
)

def capture(width=48, height=32):
    return SCENE.render(width=width, height=height)

def test_same_image_passes():
    result = assert_matches_oracle(capture(), SCENE, tolerance="exact")
    assert result.is_exact

def test_other_size_renders_the_oracle_at_that_size():
    assert_matches_oracle(capture(24, 16), SCENE, tolerance="exact")

def test_broken_capture_fails(tmp_path):
    broken = capture()
    broken[:, :, 0] = 255 - broken[:, :, 0]
    assert_matches_oracle(broken, SCENE, tolerance="gpu")

def test_stored_reference(tmp_path):
    assert_matches_oracle(capture(), SCENE, tolerance="exact", reference="refs/tiny.png")
'''


def test_plugin_passes_and_fails_with_metrics_and_images(pytester: pytest.Pytester) -> None:
    pytester.makepyfile(test_port=TEST_FILE)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "--basetemp", str(pytester.path / "tmp"))
    result.assert_outcomes(passed=2, failed=2)
    out = result.stdout.str()
    assert "OracleMismatch" in out or "capture differs from the oracle" in out
    assert "FLIP" in out and "PSNR" in out and "verdict" in out
    assert "no reference image; run pytest with --pelage-bless" in out
    written = list((pytester.path / "tmp").rglob("reference-heatmap-capture.png"))
    assert written, "the side-by-side image is written under tmp_path"
    for name in ["reference.png", "heatmap.png", "capture.png"]:
        assert (written[0].parent / name).is_file()


def test_bless_writes_references(pytester: pytest.Pytester) -> None:
    pytester.makepyfile(test_port=TEST_FILE)
    blessed = pytester.runpytest_subprocess("-p", "no:cacheprovider", "--pelage-bless", "-k", "stored")
    blessed.assert_outcomes(passed=1)
    assert "--pelage-bless" in blessed.stdout.str()
    assert (pytester.path / "refs" / "tiny.png").is_file()
    again = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-k", "stored")
    again.assert_outcomes(passed=1)


def test_help_lists_the_option(pytester: pytest.Pytester) -> None:
    result = pytester.runpytest_subprocess("--help")
    assert "--pelage-bless" in result.stdout.str()
