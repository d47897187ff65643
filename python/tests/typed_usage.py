"""Typed use of the package: `mypy --strict` must accept it (tests/test_typing.py runs it).
Not collected by pytest; never run."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import List

import numpy as np
import numpy.typing as npt

import pelage
from pelage import shading
from pelage.testing import assert_matches_oracle


def render_sweep(path: str) -> List[npt.NDArray[np.uint8]]:
    scene = pelage.Scene.load(path).with_params(number_of_shells=20, model_difference=0.5)
    points: List[pelage.SweepPoint] = scene.sweep(number_of_strands=[500, 1000])
    with ThreadPoolExecutor() as pool:
        return list(pool.map(lambda p: p.render(width=64, height=48), points))


def check(capture: npt.NDArray[np.uint8], scene: pelage.Scene) -> bool:
    result: pelage.CompareResult = pelage.compare(scene.render(), capture, tolerance="gpu")
    worst: float = result.flip_max + result.psnr + result.over_fraction
    heat: npt.NDArray[np.uint8] = result.heatmap
    assert_matches_oracle(capture, scene, tolerance=pelage.GPU_TOLERANCE)
    return bool(result) and worst >= 0 and heat.size > 0


def terms() -> float:
    tangent = np.zeros((4, 3), dtype=np.float32)
    diffuse = shading.kajiya_kay_diffuse(tangent, [0.0, 0.0, 1.0])
    colour = shading.final_colour([1.0, 0.5, 0.2], [1, 1, 1], 0.15, diffuse, 0.0, 0.0, 0.0)
    return float(colour.sum()) + shading.shadow_lookup_count(30, 2, 5)


def errors() -> str:
    try:
        pelage.Scene.from_toml("[fur]\nnumber_of_shells = -1\n")
    except pelage.SceneError as e:
        return f"{e.file}:{e.line}: {e.message}"
    return ""


def export(folder: str) -> int:
    return len(pelage.export(pelage.Scene.default().with_params(width=64, height=48), folder))
