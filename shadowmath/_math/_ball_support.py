"""The minimal enclosing sphere's support points of many point sets at once, in NumPy.

Without the compiled loops, Welzl's algorithm (:func:`._vertex_passes.enclosing_support`)
runs in Python, 15 to 100 µs per 8-point set. :func:`support_arrays` finds the same
spheres for a whole batch with a few dozen NumPy calls per round, by *support-set
iteration*: every entry holds a support set ``S`` (1 to 4 of its points) and the
sphere through them, ``B = MB(S)`` (first a long chord, :func:`_chords`); each round,
every entry with a point ``p`` outside ``B`` (the farthest such, by
:func:`._vertex_passes._outside`) replaces ``S`` by the support of ``MB(S + p)``.
Since ``p`` is outside ``MB(S)``, it lies on the boundary of ``MB(S + p)`` (Welzl's
lemma), so that sphere is the smallest of the spheres through ``p`` and 1 to 3 points
of ``S`` (:func:`._fit_formulas.sphere_through`, at most 14 candidates) that holds
``S + p``; among candidates of equal radius (to rounding) the one of fewest points.
The radius grows every round, so no set repeats; when no point is outside, ``B``
holds every point and is the sphere of a subset: the minimal one.
Entries still going after :data:`ROUNDS` rounds, or left without a candidate by
rounding (neither seen in practice), run Welzl's loop instead, as do batches of fewer
than :data:`LOOPED` entries.

The supports may differ from Welzl's where the minimal sphere has more than four
points on it (a box's corners); the sphere itself is unique, so its centre and radius
agree to rounding. Trusted inputs: float64 ``(count, N, 3)``.
"""

from __future__ import annotations

import itertools

import numpy as np

from ._specialize import formulas, scalar_formulas

#: The candidates: ``p`` and 1 to 3 of the four support slots, ordered so that a support
#: of ``k`` points needs the first ``2^k - 1`` rows only. Each row lists ``p``'s partners,
#: the last repeated to fill the three slots.
_SUBSETS = sorted(
    (s for m in (1, 2, 3) for s in itertools.combinations(range(4), m)),
    key=lambda s: (max(s), len(s)),
)
_SLOTS = np.array([[*s, *(s[-1],) * (3 - len(s))] for s in _SUBSETS])  # (15 - 1, 3)
_SIZES = np.array([1 + len(s) for s in _SUBSETS])  # points on each candidate sphere

#: Rounds before the remaining entries go to Welzl's loop (each round the radius grows).
ROUNDS = 64

#: Fewer entries than this run Welzl's loop: a round here is some 40 NumPy calls, while
#: the loop takes 50 to 300 µs per entry of 8 or 9 points (crossing near 32 entries).
LOOPED = 32

#: Relative slack in ``r^2`` within which a candidate of fewer points is preferred.
_TIE = 1e-12


def support_arrays(points: np.ndarray) -> np.ndarray:
    """The minimal enclosing sphere's support of each of ``(count, N, 3)`` float64 point
    sets: ``(count, 5)`` int32 rows ``(i_0, i_1, i_2, i_3, k)`` as
    :func:`._loops.support_loop` writes them (``k`` points, the last index repeated).

    >>> box = np.array([[x, y, z] for x in (0, 2) for y in (0, 1) for z in (0, 1)], float)
    >>> row = support_arrays(np.repeat(box[None], LOOPED, axis=0))[0]
    >>> sphere = formulas(np).sphere_through(tuple(box[row[:4]].ravel()), row[4])
    >>> [round(float(v), 12) for v in sphere]
    [1.0, 0.5, 0.5, 1.5]
    """
    count = len(points)
    if count < LOOPED:
        return _welzl(points)
    xyz = np.ascontiguousarray(np.moveaxis(points, -1, 0))  # (3, count, N)
    out, ball = _chords(xyz)
    todo, stuck = np.arange(count), []
    for _ in range(ROUNDS):
        todo, far = _farthest_outside(xyz, ball, todo)
        if len(todo) == 0:
            break
        for k in (1, 2, 3, 4):
            group = out[todo, 4] == k
            e = todo[group]
            if len(e):
                out[e], ball[:, e], ok = _grow(xyz[:, e], out[e], far[group])
                stuck.append(e[~ok])
        todo = np.setdiff1d(todo, np.concatenate(stuck[-4:]), assume_unique=True)
    rest = np.concatenate([todo, *stuck])
    if len(rest):
        out[rest] = _welzl(points[rest])
    return out


def _welzl(points: np.ndarray) -> np.ndarray:
    """Welzl's loop (:func:`._loops.support_loop`) on Python floats, entry by entry."""
    out = np.zeros((len(points), 5), dtype=np.int32)
    scalar_formulas().support_loop(points.reshape(len(points), -1).tolist(), out)
    return out


def _chords(xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The first support and sphere of each entry: ``q``, the point farthest from point 0,
    and ``r``, the one farthest from ``q`` (``S = {q, r}``, ``B`` their diameter sphere).

    ``B = MB(S)`` as the iteration needs, and often the answer (a box's diagonal).
    """
    n = np.arange(xyz.shape[1])
    q = _farthest(xyz, xyz[:, :, 0])
    r = _farthest(xyz, xyz[:, n, q])
    out = np.c_[q, r, r, r, np.where(q == r, 1, 2)].astype(np.int32)
    ends = tuple(xyz[c, n, e] for e in (q, r, r, r) for c in range(3))
    return out, np.stack(formulas(np).sphere_through(ends, out[:, 4]))


def _farthest(xyz: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Each entry's point farthest from its point ``p`` ``(3, count)`` (the first of ties)."""
    d2 = (xyz[0] - p[0, :, None]) ** 2 + (xyz[1] - p[1, :, None]) ** 2
    far: np.ndarray = np.argmax(d2 + (xyz[2] - p[2, :, None]) ** 2, axis=-1)
    return far


def _farthest_outside(
    xyz: np.ndarray, ball: np.ndarray, todo: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The entries of ``todo`` with a point outside their sphere, and that farthest point."""
    p, b = xyz[:, todo], ball[:, todo, None]
    outside = formulas(np)._outside(p, b)
    d2 = (p[0] - b[0]) ** 2 + (p[1] - b[1]) ** 2 + (p[2] - b[2]) ** 2
    far = np.argmax(np.where(outside, d2, -1.0), axis=-1)
    going = outside.any(axis=-1)
    return todo[going], far[going]


def _grow(
    xyz: np.ndarray, support: np.ndarray, far: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Support, sphere ``(4, A)`` and success of ``MB(S + p)`` for entries of one support
    size ``k``, ``p`` their point ``far``."""
    k = int(support[0, 4])
    slots, sizes = _SLOTS[: 2**k - 1], _SIZES[: 2**k - 1, None]
    n = np.arange(len(far))[:, None]
    idx = np.concatenate(
        [np.broadcast_to(far[:, None, None], (len(far), len(slots), 1)), support[:, slots]],
        axis=-1,
    )  # (A, candidates, 4): p and its partners
    q = tuple(xyz[j % 3][n, idx[..., j // 3]].T for j in range(12))
    F = formulas(np)
    cand = F.sphere_through(q, sizes)  # each (candidates, A)
    held = np.c_[far, support[:, :4]]  # (A, 5): S + p
    outside = F._outside(
        tuple(c[n, held].T[:, None] for c in xyz), tuple(v[None] for v in cand)
    )  # (5, candidates, A)
    r2 = np.where(outside.any(axis=0), np.inf, cand[3])
    least = r2.min(axis=0)
    best = np.argmin(np.where(r2 <= least * (1.0 + _TIE), sizes, 9), axis=0)
    a = n[:, 0]
    grown = np.c_[idx[a, best], _SIZES[best]].astype(np.int32)
    return grown, np.stack([v[best, a] for v in cand]), np.isfinite(least)
