"""Host data the calls borrow: meshes, guides, maps over the surface."""

from __future__ import annotations

from typing import Any, List, Optional, Union

import numpy as np

from ._ffi import ffi, lib
from ._util import ROOT_DTYPE, ptr, records, row_stride, rows

__all__ = ["Mesh", "Guides", "Map", "RegionMap", "MapLike"]


class Mesh:
    """A triangle mesh in host memory (``PelageMeshDesc``), borrowed by each
    call that takes it.

    Args:
        positions: (n, 3) float32 vertex positions. Any rows 4-byte aligned
            and a multiple of 4 bytes apart are read in place (a column
            slice of an (n, 4) array too); other dtypes are converted once,
            here.
        triangles: (m, 3) uint32 vertex indices, read in place likewise.
        uvs: optional (n, 2) float32 per-vertex UVs (texture maps need them).
        normals: optional (n, 3) float32 per-vertex normals.

    The arrays are kept, not copied: change ``mesh.positions`` in place to
    deform the mesh for the next call (a frame copies it when made).
    """

    def __init__(
        self,
        positions: Any,
        triangles: Any,
        uvs: Any = None,
        normals: Any = None,
    ) -> None:
        self.positions = rows(positions, np.float32, 3, "positions")
        self.triangles = rows(triangles, np.uint32, 3, "triangles")
        self.uvs = None if uvs is None else rows(uvs, np.float32, 2, "uvs")
        self.normals = None if normals is None else rows(normals, np.float32, 3, "normals")
        desc = ffi.new("PelageMeshDesc *")
        desc.positions = ptr(self.positions)
        desc.position_stride = row_stride(self.positions)
        desc.vertex_count = self.positions.shape[0]
        desc.indices = ptr(self.triangles)
        desc.index_stride = row_stride(self.triangles)
        desc.triangle_count = self.triangles.shape[0]
        if self.uvs is not None:
            desc.uvs = ptr(self.uvs)
            desc.uv_stride = row_stride(self.uvs)
        if self.normals is not None:
            desc.normals = ptr(self.normals)
            desc.normal_stride = row_stride(self.normals)
        self._desc = desc

    @property
    def vertex_count(self) -> int:
        """Number of vertices."""
        return int(self.positions.shape[0])

    @property
    def triangle_count(self) -> int:
        """Number of triangles."""
        return int(self.triangles.shape[0])

    @property
    def desc(self) -> Any:
        """The ``PelageMeshDesc *`` (valid while this object lives)."""
        return self._desc

    def __repr__(self) -> str:
        return f"Mesh({self.vertex_count} vertices, {self.triangle_count} triangles)"


class Guides:
    """Guide curves (``PelageGuidesDesc``), rest or posed.

    Args:
        roots: the guides' roots, an array of :data:`pelage.ROOT_DTYPE`
            (face, u, v on the mesh; id and rank unused).
        points: (guides, points_per_guide, 3) float32 world points (read in
            place when each point is packed and the points equally spaced,
            as in a [..., :3] slice of a float4 array), or (total, 3) with
            ``offsets``.
        offsets: optional (guides + 1,) uint32: guide g owns points
            ``offsets[g]:offsets[g + 1]`` of a (total, 3) ``points``.
    """

    def __init__(self, roots: Any, points: Any, offsets: Any = None) -> None:
        self.roots = records(roots, ROOT_DTYPE, "roots")
        pts = np.asarray(points)
        if offsets is None:
            if pts.ndim != 3 or pts.shape[2] != 3 or pts.shape[0] != self.roots.shape[0]:
                raise ValueError(
                    f"points: expected shape ({self.roots.shape[0]}, points_per_guide, 3), got {pts.shape}"
                )
            self.points_per_guide = int(pts.shape[1])
            flat = pts.view() if pts.dtype == np.float32 else pts.astype(np.float32)
            try:
                flat.shape = (-1, 3)
            except AttributeError:
                flat = np.ascontiguousarray(flat).reshape(-1, 3)
            self.offsets = None
        else:
            self.offsets = np.ascontiguousarray(offsets, dtype=np.uint32)
            if self.offsets.shape != (self.roots.shape[0] + 1,):
                raise ValueError("offsets: expected guides + 1 entries")
            flat = pts
            self.points_per_guide = 0
        self.points = rows(flat, np.float32, 3, "points")
        desc = ffi.new("PelageGuidesDesc *")
        desc.roots = ptr(self.roots, "PelageRoot *")
        desc.guide_count = self.roots.shape[0]
        desc.points = ptr(self.points)
        desc.point_stride = row_stride(self.points)
        desc.point_count = self.points.shape[0]
        desc.points_per_guide = self.points_per_guide
        desc.offsets = ptr(self.offsets, "uint32_t *")
        self._desc = desc

    @property
    def guide_count(self) -> int:
        """Number of guides."""
        return int(self.roots.shape[0])

    @property
    def desc(self) -> Any:
        """The ``PelageGuidesDesc *`` (valid while this object lives)."""
        return self._desc

    def __len__(self) -> int:
        return self.guide_count


class Map:
    """A scalar over the mesh surface (``PelageMap``): a constant, per-vertex
    values, or a texture over UV. Anywhere a map is taken, a number means
    :meth:`constant`, a 1-D array :meth:`per_vertex` and a 2-D array
    :meth:`texture`."""

    def __init__(self, kind: int, constant: float = 0.0, data: Optional[np.ndarray] = None) -> None:
        self.kind = kind
        self.constant = float(constant)
        self.data = data

    @classmethod
    def uniform(cls, value: float) -> "Map":
        """The same value everywhere."""
        return cls(lib.PELAGE_MAP_KIND_CONSTANT, value)

    @classmethod
    def per_vertex(cls, values: Any) -> "Map":
        """One float32 per mesh vertex, interpolated over triangles (a strided
        1-D float32 array is read in place)."""
        arr = np.asarray(values)
        if arr.ndim != 1:
            raise ValueError(f"per-vertex map: expected a 1-D array, got {arr.shape}")
        if arr.dtype != np.float32 or arr.strides[0] % 4 or arr.strides[0] < 4:
            arr = np.ascontiguousarray(arr, dtype=np.float32)
        return cls(lib.PELAGE_MAP_KIND_PER_VERTEX, 0.0, arr)

    @classmethod
    def texture(cls, image: Any) -> "Map":
        """A (height, width) texture over UV, row 0 at v = 0: uint8 (0..255
        is 0..1) or float32 (other dtypes become float32)."""
        arr = np.asarray(image)
        if arr.ndim != 2:
            raise ValueError(f"texture map: expected a 2-D array, got {arr.shape}")
        if arr.dtype != np.uint8 and arr.dtype != np.float32:
            arr = arr.astype(np.float32)
        if arr.strides[1] != arr.itemsize or arr.strides[0] < 0:
            arr = np.ascontiguousarray(arr)
        kind = lib.PELAGE_MAP_KIND_TEXTURE_U8 if arr.dtype == np.uint8 else lib.PELAGE_MAP_KIND_TEXTURE_F32
        return cls(kind, 0.0, arr)

    @classmethod
    def of(cls, value: "MapLike") -> "Map":
        """A map from a number, a 1-D array (per vertex) or a 2-D array (texture)."""
        if isinstance(value, Map):
            return value
        if np.isscalar(value):
            return cls.uniform(float(value))  # type: ignore[arg-type]
        arr = np.asarray(value)
        if arr.ndim == 0:
            return cls.uniform(float(arr))
        return cls.per_vertex(arr) if arr.ndim == 1 else cls.texture(arr)

    def fill(self, cmap: Any, keep: List[Any]) -> None:
        """Writes this map into a ``PelageMap`` struct; ``keep`` holds its data
        for the call."""
        cmap.kind = self.kind
        cmap.constant = self.constant
        if self.data is None:
            cmap.data = ffi.NULL
            return
        keep.append(self.data)
        cmap.data = ptr(self.data)
        if self.data.ndim == 1:
            cmap.stride = self.data.strides[0]
        else:
            cmap.height, cmap.width = self.data.shape
            cmap.stride = self.data.strides[0]


MapLike = Union[float, int, np.ndarray, Map]


class RegionMap:
    """Parting regions for :func:`pelage.bind` (``PelageRegionMap``): a strand
    only uses guides of its own region id.

    Args:
        ids: (vertices,) uint32 ids per vertex (a root takes its nearest
            corner's), or a (height, width) uint8 id texture over UV.
    """

    def __init__(self, ids: Any) -> None:
        arr = np.asarray(ids)
        if arr.ndim == 1:
            if arr.dtype != np.uint32 or arr.strides[0] % 4 or arr.strides[0] < 4:
                arr = np.ascontiguousarray(arr, dtype=np.uint32)
            self.kind = lib.PELAGE_REGION_KIND_PER_VERTEX
        elif arr.ndim == 2:
            if arr.dtype != np.uint8 or arr.strides[1] != 1 or arr.strides[0] < 0:
                arr = np.ascontiguousarray(arr, dtype=np.uint8)
            self.kind = lib.PELAGE_REGION_KIND_TEXTURE_U8
        else:
            raise ValueError(f"region ids: expected a 1-D or 2-D array, got {arr.shape}")
        self.ids = arr

    def fill(self, cregions: Any, keep: List[Any]) -> None:
        """Writes this map into a ``PelageRegionMap`` struct."""
        keep.append(self.ids)
        cregions.kind = self.kind
        cregions.data = ptr(self.ids)
        cregions.stride = self.ids.strides[0]
        if self.ids.ndim == 2:
            cregions.height, cregions.width = self.ids.shape
