"""Reads a fur frame exported by cpp_examples/usd_export with Pixar's own
USD reader (usd-core) and checks it against what pelage expanded (the .raw
file beside it): the prim's type and basis, curve counts, every point and
width bit for bit (float32), and the per-curve primvars."""
import struct
import sys
from array import array

from pxr import Usd, UsdGeom

usda = sys.argv[1]
stage = Usd.Stage.Open(usda)
prim = stage.GetDefaultPrim()
curves = UsdGeom.BasisCurves(prim)
assert prim.GetTypeName() == "BasisCurves", prim.GetTypeName()
assert curves.GetTypeAttr().Get() == "cubic"
assert curves.GetBasisAttr().Get() == "catmullRom"
assert curves.GetWrapAttr().Get() == "pinned"

with open(usda + ".raw", "rb") as f:
    n, per = struct.unpack("<II", f.read(8))
    pts = array("f")
    pts.frombytes(f.read(16 * n * per))
    ids = array("I")
    ids.frombytes(f.read(8 * n))

counts = curves.GetCurveVertexCountsAttr().Get()
assert len(counts) == n and all(c == per for c in counts), "curve vertex counts"
points = curves.GetPointsAttr().Get()
widths = curves.GetWidthsAttr().Get()
assert len(points) == n * per and len(widths) == n * per, "point and width counts"
assert curves.GetWidthsInterpolation() == UsdGeom.Tokens.vertex
# USD holds float32: compare as float32
want = array("f", [pts[4 * i + k] for i in range(n * per) for k in range(3)])
got = array("f", [c for p in points for c in p])
assert got == want, "points differ"
want_w = array("f", [2.0 * pts[4 * i + 3] for i in range(n * per)])
assert array("f", widths) == want_w, "widths differ"
api = UsdGeom.PrimvarsAPI(prim)
for name in ("rootUV", "strandId", "lodRank"):
    pv = api.GetPrimvar(name)
    assert pv and pv.GetInterpolation() == UsdGeom.Tokens.uniform, name
    assert len(pv.Get()) == n, name
assert list(api.GetPrimvar("strandId").Get()) == list(ids[0::2]), "strand ids"
assert list(api.GetPrimvar("lodRank").Get()) == list(ids[1::2]), "LOD ranks"
uv = api.GetPrimvar("rootUV").Get()
assert all(0.0 <= c <= 1.0 for p in uv for c in p), "root UVs in 0..1"
print(f"usd-core {Usd.GetVersion()}: {n} curves x {per} points, points, widths and primvars match pelage's output")
