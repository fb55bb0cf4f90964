"""Progress callbacks that cancel, and Python distance fields."""

from __future__ import annotations

import sys
import threading
import time

import numpy as np
import pytest

import pelage
from conftest import GUIDES, HAIRS, POINTS, diving_guides


class Recorder:
    """A progress callback that records what it hears and cancels after
    ``stop_after`` reports (never when None)."""

    def __init__(self, stop_after=None):
        self.fractions = []
        self.threads = set()
        self.stop_after = stop_after

    def __call__(self, fraction: float):
        self.fractions.append(fraction)
        self.threads.add(threading.get_ident())
        if self.stop_after is not None and len(self.fractions) > self.stop_after:
            return False
        return None  # None goes on


def test_progress_is_heard_in_order_on_the_calling_thread(sphere):
    progress = Recorder()
    pelage.stamp(sphere, 20000, progress=progress)
    assert len(progress.fractions) >= 2 and progress.fractions[-1] == 1.0
    assert progress.fractions == sorted(progress.fractions)
    assert progress.threads == {threading.get_ident()}


def test_cancelled_stamp_and_bind(sphere, scene):
    with pytest.raises(pelage.Cancelled) as caught:
        pelage.stamp(sphere, 20000, progress=lambda f: False)
    assert caught.value.status == pelage.lib.PELAGE_STATUS_CANCELLED
    with pytest.raises(pelage.Cancelled):
        pelage.bind(scene.mesh, scene.guides, scene.roots, threads=2, progress=Recorder(stop_after=1))


def test_cancelled_settle_leaves_strands_settled_or_unchanged(scene):
    guides = pelage.Guides(scene.guide_roots, diving_guides(scene.mesh, scene.guide_roots))
    bindings, _ = pelage.bind(scene.mesh, guides, scene.roots)
    before = pelage.groom_evaluate(scene.mesh, scene.roots)
    settled = before.copy()
    pelage.settle(scene.mesh, guides, scene.roots, bindings, settled)
    changed = settled != before
    assert changed.sum() > HAIRS // 2
    grooms = before.copy()
    progress = Recorder(stop_after=2)
    with pytest.raises(pelage.Cancelled):
        pelage.settle(scene.mesh, guides, scene.roots, bindings, grooms, threads=1, progress=progress)
    # the documented state: each strand settled (as a whole call settles it) or unchanged
    assert ((grooms == settled) | (grooms == before)).all()
    reached = (grooms == settled) & changed
    assert 0 < reached.sum() < changed.sum()


def test_cancelled_step_is_taken_back(scene, frame):
    with pelage.Sim(scene.mesh, scene.guides) as sim:
        sim.step(frame)
        state = bytes(sim.save())
        before = sim.read().copy()
        progress = Recorder(stop_after=1)
        with pytest.raises(pelage.Cancelled):
            sim.step(frame, progress=progress)
        assert len(progress.fractions) == 2
        assert np.array_equal(sim.read(), before)
        assert bytes(sim.save()) == state


def test_cancelled_expand_and_frame_without_guides(scene):
    with pelage.Frame(scene.mesh, GUIDES, POINTS) as frame:
        frame.set_guides(scene.guides)
        with pytest.raises(pelage.Cancelled):
            pelage.expand(frame, scene.roots, scene.bindings, scene.grooms, progress=lambda f: f < 0.5)
        # a set_guides cancelled after the check leaves the frame without guides
        with pytest.raises(pelage.Cancelled):
            frame.set_guides(scene.guides, progress=lambda f: False)
        with pytest.raises(pelage.InvalidArgument, match="guides"):
            pelage.expand(frame, scene.roots, scene.bindings, scene.grooms)
        frame.set_guides(scene.guides)
        assert np.isfinite(pelage.expand(frame, scene.roots, scene.bindings, scene.grooms)).all()


def test_progress_exception_is_re_raised(sphere):
    class Stop(Exception):
        pass

    def progress(fraction):
        raise Stop("from the callback")

    with pytest.raises(Stop, match="from the callback") as caught:
        pelage.stamp(sphere, 20000, progress=progress)
    notes = getattr(caught.value, "__notes__", [])
    assert any("pelage_stamp" in note for note in notes)


def ball(centre, radius):
    """A Python signed distance field of a ball, recording its calls."""

    calls = []

    def distance(points: np.ndarray):
        assert points.dtype == np.float32 and points.shape[1] == 3
        assert not points.flags.writeable
        calls.append((threading.get_ident(), len(points)))
        return np.linalg.norm(points - np.asarray(centre, np.float32), axis=1) - radius

    distance.calls = calls
    return distance


def posed_guides(scene, frame, colliders, threads=2):
    with pelage.Sim(scene.mesh, scene.guides) as sim:
        sim.step(frame, colliders=colliders, threads=threads)
        return sim.read().copy()


def ball_in_the_fur(scene):
    """A ball around the middle of the northernmost guide."""
    points = scene.guides.points.reshape(GUIDES, POINTS, 3)
    top = int(np.argmax(points[:, 0, 2]))
    return tuple(float(x) for x in points[top, POINTS // 2]), 0.08


def test_python_distance_field_collides(scene, frame):
    centre, radius = ball_in_the_fur(scene)
    free = posed_guides(scene, frame, None)
    sdf = ball(centre, radius)
    pushed = posed_guides(scene, frame, pelage.Colliders(distance=sdf))
    inside_free = np.linalg.norm(free - centre, axis=2) < radius - 1e-3
    inside_pushed = np.linalg.norm(pushed - centre, axis=2) < radius - 1e-3
    assert inside_free.sum() > 0, "the ball is in the way of some guide"
    assert inside_pushed.sum() < inside_free.sum() / 4
    assert sdf.calls, "the field was called"
    assert max(n for _, n in sdf.calls) >= POINTS, "points come in batches"
    # the same as pelage's own sphere collider, within the field's float32 arithmetic
    native = posed_guides(scene, frame, pelage.Colliders(spheres=[[*centre, radius]]))
    assert np.abs(native - pushed).max() < 1e-3


def test_distance_field_threads_and_push_mask(scene):
    centre, radius = ball_in_the_fur(scene)
    sdf = ball(centre, radius)
    colliders = pelage.Colliders(distance=sdf)
    with pelage.Frame(scene.mesh, GUIDES, POINTS) as frame, pelage.Groom(scene.roots, scene.bindings, scene.grooms) as groom:
        frame.set_guides(scene.guides)
        frame.set_colliders(colliders)
        plain = groom.expand(frame)
        mask = np.ones(HAIRS, np.bool_)
        pushed = groom.expand_edited(frame, push_mask=mask, threads=2)
        assert not np.array_equal(plain, pushed)
        depth = np.linalg.norm(plain[..., :3] - centre, axis=2) - radius
        assert depth.min() < -0.02, "some hairs go through the ball"
        depth = np.linalg.norm(pushed[..., :3] - centre, axis=2) - radius
        assert depth.min() > -0.01
        assert len({t for t, _ in sdf.calls}) >= 1


def test_raising_distance_field_re_raises_from_step(scene, frame):
    class Boom(RuntimeError):
        pass

    def distance(points):
        raise Boom("field failed")

    with pelage.Sim(scene.mesh, scene.guides) as sim:
        sim.step(frame)
        before = bytes(sim.save())
        with pytest.raises(Boom, match="field failed") as caught:
            sim.step(frame, colliders=pelage.Colliders(distance=distance), threads=2)
        assert any("pelage_sim_step" in note for note in getattr(caught.value, "__notes__", []))
        assert bytes(sim.save()) == before, "the step was taken back"
        # the same simulation steps on afterwards
        sim.step(frame)


def test_nan_distance_is_non_finite(scene, frame):
    colliders = pelage.Colliders(distance=lambda p: np.full(len(p), np.nan))
    with pelage.Sim(scene.mesh, scene.guides) as sim:
        with pytest.raises(pelage.NonFinite) as caught:
            sim.step(frame, colliders=colliders)
    assert caught.value.message


def test_gil_is_released_during_calls(scene, frame):
    # With a long switch interval another Python thread gets the GIL only
    # when this one lets it go: it ticks during the expansions only if cffi
    # released the GIL around the C calls (it yields right after each tick,
    # so it never keeps this thread waiting).
    ticks = []
    stop = threading.Event()

    def other():
        while not stop.is_set():
            ticks.append(1)
            time.sleep(0)

    old = sys.getswitchinterval()
    sys.setswitchinterval(10.0)
    worker = threading.Thread(target=other)
    try:
        worker.start()
        before = len(ticks)
        end = time.monotonic() + 2.0
        while time.monotonic() < end:  # until the OS scheduled the other thread meanwhile
            pelage.expand(frame, scene.roots, scene.bindings, scene.grooms, threads=1)
            if len(ticks) > before:
                break
        during = len(ticks) - before
    finally:
        stop.set()
        worker.join()
        sys.setswitchinterval(old)
    assert during > 0


def test_distance_field_from_worker_threads(sphere):
    # enough guides that the step splits them over its threads
    from conftest import combed_guides

    roots, _ = pelage.stamp(sphere, 3000, seed=5)
    guides = pelage.Guides(roots, combed_guides(sphere, roots))
    field = ball(tuple(guides.points[POINTS // 2]), 0.1)

    def sdf(points):
        time.sleep(0.001)  # a field that takes a while, as a host's does: the GIL is free meanwhile
        return field(points)

    results = []
    with pelage.Frame(sphere, len(roots), POINTS) as frame:
        for threads in (2, 1):
            with pelage.Sim(sphere, guides) as sim:
                sim.step(frame, colliders=pelage.Colliders(distance=sdf), threads=threads)
                results.append(sim.read())
            if threads == 2:
                callers = {t for t, _ in field.calls}
    assert len(callers) >= 2, "called from the step's worker threads"
    assert threading.get_ident() in callers
    assert results[0].tobytes() == results[1].tobytes()
