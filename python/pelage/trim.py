"""Trimming: where guides or hairs meet cloth or colliders, and the stored
lengths of a shot."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional, Tuple

import numpy as np

from ._ffi import ffi, lib
from ._util import TRIM_RECORD_DTYPE, Call, ProgressFn, ptr, records, write_bytes
from .errors import check
from .frame import Colliders, Frame
from .groom import Groom
from .mesh import Mesh
from .pipeline import ExpandParams

__all__ = [
    "TrimRecordsInfo",
    "trim_whole",
    "trim_find",
    "trim_shortest",
    "trim_shortest_hairs",
    "trim_records_write",
    "trim_records_info",
    "trim_records_read",
    "trim_lengths_write",
    "trim_lengths_read",
]


@dataclass(frozen=True)
class TrimRecordsInfo:
    """The counts of a trim records file (``PelageTrimRecordsInfo``)."""

    guide_count: int
    points_per_guide: int
    record_count: int


def trim_whole(strand_count: int) -> np.ndarray:
    """Stored lengths of a shot's start: every strand whole (uint16
    ``TRIM_WHOLE``)."""
    return np.full(strand_count, lib.PELAGE_TRIM_WHOLE, np.uint16)


def _lengths(lengths: Any, count: int) -> np.ndarray:
    if not (isinstance(lengths, np.ndarray) and lengths.dtype == np.uint16):
        raise TypeError("lengths: expected a uint16 numpy array (see trim_whole)")
    if not (lengths.flags.c_contiguous and lengths.flags.writeable):
        raise ValueError("lengths: updated in place, so it must be a writable C-contiguous array")
    if lengths.shape != (count,):
        raise ValueError(f"lengths: expected ({count},), got {lengths.shape}")
    return lengths


def trim_find(
    frame: Frame,
    *,
    cloth: Optional[Mesh] = None,
    colliders: Optional[Colliders] = None,
    threads: Optional[int] = None,
    progress: Optional[ProgressFn] = None,
) -> np.ndarray:
    """Where each posed guide of ``frame`` first meets ``cloth`` or enters
    ``colliders`` (``pelage_trim_find``): the records
    (:data:`TRIM_RECORD_DTYPE`), one per guide that meets something."""
    out = np.empty(frame.guide_count, TRIM_RECORD_DTYPE)
    n = ffi.new("size_t *")
    call = Call(threads, progress)
    status = lib.pelage_trim_find(
        frame._get(),
        ffi.NULL if cloth is None else cloth.desc,
        ffi.NULL if colliders is None else colliders.struct,
        call.run(),
        ptr(out, "PelageTrimRecord *"),
        out.shape[0],
        n,
    )
    call.check(status, "pelage_trim_find", [colliders])
    return out[: n[0]]


def trim_shortest(
    groom: Groom, records_: Any, guide_count: int, points_per_guide: int, lengths: np.ndarray
) -> np.ndarray:
    """Shortens ``lengths`` (uint16, one per strand of ``groom``, updated in
    place and returned) to where the strands reach the cloth under
    ``records_`` found on a frame of ``guide_count`` guides
    (``pelage_trim_shortest``)."""
    r = records(records_, TRIM_RECORD_DTYPE, "records")
    lens = _lengths(lengths, groom.strand_count)
    status = lib.pelage_trim_shortest(
        groom._get(), ptr(r, "PelageTrimRecord *"), r.shape[0], guide_count, points_per_guide,
        ptr(lens, "uint16_t *"), lens.shape[0],
    )
    check(status, "pelage_trim_shortest")
    return lens


def trim_shortest_hairs(
    groom: Groom,
    frame: Frame,
    lengths: np.ndarray,
    params: Optional[ExpandParams] = None,
    *,
    cloth: Optional[Mesh] = None,
    colliders: Optional[Colliders] = None,
    threads: Optional[int] = None,
    progress: Optional[ProgressFn] = None,
) -> np.ndarray:
    """Shortens ``lengths`` (updated in place and returned) to where each
    hair's own curve on ``frame`` first meets ``cloth`` or ``colliders``
    (``pelage_trim_shortest_hairs``). On failure ``lengths`` is unchanged."""
    lens = _lengths(lengths, groom.strand_count)
    call = Call(threads, progress)
    p = (params or ExpandParams()).struct(call)
    status = lib.pelage_trim_shortest_hairs(
        groom._get(),
        frame._get(),
        ffi.NULL if cloth is None else cloth.desc,
        ffi.NULL if colliders is None else colliders.struct,
        p,
        ptr(lens, "uint16_t *"),
        lens.shape[0],
    )
    call.check(status, "pelage_trim_shortest_hairs", [colliders])
    return lens


def trim_records_write(records_: Any, guide_count: int, points_per_guide: int) -> bytearray:
    """A trim records file of one frame's records (``pelage_trim_records_write``)."""
    r = records(records_, TRIM_RECORD_DTYPE, "records")
    n = ffi.new("size_t *")
    check(lib.pelage_trim_records_size(r.shape[0], n), "pelage_trim_records_size")
    return write_bytes(
        n[0],
        lambda out, cap, written: lib.pelage_trim_records_write(
            ptr(r, "PelageTrimRecord *"), r.shape[0], guide_count, points_per_guide, out, cap, written
        ),
        "pelage_trim_records_write",
    )


def trim_records_info(data: Any) -> TrimRecordsInfo:
    """The checked header of a trim records file (``pelage_trim_records_info``)."""
    info = ffi.new("PelageTrimRecordsInfo *")
    with ffi.from_buffer(data) as buf:
        check(lib.pelage_trim_records_info(buf, len(buf), info), "pelage_trim_records_info")
    return TrimRecordsInfo(int(info.guide_count), int(info.points_per_guide), int(info.record_count))


def trim_records_read(data: Any) -> Tuple[np.ndarray, TrimRecordsInfo]:
    """Decodes a trim records file (``pelage_trim_records_read``): the
    records and the file's counts."""
    header = trim_records_info(data)
    out = np.empty(header.record_count, TRIM_RECORD_DTYPE)
    info = ffi.new("PelageTrimRecordsInfo *")
    with ffi.from_buffer(data) as buf:
        status = lib.pelage_trim_records_read(buf, len(buf), ptr(out, "PelageTrimRecord *"), out.shape[0], info)
    check(status, "pelage_trim_records_read")
    return out, TrimRecordsInfo(int(info.guide_count), int(info.points_per_guide), int(info.record_count))


def trim_lengths_write(lengths: Any) -> bytearray:
    """A trim lengths file of a shot's stored lengths (``pelage_trim_lengths_write``)."""
    lens = np.ascontiguousarray(lengths, dtype=np.uint16)
    n = ffi.new("size_t *")
    check(lib.pelage_trim_lengths_size(lens.shape[0], n), "pelage_trim_lengths_size")
    return write_bytes(
        n[0],
        lambda out, cap, written: lib.pelage_trim_lengths_write(ptr(lens, "uint16_t *"), lens.shape[0], out, cap, written),
        "pelage_trim_lengths_write",
    )


def trim_lengths_read(data: Any) -> np.ndarray:
    """Decodes a trim lengths file (``pelage_trim_lengths_read``): uint16
    lengths, one per strand."""
    n = ffi.new("size_t *")
    with ffi.from_buffer(data) as buf:
        status = lib.pelage_trim_lengths_read(buf, len(buf), ffi.NULL, 0, n)
        if status != lib.PELAGE_STATUS_CAPACITY_EXCEEDED or n[0] == 0:
            check(status, "pelage_trim_lengths_read")
        out = np.empty(n[0], np.uint16)
        if n[0]:
            status = lib.pelage_trim_lengths_read(buf, len(buf), ptr(out, "uint16_t *"), out.shape[0], n)
            check(status, "pelage_trim_lengths_read")
    return out
