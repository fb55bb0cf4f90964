"""A head built like tests/src/head.rs (an open shell with a neck and two
eye sockets, two closed eyeballs and two thin closed ears cutting through
it), guides combed on it into a ``Curves`` object, and the add-on
registered in the ``bpy`` module."""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator, List, Tuple

import bpy
import numpy as np
import pytest

import pelage

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import pelage_fur  # noqa: E402
from pelage_fur import convert  # noqa: E402

GUIDES = 160
GUIDE_POINTS = 16
GUIDE_LENGTH = 0.12
HAIRS = 30000
FRAMES = (1, 6)
EYE_RADIUS = 0.085
NECK_THETA = 0.82 * np.pi
SOCKET_ANGLE = 0.2


def direction(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Unit vectors at polar angle ``theta`` from +z and longitude ``phi``
    (the face looks down -y, at phi = -pi/2)."""
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)


def skull_radius(d: np.ndarray) -> np.ndarray:
    """The head's distance from the origin along unit directions ``d``: an
    ellipsoid with a muzzle and a brow."""
    e = (d[..., 0] / 0.42) ** 2 + (d[..., 1] / 0.5) ** 2 + (d[..., 2] / 0.48) ** 2
    r = 1.0 / np.sqrt(e)
    for centre, width, height in (((0.58, -0.5), 0.3, 0.12), ((0.36, -0.5), 0.25, 0.03)):
        c = direction(np.pi * centre[0], np.pi * centre[1])
        a = 2.0 * np.arcsin(np.clip(0.5 * np.linalg.norm(d - c, axis=-1), 0.0, 1.0)) / width
        r = r + height * np.exp(-a * a)
    return r


EYES = [direction(0.44 * np.pi, -0.5 * np.pi + side * 0.42) for side in (-1.0, 1.0)]


def _outward(positions: np.ndarray, tris: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Triangles wound counter-clockwise seen from outside a star-shaped part."""
    a, b, c = (positions[tris[:, k]] for k in range(3))
    inward = (np.cross(b - a, c - a) * ((a + b + c) / 3.0 - centre)).sum(1) < 0.0
    tris = tris.copy()
    tris[inward] = tris[inward][:, ::-1]
    return tris


def sphere(rings: int, segments: int) -> Tuple[np.ndarray, np.ndarray]:
    """A closed unit UV sphere."""
    theta = np.linspace(0.0, np.pi, rings + 1)[1:-1]
    phi = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    ring = direction(*np.meshgrid(theta, phi, indexing="ij")).reshape(-1, 3)
    positions = np.concatenate([[[0.0, 0.0, 1.0]], ring, [[0.0, 0.0, -1.0]]])
    bottom = len(positions) - 1
    tris: List[Tuple[int, int, int]] = []
    v = lambda r, s: 1 + r * segments + s % segments  # noqa: E731
    for s in range(segments):
        tris += [(0, v(0, s), v(0, s + 1)), (bottom, v(rings - 2, s + 1), v(rings - 2, s))]
        for r in range(rings - 2):
            tris += [(v(r, s), v(r + 1, s), v(r + 1, s + 1)), (v(r, s), v(r + 1, s + 1), v(r, s + 1))]
    return positions, np.asarray(tris)


def _shell(rings: int = 36, segments: int = 72) -> Tuple[np.ndarray, np.ndarray]:
    """The head shell: open at the neck, with a hole over each eye."""
    theta = NECK_THETA * np.arange(1, rings + 1) / rings
    phi = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    d = np.concatenate([[[0.0, 0.0, 1.0]], direction(*np.meshgrid(theta, phi, indexing="ij")).reshape(-1, 3)])
    positions = d * skull_radius(d)[:, None]
    v = lambda r, s: 1 + r * segments + s % segments  # noqa: E731
    tris = [(0, v(0, s), v(0, s + 1)) for s in range(segments)]
    for r in range(rings - 1):
        for s in range(segments):
            tris += [(v(r, s), v(r + 1, s), v(r + 1, s + 1)), (v(r, s), v(r + 1, s + 1), v(r, s + 1))]
    tris = np.asarray(tris)
    centres = positions[tris].mean(1)
    centres /= np.linalg.norm(centres, axis=1, keepdims=True)
    keep = np.ones(len(tris), bool)
    for eye in EYES:
        keep &= np.arccos(np.clip(centres @ eye, -1.0, 1.0)) > SOCKET_ANGLE
    return positions, tris[keep]


def head() -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The head: (n, 3) float32 positions, (m, 3) uint32 triangles and the
    shell of each vertex (0 the head, 1 and 2 the eyes, 3 and 4 the ears)."""
    parts = []
    positions, tris = _shell()
    parts.append((positions, _outward(positions, tris, np.zeros(3))))
    unit, sphere_tris = sphere(12, 24)
    for eye in EYES:
        centre = eye * (skull_radius(eye) - 0.06)
        parts.append((centre + EYE_RADIUS * unit, _outward(centre + EYE_RADIUS * unit, sphere_tris, centre)))
    for side in (-1.0, 1.0):
        axis = direction(0.22 * np.pi, np.pi * (0.5 - 0.5 * side) - 0.15 * side)
        flat = np.cross(axis, [0.0, 1.0, 0.0])
        flat /= np.linalg.norm(flat)
        wide = np.cross(axis, flat)
        centre = axis * (skull_radius(axis) + 0.17 - 0.05)
        ear = centre + unit[:, 2:3] * 0.17 * axis + unit[:, 0:1] * 0.014 * flat + unit[:, 1:2] * 0.07 * wide
        parts.append((ear, _outward(ear, sphere_tris, centre)))
    all_positions, all_tris, shells, base = [], [], [], 0
    for shell, (p, t) in enumerate(parts):
        all_positions.append(p)
        all_tris.append(t + base)
        shells.append(np.full(len(p), shell))
        base += len(p)
    return (
        np.concatenate(all_positions).astype(np.float32),
        np.concatenate(all_tris).astype(np.uint32),
        np.concatenate(shells),
    )


def comb(positions: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Guides that leave the skin at a low angle and lie down the head, as
    a groomer combs them: (g, points, 3)."""
    down = np.array([0.0, 0.3, -1.0], np.float32)
    tangent = down - (normals @ down)[:, None] * normals
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    t = np.linspace(0.0, 1.0, GUIDE_POINTS, dtype=np.float32)[None, :, None]
    shape = 0.35 * t * normals[:, None] + (0.9 * t - 0.2 * t * t) * tangent[:, None]
    return (positions[:, None] + GUIDE_LENGTH * shape).astype(np.float32)


@dataclass
class Head:
    """The test scene: the mesh object and its arrays, the guides object
    and the guides' roots as pelage stamped them."""

    obj: bpy.types.Object
    positions: np.ndarray
    triangles: np.ndarray
    density: np.ndarray
    length: np.ndarray
    guides: bpy.types.Object
    guide_points: np.ndarray


def build_scene() -> Head:
    """An empty file with the head (density vertex group: 0 on the eyes and
    under the chin; a length attribute) and its guides."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    positions, triangles, shells = head()
    mesh = bpy.data.meshes.new("head")
    mesh.from_pydata(positions.tolist(), [], triangles.tolist())
    mesh.update()
    obj = bpy.data.objects.new("head", mesh)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    density = ((shells != 1) & (shells != 2) & (positions[:, 2] > -0.3)).astype(np.float32)
    group = obj.vertex_groups.new(name="density")
    group.add(np.flatnonzero(density).tolist(), 1.0, "REPLACE")
    length = (0.6 + 0.4 * (positions[:, 2] + 0.5)).astype(np.float32)
    attribute = mesh.attributes.new("length", "FLOAT", "POINT")
    attribute.data.foreach_set("value", length)

    pmesh = pelage.Mesh(positions, triangles)
    guide_roots, _ = pelage.stamp(pmesh, GUIDES, seed=7, density=density, bald_below=0.5)
    points = comb(*pelage.roots_evaluate(pmesh, guide_roots))
    data = convert.new_curves("guides", len(points), GUIDE_POINTS)
    convert.set_curves_points(data, np.concatenate([points, np.full(points.shape[:2] + (1,), 0.002, np.float32)], -1))
    guides = bpy.data.objects.new("guides", data)
    bpy.context.scene.collection.objects.link(guides)

    settings = obj.pelage_fur
    settings.guides = guides
    settings.count = HAIRS
    settings.density_attribute = "density"
    settings.bald_below = 0.5
    settings.seed = 3
    settings.length = 0.1
    settings.length_attribute = "length"
    settings.root_width = 0.004
    settings.tip_width = 0.0015
    settings.clump = 0.3
    settings.kink_amplitude = 0.004
    bpy.context.scene.frame_start, bpy.context.scene.frame_end = FRAMES
    bpy.context.scene.frame_set(FRAMES[0])
    return Head(obj, positions, triangles, density, length, guides, points)


def animate(obj: bpy.types.Object) -> None:
    """Keys a head turn and a move over the frame range, and bends the head
    with an animated Simple Deform modifier (the evaluated mesh deforms)."""
    first, last = FRAMES
    obj.location, obj.rotation_euler = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    obj.keyframe_insert("location", frame=first)
    obj.keyframe_insert("rotation_euler", frame=first)
    obj.location, obj.rotation_euler = (0.15, 0.0, 0.05), (0.0, 0.0, 0.6)
    obj.keyframe_insert("location", frame=last)
    obj.keyframe_insert("rotation_euler", frame=last)
    bend = obj.modifiers.new("bend", "SIMPLE_DEFORM")
    bend.deform_method = "BEND"
    bend.deform_axis = "X"
    bend.angle = 0.0
    bend.keyframe_insert("angle", frame=first)
    bend.angle = 0.5
    bend.keyframe_insert("angle", frame=last)
    # the keys hold the last values set until a frame is evaluated
    bpy.context.scene.frame_set(first)


@pytest.fixture(scope="session", autouse=True)
def addon() -> Iterator[None]:
    pelage_fur.register()
    yield
    pelage_fur.unregister()


@pytest.fixture()
def scene() -> Head:
    return build_scene()


def green_skin(head: Head) -> None:
    """Gives the head an emissive pure green skin, which the standard view
    transform keeps pure green: what :func:`skin_seen` counts."""
    skin = bpy.data.materials.new("skin")
    nodes = skin.node_tree.nodes
    nodes.clear()
    emission = nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (0.0, 1.0, 0.0, 1.0)
    skin.node_tree.links.new(emission.outputs[0], nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    head.obj.data.materials.append(skin)


def render_setup(head: Head, size: int, samples: int) -> None:
    """The render setup: a camera on the face, a sun, Cycles on the CPU,
    PNG files in the standard view transform, the guides hidden."""
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.location = (0.0, -2.2, 0.1)
    camera.rotation_euler = (np.pi / 2, 0.0, 0.0)
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.rotation_euler = (0.6, 0.0, 0.4)
    for obj in (camera, sun):
        bpy.context.scene.collection.objects.link(obj)
    s = bpy.context.scene
    s.camera = camera
    s.render.engine = "CYCLES"
    s.cycles.device = "CPU"
    s.cycles.samples = samples
    s.cycles.use_denoising = False
    s.render.resolution_x = s.render.resolution_y = size
    s.render.resolution_percentage = 100
    s.render.image_settings.file_format = "PNG"
    s.view_settings.view_transform = "Standard"
    head.guides.hide_render = True


def pixels(path: Path) -> np.ndarray:
    """An image file's float RGBA pixels, (pixels, 4)."""
    image = bpy.data.images.load(str(path))
    pixels = np.empty(image.size[0] * image.size[1] * 4, np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(-1, 4)


def skin_seen(path: Path) -> float:
    """How much of the picture is the skin's emission (pure green): the
    green above the other channels, summed over the pixels, so a pixel
    half covered by hair counts half."""
    rgb = pixels(path)[:, :3]
    return float(np.clip(rgb[:, 1] - rgb[:, [0, 2]].max(1), 0.0, 1.0).mean())
