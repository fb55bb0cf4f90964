"""pelage: fur generation for creature VFX, from Python.

A thin, Pythonic layer over pelage's C API (``include/pelage.h``), loaded
with cffi in ABI mode from the shared library bundled in this package:

* numpy arrays in and out, read and written in place where the layouts
  allow (record arrays of :data:`ROOT_DTYPE`, :data:`BINDING_DTYPE`,
  :data:`GROOM_DTYPE` ... are the C structs byte for byte);
* every status other than OK raises a :class:`PelageError` subclass
  carrying ``pelage_last_error()``'s message;
* long calls release the GIL (cffi does for every C call) and take
  ``threads`` and a ``progress`` callback that cancels by returning False
  (:class:`Cancelled`);
* :class:`Frame`, :class:`Groom` and :class:`Sim` own their C handles and
  release them on ``close()`` or at the end of a ``with`` block.

A groom, from a mesh to render curves::

    mesh = pelage.Mesh(positions, triangles)
    guide_roots, _ = pelage.stamp(mesh, 200, seed=1)
    guides = pelage.Guides(guide_roots, guide_points)   # (200, 16, 3)
    roots, _ = pelage.stamp(mesh, 20000, seed=2)
    bindings, info = pelage.bind(mesh, guides, roots)
    grooms = pelage.groom_evaluate(mesh, roots, length=0.8)
    pelage.settle(mesh, guides, roots, bindings, grooms)
    with pelage.Frame(mesh, len(guides)) as frame, pelage.Groom(roots, bindings, grooms) as groom:
        frame.set_guides(guides)
        curves = groom.expand(frame)                     # (20000, 18, 4) float32
"""

from __future__ import annotations

from typing import Tuple

from ._ffi import ffi, lib, library_path
from ._util import (
    BINDING_DTYPE,
    GROOM_DTYPE,
    PATCH_DTYPE,
    ROOT_DTYPE,
    TRIM_RECORD_DTYPE,
    ProgressFn,
)
from .errors import (
    Cancelled,
    CapacityExceeded,
    CorruptData,
    Error,
    InvalidArgument,
    Misaligned,
    NonFinite,
    NullParameter,
    OutOfMemory,
    OutOfRange,
    Panic,
    PelageError,
    VersionMismatch,
)
from .files import (
    GroomFile,
    GroomFileInfo,
    GuideCacheInfo,
    GuideSet,
    groom_file_info,
    groom_file_read,
    groom_file_write,
    guide_cache_info,
    guide_cache_read,
    guide_cache_size,
    guide_cache_write,
)
from .frame import Colliders, DistanceFn, Frame
from .groom import Groom
from .mesh import Guides, Map, MapLike, Mesh, RegionMap
from .pipeline import (
    BindInfo,
    ExpandParams,
    SettleInfo,
    StampInfo,
    bind,
    expand,
    expand_size,
    groom_evaluate,
    map_mask,
    patch_boxes,
    patch_plan,
    roots_evaluate,
    segment_indices,
    settle,
    stamp,
)
from .sim import Sim, StepInfo
from .trim import (
    TrimRecordsInfo,
    trim_find,
    trim_lengths_read,
    trim_lengths_write,
    trim_records_info,
    trim_records_read,
    trim_records_write,
    trim_shortest,
    trim_shortest_hairs,
    trim_whole,
)

#: Most guides a strand can use.
MAX_NEIGHBOURS: int = lib.PELAGE_MAX_NEIGHBOURS
#: How far a bound strand's weights may sum from 1 (the header's
#: PELAGE_WEIGHT_SUM_TOLERANCE, a float cffi's cdef cannot declare).
WEIGHT_SUM_TOLERANCE: float = 1e-4
#: The stored length of an untrimmed strand.
TRIM_WHOLE: int = lib.PELAGE_TRIM_WHOLE


def version() -> Tuple[int, int, int]:
    """The loaded library's version (major, minor, patch), from
    ``pelage_version()``."""
    v = int(lib.pelage_version())
    return v // 10000, v // 100 % 100, v % 100


def _check_version() -> str:
    header = (lib.PELAGE_VERSION_MAJOR, lib.PELAGE_VERSION_MINOR, lib.PELAGE_VERSION_PATCH)
    if version() != header:
        raise ImportError(
            f"pelage: the library at {library_path()} is version {version()}, "
            f"the declarations are {header}"
        )
    return "%d.%d.%d" % header


__version__ = _check_version()

__all__ = [
    "__version__",
    "version",
    "ffi",
    "lib",
    "library_path",
    "ROOT_DTYPE",
    "BINDING_DTYPE",
    "GROOM_DTYPE",
    "PATCH_DTYPE",
    "TRIM_RECORD_DTYPE",
    "MAX_NEIGHBOURS",
    "WEIGHT_SUM_TOLERANCE",
    "TRIM_WHOLE",
    "ProgressFn",
    "DistanceFn",
    "MapLike",
    "PelageError",
    "Error",
    "NullParameter",
    "InvalidArgument",
    "NonFinite",
    "OutOfRange",
    "CapacityExceeded",
    "Misaligned",
    "CorruptData",
    "VersionMismatch",
    "Cancelled",
    "Panic",
    "OutOfMemory",
    "Mesh",
    "Guides",
    "Map",
    "RegionMap",
    "Colliders",
    "Frame",
    "Groom",
    "Sim",
    "StampInfo",
    "BindInfo",
    "SettleInfo",
    "StepInfo",
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
    "GroomFile",
    "GroomFileInfo",
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
