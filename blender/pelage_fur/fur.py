"""The groom pipeline between Blender and the ``pelage`` package: grow,
pose each frame (simulated, restored or read from a bake) and bake.

Every step that computes hair is a call into ``pelage``; this module picks
the inputs from the settings (:class:`pelage_fur.PelageFurSettings`) and
the scene, keeps the handles alive between frames, and writes the curves
back through :mod:`.convert`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Optional

import bpy
import numpy as np

import pelage

from . import convert

__all__ = ["Fur", "grow", "pose", "bake", "groom_path", "cache_path", "forget", "get", "MAPS"]

#: The groom maps, each a constant optionally scaled by a per-vertex
#: attribute or vertex group (the settings' ``<name>`` and ``<name>_attribute``).
MAPS = (
    "length",
    "root_width",
    "tip_width",
    "bend",
    "kink_amplitude",
    "kink_frequency",
    "clump",
    "length_random",
    "clump_random",
)

GROOM_FILE = "groom.pgf"


def groom_path(directory: str) -> Path:
    """The groom file of a bake directory."""
    return Path(bpy.path.abspath(directory)) / GROOM_FILE


def cache_path(directory: str, frame: int) -> Path:
    """The guide cache of ``frame`` in a bake directory."""
    return Path(bpy.path.abspath(directory)) / f"guides.{frame:04d}.pgc"


def _threads() -> int:
    return os.cpu_count() or 1


@dataclass
class Fur:
    """A grown groom, kept between frames: the rest pose, the strands (in
    the output curves' order), the checked :class:`pelage.Groom`, and the
    simulation with its saved state after each frame it stepped to (what
    scrubbing back restores)."""

    triangles: np.ndarray
    guide_roots: np.ndarray
    roots: np.ndarray
    bindings: np.ndarray
    grooms: np.ndarray
    groom: pelage.Groom
    params: pelage.ExpandParams
    rest_mesh: Optional[pelage.Mesh] = None
    rest_guides: Optional[pelage.Guides] = None
    sim: Optional[pelage.Sim] = None
    states: Dict[int, bytes] = field(default_factory=dict)
    guide_set: Optional[pelage.GuideSet] = None
    frame: Optional[pelage.Frame] = None
    #: Whether the output holds this groom's radii (the frames then write
    #: only positions).
    radii_written: bool = False

    @property
    def points(self) -> int:
        """Points per strand, of the guides and of the render curves."""
        return int(self.params.points_per_strand or 16)

    def close(self) -> None:
        """Releases the C handles."""
        for handle in (self.frame, self.sim, self.groom):
            if handle is not None:
                handle.close()


#: The runtime state of each grown object, by the mesh object's name.
_FURS: Dict[str, Fur] = {}


def get(obj: bpy.types.Object) -> Optional[Fur]:
    """The live groom of ``obj``, if it was grown or loaded this session."""
    return _FURS.get(obj.name)


def forget(obj: Optional[bpy.types.Object] = None) -> None:
    """Drops the live groom of ``obj`` (of every object when None)."""
    names = list(_FURS) if obj is None else [obj.name]
    for name in names:
        fur = _FURS.pop(name, None)
        if fur is not None:
            fur.close()


def _map(obj: bpy.types.Object, depsgraph: Any, settings: Any, name: str) -> pelage.MapLike:
    value = float(getattr(settings, name))
    attribute = getattr(settings, name + "_attribute")
    if not attribute:
        return value
    return value * convert.vertex_values(obj, depsgraph, attribute)


def grow(obj: bpy.types.Object, depsgraph: Any) -> np.ndarray:
    """Grows the fur of mesh ``obj`` as its settings say: stamps roots
    (count or density, bald below the threshold), binds them to the guide
    ``Curves``, evaluates the groom maps, settles, and expands on the rest
    frame. Keeps the result as ``obj``'s live groom and returns the render
    curves, (strands, points, 4) float32."""
    settings = obj.pelage_fur
    if settings.guides is None or settings.guides.type != "CURVES":
        raise ValueError("choose a Curves object of guides")
    positions, triangles = convert.mesh_arrays(obj, depsgraph)
    mesh = pelage.Mesh(positions, triangles)
    density = convert.vertex_values(obj, depsgraph, settings.density_attribute) if settings.density_attribute else None
    roots, _ = pelage.stamp(
        mesh, settings.count, seed=settings.seed, density=density,
        bald_below=settings.bald_below if density is not None else None,
    )
    points, offsets = convert.curves_points(settings.guides, depsgraph)
    if len(offsets) < 2:
        raise ValueError(f"{settings.guides.name} has no guide curve")
    guide_roots = convert.project_roots(positions, triangles, points[offsets[:-1]])
    sizes = np.diff(offsets)
    if (sizes == sizes[0]).all():
        guides = pelage.Guides(guide_roots, points.reshape(len(sizes), int(sizes[0]), 3))
    else:
        guides = pelage.Guides(guide_roots, points, offsets)
    bindings, _ = pelage.bind(mesh, guides, roots, seed=settings.seed, threads=_threads())
    grooms = pelage.groom_evaluate(
        mesh, roots, seed=settings.seed, **{name: _map(obj, depsgraph, settings, name) for name in MAPS}
    )
    params = pelage.ExpandParams(points_per_strand=settings.points, pinned=False)
    if settings.settle:
        pelage.settle(mesh, guides, roots, bindings, grooms, params, threads=_threads())
    forget(obj)
    # a bake holds the strands grown before
    settings.use_bake = False
    fur = Fur(
        triangles, guide_roots, roots, bindings, grooms, pelage.Groom(roots, bindings, grooms), params,
        rest_mesh=mesh, rest_guides=guides,
    )
    _FURS[obj.name] = fur
    fur.frame = pelage.Frame(mesh, len(guides), fur.points)
    fur.frame.set_guides(guides, threads=_threads())
    return fur.groom.expand(fur.frame, params=params, threads=_threads())


def _colliders(settings: Any) -> pelage.Colliders:
    """The step's colliders: the body, when chosen, and each mesh object of
    the collider collection: a flat one as the plane through its box, along
    its flat axis; any other as the sphere at its box's centre with half the
    box's largest side (a sphere object's own)."""
    spheres, planes = [], []
    if settings.colliders is not None:
        for obj in settings.colliders.all_objects:
            if obj.type != "MESH":
                continue
            m = np.asarray(obj.matrix_world, np.float64)
            box = np.asarray(obj.bound_box, np.float64)
            corners = box @ m[:3, :3].T + m[:3, 3]
            low, high = corners.min(0), corners.max(0)
            extent = np.ptp(box, axis=0)
            if extent.min() <= 1e-6 * max(extent.max(), 1e-30):
                normal = m[:3, int(np.argmin(extent))]
                normal = normal / np.linalg.norm(normal)
                planes.append([*normal, float(normal @ corners.mean(0))])
            else:
                spheres.append([*(0.5 * (low + high)), 0.5 * float((high - low).max())])
    return pelage.Colliders(
        spheres=np.asarray(spheres, np.float32).reshape(-1, 4),
        planes=np.asarray(planes, np.float32).reshape(-1, 4),
        body=settings.body_collision,
    )


def _from_bake(obj: bpy.types.Object, directory: str) -> Fur:
    """A live groom read back from a bake's groom file (strands in the
    file's order), for rendering a baked shot without growing again."""
    gf = pelage.groom_file_read(groom_path(directory).read_bytes())
    params = pelage.ExpandParams(points_per_strand=gf.info.points_per_guide, pinned=False)
    fur = Fur(
        np.empty((0, 3), np.uint32), gf.guide_roots, gf.roots, gf.bindings, gf.grooms,
        pelage.Groom(gf.roots, gf.bindings, gf.grooms), params, guide_set=gf.guide_set,
    )
    forget(obj)
    _FURS[obj.name] = fur
    return fur


def pose(obj: bpy.types.Object, scene: bpy.types.Scene, depsgraph: Any) -> Optional[np.ndarray]:
    """The render curves of ``obj`` at the scene's current frame, from the
    deformed mesh: read from the bake when the settings use it and the
    frame's cache exists, else simulated. A frame that follows the last one
    steps the simulation; a frame stepped to before restores its saved
    state; any other jump restores the nearest earlier state (or starts
    from rest) and steps once. None when ``obj`` has no groom."""
    settings = obj.pelage_fur
    number = scene.frame_current
    fur = get(obj)
    baked = settings.use_bake and cache_path(settings.bake_directory, number).is_file()
    if baked and (fur is None or fur.guide_set is None):
        fur = _from_bake(obj, settings.bake_directory) if fur is None else fur
        if fur.guide_set is None:
            fur.guide_set = pelage.groom_file_read(groom_path(settings.bake_directory).read_bytes()).guide_set
    if fur is None:
        return None
    positions, triangles = convert.mesh_arrays(obj, depsgraph)
    if fur.triangles.shape[0] and not np.array_equal(triangles, fur.triangles):
        raise ValueError(f"{obj.name}: the mesh's triangles changed since the fur was grown")
    mesh = pelage.Mesh(positions, triangles)
    if fur.frame is not None:
        fur.frame.close()
    fur.frame = pelage.Frame(mesh, len(fur.guide_roots), fur.points)
    if baked:
        data = cache_path(settings.bake_directory, number).read_bytes()
        pelage.guide_cache_read(data, fur.guide_set, fur.frame, threads=_threads())
    else:
        _simulate(fur, settings, scene, number)
    return fur.groom.expand(fur.frame, params=fur.params, threads=_threads())


def _simulate(fur: Fur, settings: Any, scene: bpy.types.Scene, number: int) -> None:
    """Poses ``fur.frame``'s guides with the simulation at frame ``number``."""
    if fur.sim is None:
        if fur.rest_mesh is None or fur.rest_guides is None:
            raise ValueError("a groom read from a bake has no simulation: grow it, or bake this frame")
        fur.sim = pelage.Sim(fur.rest_mesh, fur.rest_guides, points_per_guide=fur.points)
    sim, frame = fur.sim, fur.frame
    assert frame is not None
    state = fur.states.get(number)
    if state is not None:
        # the bits of the step it was saved after (pelage_sim_read's promise)
        sim.restore(state)
        frame.set_guides(pelage.Guides(fur.guide_roots, sim.read()), threads=_threads())
        return
    earlier = [k for k in fur.states if scene.frame_start <= k < number]
    if earlier:
        sim.restore(fur.states[max(earlier)])
    else:
        sim.reset()
    sim.step(frame, 1.0 / (scene.render.fps / scene.render.fps_base), colliders=_colliders(settings), threads=_threads())
    frame.set_sim_guides(sim, threads=_threads())
    fur.states[number] = bytes(sim.save())


def bake(obj: bpy.types.Object, scene: bpy.types.Scene, exact: bool) -> int:
    """Writes the groom file and one guide cache per frame of the scene's
    range into the settings' bake directory, simulating each frame from
    the start. Returns the frames written."""
    settings = obj.pelage_fur
    fur = get(obj)
    if fur is None or fur.rest_mesh is None or fur.rest_guides is None:
        raise ValueError(f"{obj.name}: grow the fur before baking it")
    directory = Path(bpy.path.abspath(settings.bake_directory))
    directory.mkdir(parents=True, exist_ok=True)
    with pelage.Frame(fur.rest_mesh, len(fur.guide_roots), fur.points) as rest:
        rest.set_guides(fur.rest_guides, threads=_threads())
        data = pelage.groom_file_write(rest, fur.guide_roots, fur.roots, fur.bindings, fur.grooms)
    groom_path(settings.bake_directory).write_bytes(data)
    fur.guide_set = pelage.groom_file_read(data).guide_set
    fur.states.clear()
    # the frame handler simulates each frame as it is set
    use_bake, animate, settings.use_bake, settings.animate = settings.use_bake, settings.animate, False, True
    current = scene.frame_current
    try:
        for number in range(scene.frame_start, scene.frame_end + 1):
            scene.frame_set(number)
            assert fur.frame is not None
            cache = pelage.guide_cache_write(fur.guide_set, [fur.frame], exact=exact)
            cache_path(settings.bake_directory, number).write_bytes(cache)
    finally:
        settings.use_bake, settings.animate = use_bake, animate
        scene.frame_set(current)
    return scene.frame_end - scene.frame_start + 1
