r"""Where a camera's view depth range is cut into cascades: :func:`cascade_splits`.

Parallel-split shadow maps (Zhang et al. 2006) blend two schemes: uniform splits
spend texels evenly along the view depth, logarithmic ones keep the ratio of a
texel's size to the view distance constant. With ``i = 0 .. N``:

.. math::

    s_i^{uni} = n + (f - n) \frac{i}{N}, \qquad
    s_i^{log} = n \left(\frac{f}{n}\right)^{i / N}, \qquad
    s_i = \lambda s_i^{log} + (1 - \lambda) s_i^{uni}

(Filament's ``computePracticalSplits``, Babylon's ``lambda``, three.js's
``practical`` mode). ``s_0 = n`` and ``s_N = f`` in every scheme.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from shadowmath._boundary._messages import LOG_NEAR
from shadowmath._boundary._shapes import ArrayLike, Float, Real
from shadowmath._boundary._validate import Array, Checks, all_finite, convert, non_finite
from shadowmath._math._specialize import formulas

SplitScheme = Literal["uniform", "log", "practical"]
#: :func:`~shadowmath.fit_cascades`'s schemes: :data:`SplitScheme` and the rule ``"auto"``.
CascadeScheme = Literal["auto", "uniform", "log", "practical"]

#: The schemes :func:`cascade_splits` knows, and the ``lam`` each implies.
SCHEMES: dict[str, float | None] = {"uniform": 0.0, "log": 1.0, "practical": None}
#: The practical scheme's blend when no ``lam`` is given.
PRACTICAL_LAM = 0.75
#: ``scheme="auto"``'s blend over the camera's depth range and over a fitted one (visible
#: or measured): the best of the pose sweep's candidates over each (``docs/cascades.md``).
AUTO_LAM_CAMERA, AUTO_LAM_FITTED = PRACTICAL_LAM, 1.0
#: ``scheme="auto"``'s blend for stable cascades over the camera's range: three.js's, with
#: each cascade's blend band inside its split (:func:`stable_bands_inside`).
AUTO_LAM_STABLE = 0.5


def cascade_splits(
    near: Real[ArrayLike, "*#batch"],
    far: Real[ArrayLike, "*#batch"],
    count: int,
    *,
    scheme: SplitScheme = "practical",
    lam: Real[ArrayLike, "*#batch"] = PRACTICAL_LAM,
) -> Float[Array, "*batch {count}+1"]:
    r"""The ``count + 1`` view depths that cut ``[near, far]`` into ``count`` cascades.

    .. math:: s_i = \lambda\, n (f / n)^{i/N} + (1 - \lambda) (n + (f - n)\, i / N)

    ``scheme="uniform"`` is ``lam = 0``, ``"log"`` is ``lam = 1``, ``"practical"``
    takes ``lam`` (0.75 by default; three.js and Babylon.js use 0.5: see
    ``docs/cascades.md`` for why; :func:`~shadowmath.fit_cascades`'s default
    ``scheme="auto"`` picks 0.75 or 1 by the depth range it cuts). Differentiable in
    ``near``, ``far`` and ``lam`` (JAX).

    Arguments:
        near: ``(*batch,)`` the nearest view depth shadowed (``> 0`` unless uniform).
        far: ``(*batch,)`` the farthest (``> near``), e.g. a shadow distance.
        count: the number of cascades, ``>= 1``.
        scheme: ``"uniform"``, ``"log"`` or ``"practical"``.
        lam: ``(*batch,)`` the practical scheme's blend, in ``[0, 1]``.

    Returns:
        ``(*batch, count + 1)`` increasing depths, ``near`` first and ``far`` last.

    Raises:
        ValueError: a non-integer or non-positive ``count``, an unknown scheme,
            non-finite values, ``far <= near``, ``near <= 0`` with a logarithmic
            part, or ``lam`` outside ``[0, 1]`` (NaN under JAX transformations).

    Example:
        >>> import numpy as np
        >>> np.round(cascade_splits(1.0, 100.0, 2, scheme="log"), 6)
        array([  1.,  10., 100.])
        >>> cascade_splits(1.0, 101.0, 2, scheme="uniform")
        array([  1.,  51., 101.])
    """
    count = check_count(count)
    fixed = check_scheme(scheme)
    ctx, (n, f, lm) = convert(near=near, far=far, lam=lam if fixed is None else fixed)
    checks = Checks(ctx)
    check_range(checks, n, f, lm, fixed)
    return checks.poison(split_depths(ctx.xp, n, f, lm, count), 1)


def check_count(count: object) -> int:
    """``count`` as a positive int, or a ``ValueError`` naming it."""
    if isinstance(count, bool | np.bool_) or not isinstance(count, int | np.integer) or count < 1:
        raise ValueError(f"count: expected an integer >= 1 (cascades), got {count!r}")
    return int(count)


def check_scheme(scheme: object, *, auto: bool = False) -> float | None:
    """The ``lam`` a scheme fixes (``None``: the practical scheme, or with ``auto`` the rule
    ``"auto"``, takes ``lam``)."""
    names = ("auto", *SCHEMES) if auto else tuple(SCHEMES)
    if not isinstance(scheme, str) or scheme not in names:
        listed = ", ".join(repr(n) for n in names[:-1]) + f" or {names[-1]!r}"
        raise ValueError(f"scheme: expected {listed}, got {scheme!r}")
    return SCHEMES.get(scheme)


def scheme_lam(scheme: object, lam: Any, *, fitted_range: bool, stable: bool = False) -> Any:
    """:func:`~shadowmath.fit_cascades`'s blend: the one ``scheme`` fixes, else ``lam``,
    else ``"auto"``'s rule (:data:`AUTO_LAM_FITTED` over a visible or measured range,
    :data:`AUTO_LAM_CAMERA` over the camera's, :data:`AUTO_LAM_STABLE` there for stable
    cascades) or the practical scheme's default.

    Example:
        >>> scheme_lam("auto", None, fitted_range=True), scheme_lam("auto", 0.5, fitted_range=True)
        (1.0, 0.5)
    """
    fixed = check_scheme(scheme, auto=True)
    if fixed is not None:
        return fixed
    if lam is not None:
        return lam
    if scheme == "auto":
        if fitted_range:
            return AUTO_LAM_FITTED
        return AUTO_LAM_STABLE if stable else AUTO_LAM_CAMERA
    return PRACTICAL_LAM


def stable_bands_inside(scheme: object, lam: Any, *, fitted_range: bool, stable: bool) -> bool:
    """Whether ``"auto"``'s rule for stable cascades over the camera's range applies: the
    practical splits with :data:`AUTO_LAM_STABLE`, each cascade ending, band included, at
    its practical split (so that its sphere is no larger than three.js's: ``docs/cascades.md``).

    Example:
        >>> stable_bands_inside("auto", None, fitted_range=False, stable=True)
        True
        >>> stable_bands_inside("auto", 0.5, fitted_range=False, stable=True)
        False
    """
    return scheme == "auto" and lam is None and stable and not fitted_range


def check_range(checks: Checks, n: Array, f: Array, lm: Array, fixed: float | None) -> None:
    """The value checks of a split range (each message names its argument)."""
    xp = checks.ctx.xp
    checks.require(all_finite(xp, n, 0), non_finite("near"))
    checks.require(all_finite(xp, f, 0), non_finite("far"))
    checks.require(all_finite(xp, lm, 0), non_finite("lam"))
    checks.require((lm >= 0) & (lm <= 1), "lam: the practical scheme's blend must lie in [0, 1]")
    checks.require(f > n, "far: the split range must end beyond near (far > near)")
    if fixed != 0.0:
        checks.require(
            (n > 0) | (lm == 0),
            LOG_NEAR,
        )


def split_depths(xp: Any, n: Array, f: Array, lm: Array, count: int) -> Array:
    """The splits on trusted arrays: ``(*batch, count + 1)``."""
    shape = xp.broadcast_shapes(n.shape, f.shape, lm.shape)
    n, f, lm = (xp.broadcast_to(v, shape)[..., None] for v in (n, f, lm))
    i = xp.asarray(np.arange(count + 1) / count, dtype=n.dtype)
    s = formulas(xp).split_depth(n, f, lm, i)
    # Exact ends: s_0 = n and s_N = f whatever the rounding of the power.
    return xp.concat([n, s[..., 1:-1], f], axis=-1)
