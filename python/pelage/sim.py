"""Guide dynamics: the simulation handle."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, List, Optional, Tuple, Union

import numpy as np

from ._ffi import ffi, lib
from ._handle import Handle
from ._util import Call, ProgressFn, new_struct, point_rows, ptr, rows, set_fields, write_bytes
from .errors import check
from .frame import Colliders, Frame
from .mesh import Guides, Map, MapLike, Mesh
from .pipeline import _arena, _rest

__all__ = ["Sim", "StepInfo"]


@dataclass(frozen=True)
class StepInfo:
    """What a step reports (``PelageStepInfo``)."""

    groomed_guides: int


class Sim(Handle):
    """Simulated guides (``PelageSim``) in memory this object owns.

    Args:
        mesh, guides: the rest pose (the guides' shapes in their root frames
            are their neutral pose).
        joints ... external: ``PelageSimParams``' fields; None keeps the C
            default (16 joints and points, 1.5 Hz, amplitude 1, decay 3/s,
            no links). ``frequency``, ``amplitude``, ``decay`` and
            ``external`` are maps (:class:`Map`, a number or per-vertex
            values), sampled at the guide roots.

    Thread safety: :meth:`step`, :meth:`reset`, :meth:`restore` and
    :meth:`close` need the simulation to themselves; :meth:`read` and
    :meth:`save` may run at once.
    """

    _free = staticmethod(lib.pelage_sim_free)

    def __init__(
        self,
        mesh: Mesh,
        guides: Guides,
        *,
        joints: Optional[int] = None,
        points_per_guide: Optional[int] = None,
        frequency: Optional[MapLike] = None,
        amplitude: Optional[MapLike] = None,
        decay: Optional[MapLike] = None,
        ik_tolerance: Optional[float] = None,
        ik_max_iterations: Optional[int] = None,
        root_stiffness: Optional[float] = None,
        tip_stiffness: Optional[float] = None,
        link_radius: Optional[float] = None,
        max_links: Optional[int] = None,
        link_iterations: Optional[int] = None,
        link_stiffness: Optional[float] = None,
        teleport: Optional[float] = None,
        external: Optional[MapLike] = None,
    ) -> None:
        super().__init__()
        keep: List[Any] = []
        p = new_struct("PelageSimParams", lib.pelage_sim_params_defaults())
        set_fields(
            p,
            joints=joints,
            points_per_guide=points_per_guide,
            ik_tolerance=ik_tolerance,
            ik_max_iterations=ik_max_iterations,
            root_stiffness=root_stiffness,
            tip_stiffness=tip_stiffness,
            link_radius=link_radius,
            max_links=max_links,
            link_iterations=link_iterations,
            link_stiffness=link_stiffness,
            teleport=teleport,
        )
        for name, value in (("frequency", frequency), ("amplitude", amplitude), ("decay", decay), ("external", external)):
            if value is not None:
                Map.of(value).fill(getattr(p, name), keep)
        nbytes = ffi.new("size_t *")
        check(lib.pelage_sim_size(mesh.desc, guides.guide_count, p, nbytes), "pelage_sim_size")
        self._memory, arena = _arena(nbytes[0])
        out = ffi.new("PelageSim *")
        check(lib.pelage_sim_new(_rest(mesh, guides), p, arena, out), "pelage_sim_new")
        self._ptr = out[0]
        self.guide_count = guides.guide_count
        self.points_per_guide = int(p.points_per_guide)

    def step(
        self,
        frame: Frame,
        dt: Optional[float] = None,
        *,
        colliders: Optional[Colliders] = None,
        external_points: Any = None,
        threads: Optional[int] = None,
        progress: Optional[ProgressFn] = None,
    ) -> StepInfo:
        """Advances by ``dt`` seconds (default 1/24) to ``frame``'s mesh
        (``pelage_sim_step``). A cancelled step, or one whose Python
        distance field raised (re-raised here), is taken back whole."""
        keep: List[Any] = []
        p = new_struct("PelageStepParams", lib.pelage_step_params_defaults())
        set_fields(p, dt=dt)
        if colliders is not None:
            p.colliders = colliders.struct
        if external_points is not None:
            ext = rows(np.asarray(external_points).reshape(-1, 3), np.float32, 3, "external_points")
            keep.append(ext)
            p.external_points = ptr(ext)
            p.external_stride = int(ext.strides[0]) if ext.shape[0] > 1 else 12
        call = Call(threads, progress)
        call.fill(p.run)
        info = ffi.new("PelageStepInfo *")
        status = lib.pelage_sim_step(self._get(), frame._get(), p, info)
        call.check(status, "pelage_sim_step", [colliders])
        return StepInfo(int(info.groomed_guides))

    def read(self, out: Optional[np.ndarray] = None) -> np.ndarray:
        """The posed guides of the last step (``pelage_sim_read``): a
        (guides, points_per_guide, 3) float32 array (``out`` when given: any
        float32 array of rows of at least 3 packed floats, equally spaced)."""
        if out is None:
            out = np.empty((self.guide_count, self.points_per_guide, 3), np.float32)
        view, stride = point_rows(out, 3, "out")
        status = lib.pelage_sim_read(self._get(), ptr(view), stride, view.shape[0])
        check(status, "pelage_sim_read")
        return out

    @property
    def origin(self) -> Tuple[float, float, float]:
        """The origin the state and posed guides are relative to
        (``pelage_sim_origin``): that of the frame of the last step."""
        out = ffi.new("double[3]")
        check(lib.pelage_sim_origin(self._get(), out), "pelage_sim_origin")
        return (out[0], out[1], out[2])

    def reset(self) -> None:
        """Forgets the motion (``pelage_sim_reset``): the next step starts
        every guide from its neutral pose."""
        check(lib.pelage_sim_reset(self._get()), "pelage_sim_reset")

    def save(self) -> bytearray:
        """The simulation's state as bytes (``pelage_sim_save``)."""
        n = ffi.new("size_t *")
        check(lib.pelage_sim_state_size(self._get(), n), "pelage_sim_state_size")
        return write_bytes(n[0], lambda out, cap, written: lib.pelage_sim_save(self._get(), out, cap, written), "pelage_sim_save")

    def restore(self, data: Union[bytes, bytearray, memoryview, np.ndarray]) -> None:
        """Restores a state :meth:`save` wrote (``pelage_sim_restore``);
        on failure nothing changes."""
        with ffi.from_buffer(data) as buf:
            check(lib.pelage_sim_restore(self._get(), buf, len(buf)), "pelage_sim_restore")

    def _release(self) -> None:
        self._memory = None

    def __repr__(self) -> str:
        state = "closed" if self.closed else f"{self.guide_count} guides x {self.points_per_guide} points"
        return f"Sim({state})"

