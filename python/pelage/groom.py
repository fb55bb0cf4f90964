"""Grooms: render strands checked once, expanded per frame and patch."""

from __future__ import annotations

from typing import Any, List, Optional

import numpy as np

from ._ffi import ffi, lib
from ._handle import Handle
from ._util import PATCH_DTYPE, Call, ProgressFn, ptr, records
from .errors import check
from .frame import Frame
from .pipeline import ExpandParams, _curves, _Strands

__all__ = ["Groom"]


class Groom(Handle):
    """A groom (``PelageGroom``): render strands (roots, bindings, groom
    records) copied and checked once, then expanded on any frame.

    Thread safety: any number of expansions may run at once (from several
    Python threads, for patches); none during :meth:`close`.
    """

    _free = staticmethod(lib.pelage_groom_free)

    def __init__(self, roots: Any, bindings: Any, grooms: Any) -> None:
        super().__init__()
        strands = _Strands(roots, bindings, grooms)
        out = ffi.new("PelageGroom *")
        check(lib.pelage_groom_new(strands.struct, out), "pelage_groom_new")
        self._ptr = out[0]

    @property
    def strand_count(self) -> int:
        """Strands in the groom (``pelage_groom_strand_count``)."""
        n = ffi.new("size_t *")
        check(lib.pelage_groom_strand_count(self._get(), n), "pelage_groom_strand_count")
        return int(n[0])

    def __len__(self) -> int:
        return self.strand_count

    def _range(self, first: int, count: Optional[int]) -> int:
        return self.strand_count - first if count is None else count

    def expand(
        self,
        frame: Frame,
        first: int = 0,
        count: Optional[int] = None,
        params: Optional[ExpandParams] = None,
        *,
        out: Optional[np.ndarray] = None,
        ids: Optional[np.ndarray] = None,
        threads: Optional[int] = None,
        progress: Optional[ProgressFn] = None,
    ) -> np.ndarray:
        """Expands strands ``first .. first + count`` (default: to the end)
        on ``frame`` (``pelage_groom_expand``); ``out`` and ``ids`` as in
        :func:`pelage.expand`. Returns the (count, points_per_curve, 4)
        float32 control points (``out`` when given)."""
        return self.expand_edited(
            frame, first, count, params, out=out, ids=ids, threads=threads, progress=progress
        )

    def expand_edited(
        self,
        frame: Frame,
        first: int = 0,
        count: Optional[int] = None,
        params: Optional[ExpandParams] = None,
        *,
        lengths: Any = None,
        push_mask: Any = None,
        out: Optional[np.ndarray] = None,
        ids: Optional[np.ndarray] = None,
        threads: Optional[int] = None,
        progress: Optional[ProgressFn] = None,
    ) -> np.ndarray:
        """:meth:`expand` with per-strand edits (``pelage_groom_expand_edited``),
        each indexed over the whole groom: ``lengths`` (uint16 stored lengths,
        ``TRIM_WHOLE`` for none) cut the strands; ``push_mask`` (bool or
        uint8) selects the strands pushed out of the frame's colliders. A
        frame's Python distance field that raises is re-raised here."""
        count = self._range(first, count)
        call = Call(threads, progress)
        p = (params or ExpandParams()).struct(call)
        n = ffi.new("size_t *")
        check(lib.pelage_expand_size(p, n), "pelage_expand_size")
        result, curves, keep = _curves(count, n[0], out, ids)
        edits = ffi.NULL
        if lengths is not None or push_mask is not None:
            edits = ffi.new("PelageStrandEdits *")
            total = self.strand_count
            if lengths is not None:
                lens = np.ascontiguousarray(lengths, dtype=np.uint16)
                if lens.shape != (total,):
                    raise ValueError(f"lengths: expected ({total},), got {lens.shape}")
                keep.append(lens)
                edits.lengths = ptr(lens, "uint16_t *")
            if push_mask is not None:
                mask = np.asarray(push_mask)
                mask = np.ascontiguousarray(mask.view(np.uint8) if mask.dtype == np.bool_ else mask, dtype=np.uint8)
                if mask.shape != (total,):
                    raise ValueError(f"push_mask: expected ({total},), got {mask.shape}")
                keep.append(mask)
                edits.push_mask = ptr(mask, "uint8_t *")
        if edits == ffi.NULL:
            status = lib.pelage_groom_expand(self._get(), frame._get(), first, count, p, curves)
            call.check(status, "pelage_groom_expand", [frame.colliders])
        else:
            status = lib.pelage_groom_expand_edited(self._get(), frame._get(), first, count, edits, p, curves)
            call.check(status, "pelage_groom_expand_edited", [frame.colliders])
        return result

    def lod_counts(self, patches: Any, cutoff: int) -> np.ndarray:
        """How many of each patch's strands the LOD keeping ranks below
        ``cutoff`` keeps (``pelage_groom_lod_counts``): uint32 per patch."""
        pa = records(patches, PATCH_DTYPE, "patches")
        counts = np.empty(pa.shape[0], np.uint32)
        status = lib.pelage_groom_lod_counts(
            self._get(), ptr(pa, "PelagePatch *"), pa.shape[0], cutoff, ptr(counts, "uint32_t *")
        )
        check(status, "pelage_groom_lod_counts")
        return counts

    def __repr__(self) -> str:
        return "Groom(closed)" if self.closed else f"Groom({self.strand_count} strands)"
