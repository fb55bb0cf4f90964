"""Frames (a deformed mesh with posed guides) and colliders."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, List, Optional, Sequence, Tuple

import numpy as np

from ._ffi import ffi, lib
from ._handle import Handle
from ._util import Call, ProgressFn, ptr, rows
from .errors import check
from .mesh import Guides, Mesh

if TYPE_CHECKING:
    from .sim import Sim

__all__ = ["Frame", "Colliders", "DistanceFn"]

#: A signed distance field (negative inside): gets a read-only (n, 3)
#: float32 array of points, valid during the call only, and returns n
#: distances (anything numpy turns into n floats).
DistanceFn = Callable[[np.ndarray], Any]


class Colliders:
    """What guides (a step, trimming) or pushed render strands collide with
    (``PelageColliders``).

    Args:
        spheres: (n, 4) float32 rows (centre x, y, z, radius), read in place
            when packed float32.
        capsules: (n, 7) rows (a x, y, z, b x, y, z, radius).
        planes: (n, 4) rows (normal x, y, z, offset): the solid side is
            dot(normal, p) < offset.
        body: collide with the frame's (deformed) mesh as a solid.
        distance: a Python signed distance field (:data:`DistanceFn`).

    The distance field is called from the C call's worker threads, with a
    batch of points per call (pelage asks for many at once) and the GIL
    held for it. An exception it raises gives NaN distances, which fail the
    C call with NON_FINITE; the wrapper then re-raises the exception itself.
    """

    def __init__(
        self,
        spheres: Any = None,
        capsules: Any = None,
        planes: Any = None,
        body: bool = False,
        distance: Optional[DistanceFn] = None,
    ) -> None:
        empty = np.empty((0, 4), np.float32)
        self.spheres = rows(empty if spheres is None else spheres, np.float32, 4, "spheres")
        self.capsules = rows(np.empty((0, 7), np.float32) if capsules is None else capsules, np.float32, 7, "capsules")
        self.planes = rows(empty if planes is None else planes, np.float32, 4, "planes")
        for name, arr in (("spheres", self.spheres), ("capsules", self.capsules), ("planes", self.planes)):
            if arr.shape[0] and not arr.flags.c_contiguous:
                setattr(self, name, np.ascontiguousarray(arr))
        self.body = bool(body)
        self.distance = distance
        self._errors: List[BaseException] = []
        self._handle = ffi.new_handle(self) if distance is not None else None
        c = ffi.new("PelageColliders *")
        c.spheres = ptr(self.spheres, "PelageSphere *")
        c.sphere_count = self.spheres.shape[0]
        c.capsules = ptr(self.capsules, "PelageCapsule *")
        c.capsule_count = self.capsules.shape[0]
        c.planes = ptr(self.planes, "PelagePlane *")
        c.plane_count = self.planes.shape[0]
        c.body = 1 if self.body else 0
        if self._handle is not None:
            c.distance = _DISTANCE
            c.distance_user_data = self._handle
        self._struct = c

    @property
    def struct(self) -> Any:
        """The ``PelageColliders *`` (valid while this object lives)."""
        return self._struct

    def _take_errors(self) -> List[BaseException]:
        errors, self._errors = self._errors, []
        return errors


@ffi.callback("PelageDistanceFn")
def _DISTANCE(user_data: Any, points: Any, count: int, distances: Any) -> None:
    if count == 0:
        return
    colliders: Colliders = ffi.from_handle(user_data)
    out = np.frombuffer(ffi.buffer(distances, 4 * count), dtype=np.float32)
    try:
        pts = np.frombuffer(ffi.buffer(points, 12 * count), dtype=np.float32).reshape(count, 3)
        pts.flags.writeable = False
        result = np.asarray(colliders.distance(pts), dtype=np.float32)  # type: ignore[misc]
        out[:] = result.reshape(count)
    except BaseException as error:  # noqa: BLE001 - re-raised by the wrapper
        colliders._errors.append(error)
        out[:] = np.nan


class Frame(Handle):
    """One frame (``PelageFrame``): the deformed mesh, copied and checked,
    and its posed guides, ready for any number of expansions.

    Args:
        mesh: the deformed mesh (copied: it may change afterwards).
        guide_count: the guides it will be posed with.
        points_per_strand: points the guides are resampled to (2..64), the
            expansions' ``points_per_strand``.

    Thread safety: calls that read a frame (expansions, :meth:`inside`,
    trimming) may run at once from several Python threads; none while
    :meth:`set_guides`, :meth:`set_sim_guides`, :meth:`set_colliders` or
    :meth:`close` runs.
    """

    _free = staticmethod(lib.pelage_frame_free)

    def __init__(self, mesh: Mesh, guide_count: int, points_per_strand: int = 16) -> None:
        super().__init__()
        out = ffi.new("PelageFrame *")
        check(lib.pelage_frame_new(mesh.desc, guide_count, points_per_strand, out), "pelage_frame_new")
        self._ptr = out[0]
        self.guide_count = int(guide_count)
        self.points_per_strand = int(points_per_strand)
        self.vertex_count = mesh.vertex_count
        self.colliders: Optional[Colliders] = None

    def set_guides(
        self, guides: Guides, *, threads: Optional[int] = None, progress: Optional[ProgressFn] = None
    ) -> None:
        """Poses the frame's guides (``pelage_frame_set_guides``). Refused
        guides leave the frame as it was; once checked, a cancelled call
        leaves it without guides until guides are set again."""
        call = Call(threads, progress)
        status = lib.pelage_frame_set_guides(self._get(), guides.desc, call.run())
        call.check(status, "pelage_frame_set_guides")

    def set_sim_guides(
        self, sim: "Sim", *, threads: Optional[int] = None, progress: Optional[ProgressFn] = None
    ) -> None:
        """Poses the frame's guides with ``sim``'s posed guides of its last
        step (``pelage_frame_set_sim_guides``)."""
        call = Call(threads, progress)
        status = lib.pelage_frame_set_sim_guides(self._get(), sim._get(), call.run())
        call.check(status, "pelage_frame_set_sim_guides")

    def set_colliders(
        self,
        colliders: Optional[Colliders],
        *,
        threads: Optional[int] = None,
        progress: Optional[ProgressFn] = None,
    ) -> None:
        """Sets the colliders pushed strands are pushed out of
        (``pelage_frame_set_colliders``; None clears them). The frame keeps
        ``colliders`` (and its distance field) alive until replaced."""
        call = Call(threads, progress)
        struct = ffi.NULL if colliders is None else colliders.struct
        status = lib.pelage_frame_set_colliders(self._get(), struct, call.run())
        call.check(status, "pelage_frame_set_colliders", [colliders])
        self.colliders = colliders

    @property
    def origin(self) -> Tuple[float, float, float]:
        """Where the frame's local space sits in the host's world
        (``pelage_frame_origin``; set with ``pelage_frame_set_origin``):
        world = origin + local, in doubles. The frame's mesh, guides,
        colliders and outputs are relative to it: a character far from the
        world's origin keeps float32's precision relative to an origin near
        it, and a simulation carries its state across frames whose origins
        differ. Setting it relabels the frame; it moves nothing already in
        it."""
        out = ffi.new("double[3]")
        check(lib.pelage_frame_origin(self._get(), out), "pelage_frame_origin")
        return (out[0], out[1], out[2])

    @origin.setter
    def origin(self, origin: Sequence[float]) -> None:
        values = [float(c) for c in origin]
        if len(values) != 3:
            raise ValueError("origin: 3 values")
        check(lib.pelage_frame_set_origin(self._get(), ffi.new("double[3]", values)), "pelage_frame_set_origin")

    def inside(
        self, points: Any, *, threads: Optional[int] = None, progress: Optional[ProgressFn] = None
    ) -> np.ndarray:
        """Whether each of the (n, 3) points is inside the body of the frame's
        mesh (``pelage_frame_inside``): a bool array of n."""
        inside = self._per_point("pelage_frame_inside", points, np.uint8, "uint8_t *", threads, progress)
        return inside.view(np.bool_)

    def signed_distance(
        self, points: Any, *, threads: Optional[int] = None, progress: Optional[ProgressFn] = None
    ) -> np.ndarray:
        """The signed distance from each of the (n, 3) points to the frame's
        mesh (``pelage_frame_signed_distance``): negative inside by the
        inside rule of :meth:`inside`; a float32 array of n."""
        return self._per_point("pelage_frame_signed_distance", points, np.float32, "float *", threads, progress)

    def _per_point(
        self,
        name: str,
        points: Any,
        dtype: Any,
        c_type: str,
        threads: Optional[int],
        progress: Optional[ProgressFn],
    ) -> np.ndarray:
        """Calls the query ``name`` on the (n, 3) points; its answer per point."""
        pts = rows(points, np.float32, 3, "points")
        out = np.zeros(pts.shape[0], dtype)
        call = Call(threads, progress)
        stride = int(pts.strides[0]) if pts.shape[0] > 1 else 12
        status = getattr(lib, name)(self._get(), ptr(pts), stride, pts.shape[0], call.run(), ptr(out, c_type))
        call.check(status, name)
        return out

    def _release(self) -> None:
        self.colliders = None

    def __repr__(self) -> str:
        state = "closed" if self.closed else f"{self.guide_count} guides x {self.points_per_strand} points"
        return f"Frame({state})"


