"""Installs the packed extension as a user would (Blender's own installer,
``extensions.package_install_files``) into the user resources named by
``BLENDER_USER_RESOURCES`` (an empty directory), enables it, and grows fur
with the ``pelage`` its wheels installed, not the one the caller's
environment may hold.

    BLENDER_USER_RESOURCES=<empty dir> python install_extension.py <pelage_fur-*.zip>
"""

import os
import sys
from pathlib import Path

import bpy
import numpy as np

user = Path(os.environ["BLENDER_USER_RESOURCES"])
assert Path(bpy.utils.resource_path("USER")) == user, bpy.utils.resource_path("USER")
result = bpy.ops.extensions.package_install_files(filepath=sys.argv[1], repo="user_default", enable_on_install=True)
assert result == {"FINISHED"}, result
assert "bl_ext.user_default.pelage_fur" in bpy.context.preferences.addons.keys()
wheels = next(p for p in sys.path if Path(p).is_relative_to(user / "extensions" / ".local"))
sys.path.remove(wheels)
sys.path.insert(0, wheels)
import pelage  # noqa: E402

assert Path(pelage.__file__).is_relative_to(user), pelage.__file__

from bl_ext.user_default.pelage_fur import convert  # noqa: E402

bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3)
head = bpy.context.active_object
mesh = pelage.Mesh(*convert.mesh_arrays(head, bpy.context.evaluated_depsgraph_get()))
at, normals = pelage.roots_evaluate(mesh, pelage.stamp(mesh, 20, seed=1)[0])
t = np.linspace(0.0, 1.0, 4, dtype=np.float32)[None, :, None]
points = at[:, None] + 0.1 * t * normals[:, None]
guides = convert.new_curves("guides", len(at), 4)
convert.set_curves_points(guides, np.concatenate([points, np.full(points.shape[:2] + (1,), 0.01, np.float32)], -1))
guide_object = bpy.data.objects.new("guides", guides)
bpy.context.scene.collection.objects.link(guide_object)
head.pelage_fur.guides = guide_object
head.pelage_fur.count = 500
assert bpy.ops.pelage.grow() == {"FINISHED"}, head.pelage_fur.status
assert len(head.pelage_fur.output.data.curves) == 500
print(f"pelage_fur installed from {sys.argv[1]} and grew 500 hairs with pelage from {Path(pelage.__file__).parent}")
