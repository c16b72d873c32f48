"""Settings: shared by the operators (redo panel) and the generated objects (live mode).

The property mixins below are used both by operators and by PropertyGroups, so that an
operator's settings can be stored on the object it creates and replayed every frame."""

import math

import bpy
from bpy.props import (BoolProperty, CollectionProperty, EnumProperty, FloatProperty,
                       IntProperty, PointerProperty, StringProperty)


def _settings_changed(self, context):
    """A live object's settings changed: regenerate it now (not from an operator's props)."""
    obj = getattr(self, "id_data", None)
    if not isinstance(obj, bpy.types.Object):
        return
    from . import live
    live.settings_changed(obj, context)


class TriangulateProps:
    auto_spacing: BoolProperty(
        name="Auto Spacing", default=True, update=_settings_changed,
        description="Estimate the particle spacing r0 as the median nearest-neighbour distance "
                    "of the particles")
    spacing: FloatProperty(
        name="Spacing", default=0.1, min=1e-6, soft_max=10.0, precision=4, step=1,
        subtype="DISTANCE", unit="LENGTH", update=_settings_changed,
        description="Particle spacing r0 in world units; triangle edges are at most "
                    "Edge Factor times r0")
    max_edge_factor: FloatProperty(
        name="Edge Factor", default=2.0, min=0.1, max=20.0, soft_min=1.0, soft_max=4.0,
        update=_settings_changed,
        description="Longest triangle edge L as a multiple of the spacing (the smallest-sphere test's default "
                    "is 2); larger bridges bigger gaps")
    local_spacing: BoolProperty(
        name="Local Spacing", default=True, update=_settings_changed,
        description="Each particle's longest edge follows the spacing of the particles around "
                    "it (unevenly sampled systems and scans mesh whole); off: one longest edge, "
                    "Edge Factor times the spacing, for all")
    thin: FloatProperty(
        name="Thin Out", default=1.0, min=1.0, max=16.0, soft_max=4.0, precision=2, step=10,
        update=_settings_changed,
        description="Mesh an even subset of the particles, no two closer than this many "
                    "particle spacings (1 = every particle; 2 keeps about a fifth of evenly "
                    "spaced ones). On the Viewport settings it makes scrubbing a big system "
                    "faster while renders use the Render settings")
    raw: BoolProperty(
        name="Raw Triangles", default=False, update=_settings_changed,
        description="Keep the smallest-sphere test's exact triangle set instead of the finished surface "
                    "(not a manifold: overlapping pairs, slivers, no orientation)")
    normal_source: EnumProperty(
        name="Normals", default="AUTO", update=_settings_changed,
        description="Where the surface's normals (which side faces out) come from",
        items=[("AUTO", "Auto", "Plane fits through the particles, facing as the particles' "
                                "normals say when they have some"),
               ("INPUT", "Particles", "The particles' own normals as they are (a point cloud "
                                      "with a point_normal attribute, or a mesh's normals)"),
               ("ESTIMATE", "Estimate", "Plane fits and a spanning tree only, ignoring any "
                                        "normals the particles have")])
    normal_angle: FloatProperty(
        name="Normal Angle", default=math.radians(120.0), min=0.0, max=math.pi,
        subtype="ANGLE", update=_settings_changed,
        description="Co-normality limit: a triangle whose corner normals differ by more than "
                    "this is not surface (separates sheets facing each other; above 90 degrees "
                    "the surface turns sharp creases)")
    repair: BoolProperty(
        name="Repair", default=True, update=_settings_changed,
        description="Fill narrow holes and resolve pinched vertices")
    fill_holes: IntProperty(
        name="Fill Holes", default=100, min=0, max=1_000_000, update=_settings_changed,
        description="Fill boundary loops of up to this many edges (0 = none)")
    fill_edge_factor: FloatProperty(
        name="Fill Edge Factor", default=1.5, min=1.0, soft_max=4.0, max=100.0,
        update=_settings_changed,
        description="Filling triangles' edges are at most this times the longest edge: wider "
                    "openings are real and stay open (above 1.5, only the loops left after "
                    "every other repair step are filled that wide)")
    min_component_triangles: IntProperty(
        name="Min Piece Triangles", default=0, min=0, soft_max=100, max=1_000_000,
        update=_settings_changed,
        description="Remove every piece of the surface with fewer triangles than this (the stray "
                    "triangles a scan leaves among its rows); 0 keeps every piece")
    orient: BoolProperty(
        name="Face Outward", default=True, update=_settings_changed,
        description="Turn every closed part to face outward")


class PolygonizeProps:
    kernel: EnumProperty(
        name="Kernel", default="WYVILL", update=_settings_changed,
        description="Field of each particle, falling to zero at its radius",
        items=[("WYVILL", "Wyvill", "Wyvill's soft-object polynomial (degree 6, C1 at the radius)"),
               ("POLY4", "(1 - r\u00b2)\u00b2", "Quartic bump, C1"),
               ("POLY6", "(1 - r\u00b2)\u00b3", "Sextic bump, C2"),
               ("BLINN", "Blinn", "Blinn's exponential, truncated")])
    anisotropic: BoolProperty(
        name="Anisotropic Kernels", default=False, update=_settings_changed,
        description="Stretch each particle's field along the fluid's surface and squeeze it "
                    "across (Yu and Turk): flat faces without bumps, thin sheets that stay "
                    "whole, the volume kept. Costs about twice the time")
    radius_mode: EnumProperty(
        name="Radius", default="AUTO", update=_settings_changed,
        description="Where each particle's field radius R comes from",
        items=[("AUTO", "Auto", "The library's default: twice the particle spacing, or more for particles "
                "packed less densely than that (a fluid simulation's frame in motion)"),
               ("PARTICLE_SIZE", "Particle Size",
                "Each particle's size times the factor: a particle system's sizes, or a point "
                "cloud's or particle file's radius (Blender) or pscale (Houdini) channel"),
               ("FIXED", "Fixed", "One radius for all particles")])
    radius: FloatProperty(
        name="Radius", default=0.1, min=1e-6, soft_max=10.0, precision=4, step=1,
        subtype="DISTANCE", unit="LENGTH", update=_settings_changed,
        description="Field radius R in world units (Fixed)")
    radius_factor: FloatProperty(
        name="Size Factor", default=2.0, min=0.01, max=100.0, update=_settings_changed,
        description="Field radius as a multiple of the particle size (Particle Size)")
    threshold: FloatProperty(
        name="Threshold", default=0.0, min=0.0, soft_max=10.0, update=_settings_changed,
        description="Iso-value T of the summed field; 0 = auto: half the field inside packed "
                    "particles (2 spacings per radius, or touching balls of the particle size)")
    auto_cell: BoolProperty(
        name="Auto Cell Size", default=True, update=_settings_changed,
        description="Grid cell size as the library's default fraction of the radius")
    cell_size: FloatProperty(
        name="Cell Size", default=0.05, min=1e-6, soft_max=1.0, precision=4, step=1,
        subtype="DISTANCE", unit="LENGTH", update=_settings_changed,
        description="Marching cubes cell edge in world units; smaller is finer and slower")
    clean_slivers: BoolProperty(
        name="Clean Slivers", default=False, update=_settings_changed,
        description="Collapse marching cubes' thin sliver triangles (edges under 0.3 of a cell) "
                    "into ordinary ones, the surface kept closed and on the field: a tenth to a "
                    "fifth fewer triangles, cleaner shading and subdivision. Takes about as long "
                    "again as the polygonize on large meshes")


class SmoothProps:
    smooth: EnumProperty(
        name="Smoothing", default="NONE", update=_settings_changed,
        description="Subdivide the result into a smooth surface",
        items=[("NONE", "None", "Keep the triangles as they are"),
               ("LOOP", "Loop", "Loop subdivision (approximating; exact limit normals)"),
               ("BUTTERFLY", "Butterfly", "Modified butterfly (interpolating: keeps the "
                                          "particles on the surface)")])
    smooth_levels: IntProperty(
        name="Levels", default=1, min=1, max=4, update=_settings_changed,
        description="Subdivision levels; each multiplies the triangle count by 4")


class CommonProps:
    threads: IntProperty(
        name="Threads", default=0, min=0, max=1024, update=_settings_changed,
        description="Worker threads, 0 = all cores (the result does not depend on it)")
    custom_normals: BoolProperty(
        name="Library Normals", default=True, update=_settings_changed,
        description="Use the library's normals as custom split normals when it gives them "
                    "(Loop limit normals, a field's gradient). They shade a polygonized "
                    "surface smoother than Blender's own normals but take about 4 times as "
                    "long to write and show on big meshes. In live mode a new viewport frame "
                    "shows Blender's own normals while frames change and gets these once "
                    "the frame rests (see Finish Every Frame); renders always have them. Off "
                    "in the Viewport Settings (with Separate Render Settings on): never in "
                    "the viewport, while renders keep them")


class SourceProps:
    source: EnumProperty(
        name="Source", default="AUTO",
        description="Which particles of the active object to mesh",
        items=[("AUTO", "Auto", "The particle system if the object has one, else its vertices"),
               ("VERTICES", "Vertices", "The object's evaluated vertices (a point cloud mesh)"),
               ("PARTICLES", "Particle System", "The object's evaluated particle system "
                                                "(living particles only)")])
    particle_system: StringProperty(
        name="Particle System", default="",
        description="Name of the particle system; empty = the active one")
    live: BoolProperty(
        name="Update Every Frame", default=False,
        description="Regenerate the mesh from the evaluated source whenever the frame changes "
                    "(also while rendering)")


TRIANGULATE_KEYS = tuple(TriangulateProps.__annotations__)
POLYGONIZE_KEYS = tuple(PolygonizeProps.__annotations__)
SMOOTH_KEYS = tuple(SmoothProps.__annotations__)
COMMON_KEYS = tuple(CommonProps.__annotations__)
METHOD_KEYS = {"TRIANGULATE": TRIANGULATE_KEYS + SMOOTH_KEYS + COMMON_KEYS,
               "POLYGONIZE": POLYGONIZE_KEYS + SMOOTH_KEYS + COMMON_KEYS}
ALL_KEYS = TRIANGULATE_KEYS + POLYGONIZE_KEYS + SMOOTH_KEYS + COMMON_KEYS


def snapshot(props, method):
    """The settings of `method` as a plain dict (safe to hand to a worker thread)."""
    return {key: getattr(props, key) for key in METHOD_KEYS[method]}


def copy_settings(src, dst, keys=ALL_KEYS):
    for key in keys:
        if hasattr(src, key):
            setattr(dst, key, getattr(src, key))


class PARTICLEMESH_PG_generator(TriangulateProps, PolygonizeProps, SmoothProps, CommonProps,
                                bpy.types.PropertyGroup):
    """How a generated object is regenerated (one set for the viewport, one for renders)."""


class PARTICLEMESH_PG_bake_frame(bpy.types.PropertyGroup):
    frame: IntProperty(name="Frame")
    mesh: PointerProperty(name="Mesh", type=bpy.types.Mesh)


def _instant_frames_changed(self, context):
    if not self.instant_frames:
        from . import live
        live.stop_display(self.id_data)


def _finish_every_frame_changed(self, context):
    if self.finish_every_frame:
        from . import live
        live.finish_pending()


def _live_changed(self, context):
    from . import live
    live.live_toggled(self.id_data, context)


class PARTICLEMESH_PG_object(bpy.types.PropertyGroup):
    """On every object: whether particlemesh generated it, from what, and how."""
    is_generated: BoolProperty(name="Generated", default=False, options={"HIDDEN"})
    method: EnumProperty(
        name="Method", default="TRIANGULATE",
        items=[("TRIANGULATE", "Triangulate", "Surface particles to triangles"),
               ("POLYGONIZE", "Polygonize", "Iso-surface of volume particles")])
    source: PointerProperty(name="Source", type=bpy.types.Object,
                            description="The object whose particles this mesh is made from")
    source_kind: EnumProperty(
        name="Source Kind", default="VERTICES",
        items=[("VERTICES", "Vertices", "The source's evaluated vertices"),
               ("PARTICLES", "Particle System", "The source's particle system"),
               ("FILES", "Particle Files", "A simulation cache: one particle file per frame")])
    particle_system: StringProperty(name="Particle System", default="")
    file_pattern: StringProperty(
        name="Particle Files", default="", subtype="FILE_PATH", update=_settings_changed,
        description="With Particle Files: the frame pattern, one field {} (or zero-padded "
                    "{:04d}) for the frame number, e.g. //cache/fluid_{:04d}.vtk (.ply, .xyz, "
                    ".csv, .vtk, .vtu, .vtp, .pvtu, .pvtp, .prt, .bgeo, .bgeo.sc, .geo); or a ParaView "
                    "collection (.pvd, .series), frame n its n-th file by time")
    frame_offset: IntProperty(
        name="Frame Offset", default=0, update=_settings_changed,
        description="With Particle Files: scene frame F shows the file of frame F + offset")
    live: BoolProperty(
        name="Update Every Frame", default=False, update=_live_changed,
        description="Regenerate this mesh from its source whenever the frame changes, also "
                    "during renders (meshes already made for a frame are cached)")
    instant_frames: BoolProperty(
        name="Instant Cached Frames", default=True, update=_instant_frames_changed,
        description="Show a frame the live cache holds through a hidden holder object, so "
                    "going back to it costs Blender no evaluation. While a holder shows a "
                    "frame, the object's own mesh is not that frame: clicking the object in "
                    "the viewport does not select it, and exporting it with viewport "
                    "modifiers gives an empty mesh (stop live mode or bake first). Off: "
                    "cached frames become the object's mesh (Blender evaluates it again, "
                    "about 0.3-2 s for a 1.5M-triangle frame)")
    finish_every_frame: BoolProperty(
        name="Finish Every Frame", default=False, update=_finish_every_frame_changed,
        description="Give every new viewport frame the library's normals (Library Normals) "
                    "at once, also while playing or scrubbing, as renders do: e.g. for a "
                    "viewport render of the animation. Off: while frames change, a new frame "
                    "shows Blender's own normals and gets the library's once it rests "
                    "(about 0.3 s without a frame change, not during playback), which makes "
                    "new frames of a big polygonized mesh almost twice as fast")
    use_render_settings: BoolProperty(
        name="Separate Render Settings", default=False, update=_settings_changed,
        description="Use the Render settings (e.g. finer, smoothed) when rendering and the "
                    "Viewport settings while scrubbing")
    viewport_budget: IntProperty(
        name="Viewport Budget", default=8000, min=0, soft_min=1000, soft_max=1000000,
        update=_settings_changed,
        description="Live mode in the viewport triangulates an even subset of at most about "
                    "this many particles: a bigger system is thinned out (Thin Out raised as "
                    "far as needed) so that frames change at interactive rates. Renders, "
                    "Update Now and Bake ignore it. 0 = no budget")
    viewport: PointerProperty(type=PARTICLEMESH_PG_generator)
    render: PointerProperty(type=PARTICLEMESH_PG_generator)
    baked: BoolProperty(name="Baked", default=False,
                        description="Frames are baked: the baked mesh is shown at each frame")
    bake_start: IntProperty(name="Bake Start")
    bake_end: IntProperty(name="Bake End")
    bake_frames: CollectionProperty(type=PARTICLEMESH_PG_bake_frame)
    base_mesh: PointerProperty(name="Unbaked Mesh", type=bpy.types.Mesh,
                               description="The mesh shown before baking (restored by Free Bake)")


#: The live cache's default size: about seven 1.5M-triangle polygonized frames kept as meshes
#: with their holders (each ~290 MB, five times its 57 MB of data), or fifty-odd frames of a
#: 100k-particle triangulation.
CACHE_MEGABYTES = 2048


class PARTICLEMESH_AP_preferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    cache_megabytes: IntProperty(
        name="Live Cache (MB)", default=CACHE_MEGABYTES, min=0, soft_max=16384,
        description="Memory for meshes of frames already generated in live mode, per session "
                    "(0 = no cache). A frame kept as a mesh to show again, with its hidden "
                    "holder object evaluated, counts five times its data")

    def draw(self, context):
        from . import generate
        ok, info = generate.library_status()
        col = self.layout.column()
        col.label(text=f"particlemesh library {info}" if ok else info,
                  icon="CHECKMARK" if ok else "ERROR")
        if ok:
            pcd, where = generate.pcd_status()
            col.label(text="PCD import: PCL bridge loaded" if pcd else where,
                      icon="CHECKMARK" if pcd else "INFO")
        col.prop(self, "cache_megabytes")


def preferences(context=None):
    context = context or bpy.context
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


classes = (
    PARTICLEMESH_PG_generator,
    PARTICLEMESH_PG_bake_frame,
    PARTICLEMESH_PG_object,
    PARTICLEMESH_AP_preferences,
)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Object.particlemesh = PointerProperty(type=PARTICLEMESH_PG_object)


def unregister():
    del bpy.types.Object.particlemesh
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
