"""The demo's last step: import the demo mesh into Blender with the particlemesh add-on and
render a still with Cycles on the CPU (denoising off, small, a few seconds).

    blender --background --factory-startup -noaudio --python-exit-code 1 \
        --python scripts/blender_demo.py -- --zip ADDON.zip --mesh out/demo/trefoil.ply \
        --out out/demo/trefoil.png

The add-on is installed from the built zip into a temporary user scripts folder, exactly as a
user would install it, and its binding reads the mesh (pm_mesh_read) and builds the Blender
mesh in bulk (smooth shading, the library's normals as custom normals)."""
import argparse
import math
import os
import shutil
import sys
import tempfile
import time

import bpy
import numpy as np
from mathutils import Vector

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
parser = argparse.ArgumentParser(prog="blender_demo.py")
parser.add_argument("--zip", required=True)
parser.add_argument("--mesh", required=True)
parser.add_argument("--out", required=True)
parser.add_argument("--samples", type=int, default=16)
parser.add_argument("--size", type=int, nargs=2, default=(480, 360))
args = parser.parse_args(argv)

start = time.perf_counter()
user_scripts = tempfile.mkdtemp(prefix="pm_demo_scripts_")
os.environ["BLENDER_USER_SCRIPTS"] = user_scripts
os.environ.pop("PARTICLEMESH_LIBRARY", None)
try:
    bpy.ops.preferences.addon_install(filepath=os.path.abspath(args.zip), overwrite=True)
    bpy.ops.preferences.addon_enable(module="particlemesh")
    pm = sys.modules["particlemesh"]

    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)

    # The mesh, through the add-on: library reader, faces wound to agree with the normals,
    # bulk foreach_set, custom normals.
    data = pm.particlemesh.read_mesh(args.mesh)
    if data.normals is not None:
        data.triangles, _ = pm.mesh_arrays.orient_by_normals(data.triangles, data.normals,
                                                             data.vertices)
    name = bpy.path.display_name_from_filepath(args.mesh)
    mesh = pm.blender_mesh.write(bpy.data.meshes.new(name), data)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)

    material = bpy.data.materials.new("particlemesh")
    material.use_nodes = True
    bsdf = material.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0.85, 0.33, 0.10, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.35
    mesh.materials.append(material)

    # Frame the object: camera on a diagonal, looking at the bounding box centre.
    lo, hi = data.vertices.min(axis=0), data.vertices.max(axis=0)
    centre = Vector(((lo + hi) / 2).tolist())
    radius = float(np.linalg.norm(hi - lo)) / 2
    scene = bpy.context.scene
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    camera.data.lens = 50
    direction = Vector((0.35, -1.0, 0.75)).normalized()
    distance = radius / math.sin(math.atan(18.0 / camera.data.lens)) * 1.05
    camera.location = centre + direction * distance
    camera.rotation_euler = (-direction).to_track_quat("-Z", "Y").to_euler()
    scene.camera = camera
    for name_, energy, rot in (("Key", 4.0, (0.7, 0.2, 0.6)), ("Fill", 1.2, (1.1, 0.0, -2.2))):
        light = bpy.data.objects.new(name_, bpy.data.lights.new(name_, "SUN"))
        light.data.energy = energy
        light.rotation_euler = rot
        scene.collection.objects.link(light)
    scene.world = scene.world or bpy.data.worlds.new("World")
    scene.world.use_nodes = True
    scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.05, 0.06, 0.08, 1)

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.samples
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.render.resolution_x, scene.render.resolution_y = args.size
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = os.path.abspath(args.out)
    bpy.ops.render.render(write_still=True)
    print(f"blender_demo: {len(data.vertices)} vertices, {len(data.triangles)} triangles "
          f"rendered to {args.out} in {time.perf_counter() - start:.1f} s")
finally:
    if "particlemesh" in bpy.context.preferences.addons:
        bpy.ops.preferences.addon_disable(module="particlemesh")
    shutil.rmtree(user_scripts, ignore_errors=True)
