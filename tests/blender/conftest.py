"""Fixtures for the add-on tests inside Blender: the add-on installed from the built zip into a
temporary user scripts folder, a clean scene per test, emitters and point-cloud objects."""
import os
import shutil
import sys
import tempfile
from pathlib import Path

import bpy
import numpy as np
import pytest

ADDON = "particlemesh"


@pytest.fixture(scope="session", autouse=True)
def addon():
    """Install the zip with preferences.addon_install into a temporary BLENDER_USER_SCRIPTS and
    enable it; disable and remove it at the end."""
    zip_path = os.environ.get("PM_ADDON_ZIP")
    assert zip_path and os.path.isfile(zip_path), f"PM_ADDON_ZIP is not a file: {zip_path}"
    user_scripts = tempfile.mkdtemp(prefix="pm_blender_scripts_")
    old = os.environ.get("BLENDER_USER_SCRIPTS")
    os.environ["BLENDER_USER_SCRIPTS"] = user_scripts
    try:
        assert bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True) == {"FINISHED"}
        installed = Path(user_scripts, "addons", ADDON)
        assert (installed / "__init__.py").is_file(), os.listdir(user_scripts)
        assert bpy.ops.preferences.addon_enable(module=ADDON) == {"FINISHED"}
        module = sys.modules[ADDON]
        assert Path(module.__file__).resolve().parent == installed.resolve()
        yield module
    finally:
        if ADDON in bpy.context.preferences.addons:
            bpy.ops.preferences.addon_disable(module=ADDON)
        if old is None:
            os.environ.pop("BLENDER_USER_SCRIPTS", None)
        else:
            os.environ["BLENDER_USER_SCRIPTS"] = old
        shutil.rmtree(user_scripts, ignore_errors=True)


@pytest.fixture
def pm(addon):
    """The add-on's modules, as installed (sys.modules may be replaced by a re-enable)."""
    return sys.modules[ADDON]


@pytest.fixture(autouse=True)
def clean_scene(addon):
    """Every test starts from an empty scene at frame 1 (the add-on stays enabled)."""
    scene = bpy.context.scene
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.particles,
                       bpy.data.materials, bpy.data.cameras, bpy.data.lights, bpy.data.curves):
        for block in list(collection):
            collection.remove(block)
    scene.frame_start, scene.frame_end = 1, 250
    scene.frame_set(1)
    module = sys.modules.get(ADDON)
    if module is not None:
        module.live.clear_cache()
        module.live.last_update.clear()
        module.live.history.clear()
    yield scene


@pytest.fixture(scope="session")
def data_dir():
    d = os.environ.get("PM_TEST_DATA")
    if not d or not Path(d).is_dir():
        pytest.skip("shared test data not found (set PM_TEST_DATA to the shared/data folder)")
    return Path(d)


def make_active(obj):
    for o in bpy.context.view_layer.objects:
        o.select_set(False)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj


def point_cloud_object(name, positions, normals=None):
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(positions))
    mesh.vertices.foreach_set("co", np.asarray(positions, np.float32).ravel())
    if normals is not None:
        a = mesh.attributes.new("point_normal", "FLOAT_VECTOR", "POINT")
        a.data.foreach_set("vector", np.asarray(normals, np.float32).ravel())
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.collection.objects.link(obj)
    make_active(obj)
    return obj


def emitter(name="Emitter", subdivisions=4, speed=1.0, frame_start=1, frame_end=1, lifetime=1000,
            display_percentage=100):
    """An icosphere whose vertices each emit one particle at frame 1, flying outward at `speed`
    (no gravity): an expanding, evenly spaced sphere of surface particles."""
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=subdivisions, radius=1.0)
    obj = bpy.context.active_object
    obj.name = name
    obj.modifiers.new("particles", "PARTICLE_SYSTEM")
    settings = obj.particle_systems[0].settings
    settings.count = len(obj.data.vertices)
    settings.emit_from = "VERT"
    settings.use_emit_random = False
    settings.frame_start = frame_start
    settings.frame_end = frame_end
    settings.lifetime = lifetime
    settings.normal_factor = speed
    settings.effector_weights.gravity = 0.0
    settings.display_percentage = display_percentage
    return obj


def living_particles(obj):
    """Positions and velocities of the living particles as Blender evaluates them now."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    psys = obj.evaluated_get(depsgraph).particle_systems[0]
    n = len(psys.particles)
    states = np.empty(n, np.int32)
    psys.particles.foreach_get("alive_state", states)
    alive = bpy.types.Particle.bl_rna.properties["alive_state"].enum_items
    keep = np.isin(states, [alive["ALIVE"].value, alive["DYING"].value])
    loc = np.empty(3 * n, np.float32)
    psys.particles.foreach_get("location", loc)
    vel = np.empty(3 * n, np.float32)
    psys.particles.foreach_get("velocity", vel)
    return loc.reshape(-1, 3)[keep], vel.reshape(-1, 3)[keep]


def mesh_arrays(mesh):
    co = np.empty(3 * len(mesh.vertices), np.float32)
    mesh.vertices.foreach_get("co", co)
    tris = np.empty(3 * len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("vertices", tris)
    return co.reshape(-1, 3), tris.reshape(-1, 3)


def _override():
    window = bpy.context.window_manager.windows[0]
    return bpy.context.temp_override(window=window, screen=window.screen,
                                     area=window.screen.areas[0])


def shown_mesh(obj):
    """The mesh the viewport shows for a live object: a cached frame's (shown through its
    hidden holder object, frame_display) or the object's own."""
    return sys.modules[ADDON].frame_display.shown_mesh(obj)


def undo():
    """Edit > Undo. In background mode Blender needs an explicit ed.undo_push() first, and
    operators push undo steps only when called with undo=True (as the UI does)."""
    with _override():
        assert bpy.ops.ed.undo() == {"FINISHED"}


def redo():
    with _override():
        assert bpy.ops.ed.redo() == {"FINISHED"}
