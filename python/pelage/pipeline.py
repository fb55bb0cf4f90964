"""The groom pipeline: stamp, bind, groom maps, settle, expand, patches."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any, List, Optional, Tuple, Type, TypeVar

import numpy as np

from ._ffi import ffi, lib
from ._util import (
    BINDING_DTYPE,
    GROOM_DTYPE,
    PATCH_DTYPE,
    ROOT_DTYPE,
    Call,
    ProgressFn,
    new_struct,
    point_rows,
    ptr,
    records,
    rows,
    set_fields,
)
from .errors import check
from .frame import Frame
from .mesh import Guides, Map, MapLike, Mesh, RegionMap

__all__ = [
    "StampInfo",
    "BindInfo",
    "SettleInfo",
    "ExpandParams",
    "stamp",
    "roots_evaluate",
    "bind",
    "groom_evaluate",
    "settle",
    "expand",
    "expand_size",
    "segment_indices",
    "map_mask",
    "patch_plan",
    "patch_boxes",
]

_I = TypeVar("_I")


def _info(cls: Type[_I], struct: Any) -> _I:
    return cls(**{f.name: getattr(struct, f.name) for f in fields(cls)})  # type: ignore[arg-type]


@dataclass(frozen=True)
class StampInfo:
    """What :func:`stamp` did (``PelageStampInfo``)."""

    radius: float
    candidates: int
    pruned: int
    trimmed: int
    degenerate_triangles: int
    passes: int
    filled: int


@dataclass(frozen=True)
class BindInfo:
    """What :func:`bind` found (``PelageBindInfo``)."""

    orphans: int
    mean_guide_length: float
    mean_spacing: float


@dataclass(frozen=True)
class SettleInfo:
    """What :func:`settle` changed (``PelageSettleInfo``)."""

    lifted: int
    unclumped: int
    turned: int
    shortened: int
    unresolved: int


@dataclass
class ExpandParams:
    """Expansion parameters (``PelageExpandParams``); None keeps the C
    default (16 points per strand, pinned ends, orphan length 0.1, width
    scale 1). Threads and progress are each call's keywords."""

    points_per_strand: Optional[int] = None
    pinned: Optional[bool] = None
    orphan_length: Optional[float] = None
    width_scale: Optional[float] = None

    def struct(self, call: Optional[Call] = None) -> Any:
        """A ``PelageExpandParams *`` with these values and ``call``'s run."""
        p = new_struct("PelageExpandParams", lib.pelage_expand_params_defaults())
        end_points = None
        if self.pinned is not None:
            end_points = lib.PELAGE_END_POINTS_PINNED if self.pinned else lib.PELAGE_END_POINTS_RAW
        set_fields(
            p,
            points_per_strand=self.points_per_strand,
            end_points=end_points,
            orphan_length=self.orphan_length,
            width_scale=self.width_scale,
        )
        if call is not None:
            call.fill(p.run)
        return p


def _rest(mesh: Mesh, guides: Guides) -> Any:
    rest = ffi.new("PelageRestPose *")
    rest.mesh = mesh.desc
    rest.guides = guides.desc
    return rest


def _arena(nbytes: int) -> Tuple[np.ndarray, Any]:
    memory = np.empty(max(int(nbytes), 1), np.uint8)
    arena = ffi.new("PelageArena *")
    arena.memory = ptr(memory)
    arena.bytes = int(nbytes)
    return memory, arena[0]


def stamp(
    mesh: Mesh,
    count: int = 0,
    *,
    radius: Optional[float] = None,
    seed: Optional[int] = None,
    density: Optional[MapLike] = None,
    black_scale: Optional[float] = None,
    bald_below: Optional[float] = None,
    progress: Optional[ProgressFn] = None,
) -> Tuple[np.ndarray, StampInfo]:
    """Stamps Poisson-spaced hair roots on ``mesh`` (``pelage_stamp``).

    Args:
        mesh: the rest mesh.
        count: roots wanted (unused when ``radius`` is set).
        radius: a fixed spacing instead of a count.
        seed: the seed of every random choice (default 0).
        density: a map in [0, 1] (see :class:`Map`; default 1).
        black_scale: triangle scale for black (default 0.5).
        bald_below: density below which a triangle gets no roots.
        progress: a progress callback (the stamp runs on the calling thread).

    Returns:
        The roots (:data:`ROOT_DTYPE`, in face order, ``id`` their index)
        and a :class:`StampInfo`. The same inputs give the same bytes.
    """
    keep: List[Any] = []
    p = new_struct("PelageStampParams", lib.pelage_stamp_params_defaults())
    set_fields(p, target_count=count, radius=radius, seed=seed, black_scale=black_scale, bald_below=bald_below)
    if density is not None:
        Map.of(density).fill(p.density, keep)
    call = Call(None, progress)
    call.fill(p.run)
    sizes = ffi.new("size_t[2]")
    check(lib.pelage_stamp_size(mesh.desc, p, sizes, sizes + 1), "pelage_stamp_size")
    memory, arena = _arena(sizes[0])
    roots = np.empty(sizes[1], ROOT_DTYPE)
    n = ffi.new("size_t *")
    info = ffi.new("PelageStampInfo *")
    status = lib.pelage_stamp(mesh.desc, p, arena, ptr(roots, "PelageRoot *"), roots.shape[0], n, info)
    call.check(status, "pelage_stamp")
    return roots[: n[0]], _info(StampInfo, info)


def roots_evaluate(mesh: Mesh, roots: Any) -> Tuple[np.ndarray, np.ndarray]:
    """Positions and unit normals, each (n, 3) float32, of ``roots`` on
    ``mesh`` (``pelage_roots_evaluate``)."""
    r = records(roots, ROOT_DTYPE, "roots")
    out = np.empty((r.shape[0], 2, 3), np.float32)
    status = lib.pelage_roots_evaluate(
        mesh.desc, ptr(r, "PelageRoot *"), r.shape[0], ptr(out), 24, ptr(out[:, 1]) if r.shape[0] else ffi.NULL, 24
    )
    check(status, "pelage_roots_evaluate")
    return out[:, 0], out[:, 1]


def bind(
    mesh: Mesh,
    guides: Guides,
    roots: Any,
    *,
    min_neighbours: Optional[int] = None,
    max_neighbours: Optional[int] = None,
    seed: Optional[int] = None,
    min_normal_dot: Optional[float] = None,
    search_factor: Optional[float] = None,
    max_wrap_slope: Optional[float] = None,
    regions: Optional[RegionMap] = None,
    threads: Optional[int] = None,
    progress: Optional[ProgressFn] = None,
) -> Tuple[np.ndarray, BindInfo]:
    """Binds strands rooted at ``roots`` to the rest ``guides`` on the rest
    ``mesh`` (``pelage_bind``); None keeps each C default (3 to 6
    neighbours, 1 thread).

    Returns:
        The bindings (:data:`BINDING_DTYPE`, one per root) and a
        :class:`BindInfo`. A cancelled call raises :class:`Cancelled`.
    """
    keep: List[Any] = []
    r = records(roots, ROOT_DTYPE, "roots")
    p = new_struct("PelageBindParams", lib.pelage_bind_params_defaults())
    set_fields(
        p,
        min_neighbours=min_neighbours,
        max_neighbours=max_neighbours,
        seed=seed,
        min_normal_dot=min_normal_dot,
        search_factor=search_factor,
        max_wrap_slope=max_wrap_slope,
    )
    if regions is not None:
        regions.fill(p.regions, keep)
    call = Call(threads, progress)
    call.fill(p.run)
    nbytes = ffi.new("size_t *")
    check(lib.pelage_bind_size(mesh.desc, guides.guide_count, nbytes), "pelage_bind_size")
    memory, arena = _arena(nbytes[0])
    bindings = np.empty(r.shape[0], BINDING_DTYPE)
    info = ffi.new("PelageBindInfo *")
    status = lib.pelage_bind(
        _rest(mesh, guides),
        ptr(r, "PelageRoot *"),
        r.shape[0],
        p,
        arena,
        ptr(bindings, "PelageStrandBinding *"),
        bindings.shape[0],
        info,
    )
    call.check(status, "pelage_bind")
    return bindings, _info(BindInfo, info)


def groom_evaluate(
    mesh: Mesh,
    roots: Any,
    *,
    length: Optional[MapLike] = None,
    root_width: Optional[MapLike] = None,
    tip_width: Optional[MapLike] = None,
    bend: Optional[MapLike] = None,
    kink_amplitude: Optional[MapLike] = None,
    kink_frequency: Optional[MapLike] = None,
    clump: Optional[MapLike] = None,
    length_random: Optional[MapLike] = None,
    clump_random: Optional[MapLike] = None,
    seed: Optional[int] = None,
) -> np.ndarray:
    """Samples the groom maps at the roots (``pelage_groom_evaluate``).

    Each map is a :class:`Map`, a number, a per-vertex 1-D array or a UV
    texture 2-D array; None keeps the default (length 1, root width 0.002,
    tip width 0.0005, bend 0, kink 0 at 3 waves, clump 0, no random
    variation of length or clump: ``length_random`` and ``clump_random``,
    0 to 1, let each strand keep ``1 - v u`` of it, ``u`` uniform per strand id).

    Returns:
        The groom records (:data:`GROOM_DTYPE`), one per root.
    """
    keep: List[Any] = []
    maps = new_struct("PelageGroomMaps", lib.pelage_groom_maps_defaults())
    for name, value in (
        ("length", length),
        ("root_width", root_width),
        ("tip_width", tip_width),
        ("bend", bend),
        ("kink_amplitude", kink_amplitude),
        ("kink_frequency", kink_frequency),
        ("clump", clump),
        ("length_random", length_random),
        ("clump_random", clump_random),
    ):
        if value is not None:
            Map.of(value).fill(getattr(maps, name), keep)
    set_fields(maps, seed=seed)
    r = records(roots, ROOT_DTYPE, "roots")
    grooms = np.empty(r.shape[0], GROOM_DTYPE)
    status = lib.pelage_groom_evaluate(
        mesh.desc, maps, ptr(r, "PelageRoot *"), r.shape[0], ptr(grooms, "PelageStrandGroom *"), grooms.shape[0]
    )
    check(status, "pelage_groom_evaluate")
    return grooms


def settle(
    mesh: Mesh,
    guides: Guides,
    roots: Any,
    bindings: Any,
    grooms: np.ndarray,
    params: Optional[ExpandParams] = None,
    *,
    threads: Optional[int] = None,
    progress: Optional[ProgressFn] = None,
) -> SettleInfo:
    """Settles strands out of the body at the rest pose (``pelage_settle``),
    updating ``grooms`` (a writable C-contiguous :data:`GROOM_DTYPE` array)
    in place. A cancelled call raises :class:`Cancelled`, with some strands
    settled and the rest unchanged."""
    r = records(roots, ROOT_DTYPE, "roots")
    b = records(bindings, BINDING_DTYPE, "bindings")
    g = records(grooms, GROOM_DTYPE, "grooms", writable=True)
    if not (r.shape[0] == b.shape[0] == g.shape[0]):
        raise ValueError("roots, bindings and grooms must have the same length")
    call = Call(threads, progress)
    p = (params or ExpandParams()).struct(call)
    nbytes = ffi.new("size_t *")
    check(lib.pelage_settle_size(mesh.desc, guides.guide_count, p, nbytes), "pelage_settle_size")
    memory, arena = _arena(nbytes[0])
    info = ffi.new("PelageSettleInfo *")
    status = lib.pelage_settle(
        _rest(mesh, guides),
        ptr(r, "PelageRoot *"),
        ptr(b, "PelageStrandBinding *"),
        ptr(g, "PelageStrandGroom *"),
        r.shape[0],
        p,
        arena,
        info,
    )
    call.check(status, "pelage_settle")
    return _info(SettleInfo, info)


def expand_size(params: Optional[ExpandParams] = None) -> int:
    """Control points written per curve (``pelage_expand_size``)."""
    n = ffi.new("size_t *")
    check(lib.pelage_expand_size((params or ExpandParams()).struct(), n), "pelage_expand_size")
    return int(n[0])


class _Strands:
    """A ``PelageStrands`` over three record arrays of one length."""

    def __init__(self, roots: Any, bindings: Any, grooms: Any) -> None:
        self.roots = records(roots, ROOT_DTYPE, "roots")
        self.bindings = records(bindings, BINDING_DTYPE, "bindings")
        self.grooms = records(grooms, GROOM_DTYPE, "grooms")
        if not (self.roots.shape[0] == self.bindings.shape[0] == self.grooms.shape[0]):
            raise ValueError("roots, bindings and grooms must have the same length")
        s = ffi.new("PelageStrands *")
        s.roots = ptr(self.roots, "PelageRoot *")
        s.bindings = ptr(self.bindings, "PelageStrandBinding *")
        s.grooms = ptr(self.grooms, "PelageStrandGroom *")
        s.count = self.roots.shape[0]
        self.struct = s

    def __len__(self) -> int:
        return int(self.roots.shape[0])


def _curves(count: int, per_curve: int, out: Optional[np.ndarray], ids: Optional[np.ndarray]) -> Tuple[np.ndarray, Any, List[Any]]:
    """The output curves: ``out`` (or a new (count, per_curve, 4) array)
    and the ``PelageCurves *`` over it."""
    if out is None:
        out = np.empty((count, per_curve, 4), np.float32)
    view, stride = point_rows(out, 4, "out")
    if view.shape[0] < count * per_curve:
        raise ValueError(f"out: holds {view.shape[0]} points, {count * per_curve} needed")
    keep: List[Any] = [view]
    c = ffi.new("PelageCurves *")
    c.points = ptr(view)
    c.point_stride = stride
    c.point_capacity = view.shape[0]
    if ids is not None:
        if not (isinstance(ids, np.ndarray) and ids.dtype == np.uint32 and ids.flags.c_contiguous and ids.flags.writeable):
            raise TypeError("ids: expected a writable C-contiguous uint32 array")
        if ids.shape[0] < count:
            raise ValueError(f"ids: holds {ids.shape[0]} entries, {count} needed")
        c.curve_ids = ptr(ids, "uint32_t *")
    return out, c, keep


def expand(
    frame: Frame,
    roots: Any,
    bindings: Any,
    grooms: Any,
    params: Optional[ExpandParams] = None,
    *,
    out: Optional[np.ndarray] = None,
    ids: Optional[np.ndarray] = None,
    threads: Optional[int] = None,
    progress: Optional[ProgressFn] = None,
) -> np.ndarray:
    """Expands render curves on ``frame`` (``pelage_expand``), checking
    every record (keep a :class:`Groom` across frames instead).

    Args:
        out: optional float32 output, written in place: (strands,
            points_per_curve, 4) or any rows of at least 4 packed floats
            equally spaced (x, y, z, radius first). Default: a new array.
        ids: optional uint32 array that receives each curve's strand id.

    Returns:
        ``out``: float4 control points, ``expand_size(params)`` per curve.
    """
    strands = _Strands(roots, bindings, grooms)
    call = Call(threads, progress)
    p = (params or ExpandParams()).struct(call)
    n = ffi.new("size_t *")
    check(lib.pelage_expand_size(p, n), "pelage_expand_size")
    result, curves, keep = _curves(len(strands), n[0], out, ids)
    status = lib.pelage_expand(frame._get(), strands.struct, p, curves)
    call.check(status, "pelage_expand", [frame.colliders])
    return result


def segment_indices(curve_count: int, points_per_curve: int) -> np.ndarray:
    """Embree's index buffer for curves stored back to back
    (``pelage_curves_segment_indices``): uint32, points_per_curve - 3
    segments per curve."""
    capacity = curve_count * max(points_per_curve - 3, 0)
    indices = np.empty(capacity, np.uint32)
    status = lib.pelage_curves_segment_indices(curve_count, points_per_curve, ptr(indices, "uint32_t *"), capacity)
    check(status, "pelage_curves_segment_indices")
    return indices


def map_mask(mesh: Mesh, map: MapLike, roots: Any, threshold: float = 0.5) -> np.ndarray:
    """Where ``map`` is at least ``threshold`` at each root
    (``pelage_map_mask``): a bool array, for ``push_mask``."""
    keep: List[Any] = []
    cmap = ffi.new("PelageMap *")
    Map.of(map).fill(cmap, keep)
    r = records(roots, ROOT_DTYPE, "roots")
    mask = np.zeros(r.shape[0], np.uint8)
    status = lib.pelage_map_mask(mesh.desc, cmap, ptr(r, "PelageRoot *"), r.shape[0], threshold, ptr(mask, "uint8_t *"))
    check(status, "pelage_map_mask")
    return mask.view(np.bool_)


def patch_plan(mesh: Mesh, roots: Any, patch_size: int) -> Tuple[np.ndarray, np.ndarray]:
    """Orders strands into patches (``pelage_patch_plan``).

    Returns:
        ``order`` (uint32: the strand to place k-th; reorder roots,
        bindings and grooms with ``a[order]``) and the patches
        (:data:`PATCH_DTYPE`).
    """
    r = records(roots, ROOT_DTYPE, "roots")
    order = np.empty(r.shape[0], np.uint32)
    capacity = -(-r.shape[0] // patch_size) if patch_size > 0 else 0
    patches = np.empty(capacity, PATCH_DTYPE)
    n = ffi.new("size_t *")
    status = lib.pelage_patch_plan(
        mesh.desc, ptr(r, "PelageRoot *"), r.shape[0], patch_size, ptr(order, "uint32_t *"),
        ptr(patches, "PelagePatch *"), capacity, n,
    )
    check(status, "pelage_patch_plan")
    return order, patches[: n[0]]


def patch_boxes(
    frame: Frame,
    roots: Any,
    bindings: Any,
    grooms: Any,
    patches: Any,
    params: Optional[ExpandParams] = None,
    *,
    threads: Optional[int] = None,
    progress: Optional[ProgressFn] = None,
) -> np.ndarray:
    """The box of each patch on ``frame`` (``pelage_patch_boxes``): a
    (patches, 2, 3) float32 array of low and high corners."""
    strands = _Strands(roots, bindings, grooms)
    pa = records(patches, PATCH_DTYPE, "patches")
    call = Call(threads, progress)
    p = (params or ExpandParams()).struct(call)
    boxes = np.empty((pa.shape[0], 2, 3), np.float32)
    status = lib.pelage_patch_boxes(
        frame._get(), strands.struct, p, ptr(pa, "PelagePatch *"), pa.shape[0], ptr(boxes, "float *")
    )
    call.check(status, "pelage_patch_boxes")
    return boxes
