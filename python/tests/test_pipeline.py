"""Stamp, bind, groom, settle, frames and expansion on a UV sphere."""

from __future__ import annotations

import numpy as np
import pytest

import pelage
from conftest import GUIDES, HAIRS, LENGTH, POINTS, diving_guides


def test_stamp_count_and_determinism(sphere):
    roots, info = pelage.stamp(sphere, 2000, seed=9)
    again, _ = pelage.stamp(sphere, 2000, seed=9)
    other, _ = pelage.stamp(sphere, 2000, seed=10)
    assert roots.dtype == pelage.ROOT_DTYPE and roots.shape == (2000,)
    assert roots.tobytes() == again.tobytes()
    assert roots.tobytes() != other.tobytes()
    assert info.radius > 0 and info.passes >= 1
    assert np.array_equal(roots["id"], np.arange(2000))
    assert np.array_equal(np.sort(roots["rank"]), np.arange(2000))
    assert (roots["face"] < sphere.triangle_count).all()


def test_stamp_density_map_leaves_bald_regions(sphere):
    density = (sphere.positions[:, 2] > 0).astype(np.float32)  # per vertex: the top half
    roots, _ = pelage.stamp(sphere, 0, radius=0.08, density=density, bald_below=0.5)
    positions, _ = pelage.roots_evaluate(sphere, roots)
    assert len(roots) > 50
    assert (positions[:, 2] > -0.2).all()


def test_roots_evaluate_on_the_sphere(scene):
    positions, normals = pelage.roots_evaluate(scene.mesh, scene.roots)
    assert positions.shape == normals.shape == (HAIRS, 3)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-5)
    assert (np.einsum("ij,ij->i", positions, normals) > 0.9).all(), "normals point outward"


def test_bind_records(scene):
    b = scene.bindings
    assert b.dtype == pelage.BINDING_DTYPE and b.shape == (HAIRS,)
    used = b["count"] > 0
    assert used.mean() > 0.9
    sums = np.where(np.arange(8)[None, :] < b["count"][:, None], b["weights"], 0).sum(axis=1)
    assert np.allclose(sums[used], 1.0, atol=pelage.WEIGHT_SUM_TOLERANCE)
    assert (b["guides"][used, 0] < GUIDES).all()


def test_groom_evaluate_maps(scene):
    g = scene.grooms
    assert g.dtype == pelage.GROOM_DTYPE
    assert np.allclose(g["root_radius"], 0.005)
    lengths = pelage.groom_evaluate(scene.mesh, scene.roots, length=scene.mesh.positions[:, 2] + 2.0)["length"]
    positions, _ = pelage.roots_evaluate(scene.mesh, scene.roots)
    assert np.corrcoef(lengths, positions[:, 2])[0, 1] > 0.99
    texture = np.full((4, 4), 255, np.uint8)
    assert np.allclose(pelage.groom_evaluate(scene.mesh, scene.roots, clump=pelage.Map.uniform(0.25))["clump"], 0.25)
    with pytest.raises(pelage.InvalidArgument, match="needs mesh UVs"):
        pelage.groom_evaluate(scene.mesh, scene.roots, bend=texture)
    # random variations: each strand keeps 1 - v u of its length and pull
    varied = pelage.groom_evaluate(scene.mesh, scene.roots, clump=0.8, length_random=0.5, clump_random=1.0)
    assert ((varied["length"] > 0.5) & (varied["length"] <= 1.0)).all()
    assert abs(varied["length"].mean() - 0.75) < 0.03 and abs(varied["clump"].mean() - 0.4) < 0.04
    plain = pelage.groom_evaluate(scene.mesh, scene.roots, clump=0.8)
    assert (plain["length"] == 1.0).all() and (plain["clump"] == np.float32(0.8)).all()


def test_expand_shapes_and_values(scene, frame):
    with pelage.Groom(scene.roots, scene.bindings, scene.grooms) as groom:
        curves = groom.expand(frame)
    assert curves.shape == (HAIRS, POINTS + 2, 4) and curves.dtype == np.float32
    assert np.isfinite(curves).all()
    assert (curves[..., 3] > 0).all(), "radii are positive"
    # pinned ends: the first and last points repeat
    assert np.array_equal(curves[:, 0], curves[:, 1]) and np.array_equal(curves[:, -1], curves[:, -2])
    positions, _ = pelage.roots_evaluate(scene.mesh, scene.roots)
    assert np.allclose(curves[:, 0, :3], positions, atol=1e-5)
    tips = np.linalg.norm(curves[:, -1, :3], axis=1)
    assert tips.max() < 1.0 + 2 * LENGTH and np.median(tips) > 1.05
    raw = pelage.expand(frame, scene.roots, scene.bindings, scene.grooms, pelage.ExpandParams(pinned=False))
    assert np.array_equal(raw, curves[:, 1:-1])


def test_expand_into_a_host_buffer(scene, frame):
    with pelage.Groom(scene.roots, scene.bindings, scene.grooms) as groom:
        whole = groom.expand(frame)
        # a host's float buffer with a fifth column (say a curve parameter)
        host = np.full((HAIRS * (POINTS + 2), 5), -1.0, np.float32)
        ids = np.zeros(100, np.uint32)
        result = groom.expand(frame, 100, 100, out=host, ids=ids)
        assert result is host
        assert np.array_equal(host[: 100 * (POINTS + 2), :4].reshape(100, POINTS + 2, 4), whole[100:200])
        assert (host[:, 4] == -1).all() and (host[100 * (POINTS + 2) :, :4] == -1).all()
        assert np.array_equal(ids, scene.roots["id"][100:200])
        with pytest.raises(ValueError, match="points"):
            groom.expand(frame, out=np.empty((10, 18, 4), np.float32))
        with pytest.raises(pelage.OutOfRange):
            groom.expand(frame, HAIRS - 5, 10)


def test_groom_expand_matches_expand_with_threads(scene, frame):
    once = pelage.expand(frame, scene.roots, scene.bindings, scene.grooms, threads=1)
    many = pelage.expand(frame, scene.roots, scene.bindings, scene.grooms, threads=2)
    assert once.tobytes() == many.tobytes()


def test_settle_lifts_strands_out_of_the_body(scene):
    guides = pelage.Guides(scene.guide_roots, diving_guides(scene.mesh, scene.guide_roots))
    bindings, _ = pelage.bind(scene.mesh, guides, scene.roots)
    grooms = pelage.groom_evaluate(scene.mesh, scene.roots)
    before = grooms.copy()
    with pelage.Frame(scene.mesh, GUIDES) as frame:
        frame.set_guides(guides)
        curves = pelage.expand(frame, scene.roots, bindings, grooms)
        inside_before = frame.inside(curves[:, 3:, :3].reshape(-1, 3))
        info = pelage.settle(scene.mesh, guides, scene.roots, bindings, grooms, threads=2)
        curves = pelage.expand(frame, scene.roots, bindings, grooms)
        inside = frame.inside(curves[:, 3:, :3].reshape(-1, 3))
    assert inside.dtype == np.bool_
    assert inside_before.mean() > 0.2
    assert info.lifted > HAIRS // 2
    assert not np.array_equal(grooms["lift"], before["lift"])
    assert inside.mean() < 0.01
    with pytest.raises(ValueError, match="in place"):
        pelage.settle(scene.mesh, scene.guides, scene.roots, scene.bindings, scene.grooms)


def test_frame_inside(frame):
    points = np.array([[0, 0, 0], [0, 0, 0.9], [0, 0, 1.1], [2, 0, 0]], np.float32)
    assert frame.inside(points).tolist() == [True, True, False, False]
    with pytest.raises(pelage.NonFinite):
        frame.inside([[0, 0, np.inf]])
    distances = frame.signed_distance(points)
    assert distances.dtype == np.float32 and distances.shape == (4,)
    assert ((distances < 0) == frame.inside(points)).all()
    assert np.allclose(distances, [-1.0, -0.1, 0.1, 1.0], atol=0.05)


def test_patches_boxes_and_lod(scene, frame):
    order, patches = pelage.patch_plan(scene.mesh, scene.roots, 256)
    assert sorted(order.tolist()) == list(range(HAIRS))
    assert patches["count"].sum() == HAIRS and patches.shape == (-(-HAIRS // 256),)
    roots, bindings, grooms = scene.roots[order], scene.bindings[order], scene.grooms[order]
    boxes = pelage.patch_boxes(frame, roots, bindings, grooms, patches)
    assert boxes.shape == (len(patches), 2, 3)
    with pelage.Groom(roots, bindings, grooms) as groom:
        curves = groom.expand(frame)
        for (first, count), box in zip(patches.tolist(), boxes):
            pts = curves[first : first + count, :, :3].reshape(-1, 3)
            assert (pts >= box[0] - 1e-6).all() and (pts <= box[1] + 1e-6).all()
        counts = groom.lod_counts(patches, HAIRS // 2)
        assert counts.sum() == HAIRS // 2
        for (first, count), kept in zip(patches.tolist(), counts.tolist()):
            assert (roots["rank"][first : first + kept] < HAIRS // 2).all()


def test_map_mask(scene):
    mask = pelage.map_mask(scene.mesh, scene.mesh.positions[:, 0], scene.roots, threshold=0.0)
    positions, _ = pelage.roots_evaluate(scene.mesh, scene.roots)
    assert mask.dtype == np.bool_
    assert (mask == (positions[:, 0] >= 0))[np.abs(positions[:, 0]) > 0.1].all()


def test_regions_part_the_bindings(scene):
    regions = pelage.RegionMap((scene.mesh.positions[:, 0] > 0).astype(np.uint32))
    bindings, _ = pelage.bind(scene.mesh, scene.guides, scene.roots, regions=regions)
    gp, _ = pelage.roots_evaluate(scene.mesh, scene.guide_roots)
    hp, _ = pelage.roots_evaluate(scene.mesh, scene.roots)
    # a guide takes its nearest corner's region: away from x = 0 the side tells it
    checked = 0
    for strand in np.flatnonzero(np.abs(hp[:, 0]) > 0.2):
        used = bindings["guides"][strand, : bindings["count"][strand]]
        used = used[np.abs(gp[used, 0]) > 0.15]
        assert (np.sign(gp[used, 0]) == np.sign(hp[strand, 0])).all()
        checked += len(used)
    assert checked > 1000


def test_guides_with_offsets_match_fixed_counts(scene):
    fixed = scene.guides.points.reshape(GUIDES, POINTS, 3)
    offsets = np.arange(GUIDES + 1, dtype=np.uint32) * POINTS
    varying = pelage.Guides(scene.guide_roots, fixed.reshape(-1, 3), offsets=offsets)
    with pelage.Frame(scene.mesh, GUIDES, POINTS) as a, pelage.Frame(scene.mesh, GUIDES, POINTS) as b:
        a.set_guides(scene.guides)
        b.set_guides(varying)
        assert np.array_equal(
            pelage.expand(a, scene.roots, scene.bindings, scene.grooms),
            pelage.expand(b, scene.roots, scene.bindings, scene.grooms),
        )


def test_texture_map_with_uvs(scene):
    positions = scene.mesh.positions
    uvs = np.stack([np.arctan2(positions[:, 1], positions[:, 0]) / (2 * np.pi) + 0.5, positions[:, 2] * 0.5 + 0.5], 1)
    mesh = pelage.Mesh(positions, scene.mesh.triangles, uvs=uvs)
    texture = np.tile(np.linspace(0, 255, 64, dtype=np.float32)[:, None], (1, 8)).astype(np.uint8)  # grows with v
    length = pelage.groom_evaluate(mesh, scene.roots, length=texture)["length"]
    p, _ = pelage.roots_evaluate(mesh, scene.roots)
    assert np.corrcoef(length, p[:, 2])[0, 1] > 0.95
    assert np.allclose(pelage.groom_evaluate(mesh, scene.roots, length=texture.astype(np.float32) / 255)["length"], length, atol=1e-3)


def test_patches_expand_from_python_threads(scene, frame):
    from concurrent.futures import ThreadPoolExecutor

    with pelage.Groom(scene.roots, scene.bindings, scene.grooms) as groom:
        whole = groom.expand(frame)
        out = np.empty_like(whole)
        ranges = [(first, min(500, HAIRS - first)) for first in range(0, HAIRS, 500)]
        with ThreadPoolExecutor(2) as pool:
            list(pool.map(lambda r: groom.expand(frame, r[0], r[1], out=out[r[0] : r[0] + r[1]]), ranges))
    assert out.tobytes() == whole.tobytes()
