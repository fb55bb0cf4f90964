"""The groom file, guide caches, and trimming with its files."""

from __future__ import annotations

import numpy as np
import pytest

import pelage
from conftest import GUIDES, HAIRS, POINTS
from test_sim import moved_mesh


@pytest.fixture(scope="module")
def groom_file(scene):
    order, patches = pelage.patch_plan(scene.mesh, scene.roots, 500)
    with pelage.Frame(scene.mesh, GUIDES, POINTS) as rest:
        rest.set_guides(scene.guides)
        data = pelage.groom_file_write(
            rest, scene.guide_roots, scene.roots[order], scene.bindings[order], scene.grooms[order], patches
        )
    return data, order, patches


def test_groom_file_round_trip(scene, groom_file):
    data, order, patches = groom_file
    info = pelage.groom_file_info(data)
    assert (info.guide_count, info.points_per_guide, info.strand_count, info.patch_count) == (
        GUIDES, POINTS, HAIRS, len(patches)
    )
    read = pelage.groom_file_read(bytes(data))
    assert read.info == info
    assert read.guide_roots.tobytes() == scene.guide_roots.tobytes()
    assert read.roots.tobytes() == scene.roots[order].tobytes()
    assert read.bindings.tobytes() == scene.bindings[order].tobytes()
    assert read.grooms.tobytes() == scene.grooms[order].tobytes()
    assert read.patches.tobytes() == patches.tobytes()
    assert read.guide_points.shape == (GUIDES, POINTS, 3) and np.isfinite(read.guide_points).all()
    # the same inputs give the same bytes
    with pelage.Frame(scene.mesh, GUIDES, POINTS) as rest:
        rest.set_guides(scene.guides)
        again = pelage.groom_file_write(
            rest, scene.guide_roots, scene.roots[order], scene.bindings[order], scene.grooms[order], patches
        )
    assert again == data


def test_groom_file_errors(groom_file):
    data = groom_file[0]
    with pytest.raises(pelage.CorruptData) as caught:
        pelage.groom_file_read(data[: len(data) // 2])
    assert caught.value.message
    bad = bytearray(data)
    bad[0] ^= 0xFF
    with pytest.raises(pelage.VersionMismatch):
        pelage.groom_file_info(bad)


@pytest.mark.parametrize("exact", [True, False])
def test_guide_cache_round_trip(scene, groom_file, exact):
    data, order, _ = groom_file
    gf = pelage.groom_file_read(data)
    guide_set = gf.guide_set
    mesh = moved_mesh((0.1, 0.0, 0.0))
    with pelage.Sim(scene.mesh, scene.guides) as sim, pelage.Frame(mesh, GUIDES, POINTS) as live, pelage.Frame(
        mesh, GUIDES, POINTS
    ) as cached, pelage.Groom(gf.roots, gf.bindings, gf.grooms) as groom:
        sim.step(live)
        live.set_sim_guides(sim)
        cache = pelage.guide_cache_write(guide_set, [live], exact=exact)
        assert len(cache) <= pelage.guide_cache_size(GUIDES, POINTS, 1, exact)
        info = pelage.guide_cache_info(cache)
        assert info == pelage.GuideCacheInfo(GUIDES, POINTS, 1, exact, gf.info.id)
        pelage.guide_cache_read(cache, guide_set, cached, 0, threads=2)
        a, b = groom.expand(live), groom.expand(cached)
    if exact:
        assert np.abs(a - b).max() < 1e-5
    else:
        assert np.abs(a - b).max() < 1e-3
    with pelage.Frame(mesh, GUIDES, POINTS) as frame:
        with pytest.raises(pelage.InvalidArgument):
            pelage.guide_cache_read(cache, guide_set, frame, 1)  # one sample only
        other = pelage.GuideSet(guide_set.guide_roots, guide_set.guide_points, guide_set.groom_id ^ 1)
        with pytest.raises(pelage.InvalidArgument):
            pelage.guide_cache_read(cache, other, frame)


def test_guide_cache_progress_cancels(scene, groom_file, frame):
    gf = pelage.groom_file_read(groom_file[0])
    with pytest.raises(pelage.Cancelled):
        pelage.guide_cache_write(gf.guide_set, [frame], progress=lambda f: False)


def test_trim_find_shortest_and_files(scene):
    # a floor just above the south pole's fur cuts the guides that reach it
    floor = pelage.Colliders(planes=[[0.0, 0.0, 1.0, -1.1]])
    with pelage.Frame(scene.mesh, GUIDES, POINTS) as frame, pelage.Groom(scene.roots, scene.bindings, scene.grooms) as groom:
        frame.set_guides(scene.guides)
        records = pelage.trim_find(frame, colliders=floor, threads=2)
        assert records.dtype == pelage.TRIM_RECORD_DTYPE and 0 < len(records) < GUIDES
        assert ((records["length"] > 0) & (records["length"] < 1)).all()
        lengths = pelage.trim_whole(HAIRS)
        assert pelage.trim_shortest(groom, records, GUIDES, POINTS, lengths) is lengths
        cut = lengths < pelage.TRIM_WHOLE
        assert 0 < cut.sum() < HAIRS
        curves = groom.expand_edited(frame, lengths=lengths)
        whole = groom.expand(frame)
        assert curves.shape == whole.shape
        assert np.array_equal(curves[~cut], whole[~cut])
        assert curves[cut][..., 2].min() > whole[cut][..., 2].min()

        hair_lengths = pelage.trim_whole(HAIRS)
        pelage.trim_shortest_hairs(groom, frame, hair_lengths, colliders=floor, threads=2)
        trimmed = groom.expand_edited(frame, lengths=hair_lengths)
        assert trimmed[..., 2].min() > -1.1 - 1e-3

        with pytest.raises(pelage.Cancelled):
            pelage.trim_find(frame, colliders=floor, progress=lambda f: False)

    data = pelage.trim_records_write(records, GUIDES, POINTS)
    assert pelage.trim_records_info(data) == pelage.TrimRecordsInfo(GUIDES, POINTS, len(records))
    back, info = pelage.trim_records_read(data)
    assert back.tobytes() == records.tobytes() and info.record_count == len(records)
    data = pelage.trim_lengths_write(lengths)
    assert pelage.trim_lengths_read(data).tobytes() == lengths.tobytes()
    with pytest.raises(pelage.CorruptData):
        pelage.trim_lengths_read(data[:-1])


def test_cloth_trims_like_a_plane(scene, frame):
    # a large two-triangle sheet at z = -1.1 as the cloth
    cloth = pelage.Mesh([[-3, -3, -1.1], [3, -3, -1.1], [3, 3, -1.1], [-3, 3, -1.1]], [[0, 1, 2], [0, 2, 3]])
    records = pelage.trim_find(frame, cloth=cloth)
    assert 0 < len(records) < GUIDES
