"""pelage's add-on against Blender's own hair nodes, on the test head, its
guides and the same hair count: wall time and peak memory of growing and
of a frame's update, and a Cycles render of each (docs/BLENDER.md).

    python blender/compare.py OUT_DIR [HAIRS ...]     (default 100000 1000000)
    python blender/compare.py --stages HAIRS          (the add-on's Grow, stage by stage)

Each measurement runs in a process of its own (``--case SIDE HAIRS``), so
its peak resident set is its own: Python, bpy and the scene are in the
baseline, reported beside it. Blender's side is a geometry nodes modifier on
a ``Curves`` object: Distribute Points on Faces (the density vertex group
as its factor) into Interpolate Curves from the guides, then the bundled
Clump Hair Curves and Frizz Hair Curves assets and a tapered radius; it is
also measured without the assets (``interpolate``).
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import time
from pathlib import Path
from typing import Dict, List

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "tests"))

#: The add-on; Blender's nodes with the clump and frizz assets; Interpolate
#: Curves alone (the reference of the issue's speed target).
SIDES = ("pelage", "blender", "interpolate")
FRAMES = 6
SIZE = 256
SAMPLES = 16


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _blender_hair(head, hairs: int, groom: bool):  # type: ignore[no-untyped-def]
    """A Curves object whose modifier grows ``hairs`` hairs (about) the
    way Blender's own nodes do: Interpolate Curves, then (``groom``) the
    Clump and Frizz Hair Curves assets."""
    import bpy
    import numpy as np

    from pelage_fur import _material

    assets = next(Path(bpy.utils.resource_path("LOCAL")).glob("datafiles/assets/**/procedural_hair_node_assets.blend"))
    with bpy.data.libraries.load(str(assets)) as (src, dst):
        dst.node_groups = ["Clump Hair Curves", "Frizz Hair Curves"]
    tri = head.positions[head.triangles]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    haired = area[head.density[head.triangles].min(1) > 0.5].sum()

    group = bpy.data.node_groups.new("blender hair", "GeometryNodeTree")
    group.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    group.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    n, link = group.nodes, group.links.new
    surface = n.new("GeometryNodeObjectInfo")
    surface.transform_space = "RELATIVE"
    surface.inputs["Object"].default_value = head.obj
    guides = n.new("GeometryNodeObjectInfo")
    guides.transform_space = "RELATIVE"
    guides.inputs["Object"].default_value = head.guides
    factor = n.new("GeometryNodeInputNamedAttribute")
    factor.data_type = "FLOAT"
    factor.inputs["Name"].default_value = "density"
    density = n.new("ShaderNodeMath")
    density.operation = "MULTIPLY"
    density.inputs[1].default_value = hairs / haired
    link(factor.outputs["Attribute"], density.inputs[0])
    scatter = n.new("GeometryNodeDistributePointsOnFaces")
    link(surface.outputs["Geometry"], scatter.inputs["Mesh"])
    link(density.outputs["Value"], scatter.inputs["Density"])
    interpolate = n.new("GeometryNodeInterpolateCurves")
    link(guides.outputs["Geometry"], interpolate.inputs["Guide Curves"])
    link(scatter.outputs["Points"], interpolate.inputs["Points"])
    link(scatter.outputs["Normal"], interpolate.inputs["Point Up"])
    clump = n.new("GeometryNodeGroup")
    clump.node_tree = bpy.data.node_groups["Clump Hair Curves"]
    frizz = n.new("GeometryNodeGroup")
    frizz.node_tree = bpy.data.node_groups["Frizz Hair Curves"]
    link(interpolate.outputs["Curves"], clump.inputs[0])
    link(clump.outputs[0], frizz.inputs[0])
    hair = frizz.outputs[0] if groom else interpolate.outputs["Curves"]
    along = n.new("GeometryNodeSplineParameter")
    taper = n.new("ShaderNodeMapRange")
    taper.inputs["To Min"].default_value = 0.002
    taper.inputs["To Max"].default_value = 0.00075
    link(along.outputs["Factor"], taper.inputs["Value"])
    radius = n.new("GeometryNodeSetCurveRadius")
    link(hair, radius.inputs["Curve"])
    link(taper.outputs["Result"], radius.inputs["Radius"])
    link(radius.outputs["Curve"], n.new("NodeGroupOutput").inputs["Geometry"])

    data = bpy.data.hair_curves.new("blender hair")
    data.materials.append(_material())
    obj = bpy.data.objects.new("blender hair", data)
    bpy.context.scene.collection.objects.link(obj)
    obj.modifiers.new("hair", "NODES").node_group = group
    return obj


def _case(side: str, hairs: int, out: Path) -> Dict[str, float]:
    import bpy

    import conftest
    import pelage_fur

    pelage_fur.register()
    head = conftest.build_scene()
    settings = head.obj.pelage_fur
    settings.count = hairs
    settings.length = conftest.GUIDE_LENGTH
    settings.viewport_fraction = 1.0
    conftest.animate(head.obj)
    scene = bpy.context.scene
    scene.frame_end = FRAMES
    base = _peak_mb()
    start = time.perf_counter()
    if side == "pelage":
        assert bpy.ops.pelage.grow() == {"FINISHED"}, settings.status
        hair = settings.output
    else:
        hair = _blender_hair(head, hairs, side == "blender")
    count = len(hair.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.curves)
    grow = time.perf_counter() - start
    grow_peak = _peak_mb()
    if side == "pelage":
        assert bpy.ops.pelage.animate() == {"FINISHED"}
    times: List[float] = []
    for number in range(2, FRAMES + 1):
        start = time.perf_counter()
        scene.frame_set(number)
        len(hair.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.curves)
        times.append(time.perf_counter() - start)
    assert settings.status.startswith("grew") or side != "pelage", settings.status
    frame_peak = _peak_mb()
    # the rest pose: Blender's guides, not attached, stay where they were groomed
    scene.frame_set(1)
    _render(head, out / f"{side}_{hairs}.png")
    return {
        "hairs": count, "grow_s": grow, "frame_s": sorted(times)[len(times) // 2],
        "base_mb": base, "grow_mb": grow_peak - base, "frame_mb": frame_peak - base,
        "skin_seen": conftest.skin_seen(out / f"{side}_{hairs}.png"),
    }


def _render(head, path: Path) -> None:  # type: ignore[no-untyped-def]
    """The suite's Cycles setup (green emissive skin, a camera on the face,
    a sun), at this comparison's size and samples; the hair keeps its own
    Principled Hair BSDF."""
    import bpy
    import conftest

    conftest.green_skin(head)
    conftest.render_setup(head, SIZE, SAMPLES)
    bpy.context.scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)


def _stages(hairs: int) -> None:
    """Prints the wall time of each stage of the add-on's Grow, as
    :func:`pelage_fur.fur.grow` and :func:`pelage_fur.write_output` run
    them, and of Blender's evaluation of the object written."""
    import bpy

    import conftest
    import pelage
    import pelage_fur
    from pelage_fur import convert, fur

    pelage_fur.register()
    head = conftest.build_scene()
    settings = head.obj.pelage_fur
    settings.count, settings.length, settings.viewport_fraction = hairs, conftest.GUIDE_LENGTH, 1.0
    depsgraph = bpy.context.evaluated_depsgraph_get()
    threads = fur._threads()
    clock = [time.perf_counter()]

    def lap(name: str) -> None:
        now = time.perf_counter()
        print(f"{name:<28} {now - clock[0]:7.3f} s")
        clock[0] = now

    positions, triangles = convert.mesh_arrays(head.obj, depsgraph)
    mesh = pelage.Mesh(positions, triangles)
    density = convert.vertex_values(head.obj, depsgraph, settings.density_attribute)
    lap("mesh and density from Blender")
    roots, _ = pelage.stamp(mesh, hairs, seed=settings.seed, density=density, bald_below=settings.bald_below)
    lap("stamp")
    points, offsets = convert.curves_points(settings.guides, depsgraph)
    guides = pelage.Guides(convert.project_roots(positions, triangles, points[offsets[:-1]]),
                           points.reshape(len(offsets) - 1, -1, 3))
    lap("guides from Blender")
    bindings, _ = pelage.bind(mesh, guides, roots, seed=settings.seed, threads=threads)
    lap("bind")
    grooms = pelage.groom_evaluate(
        mesh, roots, seed=settings.seed, **{n: fur._map(head.obj, depsgraph, settings, n) for n in fur.MAPS}
    )
    lap("groom maps")
    params = pelage.ExpandParams(points_per_strand=settings.points, pinned=False)
    pelage.settle(mesh, guides, roots, bindings, grooms, params, threads=threads)
    lap("settle")
    with pelage.Groom(roots, bindings, grooms) as groom, pelage.Frame(mesh, len(guides), settings.points) as frame:
        frame.set_guides(guides, threads=threads)
        lap("groom and frame")
        curves = groom.expand(frame, params=params, threads=threads)
        lap("expand")
    data = convert.new_curves("stages", len(curves), settings.points)
    convert.set_curve_ints(data, "pelage_id", roots["id"])
    convert.set_curve_ints(data, "pelage_rank", roots["rank"])
    convert.set_curves_points(data, curves)
    lap("Curves data-block written")
    obj = bpy.data.objects.new("stages", data)
    bpy.context.scene.collection.objects.link(obj)
    len(obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.curves)
    lap("Blender evaluates the object")


def main() -> None:
    if sys.argv[1] == "--stages":
        _stages(int(sys.argv[2]))
        return
    if sys.argv[1] == "--case":
        side, hairs, out = sys.argv[2], int(sys.argv[3]), Path(sys.argv[4])
        print("RESULT " + json.dumps(_case(side, hairs, out)))
        return
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    counts = [int(a) for a in sys.argv[2:]] or [100000, 1000000]
    rows = []
    for hairs in counts:
        for side in SIDES:
            run = subprocess.run(
                [sys.executable, __file__, "--case", side, str(hairs), str(out)],
                check=True, capture_output=True, text=True,
            )
            result = json.loads(next(l for l in run.stdout.splitlines() if l.startswith("RESULT "))[7:])
            rows.append((side, hairs, result))
            print(side, hairs, result, flush=True)
    import platform

    lines = [
        f"`python blender/compare.py {out} {' '.join(map(str, counts))}` on {platform.node()} "
        f"({platform.processor() or platform.machine()}), {time.strftime('%Y-%m-%d')}, "
        f"{FRAMES - 1} frames, Cycles {SIZE}x{SIZE} at {SAMPLES} samples:",
        "",
        "| side | hairs asked | hairs | grow (s) | frame (s, median) | frames/s | grow peak (MB) "
        "| frame peak (MB) | baseline (MB) | skin seen |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for side, hairs, r in rows:
        lines.append(
            f"| {side} | {hairs:,} | {r['hairs']:,} | {r['grow_s']:.2f} | {r['frame_s']:.3f} | "
            f"{1.0 / r['frame_s']:.1f} | {r['grow_mb']:.0f} | {r['frame_mb']:.0f} | {r['base_mb']:.0f} | "
            f"{r['skin_seen']:.3f} |"
        )
    (out / "compare.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
