"""Blender data to numpy arrays and back: the add-on's only conversions.

Everything is in world space, float32 for positions (pelage's layout) and
uint32 for indices; ``foreach_get``/``foreach_set`` move whole buffers, so
no Python loop runs per vertex or per point but for vertex groups, which
Blender exposes only per vertex.
"""

from __future__ import annotations

from typing import Sequence, Tuple

import bpy
import numpy as np
from mathutils.bvhtree import BVHTree

import pelage

__all__ = [
    "mesh_arrays",
    "vertex_values",
    "curves_points",
    "project_roots",
    "new_curves",
    "set_curves_points",
    "curves_positions",
    "curves_radii",
    "set_curve_ints",
]


def _world(points: np.ndarray, matrix: Sequence[Sequence[float]]) -> np.ndarray:
    """``points`` (n, 3) moved by a 4x4 matrix, in float64 then rounded once
    to float32 (an identity matrix keeps every bit)."""
    m = np.asarray(matrix, np.float64)
    return (points.astype(np.float64) @ m[:3, :3].T + m[:3, 3]).astype(np.float32)


def mesh_arrays(obj: bpy.types.Object, depsgraph: bpy.types.Depsgraph) -> Tuple[np.ndarray, np.ndarray]:
    """The evaluated (deformed) mesh of ``obj``: (n, 3) float32 world
    positions and (m, 3) uint32 triangles (Blender's loop triangles, so
    quads and n-gons are split as the viewport splits them)."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        co = np.empty(len(mesh.vertices) * 3, np.float32)
        mesh.vertices.foreach_get("co", co)
        mesh.calc_loop_triangles()
        tris = np.empty(len(mesh.loop_triangles) * 3, np.int32)
        mesh.loop_triangles.foreach_get("vertices", tris)
    finally:
        evaluated.to_mesh_clear()
    return _world(co.reshape(-1, 3), evaluated.matrix_world), tris.view(np.uint32).reshape(-1, 3)


def vertex_values(obj: bpy.types.Object, depsgraph: bpy.types.Depsgraph, name: str) -> np.ndarray:
    """One float32 per vertex of the evaluated mesh: the float point
    attribute ``name``, else the vertex group ``name`` (0 where a vertex is
    not in it). A name that is neither is a KeyError."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        values = np.zeros(len(mesh.vertices), np.float32)
        attribute = mesh.attributes.get(name)
        if attribute is not None and attribute.domain == "POINT" and attribute.data_type == "FLOAT":
            attribute.data.foreach_get("value", values)
            return values
        group = evaluated.vertex_groups.get(name)
        if group is None:
            raise KeyError(f"{obj.name} has no float point attribute or vertex group named {name!r}")
        index = group.index
        for vertex in mesh.vertices:
            for element in vertex.groups:
                if element.group == index:
                    values[vertex.index] = element.weight
        return values
    finally:
        evaluated.to_mesh_clear()


def curves_points(obj: bpy.types.Object, depsgraph: bpy.types.Depsgraph) -> Tuple[np.ndarray, np.ndarray]:
    """The evaluated curves of a ``Curves`` object: (points, 3) float32
    world positions and (curves + 1,) uint32 offsets (curve c owns points
    ``offsets[c]:offsets[c + 1]``)."""
    evaluated = obj.evaluated_get(depsgraph)
    curves = evaluated.data
    co = np.empty(len(curves.points) * 3, np.float32)
    curves.attributes["position"].data.foreach_get("vector", co)
    offsets = np.empty(len(curves.curve_offset_data), np.int32)
    curves.curve_offset_data.foreach_get("value", offsets)
    return _world(co.reshape(-1, 3), evaluated.matrix_world), offsets.view(np.uint32)


def project_roots(positions: np.ndarray, triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Roots (:data:`pelage.ROOT_DTYPE`) on the mesh at the surface points
    nearest to ``points`` (n, 3): the face by Blender's BVH tree, (u, v)
    the barycentric weights of that face's second and third vertices, as
    pelage's roots store them (the C API has no projection of its own)."""
    tree = BVHTree.FromPolygons(positions.tolist(), triangles.tolist(), all_triangles=True)
    roots = np.zeros(len(points), pelage.ROOT_DTYPE)
    nearest = np.empty((len(points), 3), np.float64)
    for i, p in enumerate(points.tolist()):
        location, _, face, _ = tree.find_nearest(p)
        if face is None:
            raise ValueError("the mesh has no triangle to root a guide on")
        roots["face"][i] = face
        nearest[i] = location
    a, b, c = (positions[triangles[roots["face"], k]].astype(np.float64) for k in range(3))
    e1, e2, d = b - a, c - a, nearest - a
    d11, d12, d22 = (e1 * e1).sum(1), (e1 * e2).sum(1), (e2 * e2).sum(1)
    d1, d2 = (d * e1).sum(1), (d * e2).sum(1)
    det = np.where(d11 * d22 - d12 * d12 > 0.0, d11 * d22 - d12 * d12, 1.0)
    u = np.clip((d22 * d1 - d12 * d2) / det, 0.0, 1.0)
    v = np.clip((d11 * d2 - d12 * d1) / det, 0.0, 1.0)
    over = u + v > 1.0
    u[over], v[over] = u[over] / (u + v)[over], v[over] / (u + v)[over]
    roots["u"], roots["v"] = u, v
    roots["id"] = np.arange(len(points), dtype=np.uint32)
    return roots


def new_curves(name: str, curve_count: int, points_per_curve: int) -> bpy.types.Curves:
    """A new ``Curves`` data-block of ``curve_count`` Catmull-Rom curves of
    ``points_per_curve`` points each, with a point radius attribute and a
    curve resolution of 1: Blender evaluates no points between pelage's
    (at the default 12, its first evaluation of a million hairs took 2.8 s
    and 2.5 GB more; renderers and exporters read the control points)."""
    data = bpy.data.hair_curves.new(name)
    if curve_count:
        data.add_curves([points_per_curve] * curve_count)
        data.attributes.new("resolution", "INT", "CURVE").data.foreach_set(
            "value", np.ones(curve_count, np.int32)
        )
    if data.attributes.get("radius") is None:
        data.attributes.new("radius", "FLOAT", "POINT")
    return data


def set_curves_points(data: bpy.types.Curves, points: np.ndarray, radii: bool = True) -> None:
    """Writes pelage's float4 control points (x, y, z, radius), one row per
    point of ``data`` in order, into its positions and (``radii``) radii."""
    flat = points.reshape(-1, 4)
    if flat.shape[0] != len(data.points):
        raise ValueError(f"{data.name}: {len(data.points)} points, {flat.shape[0]} given")
    data.attributes["position"].data.foreach_set("vector", np.ascontiguousarray(flat[:, :3]).ravel())
    if radii:
        data.attributes["radius"].data.foreach_set("value", np.ascontiguousarray(flat[:, 3]))
    data.update_tag()


def curves_positions(data: bpy.types.Curves) -> np.ndarray:
    """(points, 3) float32 positions of a ``Curves`` data-block."""
    co = np.empty(len(data.points) * 3, np.float32)
    data.attributes["position"].data.foreach_get("vector", co)
    return co.reshape(-1, 3)


def curves_radii(data: bpy.types.Curves) -> np.ndarray:
    """(points,) float32 radii of a ``Curves`` data-block."""
    radii = np.empty(len(data.points), np.float32)
    data.attributes["radius"].data.foreach_get("value", radii)
    return radii


def set_curve_ints(data: bpy.types.Curves, name: str, values: np.ndarray) -> None:
    """Stores one integer per curve as the curve attribute ``name``."""
    found = data.attributes.get(name)
    if found is None:
        found = data.attributes.new(name, "INT", "CURVE")
    found.data.foreach_set("value", np.ascontiguousarray(values, dtype=np.int32))
