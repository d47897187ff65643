"""pelage's pytest plugin (entry point ``pytest11``, loaded by installing the package).

In a test::

    from pelage.testing import assert_matches_oracle

    def test_fur_port(tmp_path):
        capture = my_gpu_renderer.draw("scenes/torus.toml")      # H×W×4 uint8
        assert_matches_oracle(capture, "scenes/torus.toml", tolerance="gpu")

The oracle is rendered at the capture's size and compared as ``pelage compare`` does. On
failure the assertion message carries every metric, and ``reference.png``, ``heatmap.png``,
``capture.png`` and ``reference-heatmap-capture.png`` (the three side by side) are written
under the test's ``tmp_path`` (its folder is named in the message).

With ``reference="path.png"``, the capture is compared with that stored reference instead of
a fresh render (faster, and what image tests usually keep in their repository);
``pytest --pelage-bless`` renders the oracle and writes those references, and the tests that
wrote one pass.
"""

from __future__ import annotations

import os
import pathlib
import tempfile
from typing import Any, Optional, Union

import numpy as np
import numpy.typing as npt

from . import _pelage
from ._compare import CompareResult, ImageLike, as_rgba8, compare
from ._scene import Scene

__all__ = ["assert_matches_oracle", "OracleMismatch", "blessing"]

PathLike = Union[str, "os.PathLike[str]"]

# The state the hooks below keep for assert_matches_oracle: whether --pelage-bless was given,
# and the test running now (for its tmp_path).
_bless = False
_current_item: Any = None


class OracleMismatch(AssertionError):
    """A capture outside the tolerance of the oracle: the message holds the metrics and
    where the images were written; :attr:`result` the full :class:`CompareResult`."""

    def __init__(self, message: str, result: CompareResult, folder: pathlib.Path):
        super().__init__(message)
        self.result = result
        self.folder = folder


def blessing() -> bool:
    """Whether this pytest session writes references (``--pelage-bless``)."""
    return _bless


def _artifact_folder() -> pathlib.Path:
    """The running test's ``tmp_path`` (or a fresh folder of pytest's temporary root; a
    system temporary folder outside pytest)."""
    item = _current_item
    if item is not None:
        funcargs = getattr(item, "funcargs", {}) or {}
        tmp = funcargs.get("tmp_path")
        if isinstance(tmp, pathlib.Path):
            return tmp
        factory = getattr(item.config, "_tmp_path_factory", None)
        if factory is not None:
            name = "".join(c if c.isalnum() else "_" for c in item.name)[:30] or "pelage"
            folder: pathlib.Path = factory.mktemp(name, numbered=True)
            return folder
    return pathlib.Path(tempfile.mkdtemp(prefix="pelage-oracle-"))


def _side_by_side(*images: npt.NDArray[np.uint8]) -> npt.NDArray[np.uint8]:
    """Images of one height in a row, 4 white pixels between them."""
    height = max(i.shape[0] for i in images)
    gap = np.full((height, 4, 4), 255, dtype=np.uint8)
    parts = []
    for k, image in enumerate(images):
        if k:
            parts.append(gap)
        padded = np.zeros((height,) + image.shape[1:], dtype=np.uint8)
        padded[: image.shape[0]] = image
        parts.append(padded)
    return np.ascontiguousarray(np.concatenate(parts, axis=1))


def assert_matches_oracle(
    capture: ImageLike,
    scene: Union[Scene, PathLike],
    tolerance: str = "gpu",
    *,
    reference: Optional[PathLike] = None,
    time: Optional[float] = None,
    threads: Optional[int] = None,
) -> CompareResult:
    """Asserts that ``capture`` (an ``H×W×4`` ``uint8`` array or an image file) matches the
    oracle's render of ``scene`` (a :class:`Scene` or a scene file) within ``tolerance``
    (``pelage compare``'s syntax; default the ``gpu`` preset).

    The oracle is rendered at the capture's size (and at ``time``, default the scene's). With
    ``reference``, the stored image there stands for the oracle; ``--pelage-bless`` renders
    and writes it (creating its folder), and then the assertion passes. A missing reference
    fails and says how to write it.

    Raises :class:`OracleMismatch` (an :class:`AssertionError`) with the metrics and the
    folder of ``reference.png | heatmap.png | capture.png``; returns the
    :class:`CompareResult` otherwise."""
    captured = as_rgba8(capture, "capture")
    height, width = captured.shape[:2]
    if not isinstance(scene, Scene):
        scene = Scene.load(scene)
    expected: npt.NDArray[np.uint8]
    if reference is not None and not _bless:
        stored = pathlib.Path(os.fspath(reference))
        if not stored.exists():
            raise AssertionError(
                f"{stored}: no reference image; run pytest with --pelage-bless to render the "
                "oracle and write it"
            )
        expected = as_rgba8(stored, "reference")
    else:
        expected = scene.render(width=width, height=height, time=time, threads=threads)
        if reference is not None:
            stored = pathlib.Path(os.fspath(reference))
            stored.parent.mkdir(parents=True, exist_ok=True)
            _pelage.write_png(str(stored), expected)
    result = compare(expected, captured, tolerance)
    if result.passed:
        return result
    folder = _artifact_folder()
    files = {
        "reference.png": expected,
        "heatmap.png": result.heatmap,
        "capture.png": captured,
        "reference-heatmap-capture.png": _side_by_side(expected, result.heatmap, captured),
    }
    for name, image in files.items():
        _pelage.write_png(str(folder / name), image)
    raise OracleMismatch(
        f"capture differs from the oracle of {scene.name} beyond the tolerance "
        f"{tolerance!r}:\n{result}\n"
        f"images (reference | heat map | capture): {folder / 'reference-heatmap-capture.png'} "
        f"(and reference.png, heatmap.png, capture.png beside it)",
        result,
        folder,
    )


# ---- pytest hooks (this module is the plugin) --------------------------------------------


def pytest_addoption(parser: Any) -> None:
    """``--pelage-bless``: render the oracle and write the references of
    ``assert_matches_oracle(..., reference=...)``."""
    group = parser.getgroup("pelage")
    group.addoption(
        "--pelage-bless",
        action="store_true",
        default=False,
        help="pelage: render the oracle and (re)write the reference images that "
        "assert_matches_oracle(..., reference=PATH) compares against",
    )


def pytest_configure(config: Any) -> None:
    global _bless
    _bless = bool(config.getoption("pelage_bless", default=False))


def pytest_unconfigure(config: Any) -> None:
    global _bless, _current_item
    _bless = False
    _current_item = None


def pytest_runtest_setup(item: Any) -> None:
    global _current_item
    _current_item = item


def pytest_runtest_teardown(item: Any) -> None:
    global _current_item
    _current_item = None


def pytest_report_header(config: Any) -> Optional[str]:
    if config.getoption("pelage_bless", default=False):
        return "pelage: --pelage-bless (reference images are rendered and written)"
    return None
