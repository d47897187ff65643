"""Scenes, renders, sweeps and exports: the Python face of ``pelage render``, ``sweep`` and
``export``. Every call goes through the library function the command calls, so a render is
the same bytes as the command's PNG."""

from __future__ import annotations

import itertools
import json
import math
import numbers
import os
import pathlib
import warnings
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from . import _pelage

#: A value a scene parameter takes: a number, a bool, a string, or a list of them (a vector).
ParamValue = Union[bool, int, float, str, Sequence[Any]]

PathLike = Union[str, "os.PathLike[str]"]

#: The most points a sweep may have (as ``pelage sweep``).
MAX_SWEEP_POINTS = 100_000


def _plain(value: Any, name: str) -> Any:
    """A parameter value as plain Python (NumPy scalars and arrays unwrapped); refuses what
    TOML cannot hold."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        return float(value)
    if isinstance(value, str):
        return value
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(v, name) for v in value]
    raise TypeError(
        f"{name} = {value!r}: a number, bool, string or list of them is expected, "
        f"not {type(value).__name__}"
    )


def _toml(value: Any) -> str:
    """A plain value as TOML text (floats written so that they read back bit for bit)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        text = repr(value)
        return text if any(c in text for c in ".en") else text + ".0"
    if isinstance(value, str):
        # A JSON string is a TOML basic string (\", \\, \n, \uXXXX escapes).
        return json.dumps(value, ensure_ascii=False)
    return "[" + ", ".join(_toml(v) for v in value) + "]"


def _whole(name: str, value: Any, low: int, high: int) -> Optional[int]:
    """An optional whole-number argument, range-checked."""
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} = {value!r}: a whole number is expected")
    number = int(value)
    if not low <= number <= high:
        raise ValueError(f"{name} = {number}: must be in {low}..={high}")
    return number


def _seconds(value: Any) -> Optional[float]:
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"time = {value!r}: a number of seconds is expected")
    return float(value)


def _dtype_is_float(dtype: Any) -> bool:
    try:
        resolved = np.dtype(dtype)
    except TypeError as e:
        raise TypeError(f"dtype = {dtype!r}: 'uint8' or 'float32' is expected") from e
    if resolved == np.uint8:
        return False
    if resolved == np.float32:
        return True
    raise ValueError(f"dtype = {dtype!r}: 'uint8' or 'float32' is expected")


class Scene:
    """A checked pelage scene: its TOML text, where it came from, and the parameters set on it.

    Make one with :meth:`load`, :meth:`from_toml` or :meth:`default`; :meth:`with_params`
    returns a changed copy. Scenes are immutable, compare equal when their text, name, folder
    and parameters are equal, and pickle (the text and parameters travel, not the baked fur).
    """

    __slots__ = ("_text", "_name", "_base_dir", "_params", "_size", "_time")

    _text: str
    _name: str
    _base_dir: str
    _params: Dict[str, Any]
    _size: Tuple[int, int]
    _time: float

    def __init__(self, text: str, name: str, base_dir: PathLike, params: Mapping[str, Any]):
        """Checks the scene; prefer :meth:`load`, :meth:`from_toml` or :meth:`default`."""
        self._text = text
        self._name = name
        self._base_dir = os.fspath(base_dir)
        self._params = dict(params)
        width, height, time = _pelage.check_scene(self._source())
        self._size = (width, height)
        self._time = time

    def _source(self) -> Dict[str, Any]:
        return {
            "text": self._text,
            "name": self._name,
            "base_dir": self._base_dir,
            "params": [(k, _toml(v)) for k, v in self._params.items()],
        }

    @classmethod
    def load(cls, path: PathLike) -> "Scene":
        """Reads and checks a scene file (TOML); relative paths in it (OBJ, glTF, maps) start
        from its folder. Raises :class:`SceneError` naming the file, line and key, with the
        CLI's message, and :class:`FileNotFoundError` when there is no such file."""
        path = os.fspath(path)
        if not isinstance(path, str):
            raise TypeError(f"path = {path!r}: a text path is expected")
        if not os.path.exists(path):
            raise FileNotFoundError(2, "no such scene file", path)
        text, name, base_dir = _pelage.load_scene(path)
        return cls(text, name, base_dir, {})

    @classmethod
    def from_toml(
        cls, text: str, *, name: str = "<toml>", base_dir: PathLike = "."
    ) -> "Scene":
        """Parses and checks scene text. ``name`` stands for the file in error messages;
        ``base_dir`` is where relative paths in it start."""
        if not isinstance(text, str):
            raise TypeError(f"text: a str of TOML is expected, not {type(text).__name__}")
        return cls(text, name, base_dir, {})

    @classmethod
    def default(cls) -> "Scene":
        """The embedded default scene: the furred torus of thesis figure 3.1."""
        text, name, base_dir = _pelage.default_scene()
        return cls(text, name, base_dir, {})

    def with_params(self, **params: ParamValue) -> "Scene":
        """A copy with parameters set, by the names ``pelage sweep --param`` takes: the
        thesis's (``number_of_shells``, ``model_difference``, ``texture_resolution``, …),
        ``camera_distance``, ``number_of_spots``, ``lod``, or any dotted scene key
        (``"shading.weights.shadow"`` through ``**{...}``). Values are checked as in a scene
        file; a bad one raises :class:`SceneError` with the file's message."""
        merged = dict(self._params)
        for name, value in params.items():
            merged[name] = _plain(value, name)
        return Scene(self._text, self._name, self._base_dir, merged)

    @property
    def params(self) -> Dict[str, Any]:
        """The parameters set with :meth:`with_params` (a copy)."""
        return dict(self._params)

    @property
    def width(self) -> int:
        """The image width the scene asks for."""
        return self._size[0]

    @property
    def height(self) -> int:
        """The image height the scene asks for."""
        return self._size[1]

    @property
    def time(self) -> float:
        """The instant (seconds) the scene renders by default."""
        return self._time

    @property
    def name(self) -> str:
        """The name errors give the scene (its file, or ``<toml>``)."""
        return self._name

    def to_toml(self) -> str:
        """The scene, parameters applied, as TOML text that reads back to an equal scene."""
        return _pelage.scene_to_toml(self._source())

    def render(
        self,
        width: Optional[int] = None,
        height: Optional[int] = None,
        time: Optional[float] = None,
        threads: Optional[int] = None,
        tile: Optional[int] = None,
        dtype: Any = "uint8",
    ) -> npt.NDArray[Any]:
        """Renders one frame as ``pelage render`` does.

        Returns an ``H×W×4`` ``uint8`` array, row 0 at the top: the bytes of the command's
        8-bit PNG. With ``dtype="float32"``, the framebuffer before rounding (the values of its
        ``.exr`` output). ``width``, ``height`` and ``time`` override the scene's, as
        ``--width``, ``--height`` and ``--time`` (``time=None``: the scene's ``time``, 0 when
        it sets none). ``threads`` (default: every core) and ``tile`` (default 64) change the
        speed, never the image.

        The GIL is released while rendering; Ctrl-C raises :class:`KeyboardInterrupt` within a
        twentieth of a second and stops the render. Sizes and work beyond pelage's limits raise
        :class:`LimitError` before memory is spent.
        """
        as_float = _dtype_is_float(dtype)
        overrides = _overrides(width, height, time, threads, tile)
        pixels, notes = _pelage.render(self._source(), overrides, as_float)
        for note in notes:
            warnings.warn(f"{self._name}: {note}", UserWarning, stacklevel=2)
        return pixels

    def sweep(self, **params: Iterable[ParamValue]) -> List["SweepPoint"]:
        """Every point of a parameter sweep, as ``pelage sweep --param NAME=V1,V2…`` makes
        them (the last parameter varying fastest). Each point carries its scene, its
        ``params`` and ``render()``, and pickles, so any executor can run them
        (``concurrent.futures``, Dask, Ray). Every point's scene is checked here."""
        if not params:
            raise ValueError("a sweep needs at least one parameter")
        names = list(params)
        columns: List[List[Any]] = []
        for name in names:
            values = params[name]
            if isinstance(values, (str, bytes)) or not isinstance(values, Iterable):
                raise TypeError(
                    f"{name}: a list of values is expected (e.g. {name}=[10, 20]), "
                    f"not {type(values).__name__}"
                )
            column = [_plain(v, name) for v in values]
            if not column:
                raise ValueError(f"{name}: the list of values is empty")
            columns.append(column)
        count = 1
        for column in columns:
            count *= len(column)
        if count > MAX_SWEEP_POINTS:
            raise ValueError(f"the sweep has more than {MAX_SWEEP_POINTS} points")
        points = []
        for index, combination in enumerate(itertools.product(*columns)):
            values = dict(zip(names, combination))
            points.append(SweepPoint(index, values, self.with_params(**values)))
        return points

    def __reduce__(self) -> Tuple[Any, Tuple[str, str, str, Dict[str, Any]]]:
        # The folder travels absolute: another process may start elsewhere.
        return (Scene, (self._text, self._name, os.path.abspath(self._base_dir), self._params))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Scene):
            return NotImplemented
        return self._identity() == other._identity()

    def __hash__(self) -> int:
        text, name, folder, params = self._identity()
        return hash((text, name, folder, json.dumps(params, sort_keys=True)))

    def _identity(self) -> Tuple[str, str, str, Dict[str, Any]]:
        # The folder as an absolute path: a scene pickled to another process is the same one.
        return (self._text, self._name, os.path.abspath(self._base_dir), self._params)

    def __repr__(self) -> str:
        params = "".join(f", {k}={v!r}" for k, v in self._params.items())
        return f"<pelage.Scene {self._name} {self.width}×{self.height}{params}>"


def _overrides(
    width: Any, height: Any, time: Any, threads: Any, tile: Any
) -> Dict[str, Any]:
    return {
        "width": _whole("width", width, 0, 2**32 - 1),
        "height": _whole("height", height, 0, 2**32 - 1),
        "time": _seconds(time),
        "threads": _whole("threads", threads, 1, 256),
        "tile": _whole("tile", tile, 0, 2**32 - 1) if tile is not None else _pelage.DEFAULT_TILE_SIZE,
    }


class SweepPoint:
    """One point of :meth:`Scene.sweep`: its position, its parameter values and its scene.

    Picklable: send it to any executor and call :meth:`render` there."""

    __slots__ = ("index", "params", "scene")

    index: int
    params: Dict[str, Any]
    scene: Scene

    def __init__(self, index: int, params: Mapping[str, Any], scene: Scene):
        self.index = index
        self.params = dict(params)
        self.scene = scene

    @property
    def label(self) -> str:
        """``name=value name=value``, as the CLI labels a point."""
        return " ".join(f"{k}={_toml(v) if not isinstance(v, str) else v}" for k, v in self.params.items())

    def render(
        self,
        width: Optional[int] = None,
        height: Optional[int] = None,
        time: Optional[float] = None,
        threads: Optional[int] = None,
        tile: Optional[int] = None,
        dtype: Any = "uint8",
    ) -> npt.NDArray[Any]:
        """The point's frame: :meth:`Scene.render` of its scene."""
        return self.scene.render(width, height, time, threads, tile, dtype)

    def __reduce__(self) -> Tuple[Any, Tuple[int, Dict[str, Any], Scene]]:
        return (SweepPoint, (self.index, self.params, self.scene))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, SweepPoint):
            return NotImplemented
        return (self.index, self.params, self.scene) == (other.index, other.params, other.scene)

    def __hash__(self) -> int:
        return hash((self.index, self.scene))

    def __repr__(self) -> str:
        return f"<pelage.SweepPoint {self.index}: {self.label}>"


def export(
    scene: Union[Scene, PathLike],
    folder: PathLike,
    *,
    width: Optional[int] = None,
    height: Optional[int] = None,
    time: Optional[float] = None,
    threads: Optional[int] = None,
) -> List[pathlib.Path]:
    """Writes what a GPU implementation needs to draw the scene's frame into ``folder``, as
    ``pelage export -o folder`` does: ``scene.json``, ``oracle.png``, ``meshes/``,
    ``textures/``. Returns the files written. ``scene`` may be a :class:`Scene` or a path to
    a scene file. The folder is created; files of a previous export in it are replaced."""
    if not isinstance(scene, Scene):
        scene = Scene.load(scene)
    target = pathlib.Path(os.fspath(folder))
    if target.exists() and not target.is_dir():
        raise NotADirectoryError(20, "not a folder", str(target))
    overrides = _overrides(width, height, time, threads, None)
    files = _pelage.export(scene._source(), overrides, str(target))
    return [target / f for f in files]

