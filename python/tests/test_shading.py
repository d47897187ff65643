"""pelage.shading: the renderer's terms over arrays, with NumPy broadcasting and clear
refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pelage import shading


def test_documented_values():
    # A strand leaning 30° from the light: sin 30° = 0.5, raised to Banks's 4.8.
    tangent = np.array([0.5, 0.0, math.sqrt(3) / 2], dtype=np.float32)
    value = shading.kajiya_kay_diffuse(tangent, [0, 0, 1])
    assert value.shape == () and value.dtype == np.float32
    assert abs(float(value) - 0.5**4.8) < 1e-6
    assert shading.BANKS_EXPONENT == pytest.approx(4.8)
    damp = shading.dampened_specular([0.4, 0.9, 0.6, 0.0])
    assert damp.tolist() == [np.float32(0.2), np.float32(0.3), np.float32(0.3), 0.0]


def test_eq_3_5_last_term_against_float64():
    # (ψ_specularity1)^n against NumPy's float64 power: pelage's own pow01 is within
    # 3·(1 + |n·log2 s|) ulp (the library's bound), here taken as 4·(…)·2^-23 relative.
    rng = np.random.default_rng(35)
    s = rng.uniform(1e-6, 1.0, size=1000).astype(np.float32)
    n = rng.uniform(0.25, 16.0, size=1000).astype(np.float32)
    got = shading.specularity1_power(s, n)
    assert got.shape == (1000,) and got.dtype == np.float32
    exact = s.astype(np.float64) ** n.astype(np.float64)
    t = np.abs(n.astype(np.float64) * np.log2(s.astype(np.float64)))
    assert np.all(np.abs(got - exact) <= 4 * (1 + t) * exact * 2.0**-23 + 1e-38)
    # The default n = 1 is the plain specular within an ulp or two; the range is [0, 1].
    plain = shading.specularity1_power([0.25, 0.8])
    assert np.allclose(plain, [0.25, 0.8], rtol=3e-7, atol=0)
    assert shading.specularity1_power([-1.0, 2.0, math.nan], 3.0).tolist() == [0.0, 1.0, 0.0]
    # Element by element, the library's bits: a scalar call is one element of the array call.
    assert shading.specularity1_power(s[7], n[7]).tobytes() == got[7].tobytes()


def test_broadcasting_and_shapes():
    rng = np.random.default_rng(1)
    tangents = rng.normal(size=(5, 7, 3)).astype(np.float32)
    light = np.array([0.3, 0.4, 0.8], dtype=np.float32)
    eyes = rng.normal(size=(7, 3))  # float64: converted
    spec = shading.kajiya_kay_specular(tangents, light, eyes, 32.0)
    assert spec.shape == (5, 7) and spec.dtype == np.float32
    # Element by element, the same bits as one call each.
    for i in range(5):
        for j in range(7):
            one = shading.kajiya_kay_specular(tangents[i, j], light, eyes[j].astype(np.float32), 32)
            assert one.tobytes() == spec[i, j].tobytes()
    colour = shading.final_colour(
        [0.5, 0.4, 0.3], [1, 1, 1], 0.15, spec, spec, shading.dampened_specular(spec), 0.1
    )
    assert colour.shape == (5, 7, 3)
    assert np.all((colour >= 0) & (colour <= 1))
    assert shading.sin_between([1, 0, 0], [[0, 1, 0], [1, 0, 0]]).tolist() == [1.0, 0.0]


def test_shadow_terms():
    change = shading.shadow_change([0.5, 1, 0.3], [0, 0, 1], [0.2, 0.4])
    assert change.shape == (2, 3)
    uv = shading.project_to_uv(change, [1, 0, 0], [0, 1, 0])
    assert uv.shape == (2, 2)
    m = shading.shadow_lookup_count(30, 10, 5)
    assert m == 4
    points = shading.shadow_lookup_points([[0.5, 0.5]], uv[:1], m)
    assert points.shape == (1, m, 2)
    assert np.allclose(points[0, -1], np.array([0.5, 0.5]) + uv[0])
    alphas = np.array([[1.0, 0.5, 0.0, 0.25]], dtype=np.float32)
    assert shading.shell_shadow(alphas).tolist() == [1.75]
    assert shading.shell_shadow(alphas, texel="opaque").tolist() == [3.0]
    assert shading.shadow_texel([0.0, 0.5], "opaque").tolist() == [0.0, 1.0]


def test_spot_terms():
    inside = shading.ellipsoid_spot_intensity([[0, 0, 0], [5, 0, 0]], [0, 0, 0], [1, 1, 1], 0.5)
    assert inside.tolist() == [1.0, 0.0]
    lobe = shading.light_spot_intensity([0, 0, 1], [0, 0, 1], 120)
    assert float(lobe) == 1.0
    weight = shading.spot_gradient([0.9, 0.1], 0.8, 0.45)
    assert weight.tolist() == [1.0, 0.0]
    mixed = shading.apply_spot([0.2, 0.2, 0.2], [1, 1, 1], [0.0, 1.0])
    assert mixed.shape == (2, 3)
    assert mixed[1].tolist() == [1.0, 1.0, 1.0]
    stripes = shading.stripe_intensity(np.linspace(0, 2, 9), 1.0, 0.2, 0.05)
    assert stripes.shape == (9,) and stripes[0] == 1.0
    bands = shading.light_stripe_intensity([0, 0, 1], [0, 1, 0], 4, 0.25, 0.1, 0.02)
    assert bands.shape == ()


def test_nan_and_infinities_give_finite_values():
    nan = float("nan")
    values = [
        shading.kajiya_kay_diffuse([nan, 0, 0], [0, 0, 1]),
        shading.kajiya_kay_specular([1, 0, 0], [0, 0, 1], [0, 1, 0], nan),
        shading.dampened_specular([nan, math.inf, -math.inf]),
        shading.final_colour([nan, 0, 0], [1, 1, 1], nan, 0, 0, 0, 0),
        shading.spot_gradient(nan, 0.8, 0.45),
    ]
    for v in values:
        assert np.all(np.isfinite(v))


def test_refusals():
    with pytest.raises(ValueError):
        shading.kajiya_kay_diffuse([1, 0], [0, 0, 1])
    with pytest.raises(ValueError):
        shading.kajiya_kay_diffuse(np.zeros((4, 3)), np.zeros((5, 3)))
    with pytest.raises(TypeError):
        shading.dampened_specular(np.array(["a", "b"]))
    with pytest.raises(TypeError):
        shading.dampened_specular(np.array([True]))
    with pytest.raises(TypeError):
        shading.dampened_specular(np.array([1 + 2j]))
    with pytest.raises(ValueError):
        shading.final_colour([1, 1, 1], [1, 1, 1], 0, 0, 0, 0, 0, weights=(1, 2))
    with pytest.raises(ValueError):
        shading.final_colour([1, 1, 1], [1, 1, 1], 0, 0, 0, 0, 0, ambient_term="bright")
    with pytest.raises(ValueError):
        shading.shadow_texel(0.5, "grey")
    with pytest.raises(TypeError):
        shading.shadow_lookup_count(30, 1.5, 5)  # type: ignore[arg-type]
    with pytest.raises(ValueError):
        shading.shadow_lookup_points([0, 0], [1, 1], 10**6)
    with pytest.raises(ValueError):
        shading.dampened_specular(np.broadcast_to(np.float32(0), (2**20, 2**10)))
