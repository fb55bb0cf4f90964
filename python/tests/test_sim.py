"""The simulation: steps under motion, read, save and restore, reset."""

from __future__ import annotations

import numpy as np
import pytest

import pelage
from conftest import GUIDES, POINTS, uv_sphere


def moved_mesh(offset):
    positions, triangles = uv_sphere()
    return pelage.Mesh(positions + np.asarray(offset, np.float32), triangles)


def test_step_read_save_restore_reset(scene):
    with pelage.Sim(scene.mesh, scene.guides, link_radius=0.3) as sim:
        assert sim.guide_count == GUIDES and sim.points_per_guide == POINTS
        with pytest.raises(pelage.InvalidArgument):
            sim.read()  # no step yet
        frames = []
        for f in range(6):
            mesh = moved_mesh((0.05 * f, 0.0, 0.0))
            frames.append(pelage.Frame(mesh, GUIDES, POINTS))
        try:
            for f in frames[:3]:
                info = sim.step(f, 1 / 24)
                assert isinstance(info, pelage.StepInfo)
            state = sim.save()
            assert isinstance(state, bytearray) and state[:8] == b"PLGSTATE"
            after3 = sim.read().copy()
            assert np.isfinite(after3).all()
            # the roots moved with the mesh; the tips lag behind
            roots_x = after3[:, 0, 0] - scene.guides.points.reshape(GUIDES, POINTS, 3)[:, 0, 0]
            assert np.allclose(roots_x, 0.1, atol=1e-4)
            tips_x = after3[:, -1, 0] - scene.guides.points.reshape(GUIDES, POINTS, 3)[:, -1, 0]
            assert tips_x.mean() < 0.1
            for f in frames[3:]:
                sim.step(f)
            after6 = sim.read().copy()
            sim.restore(state)
            assert np.array_equal(sim.read(), after3)
            for f in frames[3:]:
                sim.step(f)
            assert after6.tobytes() == sim.read().tobytes(), "restored runs give the same bits"
            with pytest.raises(pelage.CorruptData):
                sim.restore(state[:-3])
            bad = bytearray(state)
            bad[len(bad) // 2] ^= 0xFF
            with pytest.raises(pelage.CorruptData):
                sim.restore(bad)
            sim.reset()
            with pytest.raises(pelage.InvalidArgument):
                sim.read()
        finally:
            for f in frames:
                f.close()


def test_read_into_a_float4_buffer(scene, frame):
    with pelage.Sim(scene.mesh, scene.guides) as sim:
        sim.step(frame)
        packed = sim.read()
        float4 = np.zeros((GUIDES, POINTS, 4), np.float32)
        assert sim.read(float4) is float4
        assert np.array_equal(float4[..., :3], packed) and (float4[..., 3] == 0).all()


def test_frame_posed_from_the_simulation(scene):
    with pelage.Sim(scene.mesh, scene.guides) as sim, pelage.Frame(moved_mesh((0.2, 0, 0)), GUIDES, POINTS) as frame:
        with pytest.raises(pelage.InvalidArgument):
            frame.set_sim_guides(sim)  # no step yet
        sim.step(frame)
        frame.set_sim_guides(sim)
        direct = pelage.expand(frame, scene.roots, scene.bindings, scene.grooms)
        frame.set_guides(pelage.Guides(scene.guide_roots, sim.read()))
        via_read = pelage.expand(frame, scene.roots, scene.bindings, scene.grooms)
    assert direct.tobytes() == via_read.tobytes()


def test_sim_parameters_are_checked(scene):
    with pytest.raises(pelage.InvalidArgument):
        pelage.Sim(scene.mesh, scene.guides, joints=1)
    with pytest.raises(pelage.NonFinite):
        pelage.Sim(scene.mesh, scene.guides, frequency=np.nan)
    with pelage.Sim(scene.mesh, scene.guides, joints=8, points_per_guide=12, frequency=scene.mesh.positions[:, 2] + 2) as sim:
        assert sim.points_per_guide == 12


def test_external_curves_take_over(scene, frame):
    # guides on the north half take their shape from the host's curves
    external = (scene.mesh.positions[:, 2] > 0).astype(np.float32)
    host = scene.guides.points.reshape(GUIDES, POINTS, 3).copy()
    host[:, 1:, 0] += np.linspace(0, 0.1, POINTS - 1)[None, :]  # swept along +x
    with pelage.Sim(scene.mesh, scene.guides, external=external) as sim, pelage.Sim(scene.mesh, scene.guides) as plain:
        sim.step(frame, external_points=host)
        plain.step(frame)
        a, b = sim.read(), plain.read()
    north = scene.guides.points.reshape(GUIDES, POINTS, 3)[:, 0, 2] > 0.3
    south = scene.guides.points.reshape(GUIDES, POINTS, 3)[:, 0, 2] < -0.3
    assert (a[north, -1, 0] - b[north, -1, 0]).mean() > 0.02
    assert np.abs(a[south] - b[south]).max() < 1e-6


def test_an_origin_that_follows_the_mesh_matches_the_world_origin(scene):
    # the same run at the world's origin, and far away given relative to an
    # origin that moves with the mesh: the same guides, shifted
    far = np.array([1.0e4, -2.0e3, 3.0e3])
    with pelage.Sim(scene.mesh, scene.guides) as home, pelage.Sim(scene.mesh, scene.guides) as away:
        for f in range(6):
            shift = np.array([0.05 * f, 0.0, 0.0])
            with pelage.Frame(moved_mesh(shift), GUIDES, POINTS) as here, pelage.Frame(
                moved_mesh((0.0, 0.0, 0.0)), GUIDES, POINTS
            ) as there:
                there.origin = far + shift
                assert there.origin == tuple(far + shift)
                home.step(here, 1 / 24)
                away.step(there, 1 / 24)
            assert away.origin == tuple(far + shift)
            apart = home.read().astype(np.float64) - (away.read().astype(np.float64) + shift)
            assert np.abs(apart).max() < 1e-5
        with pelage.Frame(moved_mesh((0.0, 0.0, 0.0)), GUIDES, POINTS) as frame:
            with pytest.raises(pelage.NonFinite):
                frame.origin = (0.0, float("nan"), 0.0)
            with pytest.raises(ValueError):
                frame.origin = (0.0, 0.0)
