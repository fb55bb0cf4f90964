"""The binding itself: version, record layouts, errors, handles, arrays."""

from __future__ import annotations

import gc

import numpy as np
import pytest

import pelage
from conftest import uv_sphere


def test_version_matches_the_library():
    assert pelage.version() == tuple(int(x) for x in pelage.__version__.split("."))
    assert pelage.lib.pelage_version() == 10000 * pelage.version()[0] + 100 * pelage.version()[1] + pelage.version()[2]


@pytest.mark.parametrize(
    "ctype, dtype",
    [
        ("PelageRoot", pelage.ROOT_DTYPE),
        ("PelageStrandBinding", pelage.BINDING_DTYPE),
        ("PelageStrandGroom", pelage.GROOM_DTYPE),
        ("PelagePatch", pelage.PATCH_DTYPE),
        ("PelageTrimRecord", pelage.TRIM_RECORD_DTYPE),
    ],
)
def test_record_dtypes_are_the_c_structs(ctype, dtype):
    ffi = pelage.ffi
    assert ffi.sizeof(ctype) == dtype.itemsize
    assert [name for name, _ in ffi.typeof(ctype).fields] == list(dtype.names)
    for name, field in ffi.typeof(ctype).fields:
        assert field.offset == dtype.fields[name][1]


def test_nan_positions_raise_non_finite_with_a_message():
    positions, triangles = uv_sphere(4, 8)
    positions[3, 1] = np.nan
    mesh = pelage.Mesh(positions, triangles)
    with pytest.raises(pelage.NonFinite) as caught:
        pelage.stamp(mesh, 100)
    error = caught.value
    assert isinstance(error, pelage.PelageError) and isinstance(error, ValueError)
    assert error.status == pelage.lib.PELAGE_STATUS_NON_FINITE == pelage.NonFinite.status
    assert error.function == "pelage_stamp_size"
    assert error.message, "pelage_last_error() gave no message"
    assert error.message in str(error)


def test_bad_index_is_out_of_range(sphere):
    positions, triangles = uv_sphere(4, 8)
    triangles[0, 0] = 10_000
    with pytest.raises(pelage.OutOfRange, match="pelage_stamp_size: .*out of range"):
        pelage.stamp(pelage.Mesh(positions, triangles), 100)


def test_invalid_argument_and_out_of_range_records(scene):
    roots = scene.roots.copy()
    roots["face"][5] = scene.mesh.triangle_count + 3
    with pytest.raises(pelage.OutOfRange) as caught:
        pelage.groom_evaluate(scene.mesh, roots)
    assert caught.value.message
    with pytest.raises(pelage.InvalidArgument):
        pelage.Frame(scene.mesh, scene.guides.guide_count, points_per_strand=1)


def test_wrong_record_dtype_is_a_type_error(scene):
    with pytest.raises(TypeError, match="dtype"):
        pelage.groom_evaluate(scene.mesh, np.zeros((10, 5), np.uint32))


def test_strided_positions_are_read_in_place():
    positions, triangles = uv_sphere(6, 12)
    float4 = np.ones((len(positions), 4), np.float32)
    float4[:, :3] = positions
    mesh = pelage.Mesh(float4[:, :3], triangles)
    assert np.shares_memory(mesh.positions, float4)
    assert mesh.desc.position_stride == 16
    reference, _ = pelage.stamp(pelage.Mesh(positions, triangles), 300, seed=4)
    strided, _ = pelage.stamp(mesh, 300, seed=4)
    assert strided.tobytes() == reference.tobytes()


def test_float64_positions_are_converted():
    positions, triangles = uv_sphere(6, 12)
    mesh = pelage.Mesh(positions.astype(np.float64), triangles.astype(np.int64))
    assert mesh.positions.dtype == np.float32 and mesh.triangles.dtype == np.uint32
    assert len(pelage.stamp(mesh, 100)[0]) == 100


def test_handles_are_freed_in_with_blocks(scene):
    with pelage.Frame(scene.mesh, scene.guides.guide_count) as frame:
        assert not frame.closed
        frame.set_guides(scene.guides)
    assert frame.closed
    with pytest.raises(ValueError, match="closed"):
        frame.set_guides(scene.guides)
    frame.close()  # twice is fine

    with pelage.Groom(scene.roots, scene.bindings, scene.grooms) as groom:
        assert len(groom) == len(scene.roots)
    assert groom.closed
    with pytest.raises(ValueError, match="closed"):
        groom.strand_count

    with pelage.Sim(scene.mesh, scene.guides) as sim:
        assert sim._memory is not None
    assert sim.closed and sim._memory is None
    assert "closed" in repr(sim)


def test_many_handles_do_not_leak(scene):
    # made and dropped without close(): released when collected
    for _ in range(200):
        pelage.Frame(scene.mesh, scene.guides.guide_count)
        pelage.Groom(scene.roots[:10], scene.bindings[:10], scene.grooms[:10])
    gc.collect()


def test_segment_indices():
    indices = pelage.segment_indices(3, 18)
    assert indices.dtype == np.uint32 and indices.shape == (3 * 15,)
    assert indices[:3].tolist() == [0, 1, 2] and indices[15] == 18
    with pytest.raises(pelage.InvalidArgument):
        pelage.segment_indices(3, 3)


def test_expand_size():
    assert pelage.expand_size() == 18
    assert pelage.expand_size(pelage.ExpandParams(points_per_strand=8, pinned=False)) == 8
