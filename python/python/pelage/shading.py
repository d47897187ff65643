"""The shading terms of the thesis over NumPy arrays, bit-identical to the renderer's.

Each function calls, once per element, the ``pelage::shading`` function the renderer's fragment
stage calls (its SIMD lanes are held to the same bits by the library's tests), so a port's
shader math can be unit-tested pixel-exactly from Python::

    import numpy as np
    from pelage import shading

    tangent = np.array([[0.5, 0.0, 0.8660254]], dtype=np.float32)
    light = np.array([0.0, 0.0, 1.0], dtype=np.float32)         # broadcast to every tangent
    shading.kajiya_kay_diffuse(tangent, light)                   # sin(t, l)^4.8, shape (1,)

Arguments are ``float32`` arrays (other real dtypes are converted to ``float32``, as the
renderer's values are; bools, complex and objects are refused with :class:`TypeError`).
Vectors have a last axis of 3 (``uv`` of 2); the other axes broadcast together as NumPy's do
and give the result's shape. Scalars broadcast too. NaN and infinities are taken as they come:
each term's documented convention (a NaN exponent acts as 1, a zero or NaN direction as zero,
…) gives a finite result, as in the renderer.
"""

from __future__ import annotations

import math
from typing import Any, List, Sequence, Tuple

import numpy as np
import numpy.typing as npt

from . import _pelage

__all__ = [
    "BANKS_EXPONENT",
    "SHADOW_OPAQUE_ALPHA",
    "apply_spot",
    "dampened_specular",
    "ellipsoid_spot_intensity",
    "final_colour",
    "kajiya_kay_diffuse",
    "kajiya_kay_specular",
    "light_spot_intensity",
    "light_stripe_intensity",
    "project_to_uv",
    "shadow_change",
    "shadow_lookup_count",
    "shadow_lookup_points",
    "shadow_texel",
    "shell_shadow",
    "sin_between",
    "specularity1_power",
    "spot_gradient",
    "stripe_intensity",
]

#: Banks's exponent of the diffuse term (thesis 3.2.3), the default ``banks_exponent``.
BANKS_EXPONENT: float = _pelage.BANKS_EXPONENT
#: The alpha from which a shadow lookup counts a texel as opaque (``texel="opaque"``).
SHADOW_OPAQUE_ALPHA: float = _pelage.SHADOW_OPAQUE_ALPHA

Floats = npt.NDArray[np.float32]
ArrayLike = npt.ArrayLike

#: The most elements one call takes (``2^28``): beyond, refused before memory is spent.
MAX_ELEMENTS = 1 << 28


def _float32(name: str, value: Any) -> npt.NDArray[np.float32]:
    array = np.asarray(value)
    if array.dtype.kind not in "iuf":
        raise TypeError(
            f"{name}: dtype {array.dtype}; real numbers are expected (converted to float32)"
        )
    return array.astype(np.float32, copy=False)


def _broadcast(
    *args: Tuple[str, Any, int],
) -> Tuple[int, Tuple[int, ...], List[npt.NDArray[np.float32]]]:
    """The arguments as flat, C-contiguous float32 arrays over one broadcast shape: each is
    ``(name, value, width)``, width 0 for a number per element, 2 or 3 for a vector."""
    arrays = []
    batches = []
    for name, value, width in args:
        array = _float32(name, value)
        if width:
            if array.ndim == 0 or array.shape[-1] != width:
                raise ValueError(
                    f"{name}: shape {array.shape}; a last axis of {width} is expected "
                    f"(a {width}-vector per element)"
                )
            batches.append(array.shape[:-1])
        else:
            batches.append(array.shape)
        arrays.append(array)
    try:
        shape = np.broadcast_shapes(*batches)
    except ValueError as e:
        described = ", ".join(f"{n} {b}" for (n, _, _), b in zip(args, batches))
        raise ValueError(f"shapes do not broadcast together: {described}") from e
    count = math.prod(shape)
    if count > MAX_ELEMENTS:
        raise ValueError(f"{count} elements: at most {MAX_ELEMENTS} in one call")
    flat = []
    for (_, _, width), array in zip(args, arrays):
        full = shape + ((width,) if width else ())
        flat.append(np.ascontiguousarray(np.broadcast_to(array, full)).reshape(-1))
    return count, shape, flat


def _shaped(values: Any, shape: Tuple[int, ...], width: int = 0) -> Floats:
    result: Floats = np.asarray(values, dtype=np.float32).reshape(shape + ((width,) if width else ()))
    return result


def kajiya_kay_diffuse(
    tangent: ArrayLike, light: ArrayLike, banks_exponent: ArrayLike = BANKS_EXPONENT
) -> Floats:
    """Kajiya–Kay diffuse, thesis eq. 2.5 raised to Banks's exponent: ``sin(t, l)^p``.
    Vectors need not be unit (normalised inside)."""
    n, shape, (t, l, p) = _broadcast(
        ("tangent", tangent, 3), ("light", light, 3), ("banks_exponent", banks_exponent, 0)
    )
    return _shaped(_pelage.kajiya_kay_diffuse(n, t, l, p), shape)


def kajiya_kay_specular(
    tangent: ArrayLike, light: ArrayLike, eye: ArrayLike, exponent: ArrayLike
) -> Floats:
    """Kajiya–Kay specular, thesis eq. 2.7: ``max(0, t·l t·e + sin(t, l) sin(t, e))^p``."""
    n, shape, (t, l, e, p) = _broadcast(
        ("tangent", tangent, 3), ("light", light, 3), ("eye", eye, 3), ("exponent", exponent, 0)
    )
    return _shaped(_pelage.kajiya_kay_specular(n, t, l, e, p), shape)


def sin_between(a: ArrayLike, b: ArrayLike) -> Floats:
    """The sine of the angle between two vectors, ``sqrt(max(0, 1 − cos²))`` (thesis 3.2.1)."""
    n, shape, (x, y) = _broadcast(("a", a, 3), ("b", b, 3))
    return _shaped(_pelage.sin_between(n, x, y), shape)


def dampened_specular(specular: ArrayLike) -> Floats:
    """The dampened specular of thesis 3.2.3: a gradient from 0 to 0.3 below 0.6, then 0.3."""
    n, shape, (s,) = _broadcast(("specular", specular, 0))
    return _shaped(_pelage.dampened_specular(n, s), shape)


def specularity1_power(specularity1: ArrayLike, exponent: ArrayLike = 1.0) -> Floats:
    """Thesis eq. 3.5's last term, ``(ψ_specularity1)^n``: the Kajiya–Kay specular of the
    strand's own tangent (:func:`kajiya_kay_specular` with the specular exponent) raised to
    ``n`` (``exponent``, the scene's ``specular1_exponent``, default 1). It stands where eq. 3.7
    has the dampened specular: pass it as :func:`final_colour`'s ``dampened``."""
    n, shape, (s, p) = _broadcast(("specularity1", specularity1, 0), ("exponent", exponent, 0))
    return _shaped(_pelage.specularity1_power(n, s, p), shape)


def final_colour(
    strand_colour: ArrayLike,
    light_colour: ArrayLike,
    ambient: ArrayLike,
    diffuse: ArrayLike,
    specular: ArrayLike,
    dampened: ArrayLike,
    shadow: ArrayLike,
    weights: Sequence[float] = (1.0, 1.0, 1.0, 1.0, 1.0),
    ambient_term: str = "strand",
) -> Floats:
    """Thesis eq. 3.7: ``ambient + strandColour·light·(diffuse + specular) +
    light·dampened − shadow``, each term scaled by its weight (``weights``: ambient, diffuse,
    specular, dampened, shadow), each channel clamped to [0, 1]; eq. 3.5 with
    :func:`specularity1_power` as ``dampened``. ``ambient_term``:
    ``"strand"`` (ambient times the strand colour, the default) or ``"constant"``. Returns
    RGB, a last axis of 3."""
    if isinstance(weights, (str, bytes)) or len(weights) != 5:
        raise ValueError(
            "weights: five numbers are expected (ambient, diffuse, specular, dampened, shadow)"
        )
    w = [float(np.float32(x)) for x in weights]
    if not isinstance(ambient_term, str):
        raise TypeError("ambient_term: 'strand' or 'constant' is expected")
    n, shape, (s, l, a, d, sp, dm, sh) = _broadcast(
        ("strand_colour", strand_colour, 3),
        ("light_colour", light_colour, 3),
        ("ambient", ambient, 0),
        ("diffuse", diffuse, 0),
        ("specular", specular, 0),
        ("dampened", dampened, 0),
        ("shadow", shadow, 0),
    )
    return _shaped(_pelage.final_colour(n, s, l, a, d, sp, dm, sh, w, ambient_term), shape, 3)


def shadow_change(light: ArrayLike, normal: ArrayLike, height_above: ArrayLike) -> Floats:
    """The shell shadow's ``shadowChange`` vector towards the light (thesis 3.2.2): how far
    the light's ray moves across the fur over the height above the layer."""
    n, shape, (l, nm, h) = _broadcast(
        ("light", light, 3), ("normal", normal, 3), ("height_above", height_above, 0)
    )
    return _shaped(_pelage.shadow_change(n, l, nm, h), shape, 3)


def project_to_uv(change: ArrayLike, dpdu: ArrayLike, dpdv: ArrayLike) -> Floats:
    """A change vector projected to (u, v) by dropping the axis with the least change
    (thesis 3.2.2). Returns a last axis of 2."""
    n, shape, (c, u, v) = _broadcast(("change", change, 3), ("dpdu", dpdu, 3), ("dpdv", dpdv, 3))
    return _shaped(_pelage.project_to_uv(n, c, u, v), shape, 2)


def shadow_lookup_count(number_of_shells: int, shell_index: int, divisor: int) -> int:
    """``m = (N − i)/n`` of thesis table 4.4: how many lookups shell ``i`` of ``N`` makes."""
    for name, value in (
        ("number_of_shells", number_of_shells),
        ("shell_index", shell_index),
        ("divisor", divisor),
    ):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
            raise TypeError(f"{name} = {value!r}: a whole number is expected")
        if not 0 <= int(value) < 2**32:
            raise ValueError(f"{name} = {value}: must be in 0..2^32")
    return int(_pelage.shadow_lookup_count(int(number_of_shells), int(shell_index), int(divisor)))


def _texel(texel: str) -> str:
    if not isinstance(texel, str):
        raise TypeError("texel: 'alpha' or 'opaque' is expected")
    return texel


def shadow_texel(alpha: ArrayLike, texel: str = "alpha") -> Floats:
    """What one shadow lookup adds for a texel's alpha: the alpha (``"alpha"``, the default)
    or 1 when the texel is not transparent (``"opaque"``)."""
    n, shape, (a,) = _broadcast(("alpha", alpha, 0))
    return _shaped(_pelage.shadow_texel(n, a, _texel(texel)), shape)


def _lookups(lookups: int) -> int:
    if isinstance(lookups, bool) or not isinstance(lookups, (int, np.integer)):
        raise TypeError(f"lookups = {lookups!r}: a whole number is expected")
    if not 0 <= int(lookups) <= 1 << 16:
        raise ValueError(f"lookups = {lookups}: must be in 0..=65536")
    return int(lookups)


def shadow_lookup_points(uv: ArrayLike, shadow_lookup: ArrayLike, lookups: int) -> Floats:
    """Where the shell shadow's ``m`` lookups land: ``uv + shadow_lookup·(k/m)`` for
    ``k = 1..m`` (non-finite components as 0), recorded from the renderer's own function.
    Returns shape ``(…, m, 2)``."""
    m = _lookups(lookups)
    n, shape, (p, s) = _broadcast(("uv", uv, 2), ("shadow_lookup", shadow_lookup, 2))
    points = _pelage.shadow_lookup_points(n, p, s, m)
    return np.asarray(points, dtype=np.float32).reshape(shape + (m, 2))


def shell_shadow(alphas: ArrayLike, texel: str = "alpha") -> Floats:
    """The shell shadow (thesis 3.2.2) from the alphas sampled at each point's ``m`` lookups
    (the last axis, in lookup order; see :func:`shadow_lookup_points`): the sum of
    :func:`shadow_texel` in the renderer's order, in ``[0, m]``."""
    array = _float32("alphas", alphas)
    if array.ndim == 0:
        raise ValueError("alphas: an array whose last axis holds each point's lookups is expected")
    m = _lookups(array.shape[-1])
    shape = array.shape[:-1]
    n = math.prod(shape)
    if n * m > MAX_ELEMENTS:
        raise ValueError(f"{n * m} elements: at most {MAX_ELEMENTS} in one call")
    flat = np.ascontiguousarray(array).reshape(-1)
    return _shaped(_pelage.shell_shadow(n, flat, m, _texel(texel)), shape)


def ellipsoid_spot_intensity(
    point: ArrayLike, centre: ArrayLike, radii: ArrayLike, inner: ArrayLike
) -> Floats:
    """A geometric spot (thesis 3.2.4): 1 inside the inner ellipsoid (``inner`` of the radii),
    a gradient to 0 at the ellipsoid's surface."""
    n, shape, (p, c, r, k) = _broadcast(
        ("point", point, 3), ("centre", centre, 3), ("radii", radii, 3), ("inner", inner, 0)
    )
    return _shaped(_pelage.ellipsoid_spot_intensity(n, p, c, r, k), shape)


def light_spot_intensity(normal: ArrayLike, direction: ArrayLike, exponent: ArrayLike) -> Floats:
    """A light-based spot (thesis 3.2.4): the specular lobe of a light fixed to the object."""
    n, shape, (nm, d, e) = _broadcast(
        ("normal", normal, 3), ("direction", direction, 3), ("exponent", exponent, 0)
    )
    return _shaped(_pelage.light_spot_intensity(n, nm, d, e), shape)


def spot_gradient(
    intensity: ArrayLike, inner_threshold: ArrayLike, outer_threshold: ArrayLike
) -> Floats:
    """A spot's weight from its intensity: 1 past the inner threshold (the inner circle of
    full spot colour), a smooth gradient down to 0 at the outer one."""
    n, shape, (s, a, b) = _broadcast(
        ("intensity", intensity, 0),
        ("inner_threshold", inner_threshold, 0),
        ("outer_threshold", outer_threshold, 0),
    )
    return _shaped(_pelage.spot_gradient(n, s, a, b), shape)


def apply_spot(fur_colour: ArrayLike, spot_colour: ArrayLike, weight: ArrayLike) -> Floats:
    """The fur colour moved towards the spot colour by a weight in [0, 1] (the strand colour
    eq. 3.7 takes). Returns RGB, a last axis of 3."""
    n, shape, (f, s, w) = _broadcast(
        ("fur_colour", fur_colour, 3), ("spot_colour", spot_colour, 3), ("weight", weight, 0)
    )
    return _shaped(_pelage.apply_spot(n, f, s, w), shape, 3)


def stripe_intensity(
    coordinate: ArrayLike, period: ArrayLike, width: ArrayLike, softness: ArrayLike
) -> Floats:
    """Stripes across an axis: bands of ``width`` every ``period`` along ``coordinate``, with
    soft edges."""
    n, shape, (c, p, w, s) = _broadcast(
        ("coordinate", coordinate, 0),
        ("period", period, 0),
        ("width", width, 0),
        ("softness", softness, 0),
    )
    return _shaped(_pelage.stripe_intensity(n, c, p, w, s), shape)


def light_stripe_intensity(
    normal: ArrayLike,
    direction: ArrayLike,
    exponent: ArrayLike,
    period: ArrayLike,
    width: ArrayLike,
    softness: ArrayLike,
) -> Floats:
    """The thesis's stripes: bands of the lobe of a light fixed to the object."""
    n, shape, (nm, d, e, p, w, s) = _broadcast(
        ("normal", normal, 3),
        ("direction", direction, 3),
        ("exponent", exponent, 0),
        ("period", period, 0),
        ("width", width, 0),
        ("softness", softness, 0),
    )
    return _shaped(_pelage.light_stripe_intensity(n, nm, d, e, p, w, s), shape)
