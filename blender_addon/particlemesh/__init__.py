# SPDX-License-Identifier: GPL-3.0-or-later
"""particlemesh for Blender: particles to shaded, animated meshes.

Installs as a zip on Blender 3.4+ (Preferences > Add-ons > Install) and as a Blender 4.2+
extension (blender_manifest.toml). Relative imports only, and __package__ for our own name,
so it works under either package name (`particlemesh` or `bl_ext.<repo>.particlemesh`).

Modules: particlemesh (the particlemesh Python package, the same as outside Blender, with
particlemesh/lib/: libparticlemesh.so and the libraries it needs, and for .pcd files the PCL
bridge libparticlemesh_pcl.so, loaded on the first .pcd), generate / mesh_arrays / jobs
(bpy-free work), sources (particles out of Blender), blender_mesh (bulk mesh IO), properties,
operators, live (frame handler, cache), frame_display (cached frames shown without Blender
evaluating them again), bake, ui."""

bl_info = {
    "name": "particlemesh",
    "author": "particlemesh developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Particlemesh; File > Import > Point Cloud",
    "description": "Particles to surfaces: triangulate surface particles, polygonize volume "
                   "particles, Loop/butterfly smoothing, live per-frame meshing",
    "category": "Mesh",
}

if "bpy" in locals():  # Reload Scripts (F3 > Reload Scripts) re-imports the modules.
    import importlib
    for _name in ("particlemesh", "mesh_arrays", "jobs", "generate", "blender_mesh", "sources",
                  "properties", "frame_display", "live", "bake", "operators", "ui"):
        if _name in locals():
            importlib.reload(locals()[_name])

import bpy  # noqa: E402

from . import particlemesh, mesh_arrays, jobs, generate, blender_mesh, sources  # noqa: E402,F401
from . import properties, live, bake, operators, ui  # noqa: E402

_modules = (properties, operators, ui, live)


def register():
    for module in _modules:
        module.register()


def unregister():
    for module in reversed(_modules):
        module.unregister()
