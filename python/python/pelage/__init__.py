"""pelage from Python: the deterministic fur renderer as an oracle for image tests.

The same scene gives the same bytes as ``pelage render`` (any thread count, any tile size):

>>> import pelage
>>> scene = pelage.Scene.load("scenes/torus.toml").with_params(number_of_shells=20)
>>> image = scene.render(width=320, height=240)          # H×W×4 uint8, the PNG's bytes
>>> result = pelage.compare(image, "capture.png", tolerance="gpu")
>>> assert result, str(result)                            # the metrics the CLI prints

- :class:`Scene`: load, parse and change scenes (:meth:`Scene.with_params`), render them to
  NumPy arrays (:meth:`Scene.render`), and sweep parameters (:meth:`Scene.sweep`).
- :func:`compare`: a capture against a reference, every metric of ``pelage compare``.
- :func:`export`: what a GPU port needs to draw the same frame (``pelage export``).
- :mod:`pelage.shading`: the shading terms over arrays, bit-identical to the renderer's.
- :mod:`pelage.testing`: a pytest plugin, ``assert_matches_oracle`` and ``--pelage-bless``.

Errors: :class:`SceneError` (a :class:`ValueError`) names the file, line and key as the CLI
does; :class:`LimitError` (a :class:`ValueError`) refuses work too large before memory is
spent; wrong shapes and dtypes raise :class:`ValueError` and :class:`TypeError`.
"""

from __future__ import annotations

from . import _pelage
from ._compare import CompareResult, compare
from ._pelage import LimitError, SceneError
from ._scene import ParamValue, Scene, SweepPoint, export

__all__ = [
    "CompareResult",
    "LimitError",
    "ParamValue",
    "Scene",
    "SceneError",
    "SweepPoint",
    "compare",
    "export",
    "GPU_TOLERANCE",
    "DEFAULT_TILE_SIZE",
]

#: The ``gpu`` tolerance preset, spelled out (the README's measured GPU tier).
GPU_TOLERANCE: str = _pelage.GPU_TOLERANCE
#: The tile size ``render`` uses when none is given (the image never depends on it).
DEFAULT_TILE_SIZE: int = _pelage.DEFAULT_TILE_SIZE

__version__ = "0.1.0"
