"""Live mode and baked frames: a persistent frame-change handler that regenerates generated
objects from their evaluated sources (or swaps in their baked meshes), in the viewport and
during renders, with a per-frame cache.

No operator runs in here: only module functions on data, so it is safe in a background
animation render. The depsgraph handed to the handler says whether this is a render
(depsgraph.mode == 'RENDER'), which picks the object's render settings.

In the viewport a new frame is first written without the library's normals (Blender's own
smooth normals): setting them as custom split normals, and Blender evaluating a mesh that has
them, is most of a big polygonized frame's time (bench/RESULTS.md). A polygonized frame's
channels (velocity) wait too: their interpolation is a fifth of the library's time
(generate.finish_attributes). Such an *unfinished* frame's mesh carries UNFINISHED_TAG; once
frames rest (no frame change for REST_SECONDS, no playback), a timer (finish_frames) gives
the frame on screen its custom normals and channels, so that what shows at rest is what a
one-shot generation gives. Renders, Update Now, Bake and the
operators write finished frames at once, as does the viewport with the object's Finish
Every Frame on."""

import time
import uuid
from collections import OrderedDict, deque

import bpy
from bpy.app.handlers import persistent

from . import blender_mesh, frame_display, generate, properties, sources
from . import particlemesh as pm


class _Cache:
    """Meshes already made, per object: (frame, mode, settings, particle digest) -> Mesh,
    least recently used first out, bounded by the preference's megabytes. Each entry may
    also keep the Blender mesh datablock written from it (by name, with a tag: Python
    references to IDs do not survive undo), so that showing a cached frame again shows that
    mesh (frame_display) instead of writing a new one; such an entry counts KEPT_MESH_COST
    times its bytes."""

    def __init__(self):
        self.entries = OrderedDict()
        self.counted = {}  # key -> _data_bytes(data) when put (its data can change later)
        self.meshes = {}  # key -> (mesh name, tag)
        self.reuse = {}  # what generate.run keeps from frame to frame (a Smoother)
        self.bytes = 0
        self.hits = 0
        self.misses = 0

    def get(self, key):
        data = self.entries.get(key)
        if data is None:
            self.misses += 1
            return None
        self.entries.move_to_end(key)
        self.hits += 1
        return data

    def put(self, key, data, limit):
        if limit <= 0:
            return
        self._pop(key)
        self.entries[key] = data
        self.counted[key] = _data_bytes(data)
        self.bytes += self.counted[key][0]
        self._trim(limit)

    def put_mesh(self, key, mesh, tag, limit):
        """Keep `mesh` (written from the entry `key`) as that entry's Blender mesh."""
        data = self.entries.get(key)
        if data is None or key in self.meshes:
            return False
        self.meshes[key] = (mesh.name, tag)
        self.bytes += _mesh_bytes(self.counted[key])
        self._trim(limit, keep=key)
        if self.bytes > limit:  # too big beside its data on its own: not kept
            self.meshes.pop(key)
            self.bytes -= _mesh_bytes(self.counted[key])
            return False
        return True

    def mesh(self, key):
        """The Blender mesh kept for entry `key`, if it still exists and is still the one
        written for it (undo may have removed or replaced it)."""
        name, tag = self.meshes.get(key, (None, None))
        mesh = bpy.data.meshes.get(name) if name else None
        if mesh is None or mesh.get(FRAME_TAG) != tag:
            if name is not None:
                self.meshes.pop(key)
                self.bytes -= _mesh_bytes(self.counted[key])
            return None
        return mesh

    def holds(self, mesh):
        return self.holds_tag(mesh.get(FRAME_TAG))

    def holds_tag(self, tag):
        return tag is not None and any(t == tag for _, t in self.meshes.values())

    def _pop(self, key):
        data = self.entries.pop(key, None)
        if data is None:
            return
        counted = self.counted.pop(key)
        self.bytes -= counted[0]
        kept = self.meshes.pop(key, None)
        if kept is not None:
            self.bytes -= _mesh_bytes(counted)
            _remove_unused(kept[0], kept[1])

    def _trim(self, limit, keep=None):
        """Drop the least recently used entries until under `limit`, but `keep`."""
        while self.bytes > limit and self.entries:
            key = next(iter(self.entries))
            if key == keep:
                if len(self.entries) == 1:
                    return
                self.entries.move_to_end(key)
                continue
            self._pop(key)

    def clear(self):
        generate.release(self.reuse)
        for name, tag in self.meshes.values():
            _remove_unused(name, tag)
        self.entries.clear()
        self.counted.clear()
        self.meshes.clear()
        self.bytes = 0


#: What a frame kept as a Blender mesh costs, in multiples of its data's bytes, data included:
#: the mesh (1.6-2.7 times the data for a 1.5M-triangle polygonized frame, custom normals the
#: most) and its holder's evaluation in the depsgraph (1.2-2.1 times; bench/RESULTS.md).
KEPT_MESH_COST = 5


def _data_bytes(data):
    """(the bytes a cache entry counts for mesh data `data`, those its finished frame will
    hold): its arrays, and for a frame whose channels wait, the larger of what waits (the
    particles, float64 vertices) and the channels to come; the second with the channels."""
    entry = data.nbytes + generate.pending_nbytes(data)
    return entry, data.nbytes + generate.pending_finished_nbytes(data)


def _mesh_bytes(counted):
    """What keeping an entry that counts `counted` (_data_bytes) as a mesh adds to its bytes:
    the Blender mesh of the finished frame and its evaluation."""
    return (KEPT_MESH_COST - 1) * counted[1]


#: The custom property that marks a mesh datablock as a live frame kept by the cache (its
#: value says which entry wrote it).
FRAME_TAG = "particlemesh_live_frame"
#: The custom property on a live frame's mesh written without its custom split normals (its
#: value names the pending finish; finish_frames sets them and removes it).
UNFINISHED_TAG = "particlemesh_live_unfinished"
#: Seconds without a frame change (and no playback) before the frame on screen is finished.
REST_SECONDS = 0.3
#: Viewport frames are finished at once in background mode (no one looks, timers do not run
#: while a script does, and a script that exports the frame needs its normals); the tests and
#: the benchmark set this to see the viewport's deferral there, calling finish_frames
#: themselves.
defer_in_background = False
_session = uuid.uuid4().hex[:12]
_tags = 0


def _new_tag():
    global _tags
    _tags += 1
    return f"{_session}.{_tags}"


def _remove_unused(name, tag):
    """Delete a kept frame's holder and mesh once nothing shows them (the one on screen
    stays)."""
    frame_display.remove_holder(name, tag)
    mesh = bpy.data.meshes.get(name)
    if mesh is not None and mesh.get(FRAME_TAG) == tag and mesh.users == 0:
        bpy.data.meshes.remove(mesh)


_caches = {}
#: Per object name: what the last update did (frame, mode, seconds, cached, error). For the UI,
#: the tests and the benchmark.
last_update = {}
#: The last updates of all objects, oldest first: (object name, record).
history = deque(maxlen=1000)
#: Objects not to touch from the handler (being baked or generated by an operator right now).
suspended = set()
_in_handler = False


def cache_for(obj):
    return _caches.setdefault(obj.name_full, _Cache())


def clear_cache(obj=None, remove_meshes=True):
    """Forget the cached frames of `obj` (of every object when None) and delete their kept
    meshes that nothing uses (not after loading a file: those names belong to the old one).
    The object shows the mesh on screen as its own mesh again."""
    if remove_meshes:
        for o in [obj] if obj is not None else [o for o in bpy.data.objects
                                                if frame_display.MODIFIER in o.modifiers]:
            stop_display(o)
    caches = list(_caches.values()) if obj is None else [_caches.get(obj.name_full)]
    for cache in caches:
        if cache is not None:
            if not remove_meshes:
                cache.meshes.clear()
            cache.clear()
    if obj is None:
        _caches.clear()
    else:
        _caches.pop(obj.name_full, None)
    if not _caches:  # no live object left: nor the arrays kept for writing its next frame
        blender_mesh.release_buffers()


def cache_info(obj):
    cache = _caches.get(obj.name_full)
    if cache is None:
        return 0, 0
    return len(cache.entries), cache.bytes


def _cache_limit():
    prefs = properties.preferences()
    megabytes = prefs.cache_megabytes if prefs else properties.CACHE_MEGABYTES
    return megabytes * 1024 * 1024


def settings_for(obj, mode):
    state = obj.particlemesh
    group = state.render if (mode == "RENDER" and state.use_render_settings) else state.viewport
    return properties.snapshot(group, state.method)


def compute(obj, depsgraph, mode=None, use_cache=True, progress=None, timings=None, budget=0,
            keys=None, defer_attributes=False):
    """Mesh data of generated object `obj` for the depsgraph's frame (from the cache when it
    was made before). Returns (particlemesh.Mesh, settings, cached). `timings` (a dict), if given,
    receives the seconds spent reading the source and meshing. `budget` > 0: triangulate at
    most about that many particles (live mode's Viewport Budget). `keys` (a list), if given,
    receives the frame's cache key. `defer_attributes`: a new polygonized frame may leave its
    channels for generate.finish_attributes (a viewport frame that waits for rest)."""
    state = obj.particlemesh
    mode = mode or depsgraph.mode
    source = state.source
    if source is None and state.source_kind != "FILES":
        raise sources.SourceError(f"'{obj.name}' has lost its source object")
    settings = settings_for(obj, mode)
    t0 = time.perf_counter()
    if state.source_kind == "FILES":  # a simulation cache: this frame's file
        particles = sources.read_file_frame(state.file_pattern,
                                            depsgraph.scene.frame_current + state.frame_offset)
    else:
        particles = sources.read(source, depsgraph, state.source_kind, state.particle_system,
                                 need_sizes=(state.method == "POLYGONIZE"))
    if budget > 0 and state.method == "TRIANGULATE":
        settings["viewport_budget"] = budget
    # frame_current_final includes the subframe (motion blur steps evaluate between frames).
    key = (depsgraph.scene.frame_current_final, mode, state.method, state.source_kind,
           properties_key(settings), particles.digest())
    if keys is not None:
        keys.append(key)
    t1 = time.perf_counter()
    if timings is not None:
        timings["source"] = t1 - t0
        timings["particles"] = len(particles.positions)
    cache = cache_for(obj)
    if use_cache:
        data = cache.get(key)
        if data is not None:
            return data, settings, True
    if use_cache:
        cache.reuse["max_bytes"] = _cache_limit()  # a kept Smoother fits in the cache's memory
    data = generate.run(state.method, particles, settings, progress=progress,
                        reuse=cache.reuse if use_cache else None,
                        defer_attributes=defer_attributes)
    if timings is not None:
        timings["mesh"] = time.perf_counter() - t1
        timings["smoother_reused"] = cache.reuse.pop("reused", False) if use_cache else False
    if use_cache:
        cache.put(key, data, _cache_limit())
    return data, settings, False


def properties_key(settings):
    return tuple(sorted(settings.items()))


def apply(obj, data, settings, defer=False):
    """Write mesh data into the generated object's own mesh, in place (materials stay), and
    show it. A mesh the cache kept for a frame stops being that frame's. `defer`: without
    its custom normals until the frame rests (finish_frames)."""
    frame_display.hide(obj)
    mesh = obj.data
    if FRAME_TAG in mesh:
        del mesh[FRAME_TAG]
    _write(obj, mesh, data, settings, defer)


def _write(obj, mesh, data, settings, defer):
    """blender_mesh.write of a frame that `obj` shows next; with `defer`, the custom normals
    and the channels still to interpolate are left for finish_frames (the mesh marked
    unfinished, the frame pending). Without, the frame is written finished."""
    custom = settings.get("custom_normals", True)
    waiting = generate.attributes_pending(data)
    if not defer:
        generate.finish_attributes(data)
        waiting = ()
    later = defer and (blender_mesh.has_custom_normals(data, custom) or bool(waiting))
    blender_mesh.write(mesh, data, custom_normals=custom and not later, keep_arrays=True)
    for name in waiting:  # an earlier frame's values (a mesh rewritten in place)
        attribute = mesh.attributes.get(name)
        if attribute is not None:
            mesh.attributes.remove(attribute)
    if later:
        token = _new_tag()
        mesh[UNFINISHED_TAG] = token
        _pend(obj, mesh, token, data, custom)
    elif UNFINISHED_TAG in mesh:
        del mesh[UNFINISHED_TAG]


class _Pending:
    """A frame on screen waiting for its custom normals: its mesh by name and tag (Python
    references to IDs do not survive undo) and the data it was written from."""

    __slots__ = ("mesh", "token", "data", "custom_normals")

    def __init__(self, mesh, token, data, custom_normals):
        self.mesh, self.token, self.data, self.custom_normals = mesh, token, data, custom_normals


#: Per object name: its unfinished frame on screen.
_pending = {}
_last_change = 0.0


def _pend(obj, mesh, token, data, custom):
    _pending[obj.name_full] = _Pending(mesh.name, token, data, custom)
    if not bpy.app.timers.is_registered(finish_frames):
        bpy.app.timers.register(finish_frames, first_interval=REST_SECONDS)


def _finish(mesh, data, custom):
    """The frame's custom normals and its channels that waited, on its mesh: what a one-shot
    generation gives."""
    for name in generate.finish_attributes(data):
        blender_mesh.set_point_attribute(mesh, name, data.attributes[name])
    blender_mesh.set_normals(mesh, data, custom_normals=custom)
    if UNFINISHED_TAG in mesh:
        del mesh[UNFINISHED_TAG]


def _busy():
    """Whether frames may change any moment: playback in some window, or a render running
    (it reads the meshes the finishing would change)."""
    windows = bpy.context.window_manager.windows if bpy.context.window_manager else ()
    if any(w.screen is not None and w.screen.is_animation_playing for w in windows):
        return True
    running = getattr(bpy.app, "is_job_running", None)
    return bool(running and running("RENDER"))


def finish_frames():
    """The timer (bpy.app.timers) that finishes the unfinished frames on screen once frames
    rest: no frame change for REST_SECONDS, no playback, no render. Returns the seconds until
    it looks again, or None (done: it is registered again by the next unfinished frame)."""
    if not _pending:
        return None
    wait = REST_SECONDS - (time.monotonic() - _last_change)
    if wait > 0:
        return wait
    if _busy() or _in_handler or any(name in suspended for name in _pending):
        return REST_SECONDS
    finish_pending()
    return None


def finish_pending():
    """Finish every pending frame now, where its object still shows it (an object deleted,
    a frame no longer on screen, a mesh gone with an undo: nothing to do). Errors are
    printed, never raised (a timer)."""
    finished = False
    while _pending:
        name, pending = _pending.popitem()
        obj = bpy.data.objects.get(name)
        if obj is None or obj.type != "MESH":
            continue
        mesh = frame_display.shown_mesh(obj)
        if mesh is None or mesh.name != pending.mesh or mesh.get(UNFINISHED_TAG) != pending.token:
            continue
        try:
            _finish(mesh, pending.data, pending.custom_normals)
        except (RuntimeError, ValueError, ReferenceError, pm.Error) as e:
            print(f"particlemesh: {name}: finishing the frame: {e}")
        finished = True
        record = last_update.get(name)
        if record is not None and record.get("unfinished"):
            record["unfinished"] = False
    if finished:
        _redraw()


def _redraw():
    """Redraw the 3D views and their sidebars (a timer's change draws at the next event)."""
    for window in bpy.context.window_manager.windows if bpy.context.window_manager else ():
        for area in window.screen.areas if window.screen else ():
            if area.type == "VIEW_3D":
                area.tag_redraw()


def _show(obj, mesh, cache, display=True):
    """Show the kept frame `mesh` on the object, with the materials of the object's own mesh:
    through its holder where frame_display can and `display` (not in renders: they show the
    object's own mesh), else by making it the object's mesh. A kept frame mesh that the cache
    no longer holds goes once nothing shows it."""
    own = obj.data
    if list(mesh.materials) != list(own.materials):
        mesh.materials.clear()
        for material in own.materials:
            mesh.materials.append(material)
    old_holder = frame_display.shown_holder(obj)
    old = old_holder.data if old_holder is not None else own
    if display and obj.particlemesh.instant_frames and frame_display.usable(obj):
        frame_display.show(obj, mesh, mesh[FRAME_TAG])
    else:
        if display:  # turned off; another modifier, an object material, edit mode
            stop_display(obj)
        else:  # a render: it shows the object's own mesh, the viewport's display stays
            frame_display.hide(obj)
        if obj.data != mesh:
            obj.data = mesh
    if old == mesh:
        return
    for gone in {old, own} - {mesh}:
        tag = gone.get(FRAME_TAG)
        if tag is not None and not cache.holds(gone) and gone != obj.data:
            _remove_unused(gone.name, tag)


def show_frame(obj, data, settings, key, cached, keep=True, defer=False):
    """Put the frame `key` (mesh data `data`) on the object. With the cache on, each frame is
    written once into a mesh datablock of its own that the cache keeps, and a frame seen
    again shows that mesh (no write: a 1.5M-triangle mesh with custom normals takes about
    a second to write; through frame_display, no evaluation either). With the cache off,
    the frame too big for it or `keep` false (renders: frames are rarely seen twice), the
    object's mesh is rewritten in place. `defer`: a new frame's custom normals wait until
    frames rest (finish_frames), and so do those of a kept frame shown again unfinished;
    without it such a frame is finished before it shows. Returns whether a kept mesh was
    shown again."""
    cache = cache_for(obj)
    _pending.pop(obj.name_full, None)  # the frame on screen changes
    if cached:
        mesh = cache.mesh(key)
        if mesh is not None:
            token = mesh.get(UNFINISHED_TAG)
            if token is not None:
                custom = settings.get("custom_normals", True)
                if defer:
                    _pend(obj, mesh, token, data, custom)
                else:
                    _finish(mesh, data, custom)
            _show(obj, mesh, cache, display=keep)
            return True
    limit = _cache_limit()
    counted = _data_bytes(data)
    if not keep or key not in cache.entries or counted[0] + _mesh_bytes(counted) > limit:
        apply(obj, data, settings, defer)
        return False
    mesh = bpy.data.meshes.new(f"{obj.name}.pm_live")
    tag = _new_tag()
    mesh[FRAME_TAG] = tag
    if not cache.put_mesh(key, mesh, tag, limit):
        # Too big to keep beside its data: write the object's own mesh instead.
        bpy.data.meshes.remove(mesh)
        apply(obj, data, settings, defer)
        return False
    _write(obj, mesh, data, settings, defer)
    _show(obj, mesh, cache)
    return False


def defers(obj, mode):
    """Whether a new frame of `obj` in `mode` waits for rest to get its custom normals: in
    the viewport, unless the object's Finish Every Frame is on (or in background mode)."""
    return (mode != "RENDER" and not obj.particlemesh.finish_every_frame
            and (defer_in_background or not bpy.app.background))


def update_object(obj, depsgraph, mode=None, defer=False):
    """Regenerate one live object for the current frame. Errors are recorded, never raised:
    a frame handler must not stop playback or a render. `defer`: a viewport frame may wait
    for rest to get its custom normals (defers())."""
    start = time.perf_counter()
    mode = mode or depsgraph.mode
    record = {"frame": depsgraph.scene.frame_current, "mode": mode}
    budget = obj.particlemesh.viewport_budget if mode != "RENDER" else 0
    try:
        keys = []
        deferring = defer and defers(obj, mode)
        data, settings, cached = compute(obj, depsgraph, mode, timings=record, budget=budget,
                                         keys=keys, defer_attributes=deferring)
        t = time.perf_counter()
        record["swapped"] = show_frame(obj, data, settings, keys[0], cached,
                                       keep=(mode != "RENDER"),
                                       defer=deferring)
        record["write"] = time.perf_counter() - t
        record["unfinished"] = obj.name_full in _pending
        record.update(cached=cached, vertices=data.vertex_count, triangles=data.triangle_count)
        if "thin_factor" in data.stats:
            record["thin"] = data.stats["thin_factor"]
    except (pm.Error, sources.SourceError) as e:
        record["error"] = str(e)
        print(f"particlemesh: {obj.name} at frame {record['frame']}: {e}")
    record["seconds"] = time.perf_counter() - start
    last_update[obj.name_full] = record
    history.append((obj.name_full, record))
    return record


def show_baked_frame(obj, frame):
    state = obj.particlemesh
    if not len(state.bake_frames):
        return
    frame = min(max(frame, state.bake_start), state.bake_end)
    stop_display(obj)
    for item in state.bake_frames:
        if item.frame == frame and item.mesh is not None:
            if obj.data != item.mesh:
                obj.data = item.mesh
            last_update[obj.name_full] = {"frame": frame, "mode": "BAKED", "seconds": 0.0,
                                          "cached": True}
            return


def generated_objects(scene):
    return [obj for obj in scene.objects
            if obj.type == "MESH" and obj.particlemesh.is_generated
            and obj.name_full not in suspended]


@persistent
def on_frame_change_post(scene, depsgraph=None):
    global _in_handler, _last_change
    _last_change = time.monotonic()
    if _in_handler:
        return
    _in_handler = True
    try:
        for name in [n for n in _caches if n not in bpy.data.objects]:
            _caches.pop(name).clear()  # renamed or deleted objects
        frame_display.sweep({tag for cache in _caches.values()
                             for _, tag in cache.meshes.values()})
        if depsgraph is None:
            depsgraph = bpy.context.evaluated_depsgraph_get()
        for obj in generated_objects(scene):
            state = obj.particlemesh
            if state.baked:
                show_baked_frame(obj, scene.frame_current)
            elif state.live:
                update_object(obj, depsgraph, defer=True)
    finally:
        _in_handler = False
        _last_change = time.monotonic()


@persistent
def on_depsgraph_update_post(*_args):
    """Frames rest from the end of Blender's evaluation of the last change on: evaluating a
    big new frame takes about as long as the rest, and a held arrow key's next frame change
    comes after it."""
    global _last_change
    if _pending:
        _last_change = time.monotonic()


@persistent
def on_save_pre(*_args):
    """A saved file holds each object with the mesh it shows, finished, no holders
    (frame_display)."""
    finish_pending()
    frame_display.stop_all()


@persistent
def on_load_post(*_args):
    _pending.clear()  # (Blender drops the timer with the old file)
    clear_cache(remove_meshes=False)
    frame_display.stop_all()  # a file saved without the add-on's save handler
    last_update.clear()
    history.clear()
    suspended.clear()


def lock_interface_for_renders(scene):
    """Renders started from the UI run frame handlers on the render thread: Blender asks
    handlers that edit data (ours replace meshes) to run with Render > Lock Interface on,
    which keeps the UI from touching the same data meanwhile."""
    if scene is not None and not scene.render.use_lock_interface:
        scene.render.use_lock_interface = True


def live_toggled(obj, context):
    state = obj.particlemesh
    if not state.live:
        stop_display(obj)
    if state.live:
        lock_interface_for_renders(context.scene)
    if state.live and state.is_generated and not state.baked and obj.name_full not in suspended:
        update_object(obj, context.evaluated_depsgraph_get(), defer=True)


def stop_display(obj):
    """The object shows its frame as its own mesh again; the holders of its cache go (the
    cached frames stay, as data and meshes, bounded by the cache)."""
    own = obj.data
    if not frame_display.stop(obj):
        return
    cache = _caches.get(obj.name_full)
    for name, tag in cache.meshes.values() if cache else ():
        frame_display.remove_holder(name, tag)
    tag = own.get(FRAME_TAG)
    if own != obj.data and tag is not None and not (cache and cache.holds(own)):
        _remove_unused(own.name, tag)


def settings_changed(obj, context):
    state = obj.particlemesh
    if state.is_generated and state.live and not state.baked and obj.name_full not in suspended:
        update_object(obj, context.evaluated_depsgraph_get(), defer=True)


def register():
    bpy.app.handlers.frame_change_post.append(on_frame_change_post)
    bpy.app.handlers.save_pre.append(on_save_pre)
    bpy.app.handlers.load_post.append(on_load_post)
    bpy.app.handlers.depsgraph_update_post.append(on_depsgraph_update_post)


def unregister():
    for handlers, fn in ((bpy.app.handlers.frame_change_post, on_frame_change_post),
                         (bpy.app.handlers.depsgraph_update_post, on_depsgraph_update_post),
                         (bpy.app.handlers.save_pre, on_save_pre),
                         (bpy.app.handlers.load_post, on_load_post)):
        # Remove by name too: a reloaded module has new function objects.
        for h in [h for h in handlers if getattr(h, "__name__", "") == fn.__name__
                  and getattr(h, "__module__", "") == fn.__module__]:
            handlers.remove(h)
    if bpy.app.timers.is_registered(finish_frames):
        bpy.app.timers.unregister(finish_frames)
    _pending.clear()
    clear_cache()
    frame_display.stop_all()
    last_update.clear()
    history.clear()
    suspended.clear()
