r"""A scene that lives across frames: :class:`ShadowScene`.

A renderer adds its geometries once and its objects (placements of a geometry) once,
then each frame sets the objects' world matrices as one ``(N, 4, 4)`` array and fits
all its lights. The cost of a frame grows with the number of objects and lights, not
with the number of triangles:

* what the fits read of a geometry, its **summary** (its own triangles when they are
  few, else the surface of its 26-DOP: a convex polytope of at most a few dozen
  corners that holds it; :mod:`shadowmath._scene._summary`), is computed once per
  geometry and shared by its instances;
* each frame only the objects whose matrix changed are moved to the world (their
  summary triangles, bounding sphere and box);
* each light's fit first **culls** what it need not read, from the objects' bounding
  spheres (:mod:`shadowmath._scene._cull`: a spot light's cone, the objects that may
  hold a cube map's nearest or farthest point, those that may bound a sun's box), then
  fits from the summaries of the rest (:func:`fit_shadow`, :func:`cube_depth_range`,
  :func:`fit_cascades`, :func:`fit_atlas`);
* each map gets its **draw list**: the casters whose sphere reaches into the map's clip
  volume (an empty list: nothing to draw, the map may be skipped).

The fits keep every caster (a summary holds its geometry); the maps may be slightly
larger than those fitted to every triangle (by how much: ``docs/scenes.md``). A caster
left out of a draw list puts no fragment in the map, so a renderer that draws only the
draw lists draws the same maps, texel for texel, as one that draws every caster into
every map, and the same shadows whatever its filter (the reference renderer does, with
``scene_fit="draw_lists"``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from ._boundary._messages import not_affine
from ._boundary._shapes import ArrayLike, Float, Int, Real
from ._boundary._validate import Array, check_faces, is_jax
from ._fits._spec import ShadowMapSpec
from ._fits.atlas._allocate import ShadowAtlas
from ._fits.atlas._door import fit_atlas
from ._fits.atlas._result import AtlasFit
from ._fits.cascades._door import fit_cascades
from ._fits.cascades._result import Cascades
from ._fits.cube._door import cube_depth_range
from ._fits.cube._result import CubeDepthRange
from ._fits.shadow._driver import fit_shadow
from ._fits.shadow._result import ShadowSetup
from ._geometry._cube_faces import cube_face_projection, cube_face_views
from ._math._specialize import formulas
from ._scene import _cull
from ._scene._summary import GeometrySummary, summarize
from .lights import DirectionalLight, PointLight, SpotLight
from .receivers import Mesh, Triangles

__all__ = [
    "GeometrySummary",
    "LightShadows",
    "SceneAtlas",
    "SceneCascades",
    "SceneSummaries",
    "ShadowScene",
    "SummaryFit",
    "fit_summaries",
    "summarize_geometry",
]

IntArray = Int[np.ndarray, " K"]


class LightShadows(NamedTuple):
    """One light's fit and draw lists, from :meth:`ShadowScene.fit`.

    Attributes:
        light: the light as given.
        fit: a :class:`ShadowSetup` (sun, spot) or a :class:`CubeDepthRange` (a point
            light's cube map), or None where ``skipped``.
        draws: one integer array of object indices per map: one map for a sun or a spot
            light, six cube faces (``+X, -X, +Y, -Y, +Z, -Z``) for a point light: the
            casters whose bounding sphere reaches into the map's clip volume. An empty
            array: no caster reaches that map (draw nothing into it; cleared to "far", it
            shadows nothing).
        skipped: "" when fitted; else why not (no caster in the light's reach, or the
            fit's ``ValueError`` message). A skipped light casts no shadow this frame
            (its draws are empty).
    """

    light: PointLight | SpotLight | DirectionalLight
    fit: ShadowSetup | CubeDepthRange | None
    draws: tuple[IntArray, ...]
    skipped: str


class SceneCascades(NamedTuple):
    """A directional light's cascades and their draw lists, from
    :meth:`ShadowScene.fit_cascades`.

    Attributes:
        cascades: the :class:`Cascades` of :func:`fit_cascades` over the scene's bounds.
        draws: one integer array of object indices per cascade.
    """

    cascades: Cascades
    draws: tuple[IntArray, ...]


class SceneAtlas(NamedTuple):
    """A shadow atlas fitted to the scene, with a draw list per tile, from
    :meth:`ShadowScene.fit_atlas`.

    Attributes:
        fit: the :class:`AtlasFit` of :func:`fit_atlas`.
        draws: one integer array of object indices per tile (in the atlas's tile order).
        moved: the objects whose matrix changed since the scene's previous
            :meth:`~ShadowScene.fit_atlas` (every object at the first): give it, with
            this and last frame's ``draws``, to :func:`atlas_redraw`.
    """

    fit: AtlasFit
    draws: tuple[IntArray, ...]
    moved: IntArray


class SceneSummaries(NamedTuple):
    """A scene's world-space summaries as arrays with static shapes (a JAX pytree), from
    :meth:`ShadowScene.summaries`, for :func:`fit_summaries`.

    Attributes:
        triangles: ``(T, 3, 3)`` every object's summary triangles in the world.
        owner: ``(T,)`` integer: the object of each triangle.
        center: ``(N, 3)`` each object's world bounding sphere's centre.
        radius: ``(N,)`` its radius.
        casts: ``(N,)`` bool: the object casts shadows.
        receives: ``(N,)`` bool: it receives them.
    """

    triangles: Float[Array, "T 3 3"]
    owner: Int[Array, " T"]
    center: Float[Array, "N 3"]
    radius: Float[Array, " N"]
    casts: Any
    receives: Any


class SummaryFit(NamedTuple):
    """One light's fit from :func:`fit_summaries`, with its draw lists as masks.

    Attributes:
        fit: a :class:`ShadowSetup` (sun, spot) or :class:`CubeDepthRange` (point light).
        draws: ``(maps, N)`` bool: object ``k`` is drawn into map ``m`` (one map for a
            sun or a spot, six cube faces ``+X, -X, +Y, -Y, +Z, -Z`` for a point light).
    """

    fit: ShadowSetup | CubeDepthRange
    draws: Any


class ShadowScene:
    r"""Geometries and their placements, kept across frames, fitted for many lights.

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> from shadowmath import meshes
        >>> scene = sm.ShadowScene()
        >>> ball = scene.add_geometry(meshes.sphere(0.5))
        >>> floor = scene.add_geometry(meshes.grid((10.0, 10.0)))
        >>> lift = np.eye(4); lift[2, 3] = 2.0
        >>> balls = scene.add_objects(ball, np.stack([lift, lift]))
        >>> ground = scene.add_objects(floor, casts=False, static=True)
        >>> shifted = scene.transforms; shifted[1, 0, 3] = 3.0  # the second ball moves
        >>> scene.set_transforms(shifted)
        >>> spot = sm.SpotLight(np.array([0.0, 0.0, 6.0]), np.array([0.0, 0.0, -1.0]), 0.3)
        >>> sun = sm.DirectionalLight(np.array([0.2, 0.1, 1.0]))
        >>> spot_fit, sun_fit = scene.fit([spot, sun], sm.ShadowMapSpec(1024))
        >>> spot_fit.draws[0].tolist(), sun_fit.draws[0].tolist()  # the ball at x = 3 is culled
        ([0], [0, 1])
    """

    def __init__(self) -> None:
        self._geometries: list[GeometrySummary] = []
        self._geometry_of = np.zeros(0, dtype=np.int64)
        self._casts = np.zeros(0, dtype=bool)
        self._receives = np.zeros(0, dtype=bool)
        self._static = np.zeros(0, dtype=bool)
        self._M = np.zeros((0, 4, 4))
        self._offsets = np.zeros(1, dtype=np.int64)
        self._world = np.zeros((0, 3, 3))  # every object's summary triangles, world space
        self._local = np.zeros((0, 3, 3))  # the same, local (one copy per instance)
        self._local_center = np.zeros((0, 3))
        self._local_radius = np.zeros(0)
        self._owner = np.zeros(0, dtype=np.int64)
        self._center = np.zeros((0, 3))
        self._radius = np.zeros(0)
        self._bounds = np.zeros((0, 2, 3))
        self._moved = np.zeros(0, dtype=np.int64)
        self._moved_since_atlas = np.zeros(0, dtype=bool)

    # -- building -------------------------------------------------------------------
    def add_geometry(
        self, geometry: Mesh | Triangles | Real[ArrayLike, "V 3"] | GeometrySummary
    ) -> int:
        """Add a geometry in local coordinates; returns its index for :meth:`add_objects`.

        Its summary (:mod:`shadowmath._scene._summary`) is computed here, once: about
        5-10 ms, whatever its number of triangles beyond a few thousand; or pass one from
        :func:`summarize_geometry` (a renderer's cache, shared between scenes).

        Arguments:
            geometry: an :class:`~shadowmath.Mesh` (``vertices (V, 3)``, ``faces (F, 3)``),
                :class:`~shadowmath.Triangles` ``(M, 3, 3)``, points ``(V, 3)`` (casters
                drawn as points: their summary is their 26-DOP's corners), or a
                :class:`GeometrySummary`.

        Raises:
            ValueError: naming ``geometry``: wrong shapes, no vertices, non-finite
                values, face indices outside the vertices.
        """
        summary = (
            geometry if isinstance(geometry, GeometrySummary) else summarize_geometry(geometry)
        )
        self._geometries.append(summary)
        return len(self._geometries) - 1

    def add_objects(
        self,
        geometry: int,
        transforms: Real[ArrayLike, "K 4 4"] | Real[ArrayLike, "4 4"] | None = None,
        *,
        casts: bool = True,
        receives: bool = True,
        static: bool = False,
    ) -> IntArray:
        """Place a geometry ``K`` times (instances); returns the new objects' indices.

        Arguments:
            geometry: an index from :meth:`add_geometry`.
            transforms: ``(K, 4, 4)`` or ``(4, 4)`` affine local-to-world matrices
                (column vectors; last row ``(0, 0, 0, 1)``); None: one object, identity.
            casts, receives: whether the objects cast shadows (enter the fits and draw
                lists) and receive them (push the maps' ``far``).
            static: the objects never move: :meth:`set_transforms` refuses to change them.

        Raises:
            ValueError: an unknown ``geometry``, a flag that is not a bool, transforms of
                the wrong shape, non-finite, or not affine.
        """
        if isinstance(geometry, bool) or not isinstance(geometry, int | np.integer):
            raise ValueError(f"geometry: expected an index from add_geometry, got {geometry!r}")
        if not 0 <= geometry < len(self._geometries):
            raise ValueError(
                f"geometry: no geometry {geometry} (the scene has {len(self._geometries)})"
            )
        for name, flag in (("casts", casts), ("receives", receives), ("static", static)):
            if not isinstance(flag, bool | np.bool_):
                raise ValueError(f"{name}: expected a bool, got {flag!r}")
        M = np.eye(4)[None] if transforms is None else _placements("transforms", transforms)
        M = M[None] if M.ndim == 2 else M
        first, K = len(self._M), len(M)
        g = self._geometries[geometry]
        T = len(g.triangles)
        self._geometry_of = np.concatenate([self._geometry_of, np.full(K, geometry)])
        self._casts = np.concatenate([self._casts, np.full(K, bool(casts))])
        self._receives = np.concatenate([self._receives, np.full(K, bool(receives))])
        self._static = np.concatenate([self._static, np.full(K, bool(static))])
        self._M = np.concatenate([self._M, M])
        ends = self._offsets[-1] + T * np.arange(1, K + 1)
        self._offsets = np.concatenate([self._offsets, ends])
        self._world = np.concatenate([self._world, np.zeros((K * T, 3, 3))])
        local = np.broadcast_to(g.triangles, (K, *g.triangles.shape))
        self._local = np.concatenate([self._local, local.reshape(-1, 3, 3)])
        self._local_center = np.concatenate([self._local_center, np.tile(g.center, (K, 1))])
        self._local_radius = np.concatenate([self._local_radius, np.full(K, g.radius)])
        self._owner = np.concatenate([self._owner, np.repeat(np.arange(first, first + K), T)])
        self._center = np.concatenate([self._center, np.zeros((K, 3))])
        self._radius = np.concatenate([self._radius, np.zeros(K)])
        self._bounds = np.concatenate([self._bounds, np.zeros((K, 2, 3))])
        self._moved_since_atlas = np.concatenate([self._moved_since_atlas, np.ones(K, bool)])
        self._place(np.arange(first, first + K))
        return np.arange(first, first + K)

    # -- each frame -----------------------------------------------------------------
    @property
    def transforms(self) -> Float[np.ndarray, "N 4 4"]:
        """``(N, 4, 4)`` a copy of every object's local-to-world matrix, in object order."""
        return self._M.copy()

    @property
    def moved(self) -> IntArray:
        """The objects whose matrix changed at the last :meth:`set_transforms`."""
        return self._moved.copy()

    def set_transforms(self, transforms: Real[ArrayLike, "N 4 4"]) -> None:
        """Set every object's local-to-world matrix for this frame.

        Only the objects whose matrix changed are moved (their summary, sphere and box
        in world space); the others keep last frame's.

        Arguments:
            transforms: ``(N, 4, 4)`` affine matrices, one per object in object order.

        Raises:
            ValueError: naming ``transforms``: another shape than ``(N, 4, 4)``,
                non-finite, not affine (last row not ``(0, 0, 0, 1)``), or changing an
                object added with ``static=True`` (named by its index).
        """
        M = _placements("transforms", transforms)
        if M.shape != self._M.shape:
            raise ValueError(
                f"transforms: expected shape {self._M.shape} (one matrix per object), got {M.shape}"
            )
        moved = np.flatnonzero(np.any(M != self._M, axis=(1, 2)))
        frozen = moved[self._static[moved]]
        if len(frozen):
            raise ValueError(
                f"transforms[{int(frozen[0])}]: object {int(frozen[0])} was added with "
                "static=True; its placement cannot change"
            )
        self._M[moved] = M[moved]
        self._place(moved)
        self._moved = moved
        self._moved_since_atlas[moved] = True

    def summaries(self) -> SceneSummaries:
        """The scene as it is now, as arrays with static shapes for :func:`fit_summaries`
        (copies; ``jax.numpy.asarray`` them to fit under ``jit`` and ``vmap``)."""
        return SceneSummaries(
            self._world.copy(), self._owner.copy(), self._center.copy(), self._radius.copy(),
            self._casts.copy(), self._receives.copy(),
        )  # fmt: skip

    def bounds(self) -> Float[np.ndarray, "2 3"]:
        """``(2, 3)`` the world box ``[min, max]`` of every object (for ``scene_bounds``)."""
        if len(self._bounds) == 0:
            raise ValueError("the scene has no objects: add some with add_objects")
        return np.stack([self._bounds[:, 0].min(axis=0), self._bounds[:, 1].max(axis=0)])

    def fit(
        self,
        lights: Sequence[PointLight | SpotLight | DirectionalLight],
        map_size: int | tuple[int, int] | ShadowMapSpec,
        *,
        up: Real[ArrayLike, "3"] | None = None,
        camera: Real[ArrayLike, "4 4"] | None = None,
    ) -> list[LightShadows]:
        """Fit every light to the scene as it is now, with its draw lists.

        * :class:`DirectionalLight`: :func:`fit_shadow` of every caster's summary,
          ``receivers=`` every receiver's;
        * :class:`SpotLight`: the casters whose sphere reaches into the cone
          (:func:`._cull.spot_visible`), their summaries clipped to the cone's pyramid by
          :func:`fit_shadow`, the receivers in the cone as ``receivers=``;
        * :class:`PointLight`: a cube map, :func:`cube_depth_range` of every caster's
          and receiver's summary (its six faces drawn with :func:`cube_face_views` and
          :func:`cube_face_projection` of that range, the spec's size and border).

        Every map's draw list holds the casters whose sphere reaches into its clip volume
        (:func:`._cull.clip_visible`): leaving the others out changes no texel. With
        ``camera``, a map that no receiver the camera sees reaches is sampled by no pixel:
        its list is empty (a cube face behind the camera needs no drawing).

        Arguments:
            lights: typed lights, each unbatched (``position`` and ``direction`` ``(3,)``).
            map_size: the suns' and spots' map: a size or a :class:`ShadowMapSpec`
                (cube maps use its size and border for their depth range).
            up: an optional up hint for the suns' and spots' frames (see
                :func:`fit_shadow`).
            camera: ``(4, 4)`` the viewer's world-to-clip matrix (projection @ view, any
                graphics API's: only its side planes are read), or None.

        Returns:
            One :class:`LightShadows` per light, in order.

        Raises:
            ValueError: a light that is not a typed, unbatched, finite light; an empty
                scene; a ``camera`` that is not a finite ``(4, 4)`` matrix; what
                :func:`fit_shadow` refuses of ``map_size`` or ``up``.
        """
        spec = map_size if isinstance(map_size, ShadowMapSpec) else ShadowMapSpec(map_size)
        if len(self._M) == 0:
            raise ValueError("the scene has no objects: add some with add_objects")
        checked = [_light(i, light) for i, light in enumerate(lights)]
        up_array = None if up is None else np.asarray(up, dtype=np.float64)
        seen = self._seen(camera)
        return [self._fit_light(light, spec, up_array, seen) for light in checked]

    def fit_cascades(
        self,
        light: DirectionalLight,
        view: Real[ArrayLike, "4 4"],
        projection: Real[ArrayLike, "4 4"],
        map_size: int | tuple[int, int] | ShadowMapSpec,
        **options: Any,
    ) -> SceneCascades:
        """:func:`fit_cascades` over the scene's bounds (:meth:`bounds`), with one draw
        list per cascade: the casters whose sphere reaches into its map
        (:func:`._cull.clip_visible`).

        ``options`` are :func:`fit_cascades`' keywords (``count``, ``stable``,
        ``depth_range``, ``state``...); what it raises, this raises.
        """
        cascades = fit_cascades(light, view, projection, self.bounds(), map_size, **options)
        draws = self._drawn(np.asarray(cascades.world_to_clip))
        return SceneCascades(cascades, tuple(draws))

    def fit_atlas(
        self,
        lights: Sequence[PointLight | SpotLight | DirectionalLight],
        atlas: ShadowAtlas,
        *,
        camera: Real[ArrayLike, "4 4"] | None = None,
        **options: Any,
    ) -> SceneAtlas:
        """:func:`fit_atlas` of the lights over the scene, with one draw list per tile.

        Each light reads what :meth:`fit` reads for it: a spot light the casters whose
        sphere reaches into its cone; a cube-mapped point light (``atlas.light_cube``)
        the objects that may hold its nearest or farthest point; a sun or a point light
        with a 2D map every caster. Each tile draws the casters whose sphere reaches into
        its clip volume (:func:`._cull.clip_visible`), none for a light that failed. The
        lights' summaries go to :func:`fit_atlas` as one ``(L, M, 3, 3)`` batch, each
        light's padded to the longest by repeating its first triangle (which
        changes no extreme; a 2D point light's mean direction is taken over them).

        With ``camera`` (the viewer's world-to-clip matrix), a tile that no receiver the
        camera sees reaches gets an empty list, as in :meth:`fit`.

        ``options`` are :func:`fit_atlas`' keywords (``api``, ``pcf_radius``, ``spec``...);
        the receivers are the scene's. What :func:`fit_atlas` raises, this raises; and a
        scene without casters is refused.
        """
        if not self._casts.any():
            raise ValueError("the scene has no casters: add objects with casts=True")
        checked = [_light(i, light) for i, light in enumerate(lights)]
        seen = self._seen(camera)
        if not isinstance(atlas, ShadowAtlas) or len(atlas.light_cube) != len(checked):
            raise ValueError(
                "atlas: expected the ShadowAtlas of these lights (allocate_atlas with one "
                f"entry per light: {len(checked)})"
            )
        reads = [self._atlas_reads(light, bool(cube)) for light, cube in
                 zip(checked, atlas.light_cube, strict=True)]  # fmt: skip
        longest = max(len(t) for t in reads)
        batch = np.stack(
            [np.concatenate([t, np.repeat(t[:1], longest - len(t), 0)]) for t in reads]
        )
        recv = self._triangles(self._receives) if self._receives.any() else None
        fit = fit_atlas(checked, Triangles(batch), atlas, receivers=recv, **options)
        drawn = self._drawn(np.asarray(fit.world_to_clip), seen)
        failed = [e is not None for e in fit.light_errors]
        tiles = tuple(
            np.zeros(0, np.int64) if failed and failed[light] else d
            for light, d in zip(atlas.tile_light.tolist(), drawn, strict=True)
        )
        moved = np.flatnonzero(self._moved_since_atlas)
        self._moved_since_atlas[:] = False
        return SceneAtlas(fit, tiles, moved)

    def _atlas_reads(
        self, light: PointLight | SpotLight | DirectionalLight, cube: bool
    ) -> np.ndarray:
        """One light's summary triangles ``(M, 3, 3)`` for :func:`fit_atlas`."""
        casts = self._casts
        if isinstance(light, PointLight) and cube:
            position = np.asarray(light.position)
            near, far = _cull.cube_range_candidates(position, self._center, self._radius,
                                                    casts, self._receives)  # fmt: skip
            return np.asarray(self._triangles((near | far) & casts, position).corners)
        if isinstance(light, SpotLight):
            position = np.asarray(light.position)
            reach = casts & _cull.spot_visible(
                position, np.asarray(light.direction), float(light.angle),
                self._center, self._radius,
            )  # fmt: skip
            if not reach.any():  # one triangle behind the spot: its empty fit
                behind = position - np.asarray(light.direction)
                return np.repeat(behind[None, None], 3, axis=1)
            return np.asarray(self._triangles(reach, position).corners)
        return np.asarray(self._triangles(casts).corners)

    def _drawn(
        self, world_to_clip: np.ndarray, seen: np.ndarray | None = None
    ) -> tuple[IntArray, ...]:
        """The draw list of each map ``world_to_clip`` ``(maps, 4, 4)``: the casters whose
        sphere reaches into its clip volume (:func:`._cull.clip_visible`); none where no
        receiver of the mask ``seen`` (those the camera sees) reaches it."""
        casting = np.flatnonzero(self._casts)
        keep = _cull.clip_visible(world_to_clip, self._center[casting], self._radius[casting])
        if seen is not None:
            looked = np.flatnonzero(seen)
            used = _cull.clip_visible(world_to_clip, self._center[looked], self._radius[looked])
            keep = keep & np.any(used, axis=-1)[..., None]
        return tuple(casting[k] for k in keep)

    def _seen(self, camera: object) -> np.ndarray | None:
        """The receivers whose sphere reaches into the camera's clip volume (None: no
        camera), the camera checked."""
        if camera is None:
            return None
        C = np.asarray(camera)
        if C.shape != (4, 4) or not np.issubdtype(C.dtype, np.number):
            raise ValueError(f"camera: expected a (4, 4) world-to-clip matrix, got {C.shape}")
        if not np.all(np.isfinite(C)):
            raise ValueError("camera: contains non-finite values (NaN or inf)")
        seen: np.ndarray = self._receives & _cull.clip_visible(
            C.astype(np.float64), self._center, self._radius
        )
        return seen

    # -- the steps ------------------------------------------------------------------
    def _place(self, objects: IntArray) -> None:
        """Move the summaries, spheres and boxes of ``objects`` (increasing indices) to the
        world, all at once: each triangle row by its object's matrix."""
        if len(objects) == 0:
            return
        every = len(objects) == len(self._M)  # (a renderer moving everything: no gathers)
        if every:
            rows: Any = slice(None)
            owner = self._owner
        else:
            picked = np.zeros(len(self._M), dtype=bool)
            picked[objects] = True
            rows = np.flatnonzero(picked[self._owner])
            owner = self._owner[rows]
        C = self._M[:, :3, :].reshape(-1, 12)[owner].T  # (12, R): each row's matrix entries
        local = self._local[rows]  # (R, 3 corners, 3)
        x, y, z = local[..., 0], local[..., 1], local[..., 2]
        world = np.empty_like(local)  # p_i = A_i0 x + A_i1 y + A_i2 z + t_i, (R, 3) at a time
        for i in range(3):
            a = C[4 * i : 4 * i + 4, :, None]
            world[..., i] = a[0] * x + a[1] * y + a[2] * z + a[3]
        self._world[rows] = world
        lo = np.minimum(np.minimum(world[:, 0], world[:, 1]), world[:, 2])
        hi = np.maximum(np.maximum(world[:, 0], world[:, 1]), world[:, 2])
        starts = np.flatnonzero(np.r_[True, owner[1:] != owner[:-1]])
        self._bounds[objects, 0] = np.minimum.reduceat(lo, starts)
        self._bounds[objects, 1] = np.maximum.reduceat(hi, starts)
        c, r = _cull.world_spheres(self._M[objects], self._local_center[objects],
                                   self._local_radius[objects])  # fmt: skip
        self._center[objects], self._radius[objects] = c, r

    def _rows(self, objects: np.ndarray) -> IntArray:
        """The triangle rows of the objects where the mask ``objects`` holds, in order: each
        object's ``offsets[k] .. offsets[k + 1]`` (a cost by the rows kept, not by all)."""
        k = np.flatnonzero(objects)
        starts, lengths = self._offsets[k], self._offsets[k + 1] - self._offsets[k]
        shift = np.repeat(starts - (np.cumsum(lengths) - lengths), lengths)
        rows: IntArray = np.arange(int(lengths.sum())) + shift
        return rows

    def _triangles(self, objects: np.ndarray, light: np.ndarray | None = None) -> Triangles:
        """The world summary triangles of the objects where ``objects`` (a mask) holds; for
        those whose bounding sphere holds the point ``light``, their own triangles instead
        (a summary around a light would hold the light: a torus around it)."""
        if light is None:
            return Triangles(self._world[self._rows(objects)])
        around = objects & (np.linalg.norm(self._center - light, axis=1) <= self._radius)
        if not around.any():
            return Triangles(self._world[self._rows(objects)])
        parts = [self._world[self._rows(objects & ~around)]]
        for k in np.flatnonzero(around):
            own, M = self._geometries[self._geometry_of[k]].own, self._M[k]
            parts.append(np.einsum("ij,tcj->tci", M[:3, :3], own) + M[:3, 3])
        return Triangles(np.concatenate(parts))

    def _fit_light(
        self, light: PointLight | SpotLight | DirectionalLight, spec: ShadowMapSpec,
        up: np.ndarray | None, seen: np.ndarray | None,
    ) -> LightShadows:  # fmt: skip
        casts, receives = self._casts, self._receives
        if isinstance(light, PointLight):
            return self._fit_cube(light, spec, seen)
        if isinstance(light, SpotLight):
            reach = _cull.spot_visible(
                np.asarray(light.position), np.asarray(light.direction),
                float(light.angle), self._center, self._radius,
            )  # fmt: skip
            casts, receives = casts & reach, receives & reach
        none = (np.zeros(0, np.int64),)
        if not casts.any():
            return LightShadows(light, None, none, "no caster in the light's reach")
        try:
            if isinstance(light, DirectionalLight) and not spec.stable:
                fit = self._fit_sun(light, casts, receives, spec, up)
            else:
                recv = self._triangles(receives) if receives.any() else None
                at = np.asarray(light.position) if isinstance(light, SpotLight) else None
                fit = fit_shadow(light, self._triangles(casts, at), spec, receivers=recv, up=up)
        except ValueError as err:
            return LightShadows(light, None, none, str(err))
        return LightShadows(
            light, fit, self._drawn(np.asarray(fit.blocker_to_clip)[None], seen), ""
        )

    def _fit_sun(
        self, light: DirectionalLight, casts: np.ndarray, receives: np.ndarray,
        spec: ShadowMapSpec, up: np.ndarray | None,
    ) -> ShadowSetup:  # fmt: skip
        """A sun's fit from the objects that may bound its box (:func:`._cull.sun_candidates`
        in the fit's own frame, whose rotation any fit gives: here one of a tetrahedron in
        a caster's sphere, never seen edge-on), checked against every other object
        (:func:`._cull.inside_box`, then their corners) and refitted with those that
        stick out until none does: the fit of every caster's summary."""
        k = int(np.argmax(casts))  # any caster: its sphere's tetrahedron, never seen edge-on
        r = self._radius[k] if self._radius[k] > 0 else 1.0
        one = self._center[k] + r * _TETRAHEDRON
        frame = np.asarray(fit_shadow(light, one, spec, up=up).world_to_light)
        lo, hi = _cull.light_intervals(frame, self._center, self._radius, self._bounds)
        cand_c, cand_r = _cull.sun_candidates(lo, hi, casts, receives)
        while True:
            recv = self._triangles(cand_r) if cand_r.any() else None
            fit = fit_shadow(light, self._triangles(cand_c), spec, receivers=recv, up=up)
            W2L, box = np.asarray(fit.world_to_light), fit.frustum
            shift = W2L[:3, 3] - frame[:3, 3]  # the same rotation: the origins differ
            lo_b, hi_b = lo + shift, hi + shift
            out_c = casts & ~cand_c & ~_cull.inside_box(lo_b, hi_b, box, receiver=False)
            out_r = receives & ~cand_r & ~_cull.inside_box(lo_b, hi_b, box, receiver=True)
            if out_c.any():  # their bounds stick out: read their summaries' corners
                out_c[out_c] = ~self._corners_inside(np.flatnonzero(out_c), W2L, box)
            if not (out_c.any() or out_r.any()):  # a sun uses every caster: count them all
                used = np.asarray(np.count_nonzero(casts[self._owner]))
                return fit._replace(casters_used=used)
            cand_c, cand_r = cand_c | out_c, cand_r | out_r

    def _corners_inside(self, objects: IntArray, world_to_light: np.ndarray, box: Any) -> Any:
        """``(K,)`` the objects whose summary corners all lie in an orthographic fit's box
        (``|x - c_x| <= R_x``, ``|y - c_y| <= R_y``, ``near <= z <= far``): reading them
        would change nothing."""
        picked = np.zeros(len(self._M), dtype=bool)
        picked[objects] = True
        rows = self._rows(picked)
        p = self._world[rows] @ world_to_light[:3, :3].T + world_to_light[:3, 3]
        x, y, z = (p[..., k] for k in range(3))
        ok = (np.abs(x - float(box.center_x)) <= float(box.half_width)) & (
            np.abs(y - float(box.center_y)) <= float(box.half_height)
        )
        ok = np.all(ok & (z >= float(box.near)) & (z <= float(box.far)), axis=1)
        owner = self._owner[rows]  # increasing: each object's rows in one run
        return np.logical_and.reduceat(ok, np.flatnonzero(np.r_[True, owner[1:] != owner[:-1]]))

    def _fit_cube(
        self, light: PointLight, spec: ShadowMapSpec, seen: np.ndarray | None
    ) -> LightShadows:
        position = np.asarray(light.position, dtype=np.float64)
        none = tuple(np.zeros(0, np.int64) for _ in range(6))
        if not self._casts.any():
            return LightShadows(light, None, none, "no caster in the light's reach")
        near, far = _cull.cube_range_candidates(position, self._center, self._radius,
                                                self._casts, self._receives)  # fmt: skip
        recv = self._triangles(far & self._receives) if np.any(far & self._receives) else None
        try:
            fit = cube_depth_range(position, self._triangles((near | far) & self._casts, position),
                                   receivers=recv, map_size=spec.size[0],
                                   border_texels=spec.border)  # fmt: skip
        except ValueError as err:
            return LightShadows(light, None, none, str(err))
        faces = _cube_clip(np, position, fit, spec)
        return LightShadows(light, fit, self._drawn(faces, seen), "")


#: A regular tetrahedron's corners: its shadow along any direction has an area.
_TETRAHEDRON = np.array([[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]])


def _cube_clip(xp: Any, position: Any, fit: CubeDepthRange, spec: ShadowMapSpec) -> Any:
    """``(6, 4, 4)`` world-to-clip of a cube map's faces: :func:`cube_face_projection` of
    ``fit`` with the spec's size and border ring, after :func:`cube_face_views`."""
    P = cube_face_projection(fit.near, fit.far, map_size=spec.size[0], border_texels=spec.border)
    return xp.asarray(P)[..., None, :, :] @ xp.asarray(cube_face_views(position))


def summarize_geometry(
    geometry: Mesh | Triangles | Real[ArrayLike, "V 3"],
) -> GeometrySummary:
    """What a scene's fits read of a geometry (its own triangles when few, else its
    26-DOP's surface, and its bounding sphere: :mod:`shadowmath._scene._summary`), for
    :meth:`ShadowScene.add_geometry`; computed once, it can be kept and shared.

    Arguments:
        geometry: an :class:`~shadowmath.Mesh`, :class:`~shadowmath.Triangles` ``(M, 3,
            3)`` or points ``(V, 3)``, in local coordinates.

    Returns:
        :class:`GeometrySummary` (float64 NumPy).

    Raises:
        ValueError: naming ``geometry``: wrong shapes, no vertices, non-finite values,
            face indices outside the vertices.

    Example:
        >>> import shadowmath as sm
        >>> from shadowmath import meshes
        >>> ball = sm.summarize_geometry(meshes.sphere(1.0, segments=64, rings=32))
        >>> ball.exact, ball.triangles.shape  # 3,968 triangles read as 92
        (False, (92, 3, 3))
    """
    vertices, triangles = _geometry_arrays(geometry)
    return summarize(vertices, triangles)


def _geometry_arrays(geometry: object) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices (V, 3), triangles (F, 3, 3))`` float64 of a geometry, checked."""
    name = "geometry"
    if isinstance(geometry, Mesh):
        V = _finite(f"{name}.vertices", geometry.vertices, 2)
        faces = np.asarray(geometry.faces)
        check_faces(f"{name}.faces", faces, len(V))
        return V, V[faces]
    if isinstance(geometry, Triangles):
        T = _finite(f"{name}.corners", geometry.corners, 3)
        if T.shape[1:] != (3, 3):
            raise ValueError(f"{name}.corners: expected shape (M, 3, 3), got {T.shape}")
        return T.reshape(-1, 3), T
    return _finite(name, geometry, 2), np.zeros((0, 3, 3))


def _finite(name: str, value: object, ndim: int) -> np.ndarray:
    a = np.asarray(value)
    if not (np.issubdtype(a.dtype, np.integer) or np.issubdtype(a.dtype, np.floating)):
        raise ValueError(f"{name}: expected real numbers, got dtype {a.dtype}")
    a = a.astype(np.float64)
    if a.ndim != ndim or a.shape[-1] != 3 or a.shape[0] == 0:
        want = "(V, 3)" if ndim == 2 else "(M, 3, 3)"
        raise ValueError(f"{name}: expected a non-empty array of shape {want}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains non-finite values (NaN or inf)")
    return a


def _placements(name: str, value: object) -> np.ndarray:
    """Affine ``(K, 4, 4)`` or ``(4, 4)`` matrices, float64, checked."""
    M = np.asarray(value)
    if not (np.issubdtype(M.dtype, np.integer) or np.issubdtype(M.dtype, np.floating)):
        raise ValueError(f"{name}: expected real numbers, got dtype {M.dtype}")
    M = M.astype(np.float64)
    if M.ndim not in (2, 3) or M.shape[-2:] != (4, 4):
        raise ValueError(f"{name}: expected shape (N, 4, 4) or (4, 4), got {M.shape}")
    flat = M.reshape(-1, 4, 4)
    bad = np.flatnonzero(~np.all(np.isfinite(flat), axis=(1, 2)))
    if len(bad):
        raise ValueError(f"{name}[{int(bad[0])}]: contains non-finite values (NaN or inf)")
    entries = tuple(flat[:, i // 4, i % 4] for i in range(16))
    bad = np.flatnonzero(~formulas(np).placement_affine(entries, float(np.finfo(np.float64).eps)))
    if len(bad):
        raise ValueError(not_affine(f"{name}[{int(bad[0])}]"))
    return M


def _light(i: int, light: object) -> PointLight | SpotLight | DirectionalLight:
    """A typed, unbatched, finite light (float64 fields)."""
    name = f"lights[{i}]"
    if not isinstance(light, PointLight | SpotLight | DirectionalLight):
        raise ValueError(
            f"{name}: expected an sm.PointLight, sm.SpotLight or sm.DirectionalLight, "
            f"got {type(light).__name__}"
        )
    fields = []
    for field, value in zip(light._fields, light, strict=True):
        a = np.asarray(value, dtype=np.float64)
        want = () if field == "angle" else (3,)
        if a.shape != want:
            raise ValueError(f"{name}.{field}: expected shape {want} (one light), got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{name}.{field}: contains non-finite values (NaN or inf)")
        fields.append(a)
    return type(light)(*fields)


def fit_summaries(
    light: PointLight | SpotLight | DirectionalLight,
    summaries: SceneSummaries,
    map_size: int | tuple[int, int] | ShadowMapSpec,
    *,
    up: Real[ArrayLike, "3"] | None = None,
) -> SummaryFit:
    r"""One light's fit from a scene's summaries, on whole arrays: NumPy or JAX.

    The array form of :meth:`ShadowScene.fit`, with static shapes, so that it runs under
    ``jax.jit`` and ``jax.vmap`` (a batch of lights, or of scenes of one layout): the
    culling rules of :meth:`ShadowScene.fit` give masks instead of dropped objects, and
    a triangle masked out is replaced by one that changes nothing:

    * **spot light**: the casters whose sphere reaches into the cone
      (:func:`._cull.spot_visible`); every other triangle becomes the point
      ``position - direction`` behind the light, which the spot's selection drops;
      receivers likewise. Nothing in the cone: the spot's empty fit.
    * **sun**: every caster; a receiver-only triangle becomes a copy of the first
      caster's (inside the map, before its far plane).
    * **point light**: a cube map's :func:`cube_depth_range` over every caster (others
      replaced by the first caster's triangle) and receiver.

    The draw masks are :meth:`ShadowScene.fit`'s: the casters whose sphere reaches into
    each map's clip volume (:func:`._cull.clip_visible`).

    Unlike :meth:`ShadowScene.fit`, an object whose bounding sphere holds the light is
    read by its summary too (its own triangles would change the shapes): where that
    summary holds the light, the fit refuses it as a caster at the light (NaN under JAX
    transformations, as every refusal).

    Arguments:
        light: a typed light, unbatched (``vmap`` over a batch of them).
        summaries: :meth:`ShadowScene.summaries` (NumPy or JAX arrays).
        map_size: the map's size or :class:`ShadowMapSpec` (a cube map uses its size and
            border).
        up: an optional up hint (sun, spot).

    Returns:
        :class:`SummaryFit`.

    Raises:
        ValueError: a light that is not typed, ``summaries`` that are not
            :class:`SceneSummaries` or have inconsistent shapes; what :func:`fit_shadow`
            and :func:`cube_depth_range` raise (NaN under JAX transformations).

    Example:
        >>> import numpy as np, shadowmath as sm
        >>> from shadowmath import meshes
        >>> scene = sm.ShadowScene()
        >>> box = scene.add_geometry(meshes.box())
        >>> lift = np.eye(4); lift[2, 3] = 2.0
        >>> aside = lift.copy(); aside[0, 3] = 5.0
        >>> _ = scene.add_objects(box, np.stack([lift, aside]))
        >>> spot = sm.SpotLight(np.array([0.0, 0.0, 6.0]), np.array([0.0, 0.0, -1.0]), 0.3)
        >>> one = sm.fit_summaries(spot, scene.summaries(), 512)
        >>> one.draws.tolist(), int(one.fit.casters_used)  # the box aside: masked out
        ([[True, False]], 12)
    """
    if not isinstance(light, PointLight | SpotLight | DirectionalLight):
        raise ValueError(
            "light: expected an sm.PointLight, sm.SpotLight or sm.DirectionalLight, got "
            f"{type(light).__name__}"
        )
    if not isinstance(summaries, SceneSummaries):
        raise ValueError(
            f"summaries: expected ShadowScene.summaries(), got {type(summaries).__name__}"
        )
    T, N = np.shape(summaries.triangles)[0], np.shape(summaries.center)[0]
    if (
        np.shape(summaries.triangles) != (T, 3, 3)
        or np.shape(summaries.owner) != (T,)
        or any(np.shape(a) != (N,) for a in (summaries.radius, summaries.casts, summaries.receives))
    ):
        raise ValueError("summaries: inconsistent shapes (use ShadowScene.summaries())")
    spec = map_size if isinstance(map_size, ShadowMapSpec) else ShadowMapSpec(map_size)
    xp = _namespace(summaries)
    tris, owner = summaries.triangles, summaries.owner
    casts, receives = summaries.casts, summaries.receives
    first = tris[xp.argmax(casts[owner])]  # the first caster's triangle (any, if none)
    if isinstance(light, SpotLight):
        reach = _cull.spot_visible(
            xp.asarray(light.position), xp.asarray(light.direction), light.angle,
            summaries.center, summaries.radius, xp=xp,
        )  # fmt: skip
        behind = xp.asarray(light.position) - xp.asarray(light.direction)
        gone = xp.broadcast_to(behind, (3, 3))
        cast_t = xp.where((casts & reach)[owner][:, None, None], tris, gone)
        recv_t = xp.where((receives & reach)[owner][:, None, None], tris, gone)
        spot = fit_shadow(light, Triangles(cast_t), spec, receivers=Triangles(recv_t), up=up)
        return SummaryFit(spot, _drawn_mask(xp, spot.blocker_to_clip[None], summaries))
    cast_t = xp.where(casts[owner][:, None, None], tris, first)
    recv_t = xp.where(receives[owner][:, None, None], tris, first)
    if isinstance(light, DirectionalLight):
        sun = fit_shadow(light, Triangles(cast_t), spec, receivers=Triangles(recv_t), up=up)
        used = xp.sum(casts[owner])  # the copies of the first caster are not casters
        draws = _drawn_mask(xp, sun.blocker_to_clip[None], summaries)
        return SummaryFit(sun._replace(casters_used=used), draws)
    position = xp.asarray(light.position)
    cube = cube_depth_range(position, Triangles(cast_t), receivers=Triangles(recv_t),
                            map_size=spec.size[0], border_texels=spec.border)  # fmt: skip
    return SummaryFit(cube, _drawn_mask(xp, _cube_clip(xp, position, cube, spec), summaries))


def _drawn_mask(xp: Any, world_to_clip: Any, summaries: SceneSummaries) -> Any:
    """``(maps, N)`` the casters whose sphere reaches into each map's clip volume."""
    keep = _cull.clip_visible(world_to_clip, summaries.center, summaries.radius, xp=xp)
    return keep & summaries.casts


def _namespace(summaries: SceneSummaries) -> Any:
    """``jax.numpy`` when any array is a JAX array (or tracer), else NumPy."""
    if any(is_jax(a) for a in summaries):
        import jax.numpy as jnp

        return jnp
    return np
