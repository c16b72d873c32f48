"""Baking a generated object over a frame range: one mesh datablock per frame (swapped in by
the frame handler, also in renders), optionally a PLY sequence on disk."""

import os

import bpy

from . import blender_mesh, live
from . import particlemesh as pm


def baked_mesh_name(obj, frame):
    return f"{obj.name}.pm{frame:05d}"


def ply_path(directory, obj, frame):
    return os.path.join(bpy.path.abspath(directory), f"{bpy.path.clean_name(obj.name)}_{frame:05d}.ply")


def begin(obj):
    """Free an older bake and remember the mesh shown before baking."""
    live.stop_display(obj)
    free(obj)
    state = obj.particlemesh
    state.base_mesh = obj.data


def bake_frame(context, obj, frame, mode, directory=""):
    """Generate `obj` at `frame` into a new mesh datablock and record it. Runs on the main
    thread: it changes the scene's frame."""
    scene = context.scene
    scene.frame_set(frame)
    depsgraph = context.evaluated_depsgraph_get()
    data, settings, _ = live.compute(obj, depsgraph, mode=mode, use_cache=False)
    mesh = bpy.data.meshes.new(baked_mesh_name(obj, frame))
    for material in obj.particlemesh.base_mesh.materials if obj.particlemesh.base_mesh else ():
        mesh.materials.append(material)
    blender_mesh.write(mesh, data, custom_normals=settings.get("custom_normals", True))
    item = obj.particlemesh.bake_frames.add()
    item.frame = frame
    item.mesh = mesh
    if directory:
        os.makedirs(bpy.path.abspath(directory), exist_ok=True)
        pm.write_mesh(data, ply_path(directory, obj, frame))
    return mesh


def finish(context, obj, start, end):
    state = obj.particlemesh
    state.bake_start = start
    state.bake_end = end
    state.baked = True
    live.lock_interface_for_renders(context.scene)
    live.show_baked_frame(obj, context.scene.frame_current)


def free(obj):
    """Forget the baked frames, show the mesh from before the bake again, and delete baked
    meshes nothing else uses."""
    state = obj.particlemesh
    meshes = [item.mesh for item in state.bake_frames if item.mesh is not None]
    if state.base_mesh is not None and obj.data != state.base_mesh:
        obj.data = state.base_mesh
    state.bake_frames.clear()
    state.baked = False
    for mesh in meshes:
        if mesh.users == 0 and mesh != obj.data:
            bpy.data.meshes.remove(mesh)
