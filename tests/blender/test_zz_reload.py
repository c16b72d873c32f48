"""Disable and re-enable the add-on (runs last: pytest collects files in name order)."""
import sys

import bpy
import numpy as np

from conftest import ADDON, emitter


def handler_names(handlers):
    return [getattr(h, "__name__", "") for h in handlers]


def test_disable_and_enable_cleanly(clean_scene):
    emitter()
    assert bpy.ops.particlemesh.triangulate(live=True, max_edge_factor=1.8) == {"FINISHED"}
    generated = bpy.context.active_object.name

    assert bpy.ops.preferences.addon_disable(module=ADDON) == {"FINISHED"}
    assert ADDON not in bpy.context.preferences.addons
    assert not hasattr(bpy.types, "PARTICLEMESH_OT_triangulate")
    assert not hasattr(bpy.types, "VIEW3D_PT_particlemesh")
    assert not hasattr(bpy.types.Object, "particlemesh")
    assert "on_frame_change_post" not in handler_names(bpy.app.handlers.frame_change_post)
    assert "on_load_post" not in handler_names(bpy.app.handlers.load_post)
    assert "on_depsgraph_update_post" not in handler_names(bpy.app.handlers.depsgraph_update_post)
    clean_scene.frame_set(4)  # no handler left behind to fail

    assert bpy.ops.preferences.addon_enable(module=ADDON) == {"FINISHED"}
    assert handler_names(bpy.app.handlers.frame_change_post).count("on_frame_change_post") == 1
    assert handler_names(bpy.app.handlers.load_post).count("on_load_post") == 1
    # The settings stored on the object survived; live mode carries on.
    obj = bpy.data.objects[generated]
    state = obj.particlemesh
    assert state.is_generated and state.live and abs(state.viewport.max_edge_factor - 1.8) < 1e-6
    clean_scene.frame_set(6)
    record = sys.modules[ADDON].live.last_update[obj.name]
    assert record["frame"] == 6 and "error" not in record
    assert len(obj.data.polygons) > 1000
    # Twice more, to be sure nothing accumulates.
    for _ in range(2):
        bpy.ops.preferences.addon_disable(module=ADDON)
        bpy.ops.preferences.addon_enable(module=ADDON)
    assert handler_names(bpy.app.handlers.frame_change_post).count("on_frame_change_post") == 1
    assert handler_names(bpy.app.handlers.depsgraph_update_post).count("on_depsgraph_update_post") == 1
    assert np.isfinite(sys.modules[ADDON].particlemesh.triangulate(np.eye(3, dtype=np.float32) +
                                                                   [[0, 0, 0]]).vertices).all()
