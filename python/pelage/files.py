"""The groom file (a groom's rest guides and render strands) and guide
caches (a frame's posed guides, coded against a groom file)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional, Sequence

import numpy as np

from ._ffi import ffi, lib
from ._util import BINDING_DTYPE, GROOM_DTYPE, PATCH_DTYPE, ROOT_DTYPE, Call, ProgressFn, ptr, records, write_bytes
from .errors import check
from .frame import Frame
from .pipeline import _Strands

__all__ = [
    "GroomFileInfo",
    "GroomFile",
    "GuideSet",
    "GuideCacheInfo",
    "groom_file_write",
    "groom_file_info",
    "groom_file_read",
    "guide_cache_size",
    "guide_cache_write",
    "guide_cache_info",
    "guide_cache_read",
]


@dataclass(frozen=True)
class GroomFileInfo:
    """The counts and id in a groom file's header (``PelageGroomFileInfo``)."""

    guide_count: int
    points_per_guide: int
    strand_count: int
    patch_count: int
    id: int


@dataclass(frozen=True)
class GuideSet:
    """The guides a guide cache is coded against (``PelageGuideSet``), as a
    groom file gives them: roots, (guides, points_per_guide, 3) float32
    rest points in their root frames, and the groom file's id."""

    guide_roots: np.ndarray
    guide_points: np.ndarray
    groom_id: int

    @property
    def guide_count(self) -> int:
        """Guides."""
        return int(self.guide_roots.shape[0])

    @property
    def points_per_guide(self) -> int:
        """Points per guide."""
        return int(self.guide_points.shape[1])

    def _struct(self) -> Any:
        roots = records(self.guide_roots, ROOT_DTYPE, "guide_roots")
        points = np.ascontiguousarray(self.guide_points, dtype=np.float32)
        if points.ndim != 3 or points.shape[0] != roots.shape[0] or points.shape[2] != 3:
            raise ValueError(f"guide_points: expected ({roots.shape[0]}, points_per_guide, 3), got {points.shape}")
        s = ffi.new("PelageGuideSet *")
        s.guide_roots = ptr(roots, "PelageRoot *")
        s.guide_points = ptr(points, "float *")
        s.guide_count = roots.shape[0]
        s.points_per_guide = points.shape[1]
        s.groom_id = self.groom_id
        return s, (roots, points)


@dataclass(frozen=True)
class GroomFile:
    """A groom file's contents (``pelage_groom_file_read``)."""

    info: GroomFileInfo
    guide_roots: np.ndarray
    guide_points: np.ndarray
    roots: np.ndarray
    bindings: np.ndarray
    grooms: np.ndarray
    patches: np.ndarray

    @property
    def guide_set(self) -> GuideSet:
        """The guides a guide cache of this groom is coded against."""
        return GuideSet(self.guide_roots, self.guide_points, self.info.id)


@dataclass(frozen=True)
class GuideCacheInfo:
    """The counts in a guide cache's header (``PelageGuideCacheInfo``)."""

    guide_count: int
    points_per_guide: int
    sample_count: int
    exact: bool
    groom_id: int


def groom_file_write(
    rest_frame: Frame,
    guide_roots: Any,
    roots: Any,
    bindings: Any,
    grooms: Any,
    patches: Any = None,
) -> bytearray:
    """A groom file (``pelage_groom_file_write``): ``rest_frame`` is the rest
    mesh's frame posed with the rest guides (rooted at ``guide_roots``);
    the strands in patch order when there are ``patches``."""
    strands = _Strands(roots, bindings, grooms)
    groots = records(guide_roots, ROOT_DTYPE, "guide_roots")
    pa = records(np.empty(0, PATCH_DTYPE) if patches is None else patches, PATCH_DTYPE, "patches")
    desc = ffi.new("PelageGroomFileDesc *")
    desc.rest_frame = rest_frame._get()
    desc.guide_roots = ptr(groots, "PelageRoot *")
    desc.strands = strands.struct[0]
    desc.patches = ptr(pa, "PelagePatch *") if pa.shape[0] else ffi.NULL
    desc.patch_count = pa.shape[0]
    n = ffi.new("size_t *")
    status = lib.pelage_groom_file_write(desc, ffi.NULL, 0, n)
    if status != lib.PELAGE_STATUS_CAPACITY_EXCEEDED:
        check(status, "pelage_groom_file_write")
    return write_bytes(
        n[0], lambda out, cap, written: lib.pelage_groom_file_write(desc, out, cap, written), "pelage_groom_file_write"
    )


def groom_file_info(data: Any) -> GroomFileInfo:
    """A groom file's checked header (``pelage_groom_file_info``)."""
    info = ffi.new("PelageGroomFileInfo *")
    with ffi.from_buffer(data) as buf:
        check(lib.pelage_groom_file_info(buf, len(buf), info), "pelage_groom_file_info")
    return GroomFileInfo(
        int(info.guide_count), int(info.points_per_guide), int(info.strand_count), int(info.patch_count), int(info.id)
    )


def groom_file_read(data: Any) -> GroomFile:
    """Reads a whole groom file (``pelage_groom_file_read``), every record
    checked."""
    info = groom_file_info(data)
    g, s = info.guide_count, info.strand_count
    out = GroomFile(
        info,
        np.empty(g, ROOT_DTYPE),
        np.empty((g, info.points_per_guide, 3), np.float32),
        np.empty(s, ROOT_DTYPE),
        np.empty(s, BINDING_DTYPE),
        np.empty(s, GROOM_DTYPE),
        np.empty(info.patch_count, PATCH_DTYPE),
    )
    b = ffi.new("PelageGroomFileBuffers *")
    b.guide_roots = ptr(out.guide_roots, "PelageRoot *")
    b.guide_points = ptr(out.guide_points, "float *")
    b.guide_capacity = g
    b.roots = ptr(out.roots, "PelageRoot *")
    b.bindings = ptr(out.bindings, "PelageStrandBinding *")
    b.grooms = ptr(out.grooms, "PelageStrandGroom *")
    b.strand_capacity = s
    b.patches = ptr(out.patches, "PelagePatch *")
    b.patch_capacity = info.patch_count
    with ffi.from_buffer(data) as buf:
        check(lib.pelage_groom_file_read(buf, len(buf), b), "pelage_groom_file_read")
    return out


def guide_cache_size(guide_count: int, points_per_guide: int, sample_count: int = 1, exact: bool = False) -> int:
    """The most bytes a guide cache takes (``pelage_guide_cache_size``)."""
    n = ffi.new("size_t *")
    check(
        lib.pelage_guide_cache_size(guide_count, points_per_guide, sample_count, 1 if exact else 0, n),
        "pelage_guide_cache_size",
    )
    return int(n[0])


def guide_cache_write(
    guides: GuideSet,
    samples: Sequence[Frame],
    *,
    exact: bool = False,
    progress: Optional[ProgressFn] = None,
) -> bytearray:
    """One frame's guide cache (``pelage_guide_cache_write``): ``samples``
    are the shutter samples' frames, posed with their guides; quantized
    (default) or ``exact`` float32. Codes on the calling thread."""
    set_struct, keep = guides._struct()
    frames = ffi.new("PelageFrame[]", [f._get() for f in samples])
    capacity = guide_cache_size(guides.guide_count, guides.points_per_guide, len(samples), exact)
    call = Call(None, progress)
    run = call.run()
    return write_bytes(
        capacity,
        lambda out, cap, written: lib.pelage_guide_cache_write(
            set_struct, frames, len(samples), 1 if exact else 0, run, out, cap, written
        ),
        "pelage_guide_cache_write",
        call,
    )


def guide_cache_info(data: Any) -> GuideCacheInfo:
    """A guide cache's checked header (``pelage_guide_cache_info``)."""
    info = ffi.new("PelageGuideCacheInfo *")
    with ffi.from_buffer(data) as buf:
        check(lib.pelage_guide_cache_info(buf, len(buf), info), "pelage_guide_cache_info")
    return GuideCacheInfo(
        int(info.guide_count), int(info.points_per_guide), int(info.sample_count), bool(info.exact), int(info.groom_id)
    )


def guide_cache_read(
    data: Any,
    guides: GuideSet,
    frame: Frame,
    sample: int = 0,
    *,
    threads: Optional[int] = None,
    progress: Optional[ProgressFn] = None,
) -> None:
    """Decodes shutter sample ``sample`` of a guide cache into ``frame``'s
    posed guides (``pelage_guide_cache_read``)."""
    set_struct, keep = guides._struct()
    call = Call(threads, progress)
    with ffi.from_buffer(data) as buf:
        status = lib.pelage_guide_cache_read(buf, len(buf), set_struct, sample, frame._get(), call.run())
    call.check(status, "pelage_guide_cache_read")
