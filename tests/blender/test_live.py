"""Live mode (a persistent frame handler regenerates the mesh from the evaluated particles,
with a per-frame cache, render settings while rendering) and baking (one mesh per frame,
swapped in as the frame changes; PLY sequence)."""
import os
import sys

import bpy
import numpy as np
import pytest

from conftest import emitter, living_particles, make_active, mesh_arrays, shown_mesh, undo


def live_object(pm, method="triangulate", **kwargs):
    """The active object's particles meshed in live mode by `method` (an operator's name)."""
    assert getattr(bpy.ops.particlemesh, method)(live=True, **kwargs) == {"FINISHED"}
    obj = bpy.context.active_object
    assert obj.particlemesh.live
    assert bpy.context.scene.render.use_lock_interface  # safe renders from the UI
    return obj


def test_live_mesh_follows_the_particles(pm, clean_scene):
    em = emitter(speed=1.0)
    obj = live_object(pm)
    assert pm.live.on_frame_change_post in bpy.app.handlers.frame_change_post
    radii = []
    for frame in (1, 5, 10, 20):
        clean_scene.frame_set(frame)
        record = pm.live.last_update[obj.name]
        assert record["frame"] == frame and record["mode"] == "VIEWPORT"
        assert "error" not in record, record
        positions, velocities = living_particles(em)
        co, tris = mesh_arrays(shown_mesh(obj))
        np.testing.assert_allclose(co, positions, atol=1e-5)  # vertex i is particle i, now
        np.testing.assert_allclose(pm.blender_mesh.get_point_attribute(shown_mesh(obj), "velocity"),
                                   velocities, atol=1e-5)
        assert 2 * 642 * 0.95 <= len(tris) <= 2 * 642 * 1.35
        assert not shown_mesh(obj).validate(verbose=False)
        radii.append(float(np.linalg.norm(co, axis=1).mean()))
    assert radii == sorted(radii) and radii[-1] > radii[0] + 0.5  # the sphere expands
    # The same frame again comes from the cache.
    clean_scene.frame_set(10)
    assert pm.live.last_update[obj.name]["cached"] is True
    entries, size = pm.live.cache_info(obj)
    assert entries >= 4 and size > 0
    # Its writes kept their working arrays for the next frame (blender_mesh._kept); clearing
    # the last cache lets them go.
    assert len(pm.blender_mesh._kept_arrays["corners"]) >= len(tris) * 3
    pm.live.clear_cache(obj)
    assert not pm.blender_mesh._kept_arrays


def test_cached_frames_swap_in_their_kept_mesh(pm, clean_scene):
    """Each live frame is written once into a mesh of its own that the cache keeps; a frame
    seen again swaps that mesh in (same geometry, the object's materials), clearing the cache
    deletes the kept meshes not on screen, and with the cache off the object's own mesh is
    rewritten in place."""
    em = emitter(speed=1.0)
    obj = live_object(pm)
    material = bpy.data.materials.new("Live")
    obj.data.materials.append(material)
    shown = {}
    for frame in (2, 3, 4):
        clean_scene.frame_set(frame)
        record = pm.live.last_update[obj.name]
        assert not record["cached"] and not record["swapped"], record
        assert pm.live.FRAME_TAG in shown_mesh(obj) and list(shown_mesh(obj).materials) == [material]
        shown[frame] = shown_mesh(obj).name
    assert len(set(shown.values())) == 3
    for frame in (3, 2, 4, 3):
        clean_scene.frame_set(frame)
        record = pm.live.last_update[obj.name]
        assert record["cached"] and record["swapped"], record
        assert shown_mesh(obj).name == shown[frame]
        assert list(shown_mesh(obj).materials) == [material]
        positions, _ = living_particles(em)
        co, tris = mesh_arrays(shown_mesh(obj))
        np.testing.assert_allclose(co, positions, atol=1e-5)
        assert not shown_mesh(obj).validate(verbose=False)
    # A material added later follows to the frames swapped in.
    other = bpy.data.materials.new("Other")
    obj.data.materials.append(other)
    clean_scene.frame_set(2)
    assert list(shown_mesh(obj).materials) == [material, other]
    # Clearing the cache deletes the kept meshes but the one on screen.
    assert bpy.ops.particlemesh.clear_cache() == {"FINISHED"}
    assert [n for n in shown.values() if n in bpy.data.meshes] == [shown[2]]
    # With the cache off the object's mesh is rewritten in place.
    prefs = bpy.context.preferences.addons["particlemesh"].preferences
    old = prefs.cache_megabytes
    try:
        prefs.cache_megabytes = 0
        mesh = obj.data
        clean_scene.frame_set(6)
        assert obj.data == mesh and pm.live.FRAME_TAG not in mesh
        positions, _ = living_particles(em)
        assert shown_mesh(obj) == obj.data
        np.testing.assert_allclose(mesh_arrays(obj.data)[0], positions, atol=1e-5)
    finally:
        prefs.cache_megabytes = old


def test_kept_meshes_go_with_their_frames(pm, clean_scene, monkeypatch):
    """A cache too small for every frame drops the oldest and deletes their meshes (no
    datablocks pile up); the mesh on screen is never deleted."""
    em = emitter(speed=1.0)
    obj = live_object(pm)
    clean_scene.frame_set(2)
    entry = pm.live.cache_for(obj).entries
    frame_bytes = next(reversed(entry.values())).nbytes
    limit = (2 * pm.live.KEPT_MESH_COST + 0.5) * frame_bytes  # 2 kept frames
    monkeypatch.setattr(pm.live, "_cache_limit", lambda: int(limit))
    for frame in range(3, 10):
        clean_scene.frame_set(frame)
        kept = [m for m in bpy.data.meshes if pm.live.FRAME_TAG in m]
        assert shown_mesh(obj) in kept and len(kept) <= 3, [m.name for m in kept]
        positions, _ = living_particles(em)
        np.testing.assert_allclose(mesh_arrays(shown_mesh(obj))[0], positions, atol=1e-5)
    entries, size = pm.live.cache_info(obj)
    assert entries >= 2 and size <= limit
    clean_scene.frame_set(8)  # still cached and kept
    assert pm.live.last_update[obj.name]["swapped"]


def test_cached_frames_survive_their_meshes_going(pm, clean_scene):
    """The cache keeps its meshes by name and tag, not by reference (undo reloads or drops
    datablocks): a kept mesh deleted, or replaced by another of the same name, makes that
    frame be written again."""
    em = emitter(speed=1.0)
    obj = live_object(pm)
    names = {}
    for frame in (2, 3, 4):
        clean_scene.frame_set(frame)
        names[frame] = shown_mesh(obj).name
    bpy.data.meshes.remove(bpy.data.meshes[names[2]])
    impostor = bpy.data.meshes[names[3]]
    impostor.name = "elsewhere"
    bpy.data.meshes.new(names[3])  # an unrelated mesh under the kept name
    for frame in (2, 3):
        clean_scene.frame_set(frame)
        record = pm.live.last_update[obj.name]
        assert record["cached"] and not record["swapped"], record
        positions, _ = living_particles(em)
        np.testing.assert_allclose(mesh_arrays(shown_mesh(obj))[0], positions, atol=1e-5)
    clean_scene.frame_set(4)
    assert pm.live.last_update[obj.name]["swapped"] and shown_mesh(obj).name == names[4]


def holders(pm):
    return sorted(o.name for o in bpy.data.objects if pm.frame_display.HOLDER_TAG in o)


def shown_instance(obj):
    """What the viewport's depsgraph draws for `obj`'s frame: the visible holder under it and
    the holder's evaluated mesh (the object itself drawing nothing), or None when the object
    draws its own mesh."""
    tag = sys.modules["particlemesh"].frame_display.HOLDER_TAG
    depsgraph = bpy.context.evaluated_depsgraph_get()
    found = [(i.object.original, i.object.data) for i in depsgraph.object_instances
             if not i.is_instance and i.object.original.parent == obj and tag in i.object.original]
    assert len(found) <= 1, found
    if found:
        assert len(obj.evaluated_get(depsgraph).data.vertices) == 0
    return found[0] if found else None


def test_cached_frames_show_through_hidden_holders(pm, clean_scene):
    """A frame the cache keeps is shown through its holder (a hidden, unselectable,
    unrendered object with the frame's mesh) instanced by the object's viewport-only
    modifier: the depsgraph draws the frame's geometry, and going back to a cached frame
    evaluates no holder again (their evaluated meshes stay the same)."""
    em = emitter(speed=1.0)
    obj = live_object(pm)
    for frame in (2, 3, 4):
        clean_scene.frame_set(frame)
    assert len(holders(pm)) == 3
    for name in holders(pm):
        holder = bpy.data.objects[name]
        assert holder.parent == obj and holder.hide_render and holder.hide_select
        assert holder.hide_get() == (holder.data != shown_mesh(obj))  # only the frame's shows
    modifier = obj.modifiers[pm.frame_display.MODIFIER]
    assert modifier.show_viewport and not modifier.show_render
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = {n: bpy.data.objects[n].evaluated_get(depsgraph).data.as_pointer()
                 for n in holders(pm)}
    for frame in (3, 2, 4, 3):
        clean_scene.frame_set(frame)
        assert pm.live.last_update[obj.name]["swapped"]
        holder, mesh = shown_instance(obj)
        assert pm.frame_display.HOLDER_TAG in holder and holder.data == shown_mesh(obj)
        positions, _ = living_particles(em)
        co, tris = mesh_arrays(mesh)  # the evaluated mesh the viewport draws
        np.testing.assert_allclose(co, positions, atol=1e-5)
        np.testing.assert_array_equal(tris, mesh_arrays(holder.data)[1])
    depsgraph = bpy.context.evaluated_depsgraph_get()
    assert {n: bpy.data.objects[n].evaluated_get(depsgraph).data.as_pointer()
            for n in holders(pm)} == evaluated
    # Renders never see holders: the modifier is off there and the holders hidden in renders.
    assert all(bpy.data.objects[n].hide_render for n in holders(pm))
    # The object's viewport display (wireframe, colour) carries over to its frames.
    obj.display_type, obj.color = "WIRE", (1.0, 0.0, 0.0, 1.0)
    clean_scene.frame_set(2)
    holder = shown_instance(obj)[0]
    assert holder.display_type == "WIRE" and tuple(holder.color) == (1.0, 0.0, 0.0, 1.0)
    # The object hidden with the eye: its frames too, from the next frame change on.
    obj.hide_set(True)
    clean_scene.frame_set(4)
    assert shown_instance(obj) is None and all(bpy.data.objects[n].hide_get() for n in holders(pm))
    obj.hide_set(False)
    clean_scene.frame_set(3)
    assert shown_instance(obj)[0].data == shown_mesh(obj)
    # Another object aiming at it (it would see the emptied mesh): frames are swapped in as
    # the object's own mesh instead, and likewise with another modifier on the object.
    other = bpy.data.objects.new("other", bpy.data.meshes.new("other"))
    clean_scene.collection.objects.link(other)
    other.modifiers.new("shrink", "SHRINKWRAP").target = obj
    clean_scene.frame_set(4)
    assert pm.frame_display.MODIFIER not in obj.modifiers and shown_instance(obj) is None
    assert holders(pm) == [] and pm.live.last_update[obj.name]["swapped"]
    positions, _ = living_particles(em)
    np.testing.assert_allclose(mesh_arrays(obj.data)[0], positions, atol=1e-5)
    bpy.data.objects.remove(other)
    clean_scene.frame_set(3)
    assert shown_instance(obj)[0].data == shown_mesh(obj) != obj.data
    # Another modifier on the object: frames are swapped in as its own mesh instead.
    obj.modifiers.new("weld", "WELD")
    clean_scene.frame_set(2)
    assert pm.frame_display.MODIFIER not in obj.modifiers and shown_instance(obj) is None
    positions, _ = living_particles(em)
    np.testing.assert_allclose(mesh_arrays(obj.data)[0], positions, atol=1e-5)
    assert pm.live.FRAME_TAG in obj.data and shown_mesh(obj) == obj.data


def test_instant_cached_frames_off_swaps_frames_in(pm, clean_scene):
    """Instant Cached Frames off (for scripts and exporters that read the object's mesh):
    turning it off while a holder shows a frame makes that frame the object's own mesh and
    removes the holders; cached frames are then swapped in as the object's mesh."""
    em = emitter(speed=1.0)
    obj = live_object(pm)
    for frame in (2, 3, 4, 3):
        clean_scene.frame_set(frame)
    assert shown_instance(obj) is not None and shown_mesh(obj) != obj.data
    shown = shown_mesh(obj)
    obj.particlemesh.instant_frames = False
    assert holders(pm) == [] and pm.frame_display.MODIFIER not in obj.modifiers
    assert obj.data == shown and shown_instance(obj) is None
    for frame in (2, 4):
        clean_scene.frame_set(frame)
        assert pm.live.last_update[obj.name]["swapped"]
        assert holders(pm) == [] and shown_instance(obj) is None
        assert pm.frame_display.MODIFIER not in obj.modifiers and shown_mesh(obj) == obj.data
        positions, _ = living_particles(em)
        np.testing.assert_allclose(mesh_arrays(obj.data)[0], positions, atol=1e-5)
    obj.particlemesh.instant_frames = True
    clean_scene.frame_set(3)
    assert shown_instance(obj)[0].data == shown_mesh(obj) != obj.data


def test_stopping_live_mode_leaves_no_holders(pm, clean_scene):
    """Live mode off: the frame on screen becomes the object's own mesh; no holder, no
    modifier is left, and the only meshes besides it are the frames the cache keeps (bounded);
    Clear Cache deletes those too. Deleting the object takes its holders with it."""
    em = emitter(speed=1.0)
    obj = live_object(pm)
    for frame in (2, 3, 4, 3):
        clean_scene.frame_set(frame)
    shown = shown_mesh(obj)
    obj.particlemesh.live = False
    assert holders(pm) == [] and pm.frame_display.MODIFIER not in obj.modifiers
    assert obj.data == shown and shown_instance(obj) is None
    positions, _ = living_particles(em)
    np.testing.assert_allclose(mesh_arrays(obj.data)[0], positions, atol=1e-5)
    kept = {m.name for m in bpy.data.meshes if pm.live.FRAME_TAG in m}
    held = {name for name, _ in pm.live.cache_for(obj).meshes.values()}
    assert kept <= held | {obj.data.name} and len(kept) == 3, (kept, held)
    assert bpy.ops.particlemesh.clear_cache() == {"FINISHED"}
    assert [m.name for m in bpy.data.meshes if pm.live.FRAME_TAG in m] == [obj.data.name]
    # Live again, then the object deleted: its holders go at the next frame change.
    obj.particlemesh.live = True  # regenerates frame 3 at once
    for frame in (5, 6):
        clean_scene.frame_set(frame)
    assert len(holders(pm)) == 3
    bpy.data.objects.remove(obj)
    clean_scene.frame_set(7)
    assert holders(pm) == []
    assert em.name in bpy.data.objects


def test_holders_are_never_saved(pm, clean_scene, tmp_path):
    """Saving puts the frame on screen on the object as its own mesh and removes holders and
    the modifier first: the file holds the object and that mesh only."""
    em = emitter(speed=1.0)
    obj = live_object(pm)
    for frame in (2, 3):
        clean_scene.frame_set(frame)
    shown = shown_mesh(obj)
    blend = tmp_path / "live.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    assert holders(pm) == [] and obj.data == shown
    with bpy.data.libraries.load(str(blend)) as (data_from, _):
        saved_objects, saved_groups = list(data_from.objects), list(data_from.node_groups)
    assert sorted(saved_objects) == sorted([obj.name, em.name]), saved_objects
    assert pm.frame_display.NODE_GROUP not in saved_groups
    # The session goes on showing cached frames through holders.
    clean_scene.frame_set(2)
    assert pm.live.last_update[obj.name]["swapped"] and len(holders(pm)) == 1
    positions, _ = living_particles(em)
    np.testing.assert_allclose(mesh_arrays(shown_instance(obj)[1])[0], positions, atol=1e-5)


def test_cached_frames_after_undo(pm, clean_scene):
    """Undo brings back the holders and meshes of its step and drops later ones: every frame
    still shows its own geometry afterwards, and holders the cache no longer keeps go."""
    em = emitter(speed=1.0)
    obj = live_object(pm)
    name, em_name = obj.name, em.name
    for frame in (2, 3):
        clean_scene.frame_set(frame)
    bpy.ops.ed.undo_push(message="frames 2, 3")
    for frame in (4, 5):
        clean_scene.frame_set(frame)
    bpy.ops.ed.undo_push(message="frames 4, 5")
    undo()
    # References die with undo.
    obj, em, scene = bpy.data.objects[name], bpy.data.objects[em_name], bpy.context.scene
    for frame in (4, 2, 5, 3, 4):
        scene.frame_set(frame)
        record = pm.live.last_update[name]
        assert "error" not in record, record  # (undo resets the particle cache: maybe re-made)
        positions, _ = living_particles(em)
        np.testing.assert_allclose(mesh_arrays(shown_mesh(obj))[0], positions, atol=1e-5)
        holder, mesh = shown_instance(obj)
        np.testing.assert_allclose(mesh_arrays(mesh)[0], positions, atol=1e-5)
    held = {tag for _, tag in pm.live.cache_for(obj).meshes.values()}
    assert {bpy.data.objects[n][pm.frame_display.HOLDER_TAG] for n in holders(pm)} <= held


def test_live_loop_smoothing_refines_once_while_the_triangles_stay(pm, clean_scene):
    """Live mode keeps a Smoother while the triangles come back unchanged (a system moving
    without changing its triangles): the same mesh as a plain smooth, from the second
    unchanged frame on."""
    em = emitter(speed=0.0)
    positions, _ = living_particles(em)
    settings = {"smooth": "LOOP", "smooth_levels": 2}
    reuse = {}
    meshes = []
    for scale in (1, 2, 4, 8):  # exact in floating point: the same triangles
        particles = pm.generate.Particles(positions * np.float32(scale))
        meshes.append(pm.generate.run("TRIANGULATE", particles, settings, reuse=reuse))
        assert reuse.pop("reused", False) == (scale > 1)
        plain = pm.generate.run("TRIANGULATE", particles, settings)
        np.testing.assert_array_equal(meshes[-1].triangles, plain.triangles)
        np.testing.assert_array_equal(meshes[-1].vertices, plain.vertices)
        np.testing.assert_array_equal(meshes[-1].normals, plain.normals)
    # Other triangles: a plain smooth again.
    particles = pm.generate.Particles(positions[::2].copy())
    pm.generate.run("TRIANGULATE", particles, settings, reuse=reuse)
    assert not reuse.pop("reused", False)
    pm.generate.release(reuse)
    assert "smoother" not in reuse
    # No Smoother bigger than the memory allowed (live mode: the cache's).
    reuse = {"max_bytes": 1000}
    for scale in (1, 2, 4):
        pm.generate.run("TRIANGULATE", pm.generate.Particles(positions * np.float32(scale)),
                        settings, reuse=reuse)
        assert not reuse.pop("reused", False) and "smoother" not in reuse


def corner_normals(mesh):
    """The normals Blender shades each face corner with (custom split normals if any)."""
    out = np.empty(3 * len(mesh.loops), np.float32)
    if hasattr(mesh, "corner_normals"):  # Blender 4.1+
        mesh.corner_normals.foreach_get("vector", out)
    else:
        mesh.calc_normals_split()
        mesh.loops.foreach_get("normal", out)
    return out.reshape(-1, 3)


@pytest.fixture
def deferring(pm, monkeypatch):
    """Viewport frames wait for rest to get their custom normals, as in the UI (background
    mode finishes them at once); finish_frames is called by hand (no timers run here)."""
    monkeypatch.setattr(pm.live, "defer_in_background", True)
    yield pm.live
    pm.live.finish_pending()


def rest(live, monkeypatch):
    """The frames rest: the timer's function, as Blender calls it once no frame changed for
    REST_SECONDS. Returns what it returned (None: done)."""
    monkeypatch.setattr(live, "REST_SECONDS", 0.0)
    return live.finish_frames()


def one_shot(pm, em, frame):
    """The polygonize operator's mesh of the emitter's particles at `frame` (no live mode)."""
    bpy.context.scene.frame_set(frame)
    make_active(em)
    assert bpy.ops.particlemesh.polygonize() == {"FINISHED"}
    return bpy.context.active_object.data


def same_velocity(pm, mesh, reference):
    """The `velocity` attributes of the two meshes are the same bits."""
    got = pm.blender_mesh.get_point_attribute(mesh, "velocity")
    want = pm.blender_mesh.get_point_attribute(reference, "velocity")
    assert got is not None and want is not None
    assert got.shape == want.shape and got.tobytes() == want.tobytes()


def cached_data(live, obj, frame):
    """The live cache's mesh data of `obj` at `frame`."""
    return next(d for k, d in live.cache_for(obj).entries.items() if k[0] == frame)


def test_viewport_frames_get_their_normals_once_frames_rest(pm, clean_scene, deferring,
                                                              monkeypatch):
    """While frames change, a new viewport frame shows Blender's own normals and no channels
    (velocity); once frames rest the timer gives the frame on screen the library's normals as
    custom split normals and its channels: then it is what a one-shot polygonize gives, bit
    for bit, and the cache shows it finished from then on."""
    live = deferring
    em = emitter(speed=1.0)
    make_active(em)
    obj = live_object(pm, "polygonize")
    clean_scene.frame_set(4)
    mesh = shown_mesh(obj)
    assert not mesh.has_custom_normals and live.UNFINISHED_TAG in mesh
    assert pm.blender_mesh.get_point_attribute(mesh, "velocity") is None
    assert pm.generate.attributes_pending(cached_data(live, obj, 4)) == ("velocity",)
    assert live.last_update[obj.name]["unfinished"]
    assert any(kind == "label" and "finished at rest" in text
               for kind, text in draw_panels(pm, bpy.context))
    assert bpy.app.timers.is_registered(live.finish_frames)
    # Not yet at rest: the timer looks again later and leaves the frame as it is.
    wait = live.finish_frames()
    assert wait is not None and 0 < wait <= live.REST_SECONDS
    assert not shown_mesh(obj).has_custom_normals
    clean_scene.frame_set(5)  # the next new frame: frame 4 (cached, unfinished) is left alone
    assert live.UNFINISHED_TAG in shown_mesh(obj) and list(live._pending) == [obj.name]
    assert pm.blender_mesh.get_point_attribute(shown_mesh(obj), "velocity") is None
    cache = live.cache_for(obj)
    counted = cache.bytes
    assert rest(live, monkeypatch) is None
    mesh = shown_mesh(obj)
    assert mesh.has_custom_normals and live.UNFINISHED_TAG not in mesh
    assert not live.last_update[obj.name]["unfinished"]
    assert not pm.generate.attributes_pending(cached_data(live, obj, 5))
    assert pm.generate.attributes_pending(cached_data(live, obj, 4)) == ("velocity",)
    assert cache.bytes == counted  # entries count what they hold or will hold, once
    finished_5 = mesh.name
    reference = one_shot(pm, em, 5)
    np.testing.assert_array_equal(mesh_arrays(mesh)[0], mesh_arrays(reference)[0])
    np.testing.assert_array_equal(mesh_arrays(mesh)[1], mesh_arrays(reference)[1])
    np.testing.assert_allclose(corner_normals(mesh), corner_normals(reference), atol=1e-6)
    same_velocity(pm, mesh, reference)
    # Frame 4 shown again from the cache: still unfinished, so it waits for rest again.
    clean_scene.frame_set(4)
    assert live.last_update[obj.name]["cached"] and live.last_update[obj.name]["unfinished"]
    assert not shown_mesh(obj).has_custom_normals
    assert pm.blender_mesh.get_point_attribute(shown_mesh(obj), "velocity") is None
    assert rest(live, monkeypatch) is None and shown_mesh(obj).has_custom_normals
    same_velocity(pm, shown_mesh(obj), one_shot(pm, em, 4))
    # The finished frame 5 from the cache: its kept mesh, finished, nothing left to do.
    clean_scene.frame_set(5)
    record = live.last_update[obj.name]
    assert record["cached"] and record["swapped"] and not record["unfinished"]
    assert shown_mesh(obj).name == finished_5 and shown_mesh(obj).has_custom_normals
    assert not live._pending


def test_renders_update_now_and_finish_every_frame_have_normals_at_once(pm, clean_scene,
                                                                        deferring):
    live = deferring
    em = emitter(speed=1.0)
    make_active(em)
    obj = live_object(pm, "polygonize")
    depsgraph = bpy.context.evaluated_depsgraph_get()
    clean_scene.frame_set(3)
    assert not shown_mesh(obj).has_custom_normals
    # A render's frame (the handler with a render depsgraph) is finished as it is written.
    record = live.update_object(obj, depsgraph, mode="RENDER", defer=True)
    assert not record["unfinished"] and obj.data.has_custom_normals
    assert live.UNFINISHED_TAG not in obj.data and not live._pending
    assert pm.blender_mesh.get_point_attribute(obj.data, "velocity") is not None
    # Update Now writes the object's own mesh with its normals and channels (from the cached
    # frame 6, written unfinished: its channels interpolated now).
    clean_scene.frame_set(6)
    assert pm.generate.attributes_pending(cached_data(live, obj, 6))
    with bpy.context.temp_override(active_object=obj, object=obj):
        assert bpy.ops.particlemesh.update() == {"FINISHED"}
    assert obj.data.has_custom_normals and live.UNFINISHED_TAG not in obj.data
    assert not pm.generate.attributes_pending(cached_data(live, obj, 6))
    own = obj.data
    same_velocity(pm, own, one_shot(pm, em, 6))
    make_active(obj)
    # Finish Every Frame: viewport frames too, new ones and unfinished cached ones.
    clean_scene.frame_set(7)
    assert live.UNFINISHED_TAG in shown_mesh(obj)
    clean_scene.frame_set(8)
    obj.particlemesh.finish_every_frame = True
    for frame in (7, 9):
        clean_scene.frame_set(frame)
        assert shown_mesh(obj).has_custom_normals and live.UNFINISHED_TAG not in shown_mesh(obj)
        assert not live.last_update[obj.name]["unfinished"] and not live._pending
        assert pm.blender_mesh.get_point_attribute(shown_mesh(obj), "velocity") is not None


def test_the_finishing_timer_copes_with_objects_gone_and_live_mode_off(pm, clean_scene,
                                                                      deferring, monkeypatch,
                                                                      tmp_path):
    live = deferring
    em = emitter(speed=1.0)
    make_active(em)
    obj = live_object(pm, "polygonize")
    # A save finishes the frame on screen first (a file holds finished meshes only).
    clean_scene.frame_set(2)
    assert live._pending
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "live.blend"), copy=True)
    assert not live._pending and obj.data.has_custom_normals
    assert live.UNFINISHED_TAG not in obj.data
    clean_scene.frame_set(3)
    assert live._pending
    # Live mode off: the frame on screen becomes the object's mesh and is finished at rest.
    obj.particlemesh.live = False
    assert live.UNFINISHED_TAG in obj.data
    assert rest(live, monkeypatch) is None
    assert obj.data.has_custom_normals and live.UNFINISHED_TAG not in obj.data
    # The object deleted before the frames rest: nothing to finish, no error.
    obj.particlemesh.live = True
    clean_scene.frame_set(4)
    assert live._pending
    mesh_name = shown_mesh(obj).name
    bpy.data.objects.remove(obj)
    assert rest(live, monkeypatch) is None and not live._pending
    mesh = bpy.data.meshes.get(mesh_name)
    assert mesh is None or not mesh.has_custom_normals
    # The frame's mesh replaced under the same name (as an undo can): left alone.
    em2 = emitter("Emitter2", speed=1.0)
    make_active(em2)
    obj = live_object(pm, "polygonize")
    clean_scene.frame_set(6)
    del shown_mesh(obj)[live.UNFINISHED_TAG]
    assert rest(live, monkeypatch) is None and not shown_mesh(obj).has_custom_normals


def test_live_off_leaves_the_mesh_alone(pm, clean_scene):
    emitter()
    assert bpy.ops.particlemesh.triangulate() == {"FINISHED"}
    obj = bpy.context.active_object
    before, _ = mesh_arrays(shown_mesh(obj))
    clean_scene.frame_set(8)
    after, _ = mesh_arrays(shown_mesh(obj))
    np.testing.assert_array_equal(before, after)
    # Switching it on regenerates at once.
    obj.particlemesh.live = True
    now, _ = mesh_arrays(shown_mesh(obj))
    assert np.linalg.norm(now, axis=1).mean() > np.linalg.norm(before, axis=1).mean() + 0.2


def test_settings_change_regenerates(pm, clean_scene):
    emitter()
    obj = live_object(pm)
    faces = len(shown_mesh(obj).polygons)
    obj.particlemesh.viewport.max_edge_factor = 1.05  # tighter than the icosphere's edges
    assert len(shown_mesh(obj).polygons) < faces
    assert pm.live.last_update[obj.name]["cached"] is False


def test_a_live_error_is_recorded_not_raised(pm, clean_scene):
    em = emitter(frame_start=1, frame_end=1, lifetime=5)  # all particles die at frame 6
    obj = live_object(pm)
    clean_scene.frame_set(10)
    record = pm.live.last_update[obj.name]
    assert "no living particles" in record["error"]
    clean_scene.frame_set(3)  # and it recovers
    assert "error" not in pm.live.last_update[obj.name]
    assert em.name in bpy.data.objects


def render_animation(scene, tmp_path, frames):
    render_animation_settings(scene, tmp_path, frames)
    assert bpy.ops.render.render(animation=True) == {"FINISHED"}


def render_animation_settings(scene, tmp_path, frames):
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False
    scene.render.resolution_x = scene.render.resolution_y = 16
    scene.render.resolution_percentage = 100
    scene.frame_start, scene.frame_end = frames
    scene.render.filepath = str(tmp_path / "frame_")
    if scene.camera is None:
        cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
        scene.collection.objects.link(cam)
        cam.location = (0, -8, 0)
        cam.rotation_euler = (1.5708, 0, 0)
        scene.camera = cam


def test_a_still_render_shows_the_frame_on_screen(pm, clean_scene, tmp_path):
    """A still render (F12) of a frame the viewport shows through a holder renders that frame's
    geometry: the object's own mesh, since renders never see holders."""
    em = emitter(speed=1.0)
    obj = live_object(pm)
    for frame in (2, 3, 2):
        clean_scene.frame_set(frame)
    assert shown_instance(obj) is not None
    seen = []

    def watch(scene, *_):
        seen.append(mesh_arrays(obj.data)[0].copy())

    render_animation_settings(clean_scene, tmp_path, (2, 2))
    bpy.app.handlers.render_post.append(watch)
    try:
        assert bpy.ops.render.render(write_still=False) == {"FINISHED"}
    finally:
        bpy.app.handlers.render_post.remove(watch)
    positions, _ = living_particles(em)
    assert len(seen) == 1
    np.testing.assert_allclose(seen[0], positions, atol=1e-5)


def test_render_uses_the_render_settings(pm, clean_scene, tmp_path):
    emitter()
    obj = live_object(pm)
    state = obj.particlemesh
    state.use_render_settings = True
    state.render.raw = True  # the seed's raw triangles: more than the viewport's surface
    viewport_triangles = len(shown_mesh(obj).polygons)
    assert viewport_triangles == 2 * 642 - 4
    pm.live.history.clear()
    render_animation(clean_scene, tmp_path, (2, 3))
    renders = [r for name, r in pm.live.history if name == obj.name and r["mode"] == "RENDER"]
    assert [r["frame"] for r in renders] == [2, 3], list(pm.live.history)
    assert all("error" not in r for r in renders)
    assert all(r["vertices"] == 642 and r["triangles"] > viewport_triangles for r in renders)
    assert (tmp_path / "frame_0002.png").is_file() and (tmp_path / "frame_0003.png").is_file()
    # Back in the viewport: the viewport settings again.
    clean_scene.frame_set(5)
    record = pm.live.last_update[obj.name]
    assert record["mode"] == "VIEWPORT" and record["triangles"] == viewport_triangles


def closed_and_consistent(tris):
    """Every edge in exactly two triangles, once in each direction."""
    directed = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    pairs, counts = np.unique(directed, axis=0, return_counts=True)
    reverse = {tuple(e) for e in pairs}
    return counts.max() == 1 and all((b, a) in reverse for a, b in pairs)


def test_viewport_thins_out_while_renders_use_every_particle(pm, clean_scene):
    em = emitter(subdivisions=5, speed=1.0)  # 2562 particles
    obj = live_object(pm)
    state = obj.particlemesh
    state.use_render_settings = True
    state.viewport.thin = 2.0  # regenerates at once, coarser
    for frame in (3, 6):
        clean_scene.frame_set(frame)
        record = pm.live.last_update[obj.name]
        assert "error" not in record and record["cached"] is False, record
        co, tris = mesh_arrays(shown_mesh(obj))
        assert 2562 / 8 < len(co) < 2562 / 3, len(co)
        positions, _ = living_particles(em)
        # Each vertex is one of the particles, and they are at least the thinning apart.
        nearest = np.linalg.norm(co[:, None] - positions[None], axis=-1).min(axis=1)
        assert nearest.max() < 1e-5
        gaps = np.linalg.norm(co[:, None] - co[None], axis=-1) + np.eye(len(co)) * 1e9
        spacing = np.sort(np.linalg.norm(positions[:, None] - positions[None], axis=-1), 1)[:, 1]
        r0 = np.sort(spacing)[(len(spacing) - 1) // 2]  # the lower median, as the library
        assert gaps.min() >= 2.0 * r0 * 0.999
        assert closed_and_consistent(tris) and len(co) - len(tris) // 2 == 2  # a sphere
    # The panel says how many were meshed.
    log = draw_panels(pm, bpy.context)
    assert any(kind == "label" and "of 2562 particles meshed" in text for kind, text in log), log
    # The render settings keep every particle.
    depsgraph = bpy.context.evaluated_depsgraph_get()
    data, settings, _ = pm.live.compute(obj, depsgraph, mode="RENDER", use_cache=False)
    assert settings["thin"] == 1.0 and data.vertex_count == 2562
    # The thinning is part of the cache key: back to 1, the full mesh, not the cached preview.
    state.viewport.thin = 1.0
    assert len(shown_mesh(obj).vertices) == 2562


def test_viewport_budget_previews_a_big_system_while_renders_mesh_it_whole(pm, clean_scene):
    """Live mode in the viewport meshes an even subset of at most about Viewport Budget
    particles (a closed sphere still); renders, Update Now and budget 0 mesh every particle."""
    em = emitter(subdivisions=5, speed=1.0)  # 2562 particles
    obj = live_object(pm)
    state = obj.particlemesh
    assert state.viewport_budget == 8000  # the documented default: over 2562, so no thinning
    assert len(shown_mesh(obj).vertices) == 2562  # the operator meshes every particle
    state.viewport_budget = 600  # regenerates at once
    for frame in (3, 6):
        clean_scene.frame_set(frame)
        record = pm.live.last_update[obj.name]
        assert "error" not in record and record["mode"] == "VIEWPORT", record
        co, tris = mesh_arrays(shown_mesh(obj))
        assert 600 / 2 <= len(co) <= 600 * pm.generate.BUDGET_SLACK, len(co)
        assert record["thin"] > 1.0
        positions, _ = living_particles(em)
        nearest = np.linalg.norm(co[:, None] - positions[None], axis=-1).min(axis=1)
        assert nearest.max() < 1e-5  # each vertex is one of the particles
        assert closed_and_consistent(tris) and len(co) - len(tris) // 2 == 2  # a sphere
    log = draw_panels(pm, bpy.context)
    assert ("prop", "viewport_budget") in log
    assert any(kind == "label" and "of 2562 particles meshed (Thin Out" in text
               for kind, text in log), log
    # Renders and Update Now mesh every particle (the budget is for live scrubbing only).
    depsgraph = bpy.context.evaluated_depsgraph_get()
    data, settings, _ = pm.live.compute(obj, depsgraph, mode="RENDER", use_cache=False)
    assert data.vertex_count == 2562 and "viewport_budget" not in settings
    assert bpy.ops.particlemesh.update() == {"FINISHED"}
    assert len(shown_mesh(obj).vertices) == 2562
    # The budget is part of the cache key: scrubbing back shows the cached preview ...
    clean_scene.frame_set(3)
    assert pm.live.last_update[obj.name]["cached"] and len(shown_mesh(obj).vertices) < 2562
    # ... and with no budget the viewport meshes every particle too.
    state.viewport_budget = 0
    assert len(shown_mesh(obj).vertices) == 2562


def test_bake_five_frames_and_step_through(pm, clean_scene, tmp_path):
    em = emitter(speed=1.0)
    obj = live_object(pm)
    material = bpy.data.materials.new("Baked")
    obj.data.materials.append(material)
    unbaked = obj.data
    folder = tmp_path / "seq"
    assert bpy.ops.particlemesh.bake(frame_start=1, frame_end=5, write_ply=True,
                                     directory=str(folder)) == {"FINISHED"}
    state = obj.particlemesh
    assert state.baked and (state.bake_start, state.bake_end) == (1, 5)
    assert sorted(item.frame for item in state.bake_frames) == [1, 2, 3, 4, 5]
    meshes = {item.frame: item.mesh for item in state.bake_frames}
    assert len(set(m.name for m in meshes.values())) == 5
    files = sorted(os.listdir(folder))
    assert files == [f"{obj.name}_{f:05d}.ply" for f in range(1, 6)]
    for frame in (1, 2, 3, 4, 5, 3, 1):
        clean_scene.frame_set(frame)
        assert obj.data == meshes[frame], frame
        assert list(obj.data.materials) == [material]
        positions, _ = living_particles(em)
        co, tris = mesh_arrays(obj.data)
        np.testing.assert_allclose(co, positions, atol=1e-5)
        on_disk = pm.particlemesh.read_mesh(folder / f"{obj.name}_{frame:05d}.ply")
        assert on_disk.triangle_count == len(tris)
        np.testing.assert_allclose(on_disk.vertices, co, atol=1e-6)
    clean_scene.frame_set(9)  # past the range: the last baked frame stays
    assert obj.data == meshes[5]
    # Free the bake: the live mesh comes back, the baked meshes go.
    names = [m.name for m in meshes.values()]
    assert bpy.ops.particlemesh.free_bake() == {"FINISHED"}
    assert obj.data == unbaked and not state.baked
    assert not any(name in bpy.data.meshes for name in names)


def test_baked_frames_render(pm, clean_scene, tmp_path):
    emitter(speed=1.0)
    obj = live_object(pm)
    assert bpy.ops.particlemesh.bake(frame_start=1, frame_end=3) == {"FINISHED"}
    meshes = {item.frame: item.mesh.name for item in obj.particlemesh.bake_frames}
    seen = []

    def watch(scene, depsgraph=None):
        seen.append((scene.frame_current, obj.data.name))

    bpy.app.handlers.render_post.append(watch)
    try:
        render_animation(clean_scene, tmp_path, (2, 3))
    finally:
        bpy.app.handlers.render_post.remove(watch)
    assert seen == [(2, meshes[2]), (3, meshes[3])]


def test_bake_undo(pm, clean_scene):
    emitter()
    obj = live_object(pm)
    name = obj.name
    bpy.ops.ed.undo_push(message="before bake")
    assert bpy.ops.particlemesh.bake("INVOKE_DEFAULT", True, frame_start=1, frame_end=3) == {"FINISHED"}
    assert obj.particlemesh.baked and len(obj.particlemesh.bake_frames) == 3
    undo()
    obj = bpy.data.objects[name]
    assert not obj.particlemesh.baked and len(obj.particlemesh.bake_frames) == 0


def test_update_now_and_clear_cache(pm, clean_scene):
    em = emitter(speed=1.0)
    assert bpy.ops.particlemesh.triangulate() == {"FINISHED"}  # live off
    obj = bpy.context.active_object
    clean_scene.frame_set(12)
    before, _ = mesh_arrays(obj.data)
    assert bpy.ops.particlemesh.update() == {"FINISHED"}
    after, _ = mesh_arrays(obj.data)
    positions, _ = living_particles(em)
    np.testing.assert_allclose(after, positions, atol=1e-5)
    assert not np.allclose(before, after)
    assert pm.live.cache_info(obj)[0] == 1
    assert bpy.ops.particlemesh.clear_cache() == {"FINISHED"}
    assert pm.live.cache_info(obj) == (0, 0)


def test_source_deleted(pm, clean_scene):
    em = emitter()
    obj = live_object(pm)
    bpy.data.objects.remove(em)
    clean_scene.frame_set(3)
    assert "lost its source" in pm.live.last_update[obj.name]["error"]
    make_active(obj)
    with pytest.raises(RuntimeError, match="lost its source"):
        bpy.ops.particlemesh.update()


def test_command_line_animation_render(pm, clean_scene, tmp_path):
    """`blender -b file.blend -a` in a separate process: the saved live object regenerates at
    every rendered frame, with the render settings."""
    import json
    import os
    import subprocess

    emitter(speed=1.0)
    obj = live_object(pm)
    obj.particlemesh.use_render_settings = True
    obj.particlemesh.render.raw = True
    render_animation_settings(clean_scene, tmp_path, (2, 4))
    blend = tmp_path / "live.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    log = tmp_path / "frames.jsonl"
    expr = (
        "import bpy, json\n"
        "def post(scene, depsgraph=None):\n"
        f"    o = bpy.data.objects[{obj.name!r}]\n"
        f"    with open({str(log)!r}, 'a') as f:\n"
        "        f.write(json.dumps([scene.frame_current, len(o.data.vertices), len(o.data.polygons),"
        " sum(v.co.length for v in o.data.vertices[:50]) / 50]) + '\\n')\n"
        "bpy.app.handlers.render_post.append(post)\n")
    env = dict(os.environ)
    proc = subprocess.run(
        [bpy.app.binary_path, "--background", "--factory-startup", "-noaudio", str(blend),
         "--addons", "particlemesh", "--python-expr", expr, "--render-anim"],
        env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    rows = [json.loads(line) for line in log.read_text().splitlines()]
    assert [r[0] for r in rows] == [2, 3, 4], proc.stdout[-2000:]
    assert all(r[1] == 642 for r in rows)
    viewport_faces = len(obj.data.polygons)
    assert all(r[2] > viewport_faces for r in rows)  # the render settings' raw triangles
    radii = [r[3] for r in rows]
    assert radii == sorted(radii) and radii[-1] > radii[0]  # regenerated at every frame
    for frame in (2, 3, 4):
        assert (tmp_path / f"frame_{frame:04d}.png").is_file()


class _Layout:
    """Records what a panel draws; checks every property and operator it names exists."""

    def __init__(self, log):
        self.log = log
        self.use_property_split = False
        self.active = self.enabled = self.alert = True

    def _child(self, *args, **kwargs):
        return _Layout(self.log)

    column = row = box = split = _child

    def prop(self, data, name, **kwargs):
        assert name in data.bl_rna.properties, f"{type(data).__name__} has no property {name}"
        self.log.append(("prop", name))

    def operator(self, idname, **kwargs):
        module, name = idname.split(".")
        assert hasattr(getattr(bpy.ops, module), name), idname
        self.log.append(("operator", idname))

    def label(self, text="", **kwargs):
        self.log.append(("label", text))


class _PanelSelf:
    def __init__(self, log):
        self.layout = _Layout(log)


def draw_panels(pm, context):
    log = []
    for cls in pm.ui.classes:
        if hasattr(cls, "poll") and not cls.poll(context):
            continue
        panel = _PanelSelf(log)
        if hasattr(cls, "draw_header"):
            cls.draw_header(panel, context)
        cls.draw(panel, context)
    return log


def test_panels_draw(pm, clean_scene):
    log = draw_panels(pm, bpy.context)
    assert ("operator", "particlemesh.triangulate") in log
    assert ("operator", "particlemesh.import_cloud") in log
    em = emitter()
    obj = live_object(pm)
    clean_scene.frame_set(3)
    log = draw_panels(pm, bpy.context)
    props = [name for kind, name in log if kind == "prop"]
    for name in ("source", "live", "auto_spacing", "max_edge_factor", "smooth", "use_render_settings",
                 "instant_frames", "finish_every_frame"):
        assert name in props, name
    assert any(kind == "label" and "frame 3" in text for kind, text in log)
    assert ("operator", "particlemesh.bake") in log
    obj.particlemesh.method = "POLYGONIZE"
    props = [name for kind, name in draw_panels(pm, bpy.context) if kind == "prop"]
    assert "kernel" in props and "radius_mode" in props
    assert em.name in bpy.data.objects


def test_operator_redo_panels_draw(pm):
    """Each operator's draw() (its redo panel) names only real properties."""
    for cls in (pm.operators.PARTICLEMESH_OT_triangulate, pm.operators.PARTICLEMESH_OT_polygonize):
        log = []
        props = bpy.context.window_manager.operator_properties_last(cls.bl_idname)
        fake = _PanelSelf(log)
        for name in props.bl_rna.properties.keys():
            if name != "rna_type":
                setattr(fake, name, getattr(props, name))
        fake.bl_rna = props.bl_rna  # the layout checks names against the operator's RNA
        fake.method = cls.method
        cls.draw(fake, bpy.context)
        assert ("prop", "source") in log and ("prop", "live") in log


def test_import_particle_sequence_follows_the_scene_frame(pm, clean_scene, tmp_path):
    """File > Import > Particle Sequence: a simulation cache (one .vtk per frame) becomes a
    live mesh showing the scene frame's file, meshed with the object's settings, velocity
    carried as the motion-blur attribute; a frame without a file is reported, not fatal."""
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "cli"))
    from particle_files import particles, write_vtk

    for f in (1, 2, 3):
        p, a = particles(f, n=8)
        write_vtk(tmp_path / f"fluid_{f:04d}.vtk", p, a)
    scene = bpy.context.scene
    scene.frame_start = 10
    scene.frame_set(10)
    assert bpy.ops.particlemesh.import_sequence(filepath=str(tmp_path / "fluid_0002.vtk")) == {"FINISHED"}
    obj = bpy.context.active_object
    state = obj.particlemesh
    assert obj.name == "fluid" and state.source_kind == "FILES" and state.live
    assert state.file_pattern == str(tmp_path / "fluid_{:04d}.vtk")
    assert state.frame_offset == 1 - 10  # the first file at the scene's start
    centres = {}
    for frame, file_frame in ((10, 1), (11, 2), (12, 3)):
        scene.frame_set(frame)
        record = pm.live.last_update[obj.name_full]
        assert "error" not in record, record
        co = np.empty(3 * len(shown_mesh(obj).vertices), dtype=np.float32)
        shown_mesh(obj).vertices.foreach_get("co", co)
        co = co.reshape(-1, 3)
        # the mesh is that file's, meshed with the object's settings
        expected = pm.generate.run("POLYGONIZE",
                                   pm.sources.read_file_frame(state.file_pattern, file_frame),
                                   pm.live.settings_for(obj, "VIEWPORT"))
        assert len(co) == expected.vertex_count > 0
        np.testing.assert_allclose(co, expected.vertices, atol=1e-6)
        velocity = shown_mesh(obj).attributes["velocity"]
        assert velocity.data_type == "FLOAT_VECTOR" and velocity.domain == "POINT"
        centres[file_frame] = co.mean(axis=0)
    # the particles move 1/64 along x per frame: so does the mesh
    assert abs((centres[3][0] - centres[1][0]) - 2 / 64) < 0.01
    scene.frame_set(20)  # no file for frame 11
    record = pm.live.last_update[obj.name_full]
    assert "no particle file for frame 11" in record["error"]
    scene.frame_set(10)
    assert "error" not in pm.live.last_update[obj.name_full]
    # A ParaView collection listing the same files out of order: frame n is its n-th by time.
    series = tmp_path / "fluid.vtk.series"
    series.write_text('{"file-series-version": "1.0", "files": [{"name": "fluid_0003.vtk", "time": 0.2}, '
                      '{"name": "fluid_0001.vtk", "time": 0.0}, {"name": "fluid_0002.vtk", "time": 0.1}]}')
    assert bpy.ops.particlemesh.import_sequence(filepath=str(series)) == {"FINISHED"}
    col = bpy.context.active_object
    assert col.particlemesh.file_pattern == str(series) and col.particlemesh.frame_offset == 0 - 10
    for frame, file_frame in ((10, 1), (12, 3)):
        scene.frame_set(frame)
        assert "error" not in pm.live.last_update[col.name_full]
        co = np.empty(3 * len(shown_mesh(col).vertices), dtype=np.float32)
        shown_mesh(col).vertices.foreach_get("co", co)
        assert abs(co.reshape(-1, 3).mean(axis=0)[0] - centres[file_frame][0]) < 1e-6
    scene.frame_set(13)  # the collection lists 3 frames
    assert "lists frames 0..2" in pm.live.last_update[col.name_full]["error"]
