"""Operators. Thin: the work lives in sources / generate / blender_mesh / live / bake.

Every failure is `self.report({'ERROR'}, message)` and {'CANCELLED'}: never a traceback in the
user's face, never a crashed Blender. In the interactive UI the native call runs in a worker
thread (jobs.Job) while a modal loop shows progress; Esc cancels it through the library's
progress callback. In background mode, and when the redo panel re-executes, execute() runs
the same work synchronously."""

import os
import re
import traceback
import warnings

import bpy
from bpy.props import BoolProperty, CollectionProperty, EnumProperty, IntProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

from . import bake, blender_mesh, generate, jobs, live, properties, smooth_carry, sources
from . import particlemesh as pm
from .properties import CommonProps, PolygonizeProps, SmoothProps, SourceProps, TriangulateProps

# Events a running job lets through, so the view can still be navigated.
_NAVIGATION = {"MIDDLEMOUSE", "WHEELUPMOUSE", "WHEELDOWNMOUSE", "MOUSEMOVE", "INBETWEEN_MOUSEMOVE",
               "TRACKPADPAN", "TRACKPADZOOM", "NDOF_MOTION"}


def report_failure(operator, error):
    """Turn any exception into a report and {'CANCELLED'}."""
    if isinstance(error, pm.CancelledError):
        operator.report({"WARNING"}, "particlemesh: cancelled")
    elif isinstance(error, (pm.Error, sources.SourceError)):
        operator.report({"ERROR"}, str(error))
    else:  # a bug: keep the details on the console for a report, tell the user in one line
        traceback.print_exception(type(error), error, error.__traceback__)
        operator.report({"ERROR"}, f"particlemesh internal error: {type(error).__name__}: {error}")
    return {"CANCELLED"}


def _interactive(context):
    return not bpy.app.background and context.window is not None


def _select_only(context, objects):
    """Select `objects` alone, the last one active."""
    for selected in context.selected_objects:
        selected.select_set(False)
    for obj in objects:
        obj.select_set(True)
    context.view_layer.objects.active = objects[-1]


class _ModalJob:
    """Mixin: run a jobs.Job with a progress bar, status text and Esc to cancel.

    The operator defines prepare_work(context), which reads what the work needs from Blender
    (on the main thread) and returns (function, args, kwargs), and job_finished(context,
    result), which puts the result into Blender. execute() runs the function at once;
    invoke() in a worker thread, unless Blender runs in the background."""

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.mode == "OBJECT"

    def execute(self, context):
        try:
            function, args, kwargs = self.prepare_work(context)
            self.job_finished(context, function(*args, **kwargs))
        except Exception as e:  # noqa: BLE001
            return report_failure(self, e)
        return {"FINISHED"}

    def invoke(self, context, event):
        if not _interactive(context):
            return self.execute(context)
        try:
            function, args, kwargs = self.prepare_work(context)
        except Exception as e:  # noqa: BLE001
            return report_failure(self, e)
        return self.start_job(context, jobs.Job(function, *args, **kwargs))

    def start_job(self, context, job):
        self._job = job.start()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0, 100)
        return {"RUNNING_MODAL"}

    def _end_job(self, context):
        wm = context.window_manager
        if getattr(self, "_timer", None) is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)

    def modal(self, context, event):
        job = self._job
        if event.type == "ESC" and event.value == "PRESS":
            job.cancel()
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"} if event.type in _NAVIGATION else {"RUNNING_MODAL"}
        context.window_manager.progress_update(int(100 * job.progress.fraction))
        if context.workspace is not None:
            context.workspace.status_text_set(job.status_text())
        if not job.done:
            return {"RUNNING_MODAL"}
        self._end_job(context)
        if job.error is not None:
            return report_failure(self, job.error)
        try:
            self.job_finished(context, job.result)
        except Exception as e:  # noqa: BLE001 - reported, never raised into Blender
            return report_failure(self, e)
        return {"FINISHED"}

    def cancel(self, context):
        # Blender ends the modal operator (file load, quit): stop the worker first.
        job = getattr(self, "_job", None)
        if job is not None:
            job.cancel()
            job.wait(10)
        self._end_job(context)


class _Generate(SourceProps, CommonProps, SmoothProps, _ModalJob):
    """Shared by triangulate and polygonize: read the active object's particles, mesh them,
    make a new object beside the source and make it active."""

    method = "TRIANGULATE"
    bl_options = {"REGISTER", "UNDO"}

    def prepare_work(self, context):
        pm.version()  # LibraryNotFoundError saying where it looked
        obj = context.active_object
        sources.check_object(obj)
        kind = sources.resolve_kind(obj, self.source)
        system = ""
        if kind == "PARTICLES":
            system = sources.find_system(obj, self.particle_system).name
        particles = sources.read(obj, context.evaluated_depsgraph_get(), kind, system,
                                 need_sizes=(self.method == "POLYGONIZE"))
        self._request = (obj.name, kind, system, properties.snapshot(self, self.method))
        return generate.run, (self.method, particles, self._request[3]), {}

    def job_finished(self, context, data):
        source_name, kind, system, settings = self._request
        source = bpy.data.objects.get(source_name)
        if source is None:
            raise sources.SourceError(f"the source object '{source_name}' was deleted meanwhile")
        name = f"{source.name}_{self.method.lower()}"
        mesh = bpy.data.meshes.new(name)
        blender_mesh.write(mesh, data, custom_normals=settings["custom_normals"])
        obj = bpy.data.objects.new(name, mesh)
        collections = [c for c in source.users_collection if c.library is None]
        (collections[0] if collections else context.collection).objects.link(obj)
        state = obj.particlemesh
        live.suspended.add(obj.name_full)
        try:
            state.is_generated = True
            state.method = self.method
            state.source = source
            state.source_kind = kind
            state.particle_system = system
            properties.copy_settings(self, state.viewport)
            properties.copy_settings(self, state.render)
            state.live = self.live
            if self.live:
                live.lock_interface_for_renders(context.scene)
        finally:
            live.suspended.discard(obj.name_full)
        _select_only(context, [obj])
        stats = data.stats
        if self.method == "POLYGONIZE" and "radius" in stats:
            detail = f", radius {stats['radius']:.4g}, cell {stats['cell_size']:.4g}"
        elif "spacing" in stats:
            detail = f", spacing {stats['spacing']:.4g}"
        else:
            detail = ""
        self.report({"INFO"}, f"{obj.name}: {data.vertex_count} vertices, "
                              f"{data.triangle_count} triangles{detail}")
        if self.method == "TRIANGULATE":
            system_of = source.particle_systems.get(system) if kind == "PARTICLES" else None
            emission = ((system_of.settings.emit_from, system_of.settings.distribution)
                        if system_of is not None else None)
            jittered = generate.jittered_emission_warning(stats, settings, emission)
            # (A fill does not close the gaps of a jittered emission: its advice would mislead.)
            warnings = (generate.volume_particles_warning(stats), generate.uneven_spacing_warning(stats),
                        jittered or generate.narrow_holes_warning(stats, settings),
                        generate.stray_pieces_warning(stats, settings, data.triangle_count))
        else:
            # The pieces from the mesh's topology (about 50 ms per million triangles).
            pieces = pm.topology(data)["components"] if stats.get("particles", 0) >= generate.PIECES_MIN else 0
            warnings = (generate.enclosure_warning(stats), generate.pieces_warning(pieces, stats.get("particles", 0)))
        for warning in warnings:
            if warning:
                self.report({"WARNING"}, f"{obj.name}: {warning}")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "source")
        if self.source != "VERTICES":
            layout.prop(self, "particle_system")
        draw_method_settings(layout, self, self.method)
        layout.prop(self, "live")


def draw_method_settings(layout, props, method):
    col = layout.column()
    if method == "TRIANGULATE":
        col.prop(props, "auto_spacing")
        sub = col.column()
        sub.active = not props.auto_spacing
        sub.prop(props, "spacing")
        col.prop(props, "max_edge_factor")
        col.prop(props, "local_spacing")
        col.prop(props, "thin")
        col.prop(props, "raw")
        sub = col.column()
        sub.active = not props.raw
        sub.prop(props, "normal_source")
        sub.prop(props, "normal_angle")
        sub.prop(props, "repair")
        fill = sub.column()
        fill.active = props.repair
        fill.prop(props, "fill_holes")
        fill.prop(props, "fill_edge_factor")
        sub.prop(props, "min_component_triangles")
        sub.prop(props, "orient")
    else:
        col.prop(props, "kernel")
        col.prop(props, "anisotropic")
        col.prop(props, "radius_mode")
        if props.radius_mode == "FIXED":
            col.prop(props, "radius")
        elif props.radius_mode == "PARTICLE_SIZE":
            col.prop(props, "radius_factor")
        col.prop(props, "threshold")
        col.prop(props, "auto_cell")
        sub = col.column()
        sub.active = not props.auto_cell
        sub.prop(props, "cell_size")
        col.prop(props, "clean_slivers")
    col.prop(props, "smooth")
    sub = col.column()
    sub.active = props.smooth != "NONE"
    sub.prop(props, "smooth_levels")
    col.prop(props, "custom_normals")
    col.prop(props, "threads")


class PARTICLEMESH_OT_triangulate(TriangulateProps, _Generate, bpy.types.Operator):
    """Triangulate surface particles (the active object's vertices or particle system) into a new mesh object"""
    bl_idname = "particlemesh.triangulate"
    bl_label = "Triangulate Particles"
    method = "TRIANGULATE"


class PARTICLEMESH_OT_polygonize(PolygonizeProps, _Generate, bpy.types.Operator):
    """Mesh the iso-surface of volume particles (the active object's vertices or particle system) into a new mesh object"""
    bl_idname = "particlemesh.polygonize"
    bl_label = "Polygonize Particles"
    method = "POLYGONIZE"


class PARTICLEMESH_OT_smooth(_ModalJob, bpy.types.Operator):
    """Subdivide the active mesh object in place: Loop (smooth, approximating) or modified butterfly (interpolating)"""
    bl_idname = "particlemesh.smooth"
    bl_label = "Smooth (Loop / Butterfly)"
    bl_options = {"REGISTER", "UNDO"}

    scheme: EnumProperty(
        name="Scheme", default="LOOP",
        items=[("LOOP", "Loop", "Loop subdivision (approximating; exact limit normals)"),
               ("BUTTERFLY", "Butterfly", "Modified butterfly (interpolating)")])
    levels: IntProperty(name="Levels", default=1, min=1, max=4,
                        description="Each level multiplies the triangle count by 4")
    custom_normals: BoolProperty(
        name="Library Normals", default=True,
        description="Use the library's normals (Loop: exact limit normals) as custom normals")

    def prepare_work(self, context):
        obj = context.active_object
        sources.check_object(obj)
        mesh = obj.data
        # Shape keys, vertex groups, materials, UV maps and corner colours go along
        # (smooth_carry.py); edge data cannot, and is named.
        triangles, attributes, corners, self._carried = smooth_carry.prepare(obj, mesh)
        if len(triangles) == 0:
            raise sources.SourceError(f"'{obj.name}' has no faces to smooth")
        source = pm.Mesh(blender_mesh.positions(mesh), triangles, attributes=attributes,
                         corner_attributes=corners)
        self._target = obj.name
        options = dict(scheme=self.scheme, levels=self.levels)
        carried = self._carried
        if carried.crease_edges is not None and len(carried.crease_edges):
            if self.scheme == "LOOP":  # Blender's edge creases, as its Subdivision Surface takes them
                options.update(crease_edges=carried.crease_edges, crease_sharpness=carried.crease_sharpness)
            else:
                carried.not_carried.append("edge creases (the butterfly has none: Loop keeps them)")
        return pm.smooth, (source,), options

    def job_finished(self, context, data):
        obj = bpy.data.objects.get(self._target)
        if obj is None:
            raise sources.SourceError(f"'{self._target}' was deleted meanwhile")
        carried = self._carried
        channels = smooth_carry.take_channels(data, carried)
        smooth_carry.append_loose(data, channels, carried)
        smooth_carry.before_write(obj)
        blender_mesh.write(obj.data, data, custom_normals=self.custom_normals)
        smooth_carry.restore(obj, obj.data, carried, data, channels, self.levels)
        self.report({"INFO"}, f"{obj.name}: {data.triangle_count} triangles")
        if carried.not_carried:
            self.report({"WARNING"}, f"{obj.name}: not carried through the subdivision: "
                                     + "; ".join(carried.not_carried))


class PARTICLEMESH_OT_import_cloud(bpy.types.Operator, ImportHelper):
    """Import point clouds and simulation particles (.ply, .xyz, .pts, .txt, .csv, .las, .pcd, .vtk, .vtu, .vtp, .pvtu, .pvtp, .prt, .bgeo, .bgeo.sc, .geo) as vertex-only mesh objects; normals, colours, velocity and other channels become attributes"""
    bl_idname = "particlemesh.import_cloud"
    bl_label = "Import Point Cloud"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".ply"
    filter_glob: StringProperty(default="*.ply;*.xyz;*.pts;*.txt;*.csv;*.pcd;*.vtk;*.vtu;*.vtp;*.pvtu;*.pvtp;*.prt;*.las;*.bgeo;*.bgeo.gz;*.bgeo.sc;*.geo;*.geo.gz;*.geo.sc",
                                options={"HIDDEN"})
    files: CollectionProperty(type=bpy.types.OperatorFileListElement,
                              options={"HIDDEN", "SKIP_SAVE"})
    directory: StringProperty(subtype="DIR_PATH", options={"HIDDEN", "SKIP_SAVE"})

    def execute(self, context):
        paths = [os.path.join(self.directory, f.name) for f in self.files if f.name]
        if not paths:
            paths = [self.filepath]
        made, failures, notes = [], [], []
        for path in paths:
            try:
                with warnings.catch_warnings():  # said in the operator's report instead
                    warnings.simplefilter("ignore", pm.NotReadWarning)
                    cloud = pm.read_points(path)
            except pm.Error as e:
                failures.append(str(e))
                continue
            except Exception as e:  # noqa: BLE001
                return report_failure(self, e)
            name = bpy.path.display_name_from_filepath(path) or "PointCloud"
            colors = cloud.attributes.get("color", cloud.attributes.get("rgb"))
            extra = {k: v for k, v in cloud.attributes.items() if k not in ("color", "rgb")}
            mesh = blender_mesh.new_point_cloud_mesh(name, cloud.positions, cloud.normals,
                                                     colors=colors, attributes=extra)
            obj = bpy.data.objects.new(name, mesh)
            context.collection.objects.link(obj)
            made.append(obj)
            dropped = cloud.info.get("invalid_points", 0)
            if dropped:  # e.g. a depth-camera frame's pixels without depth
                notes.append(f"{obj.name}: {dropped} points with a NaN coordinate dropped")
            if cloud.info.get("not_read"):  # string attributes, list properties: no point channel
                notes.append(f"{obj.name}: not read: " + "; ".join(cloud.info["not_read"]))
        if not made:
            self.report({"ERROR"}, "; ".join(failures) or "nothing to import")
            return {"CANCELLED"}
        _select_only(context, made)
        if failures:
            self.report({"WARNING"}, "not imported: " + "; ".join(failures))
        else:
            self.report({"INFO"}, ", ".join([f"{o.name}: {len(o.data.vertices)} points" for o in made]
                                            + notes))
        return {"FINISHED"}


def _generated(context):
    obj = context.active_object
    return obj is not None and obj.type == "MESH" and obj.particlemesh.is_generated


class PARTICLEMESH_OT_bake(bpy.types.Operator):
    """Generate the active particlemesh object for every frame of a range; the baked meshes are swapped in as the frame changes (also in renders)"""
    bl_idname = "particlemesh.bake"
    bl_label = "Bake Frames"
    bl_options = {"REGISTER", "UNDO"}

    frame_start: IntProperty(name="Start", default=1, description="First frame to bake")
    frame_end: IntProperty(name="End", default=250, description="Last frame to bake")
    quality: EnumProperty(
        name="Settings", default="RENDER",
        items=[("RENDER", "Render", "The object's render settings (particle counts are the "
                                          "viewport's: Blender gives operators no render depsgraph)"),
               ("VIEWPORT", "Viewport", "The object's viewport settings")])
    write_ply: BoolProperty(name="Write PLY Sequence", default=False,
                            description="Also write each frame as a binary PLY file")
    directory: StringProperty(name="Folder", subtype="DIR_PATH", default="//particlemesh_bake/",
                              description="Where the PLY sequence goes (<object>_<frame>.ply)")

    @classmethod
    def poll(cls, context):
        return _generated(context) and context.mode == "OBJECT"

    def _frames(self):
        return range(self.frame_start, self.frame_end + 1)

    def _check(self):
        if self.frame_end < self.frame_start:
            raise sources.SourceError(f"the frame range {self.frame_start}..{self.frame_end} is empty")
        if self.write_ply and not self.directory:
            raise sources.SourceError("choose a folder for the PLY sequence")

    def _begin(self, context):
        self._check()
        pm.version()
        obj = context.active_object
        self._target = obj.name
        self._frame = context.scene.frame_current
        live.suspended.add(obj.name_full)
        bake.begin(obj)

    def _step(self, context, frame):
        obj = bpy.data.objects[self._target]
        bake.bake_frame(context, obj, frame, self.quality,
                        self.directory if self.write_ply else "")

    def _end(self, context, ok):
        obj = bpy.data.objects.get(self._target)
        live.suspended.discard(self._target)
        if obj is not None:
            if ok:
                bake.finish(context, obj, self.frame_start, self.frame_end)
            else:
                bake.free(obj)
        context.scene.frame_set(self._frame)

    def execute(self, context):
        try:
            self._begin(context)
        except Exception as e:  # noqa: BLE001
            return report_failure(self, e)
        try:
            for frame in self._frames():
                self._step(context, frame)
        except Exception as e:  # noqa: BLE001
            self._end(context, False)
            return report_failure(self, e)
        self._end(context, True)
        self.report({"INFO"}, f"baked frames {self.frame_start}..{self.frame_end}")
        return {"FINISHED"}

    def invoke(self, context, event):
        scene = context.scene
        if not self.properties.is_property_set("frame_start"):
            self.frame_start = scene.frame_start
        if not self.properties.is_property_set("frame_end"):
            self.frame_end = scene.frame_end
        if not _interactive(context):
            return self.execute(context)
        try:
            self._begin(context)
        except Exception as e:  # noqa: BLE001
            return report_failure(self, e)
        self._pending = list(self._frames())
        self._total = len(self._pending)
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.01, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0, self._total)
        return {"RUNNING_MODAL"}

    def _stop_modal(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            self._stop_modal(context)
            self._end(context, False)
            self.report({"WARNING"}, "particlemesh: bake cancelled")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"} if event.type in _NAVIGATION else {"RUNNING_MODAL"}
        frame = self._pending.pop(0)
        try:
            self._step(context, frame)
        except Exception as e:  # noqa: BLE001
            self._stop_modal(context)
            self._end(context, False)
            return report_failure(self, e)
        done = self._total - len(self._pending)
        context.window_manager.progress_update(done)
        context.workspace.status_text_set(
            f"particlemesh: baked frame {frame} ({done}/{self._total})  (Esc to cancel)")
        if self._pending:
            return {"RUNNING_MODAL"}
        self._stop_modal(context)
        self._end(context, True)
        self.report({"INFO"}, f"baked frames {self.frame_start}..{self.frame_end}")
        return {"FINISHED"}

    def cancel(self, context):
        self._stop_modal(context)
        self._end(context, False)


class PARTICLEMESH_OT_free_bake(bpy.types.Operator):
    """Forget the baked frames of the active particlemesh object"""
    bl_idname = "particlemesh.free_bake"
    bl_label = "Free Bake"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _generated(context) and context.active_object.particlemesh.baked

    def execute(self, context):
        bake.free(context.active_object)
        return {"FINISHED"}


class PARTICLEMESH_OT_clear_cache(bpy.types.Operator):
    """Forget the live-mode meshes cached for the active particlemesh object"""
    bl_idname = "particlemesh.clear_cache"
    bl_label = "Clear Cache"

    @classmethod
    def poll(cls, context):
        return _generated(context)

    def execute(self, context):
        live.clear_cache(context.active_object)
        return {"FINISHED"}


class PARTICLEMESH_OT_update(bpy.types.Operator):
    """Regenerate the active particlemesh object from its source now"""
    bl_idname = "particlemesh.update"
    bl_label = "Update Now"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _generated(context) and not context.active_object.particlemesh.baked

    def execute(self, context):
        obj = context.active_object
        try:
            data, settings, _ = live.compute(obj, context.evaluated_depsgraph_get())
            live.apply(obj, data, settings)
        except Exception as e:  # noqa: BLE001
            return report_failure(self, e)
        return {"FINISHED"}


class PARTICLEMESH_OT_import_sequence(bpy.types.Operator, ImportHelper):
    """Import a simulation cache (one particle file per frame: .ply, .xyz, .pts, .txt, .csv, .vtk, .vtu, .vtp, .pvtu, .pvtp, .prt, .bgeo, .bgeo.sc, .geo; or a ParaView collection listing them, .pvd or .series) as a live mesh that shows the scene frame's file, meshed"""
    bl_idname = "particlemesh.import_sequence"
    bl_label = "Import Particle Sequence"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".vtk"
    filter_glob: StringProperty(default="*.ply;*.xyz;*.pts;*.txt;*.csv;*.vtk;*.vtu;*.vtp;*.pvtu;*.pvtp;*.prt;*.bgeo;*.bgeo.gz;*.bgeo.sc;*.geo;*.geo.gz;*.geo.sc;"
                                        "*.pvd;*.series",
                                options={"HIDDEN"})
    method: EnumProperty(
        name="Method", default="POLYGONIZE",
        items=[("POLYGONIZE", "Polygonize", "Iso-surface of volume particles (fluids)"),
               ("TRIANGULATE", "Triangulate", "Surface particles to triangles")])
    start_at_scene_start: BoolProperty(
        name="Start at Scene Start", default=True,
        description="Show the sequence's first file at the scene's start frame (else the file "
                    "of frame F at scene frame F)")

    def execute(self, context):
        try:
            pm.version()
            if sources.is_collection(self.filepath):  # frame n: its n-th file by time
                pattern = self.filepath
                frames = sources.find_frames(pattern)
                if not frames:
                    raise sources.SourceError(f"none of the files '{pattern}' lists exists")
                name = os.path.basename(pattern).split(".")[0] or "particles"
            else:
                pattern, _ = sources.pattern_from_file(self.filepath)
                frames = sources.find_frames(pattern)
                if not frames:
                    raise sources.SourceError(f"no file matches '{pattern}'")
                name = re.sub(r"[_.\- ]*\{[^}]*\}.*$", "", os.path.basename(pattern)) or "particles"
            scene = context.scene
            offset = frames[0] - scene.frame_start if self.start_at_scene_start else 0
            mesh = bpy.data.meshes.new(name)
            obj = bpy.data.objects.new(name, mesh)
            context.collection.objects.link(obj)
            state = obj.particlemesh
            live.suspended.add(obj.name_full)
            try:
                state.is_generated = True
                state.method = self.method
                state.source_kind = "FILES"
                state.file_pattern = pattern
                state.frame_offset = offset
                state.live = True
            finally:
                live.suspended.discard(obj.name_full)
            live.lock_interface_for_renders(scene)
            _select_only(context, [obj])
            record = live.update_object(obj, context.evaluated_depsgraph_get())
        except Exception as e:  # noqa: BLE001
            return report_failure(self, e)
        if "error" in record:
            self.report({"WARNING"}, f"{obj.name}: frame {record['frame']}: {record['error']}")
        else:
            self.report({"INFO"}, f"{obj.name}: {len(frames)} frames ({frames[0]}..{frames[-1]}) "
                                  f"from '{pattern}'; frame {record['frame']}: "
                                  f"{record['triangles']} triangles")
        return {"FINISHED"}


def menu_import(self, context):
    self.layout.operator(PARTICLEMESH_OT_import_cloud.bl_idname,
                         text="Point Cloud (.ply/.xyz/.csv/.pcd/.vtk/.vtu/.bgeo)")
    self.layout.operator(PARTICLEMESH_OT_import_sequence.bl_idname,
                         text="Particle Sequence (simulation cache)")


classes = (
    PARTICLEMESH_OT_triangulate,
    PARTICLEMESH_OT_polygonize,
    PARTICLEMESH_OT_smooth,
    PARTICLEMESH_OT_import_cloud,
    PARTICLEMESH_OT_import_sequence,
    PARTICLEMESH_OT_bake,
    PARTICLEMESH_OT_free_bake,
    PARTICLEMESH_OT_clear_cache,
    PARTICLEMESH_OT_update,
)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.TOPBAR_MT_file_import.append(menu_import)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(menu_import)
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
