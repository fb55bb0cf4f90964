"""pelage fur: grows, animates and bakes pelage's fur on Blender meshes.

Settings live on the mesh object (``Object.pelage_fur``); the operators
(``pelage.grow``, ``pelage.animate``, ``pelage.bake``) and the frame
handler call the ``pelage`` package through :mod:`.fur`, and write a
``Curves`` object of render hairs that Cycles, EEVEE and the USD exporter
take as any hair. Nothing runs at import: everything is set up by
:func:`register`.
"""

# No `from __future__ import annotations`: Blender reads the property
# annotations of PropertyGroup classes as objects, not strings.
from typing import Any, Set

import bpy
import numpy as np
from bpy.app.handlers import persistent
from bpy.props import BoolProperty, FloatProperty, IntProperty, PointerProperty, StringProperty

bl_info = {
    "name": "pelage fur",
    "author": "pelage authors",
    "version": (0, 12, 0),
    "blender": (4, 2, 0),
    "location": "3D Viewport > Sidebar > Pelage",
    "description": "Fur from guide curves with the pelage library: grow, simulate, bake",
    "category": "Object",
}

VIEWPORT_GROUP = "pelage viewport fraction"
MATERIAL = "pelage fur"


def _is_curves(_: Any, obj: bpy.types.Object) -> bool:
    return obj.type == "CURVES"


def _map_props(name: str, default: float, soft_max: float, doc: str) -> dict:
    return {
        name: FloatProperty(name=name.replace("_", " ").capitalize(), default=default, min=0.0, soft_max=soft_max,
                            precision=4, description=doc),
        name + "_attribute": StringProperty(
            name="Attribute", description=f"Float point attribute or vertex group scaling the {doc.lower()}"),
    }


class PelageFurSettings(bpy.types.PropertyGroup):
    """What the operators read: the guides, the stamp, the groom maps, the
    simulation's colliders and the bake."""

    guides: PointerProperty(name="Guides", type=bpy.types.Object, poll=_is_curves,
                            description="Curves object of guide hairs, combed on this mesh")
    output: PointerProperty(name="Output", type=bpy.types.Object, poll=_is_curves,
                            description="Curves object the render hairs are written to (made by Grow)")
    count: IntProperty(name="Count", default=20000, min=1, soft_max=1000000, description="Hairs to grow")
    density_attribute: StringProperty(
        name="Density", description="Float point attribute or vertex group in [0, 1]: where the hairs grow")
    bald_below: FloatProperty(name="Bald below", default=0.01, min=0.0, max=1.0,
                              description="Density under which a triangle grows no hair")
    seed: IntProperty(name="Seed", default=0, min=0, description="Seed of every random choice")
    points: IntProperty(name="Points", default=16, min=4, max=64, description="Control points per hair")
    settle: BoolProperty(name="Settle", default=True, description="Lift hairs out of the body at rest")
    viewport_fraction: FloatProperty(
        name="Viewport", default=0.25, min=0.0, max=1.0, subtype="FACTOR",
        description="Share of the hairs drawn in the viewport (an evenly spread subset; renders draw all)",
        update=lambda self, _: self.output and set_viewport_fraction(self.output, self.viewport_fraction))
    animate: BoolProperty(name="Animate", default=False,
                          description="Pose, simulate and expand the hairs on every frame change")
    body_collision: BoolProperty(name="Body", default=True, description="Guides collide with the mesh itself")
    colliders: PointerProperty(name="Colliders", type=bpy.types.Collection,
                               description="Objects the guides collide with: flat ones as planes, others as spheres")
    bake_directory: StringProperty(name="Bake", subtype="DIR_PATH", default="//pelage_bake/",
                                   description="Directory of the groom file and per-frame guide caches")
    bake_exact: BoolProperty(name="Exact", default=False, description="Float32 guide caches instead of quantized")
    use_bake: BoolProperty(name="Use bake", default=False,
                           description="Pose frames from the baked guide caches where they exist")
    status: StringProperty(name="Status", default="", description="The last operation's outcome")
    __annotations__.update(_map_props("length", 0.1, 1.0, "Length of the hairs"))
    __annotations__.update(_map_props("root_width", 0.002, 0.01, "Width at the root"))
    __annotations__.update(_map_props("tip_width", 0.0005, 0.01, "Width at the tip"))
    __annotations__.update(_map_props("bend", 0.0, 1.0, "Bend along the hair"))
    __annotations__.update(_map_props("kink_amplitude", 0.0, 0.1, "Kink amplitude"))
    __annotations__.update(_map_props("kink_frequency", 3.0, 10.0, "Kink waves along the hair"))
    __annotations__.update(_map_props("clump", 0.0, 1.0, "Pull toward the clump's guide"))
    __annotations__.update(_map_props("length_random", 0.0, 1.0, "Share of the length each hair may lose at random"))
    __annotations__.update(_map_props("clump_random", 0.0, 1.0, "Share of the clump pull each hair may lose at random"))


def _viewport_group() -> bpy.types.NodeTree:
    """The geometry nodes that keep the curves whose ``pelage_rank`` is
    below the modifier's Keep input: pelage's ranks make every prefix an
    evenly spread subset."""
    group = bpy.data.node_groups.get(VIEWPORT_GROUP)
    if group is not None:
        return group
    group = bpy.data.node_groups.new(VIEWPORT_GROUP, "GeometryNodeTree")
    group.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    group.interface.new_socket("Keep", in_out="INPUT", socket_type="NodeSocketInt")
    group.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    nodes, links = group.nodes, group.links
    inputs, outputs = nodes.new("NodeGroupInput"), nodes.new("NodeGroupOutput")
    rank = nodes.new("GeometryNodeInputNamedAttribute")
    rank.data_type = "INT"
    rank.inputs["Name"].default_value = "pelage_rank"
    compare = nodes.new("FunctionNodeCompare")
    compare.data_type = "INT"
    compare.operation = "GREATER_EQUAL"
    delete = nodes.new("GeometryNodeDeleteGeometry")
    delete.domain = "CURVE"
    # the integer sockets share their names with the float ones
    a, b = (next(s for s in compare.inputs if s.identifier == name) for name in ("A_INT", "B_INT"))
    links.new(rank.outputs["Attribute"], a)
    links.new(inputs.outputs["Keep"], b)
    links.new(inputs.outputs["Geometry"], delete.inputs["Geometry"])
    links.new(compare.outputs["Result"], delete.inputs["Selection"])
    links.new(delete.outputs["Geometry"], outputs.inputs["Geometry"])
    return group


def _material() -> bpy.types.Material:
    """A Principled Hair BSDF material (Cycles and EEVEE)."""
    material = bpy.data.materials.get(MATERIAL)
    if material is None:
        material = bpy.data.materials.new(MATERIAL)
        if bpy.app.version < (5, 0, 0):  # always on from 5.0, and deprecated
            material.use_nodes = True
        nodes = material.node_tree.nodes
        nodes.clear()
        hair = nodes.new("ShaderNodeBsdfHairPrincipled")
        out = nodes.new("ShaderNodeOutputMaterial")
        material.node_tree.links.new(hair.outputs[0], out.inputs["Surface"])
    return material


def set_viewport_fraction(out: bpy.types.Object, fraction: float) -> None:
    """Shows the ``fraction`` of ``out``'s curves of lowest rank in the
    viewport (a geometry nodes modifier off at render)."""
    modifier = out.modifiers.get("pelage viewport")
    if modifier is None:
        modifier = out.modifiers.new("pelage viewport", "NODES")
        modifier.node_group = _viewport_group()
        modifier.show_render = False
    keep = modifier.node_group.interface.items_tree["Keep"].identifier
    modifier[keep] = int(round(fraction * len(out.data.curves)))
    # keeping every curve would still cost the modifier a pass over them
    modifier.show_viewport = fraction < 1.0
    out.update_tag()


def write_output(obj: bpy.types.Object, curves: np.ndarray, radii: bool = True) -> bpy.types.Object:
    """Writes render curves into ``obj``'s output ``Curves`` object: the
    points in place when the counts match (their radii only when ``radii``:
    a frame of the same groom keeps them), else new curves (with the
    strands' ``pelage_id`` and ``pelage_rank`` as curve attributes, the
    hair material and the viewport fraction)."""
    from . import convert, fur

    settings = obj.pelage_fur
    out = settings.output
    count, per = curves.shape[:2]
    if out is None or len(out.data.curves) != count or len(out.data.points) != count * per:
        data = convert.new_curves(obj.name + " fur", count, per)
        live = fur.get(obj)
        if live is not None:
            convert.set_curve_ints(data, "pelage_id", live.roots["id"])
            convert.set_curve_ints(data, "pelage_rank", live.roots["rank"])
        data.materials.append(_material())
        if out is None:
            out = bpy.data.objects.new(obj.name + " fur", data)
            for collection in obj.users_collection:
                collection.objects.link(out)
            settings.output = out
        else:
            old, out.data = out.data, data
            if old.users == 0:
                bpy.data.hair_curves.remove(old)
        out.matrix_world.identity()
        set_viewport_fraction(out, settings.viewport_fraction)
        radii = True
    convert.set_curves_points(out.data, curves, radii)
    return out


class PELAGE_OT_grow(bpy.types.Operator):
    """Grow fur on the active mesh from its guide curves"""

    bl_idname = "pelage.grow"
    bl_label = "Grow"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return context.active_object is not None and context.active_object.type == "MESH"

    def execute(self, context: bpy.types.Context) -> Set[str]:
        from . import fur

        obj = context.active_object
        try:
            curves = fur.grow(obj, context.evaluated_depsgraph_get())
        except (ValueError, KeyError, pelage_error()) as error:
            obj.pelage_fur.status = f"grow: {error}"
            self.report({"ERROR"}, obj.pelage_fur.status)
            return {"CANCELLED"}
        write_output(obj, curves)
        fur.get(obj).radii_written = True
        obj.pelage_fur.status = f"grew {curves.shape[0]} hairs"
        self.report({"INFO"}, obj.pelage_fur.status)
        return {"FINISHED"}


class PELAGE_OT_animate(bpy.types.Operator):
    """Turn the fur's animation on or off (simulated on frame changes)"""

    bl_idname = "pelage.animate"
    bl_label = "Animate"

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return context.active_object is not None and context.active_object.type == "MESH"

    def execute(self, context: bpy.types.Context) -> Set[str]:
        settings = context.active_object.pelage_fur
        settings.animate = not settings.animate
        if settings.animate:
            _update(context.active_object, context.scene, context.evaluated_depsgraph_get())
        return {"FINISHED"}


class PELAGE_OT_bake(bpy.types.Operator):
    """Bake the groom file and a guide cache per frame, then render from them"""

    bl_idname = "pelage.bake"
    bl_label = "Bake"

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return context.active_object is not None and context.active_object.type == "MESH"

    def execute(self, context: bpy.types.Context) -> Set[str]:
        from . import fur

        obj = context.active_object
        settings = obj.pelage_fur
        try:
            frames = fur.bake(obj, context.scene, settings.bake_exact)
        except (ValueError, OSError, pelage_error()) as error:
            settings.status = f"bake: {error}"
            self.report({"ERROR"}, settings.status)
            return {"CANCELLED"}
        settings.use_bake = True
        settings.status = f"baked {frames} frames to {fur.groom_path(settings.bake_directory).parent}"
        self.report({"INFO"}, settings.status)
        return {"FINISHED"}


def pelage_error() -> type:
    """The package's error class (imported when first needed)."""
    import pelage

    return pelage.PelageError


class PELAGE_PT_fur(bpy.types.Panel):
    """The settings and operators of the active mesh's fur."""

    bl_label = "pelage fur"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Pelage"

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return context.active_object is not None and context.active_object.type == "MESH"

    def draw(self, context: bpy.types.Context) -> None:
        settings = context.active_object.pelage_fur
        layout = self.layout
        layout.use_property_split = True
        for name in ("guides", "count", "density_attribute", "bald_below", "seed", "points", "settle"):
            layout.prop(settings, name)
        from .fur import MAPS

        for name in MAPS:
            row = layout.row(align=True)
            row.prop(settings, name)
            row.prop(settings, name + "_attribute", text="")
        layout.prop(settings, "viewport_fraction")
        layout.operator("pelage.grow")
        layout.separator()
        for name in ("body_collision", "colliders"):
            layout.prop(settings, name)
        layout.operator("pelage.animate", depress=settings.animate)
        layout.separator()
        for name in ("bake_directory", "bake_exact", "use_bake"):
            layout.prop(settings, name)
        layout.operator("pelage.bake")
        if settings.status:
            layout.label(text=settings.status)


def _update(obj: bpy.types.Object, scene: bpy.types.Scene, depsgraph: Any) -> None:
    from . import fur

    try:
        curves = fur.pose(obj, scene, depsgraph)
    except (ValueError, OSError, pelage_error()) as error:
        obj.pelage_fur.status = f"frame {scene.frame_current}: {error}"
        print(f"pelage fur: {obj.name}: {obj.pelage_fur.status}")
        return
    if curves is not None:
        live = fur.get(obj)
        write_output(obj, curves, radii=not live.radii_written)
        live.radii_written = True


@persistent
def on_frame_change(scene: bpy.types.Scene, depsgraph: Any) -> None:
    """Poses the fur of every animated mesh of the scene at the new frame."""
    for obj in scene.objects:
        if obj.type == "MESH" and obj.pelage_fur.animate:
            _update(obj, scene, depsgraph)


@persistent
def on_load(_: Any) -> None:
    """A file loaded drops the live grooms of the one before."""
    from . import fur

    fur.forget()


CLASSES = (PelageFurSettings, PELAGE_OT_grow, PELAGE_OT_animate, PELAGE_OT_bake, PELAGE_PT_fur)


def register() -> None:
    """Registers the settings, operators, panel and handlers."""
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Object.pelage_fur = PointerProperty(type=PelageFurSettings)
    bpy.app.handlers.frame_change_post.append(on_frame_change)
    bpy.app.handlers.load_pre.append(on_load)


def unregister() -> None:
    """Undoes :func:`register` and frees the live grooms."""
    from . import fur

    fur.forget()
    bpy.app.handlers.load_pre.remove(on_load)
    bpy.app.handlers.frame_change_post.remove(on_frame_change)
    del bpy.types.Object.pelage_fur
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
