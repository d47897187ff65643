"""``pelage compare`` from Python: a capture against a reference, on arrays or image files."""

from __future__ import annotations

import json
import math
import os
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

from . import _pelage

#: An image: an ``H×W×4`` (or ``H×W×3``, ``H×W``) ``uint8`` array, or a path to an image file.
ImageLike = Union[npt.ArrayLike, str, "os.PathLike[str]"]

_PRESETS = ("exact", "gpu")


def as_rgba8(image: Any, what: str) -> npt.NDArray[np.uint8]:
    """An image argument as a C-contiguous ``H×W×4`` ``uint8`` array.

    A path is read as ``pelage compare`` reads it (PNG, JPEG, BMP, EXR; grey and RGB get an
    opaque alpha). An array must hold whole numbers in 0..=255: ``uint8`` is taken as it is,
    other integer dtypes are converted when every value fits; floats, bools and objects are
    refused (their scale is ambiguous). ``H×W`` (grey) and ``H×W×3`` (RGB) get an opaque
    alpha, as a file would."""
    if isinstance(image, (str, os.PathLike)):
        path = os.fspath(image)
        if not os.path.exists(path):
            raise FileNotFoundError(2, f"{what}: no such image", path)
        return _pelage.read_image(path)
    if not isinstance(image, np.ndarray):
        try:
            image = np.asarray(image)
        except (TypeError, ValueError) as e:
            raise TypeError(f"{what}: an array or a path is expected ({e})") from e
    array: npt.NDArray[Any] = image
    if array.dtype != np.uint8:
        if not np.issubdtype(array.dtype, np.integer) or array.dtype == np.bool_:
            raise TypeError(
                f"{what}: dtype {array.dtype}; a uint8 array (0..=255) is expected "
                "(floats in [0, 1]: (np.clip(a, 0, 1) * 255 + 0.5).astype(np.uint8))"
            )
        if array.size and (array.min() < 0 or array.max() > 255):
            raise ValueError(
                f"{what}: dtype {array.dtype} with values outside 0..=255 "
                f"({array.min()}..{array.max()})"
            )
        array = array.astype(np.uint8)
    if array.ndim == 2:
        array = np.stack([array, array, array, np.full_like(array, 255)], axis=-1)
    elif array.ndim == 3 and array.shape[2] == 3:
        alpha = np.full(array.shape[:2] + (1,), 255, dtype=np.uint8)
        array = np.concatenate([array, alpha], axis=2)
    if array.ndim != 3 or array.shape[2] != 4:
        raise ValueError(
            f"{what}: shape {array.shape}; an H×W×4 (RGBA), H×W×3 (RGB) or H×W (grey) "
            "array is expected"
        )
    if array.shape[0] == 0 or array.shape[1] == 0:
        raise ValueError(f"{what}: shape {array.shape} has no pixels")
    return np.ascontiguousarray(array)


def _tolerance_text(tolerance: Any) -> str:
    if not isinstance(tolerance, str):
        raise TypeError(
            f"tolerance = {tolerance!r}: a preset ('exact', 'gpu') or bounds "
            "('threshold=8,over=0.005,…') are expected as a str"
        )
    return tolerance


class CompareResult:
    """Everything ``pelage compare`` measures between a reference and a capture, and the
    verdict against the tolerance. ``bool(result)`` is :attr:`passed`; ``str(result)`` is
    the text the command prints; :attr:`heatmap` is the heat map of the differences as an
    ``H×W×4`` ``uint8`` array (log scale of the largest channel difference, without the
    legend the command draws below its PNG)."""

    __slots__ = ("_metrics", "_text", "heatmap", "passed")

    heatmap: npt.NDArray[np.uint8]
    passed: bool

    def __init__(
        self, metrics: Dict[str, Any], text: str, heatmap: npt.NDArray[np.uint8], passed: bool
    ):
        self._metrics = metrics
        self._text = text
        self.heatmap = heatmap
        self.passed = passed

    def __bool__(self) -> bool:
        return self.passed

    def __str__(self) -> str:
        return self._text

    def __repr__(self) -> str:
        verdict = "passed" if self.passed else "FAILED"
        return (
            f"<pelage.CompareResult {verdict}: {self.width}×{self.height}, "
            f"{self.exact_pixels} of {self.pixels} exact, PSNR {self.psnr:.2f} dB, "
            f"FLIP mean {self.flip_mean:.5f}>"
        )

    def as_dict(self) -> Dict[str, Any]:
        """The metrics as ``pelage compare --json`` prints them (PSNR ``"inf"`` when equal)."""
        return json.loads(json.dumps(self._metrics))  # type: ignore[no-any-return]

    @property
    def width(self) -> int:
        """Width in pixels."""
        return int(self._metrics["width"])

    @property
    def height(self) -> int:
        """Height in pixels."""
        return int(self._metrics["height"])

    @property
    def pixels(self) -> int:
        """``width × height``."""
        return int(self._metrics["pixels"])

    @property
    def exact_pixels(self) -> int:
        """Pixels equal in all four channels."""
        return int(self._metrics["exact_pixels"])

    @property
    def is_exact(self) -> bool:
        """Whether the images are identical."""
        return self.exact_pixels == self.pixels

    @property
    def max_abs_error(self) -> Tuple[int, int, int, int]:
        """Largest absolute difference per channel, R, G, B, A (8-bit steps)."""
        r, g, b, a = self._metrics["max_abs_error"]
        return (int(r), int(g), int(b), int(a))

    @property
    def mean_abs_error(self) -> Tuple[float, float, float, float]:
        """Mean absolute difference per channel, R, G, B, A (8-bit steps)."""
        r, g, b, a = self._metrics["mean_abs_error"]
        return (float(r), float(g), float(b), float(a))

    @property
    def psnr(self) -> float:
        """PSNR over R, G, B in dB; ``math.inf`` when the images are identical."""
        value = self._metrics["psnr"]
        return math.inf if value == "inf" else float(value)

    @property
    def over_threshold(self) -> int:
        """Pixels where some channel differs by more than the tolerance's threshold."""
        return int(self._metrics["over_threshold"])

    @property
    def over_fraction(self) -> float:
        """:attr:`over_threshold` as a fraction of the pixels."""
        return self.over_threshold / self.pixels

    @property
    def neighbour_over_threshold(self) -> int:
        """Of those, pixels with no match within the threshold among the other image's 3×3
        neighbours."""
        return int(self._metrics["neighbour_over_threshold"])

    @property
    def neighbour_over_fraction(self) -> float:
        """:attr:`neighbour_over_threshold` as a fraction of the pixels."""
        return self.neighbour_over_threshold / self.pixels

    @property
    def flip_mean(self) -> float:
        """FLIP's mean error (its recommended single figure)."""
        return float(self._metrics["flip"]["mean"])

    @property
    def flip_median(self) -> float:
        """FLIP's median error."""
        return float(self._metrics["flip"]["median"])

    @property
    def flip_p95(self) -> float:
        """FLIP's 95th percentile."""
        return float(self._metrics["flip"]["p95"])

    @property
    def flip_p99(self) -> float:
        """FLIP's 99th percentile."""
        return float(self._metrics["flip"]["p99"])

    @property
    def flip_max(self) -> float:
        """FLIP's largest error."""
        return float(self._metrics["flip"]["max"])

    @property
    def flip_checked_percentile(self) -> Optional[Tuple[float, float]]:
        """The percentile the tolerance asked for, and its value (``None`` when none was)."""
        checked = self._metrics["flip"]["checked_percentile"]
        return None if checked is None else (float(checked[0]), float(checked[1]))

    @property
    def tolerance(self) -> Dict[str, Any]:
        """The tolerance the verdict used, its bounds by name (``None``: not checked)."""
        return dict(self._metrics["tolerance"])

    @property
    def checked(self) -> List[str]:
        """The criteria the verdict checked, one phrase each."""
        return list(self._metrics["checked"])

    @property
    def failures(self) -> List[str]:
        """Every bound exceeded, one line each; empty when within tolerance."""
        return list(self._metrics["failures"])


def compare(reference: ImageLike, capture: ImageLike, tolerance: str = "gpu") -> CompareResult:
    """Compares a capture (e.g. a GPU frame) with a reference (e.g. pelage's render), as
    ``pelage compare REFERENCE CAPTURE --tolerance TOLERANCE`` does.

    ``reference`` and ``capture`` are arrays (``H×W×4`` ``uint8``; see :func:`as_rgba8`) or
    paths to image files, of the same size. ``tolerance`` takes the command's syntax: a preset
    (``"exact"``: every pixel equal; ``"gpu"``: the measured GPU tier, :data:`GPU_TOLERANCE`)
    and/or comma-separated bounds read left to right (``threshold=N``, ``over=F``,
    ``neighbour-over=F``, ``flip-mean=F``, ``flip-pNN=F``, ``psnr=DB``).

    Raises :class:`ValueError` for a bad tolerance or images of different sizes."""
    text = _tolerance_text(tolerance)
    a = as_rgba8(reference, "reference")
    b = as_rgba8(capture, "capture")
    metrics, printed, heatmap, passed = _pelage.compare(a, b, text)
    return CompareResult(json.loads(metrics), printed, heatmap, passed)
