"""Reads the curves of a USD file with Pixar's own reader (usd-core) and
writes what it found beside it as ``<file>.npz``: run in its own process,
since bpy links a USD of its own.

    python read_usd.py <file.usd[a|c]>
"""

import sys

import numpy as np
from pxr import Usd, UsdGeom

stage = Usd.Stage.Open(sys.argv[1])
found = [p for p in stage.Traverse() if p.IsA(UsdGeom.BasisCurves)]
assert len(found) == 1, [str(p.GetPath()) for p in found]
curves = UsdGeom.BasisCurves(found[0])
world = UsdGeom.Xformable(found[0]).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
primvars = UsdGeom.PrimvarsAPI(found[0])
per_curve = {
    name: np.asarray(primvars.GetPrimvar(name).Get(), np.int64)
    for name in ("pelage_id", "pelage_rank")
    if primvars.GetPrimvar(name) and primvars.GetPrimvar(name).GetInterpolation() == UsdGeom.Tokens.uniform
}
np.savez(
    sys.argv[1] + ".npz",
    type=str(curves.GetTypeAttr().Get()),
    basis=str(curves.GetBasisAttr().Get()),
    wrap=str(curves.GetWrapAttr().Get()),
    counts=np.asarray(curves.GetCurveVertexCountsAttr().Get(), np.int64),
    points=np.asarray(curves.GetPointsAttr().Get(), np.float32),
    widths=np.asarray(curves.GetWidthsAttr().Get(), np.float32),
    world=np.asarray(world, np.float64),
    version=str(Usd.GetVersion()),
    **per_curve,
)
