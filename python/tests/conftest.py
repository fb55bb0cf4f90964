"""Shared fixtures: a UV sphere made in numpy, combed guides on it, and a
bound, settled groom."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

import pelage

GUIDES = 60
HAIRS = 3000
POINTS = 16
LENGTH = 0.3


def uv_sphere(rings: int = 16, segments: int = 32, radius: float = 1.0):
    """A closed UV sphere: (positions (n, 3) float32, triangles (m, 3) uint32)."""
    theta = np.linspace(0.0, np.pi, rings + 1)[1:-1]
    phi = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1).reshape(-1, 3)
    positions = np.concatenate([[[0.0, 0.0, 1.0]], ring, [[0.0, 0.0, -1.0]]]) * radius
    top, bottom = 0, len(positions) - 1

    def v(r: int, s: int) -> int:
        return 1 + r * segments + s % segments

    tris = []
    for s in range(segments):
        tris.append((top, v(0, s), v(0, s + 1)))
        tris.append((bottom, v(rings - 2, s + 1), v(rings - 2, s)))
    for r in range(rings - 2):
        for s in range(segments):
            a, b, c, d = v(r, s), v(r, s + 1), v(r + 1, s + 1), v(r + 1, s)
            tris.append((a, d, c))
            tris.append((a, c, b))
    return positions.astype(np.float32), np.asarray(tris, np.uint32)


def combed_guides(mesh: pelage.Mesh, roots: np.ndarray, points: int = POINTS, length: float = LENGTH) -> np.ndarray:
    """Guides that leave along the normal and bend toward -z: (g, points, 3)."""
    p, n = pelage.roots_evaluate(mesh, roots)
    t = np.linspace(0.0, 1.0, points, dtype=np.float32)[None, :, None]
    comb = np.array([0.0, 0.0, -0.5], np.float32)
    return (p[:, None, :] + length * (t * n[:, None, :] + t * t * comb)).astype(np.float32)


def diving_guides(mesh: pelage.Mesh, roots: np.ndarray, points: int = POINTS, length: float = LENGTH) -> np.ndarray:
    """Guides that leave along the surface and dive into the body (strands
    bound to them need settling): (g, points, 3)."""
    p, n = pelage.roots_evaluate(mesh, roots)
    tangent = np.cross(n, [0.0, 0.0, 1.0])
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    t = np.linspace(0.0, 1.0, points)[None, :, None]
    return (p[:, None] + length * (t * tangent[:, None] - 0.5 * t * t * n[:, None])).astype(np.float32)


@dataclass
class Scene:
    mesh: pelage.Mesh
    guide_roots: np.ndarray
    guides: pelage.Guides
    roots: np.ndarray
    bindings: np.ndarray
    grooms: np.ndarray


@pytest.fixture(scope="session")
def sphere() -> pelage.Mesh:
    return pelage.Mesh(*uv_sphere())


@pytest.fixture(scope="session")
def scene(sphere: pelage.Mesh) -> Scene:
    guide_roots, _ = pelage.stamp(sphere, GUIDES, seed=1)
    guides = pelage.Guides(guide_roots, combed_guides(sphere, guide_roots))
    roots, _ = pelage.stamp(sphere, HAIRS, seed=2)
    bindings, _ = pelage.bind(sphere, guides, roots)
    grooms = pelage.groom_evaluate(sphere, roots, length=1.0, root_width=0.01)
    pelage.settle(sphere, guides, roots, bindings, grooms)
    for a in (guide_roots, roots, bindings, grooms):
        a.flags.writeable = False
    return Scene(sphere, guide_roots, guides, roots, bindings, grooms)


@pytest.fixture()
def frame(scene: Scene):
    with pelage.Frame(scene.mesh, scene.guides.guide_count, POINTS) as f:
        f.set_guides(scene.guides)
        yield f
