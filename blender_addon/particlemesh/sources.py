"""Particles from Blender: an object's evaluated vertices (a point cloud mesh) or one of its
evaluated particle systems (living particles only), as numpy arrays in world space; or a
simulation cache's file for a frame (a frame pattern, or a ParaView collection, as the
command-line tool takes)."""

import glob
import os
import re
import warnings

import bpy
import numpy as np

from . import blender_mesh, mesh_arrays
from .generate import Particles


class SourceError(Exception):
    """The source cannot give particles (wrong type, empty, hair...). The message is for the
    user."""


def _alive_state_values(settings):
    """alive_state values to keep: alive ones, plus unborn / dead ones when the particle
    settings show them (Blender's own Unborn / Died visibility)."""
    items = bpy.types.Particle.bl_rna.properties["alive_state"].enum_items
    keep = {"ALIVE", "DYING"}
    if getattr(settings, "show_unborn", False):
        keep.add("UNBORN")
    if getattr(settings, "use_dead", False):
        keep.add("DEAD")
    return [items[name].value for name in keep]


def pattern_from_file(path):
    """The frame pattern of one frame's file: its name's last run of digits becomes the field,
    zero-padded ({:04d}) when the digits start with 0 ("fluid_0012.vtk" -> "fluid_{:04d}.vtk",
    "fluid_12.vtk" -> "fluid_{}.vtk"), and that frame's number. SourceError without digits."""
    folder, name = os.path.split(path)
    matches = list(re.finditer(r"\d+", name))
    if not matches:
        raise SourceError(f"'{name}' has no frame number in its name (e.g. fluid_0001.vtk)")
    m = matches[-1]
    digits = m.group(0)
    field = f"{{:0{len(digits)}d}}" if len(digits) > 1 and digits[0] == "0" else "{}"
    pattern = name[:m.start()].replace("{", "{{").replace("}", "}}") + field + \
        name[m.end():].replace("{", "{{").replace("}", "}}")
    return os.path.join(folder, pattern), int(digits)


def is_collection(path):
    """Whether `path` is a ParaView collection (.pvd, .series, no frame field): frame n is the
    n-th file it lists by time, as in the command-line tool (the package's rule)."""
    from . import particlemesh as pm
    return pm.is_frame_collection(path)


_collections = {}  # absolute path -> (modification time, its files by time)


def collection_files(path):
    """The files a collection lists, by time (read again when the collection changes)."""
    from . import particlemesh as pm
    path = bpy.path.abspath(path)
    try:
        stamp = os.stat(path).st_mtime_ns
    except OSError as e:
        raise SourceError(f"the collection '{path}' cannot be read ({e.strerror})") from None
    cached = _collections.get(path)
    if cached is None or cached[0] != stamp:
        cached = (stamp, [file for _, file in pm.read_frame_collection(path)])
        _collections[path] = cached
    return cached[1]


def frame_file(pattern, frame):
    """The file of `frame` under a pattern ("//" paths relative to the .blend file), or the
    frame-th file of a collection."""
    if is_collection(pattern):
        files = collection_files(pattern)
        if not 0 <= frame < len(files):
            raise SourceError(f"no particle file for frame {frame}: '{os.path.basename(pattern)}' lists "
                              f"frames 0..{len(files) - 1}")
        return files[frame]
    try:
        return bpy.path.abspath(pattern.format(frame))
    except (IndexError, KeyError, ValueError) as e:
        raise SourceError(f"'{pattern}' is not a frame pattern with one field, {{}} or {{:04d}} "
                          f"({e})") from None


def find_frames(pattern):
    """The frame numbers of the files the pattern names (or a collection lists and exist),
    ascending."""
    if is_collection(pattern):
        return [n for n, file in enumerate(collection_files(pattern)) if os.path.isfile(file)]
    path = bpy.path.abspath(pattern)
    head, sep, rest = path.partition("{")
    _, _, tail = rest.partition("}")
    frames = set()
    for candidate in glob.glob(glob.escape(head) + "*" + glob.escape(tail)):
        number = candidate[len(head):len(candidate) - len(tail)]
        if sep and re.fullmatch(r"-?\d+", number) and frame_file(pattern, int(number)) == candidate:
            frames.add(int(number))
    return sorted(frames)


#: One-component point channels that give each particle's size (radius) for the Particle Size
#: radius mode: Blender's point clouds and Geometry Nodes write `radius`, Houdini `pscale`.
SIZE_CHANNELS = ("radius", "pscale")


def _sizes(channel_of):
    """The first of SIZE_CHANNELS that `channel_of(name)` gives as one component, flattened to
    float32, or None."""
    for name in SIZE_CHANNELS:
        values = channel_of(name)
        if values is not None and values.ndim == 2 and values.shape[1] == 1:
            return np.ascontiguousarray(values[:, 0], dtype=np.float32)
    return None


def read_file_frame(pattern, frame):
    """The particles of one frame's file: positions, normals and a 3-component `velocity`
    channel (what motion blur reads on the mesh). SourceError when the file is missing;
    particlemesh.Error when it cannot be read."""
    from . import particlemesh as pm
    path = frame_file(pattern, frame)
    if not os.path.isfile(path):
        raise SourceError(f"no particle file for frame {frame}: '{path}' does not exist")
    with warnings.catch_warnings():  # only positions, normals, velocity and sizes are used here
        warnings.simplefilter("ignore", pm.NotReadWarning)
        cloud = pm.read_points(path)
    velocity = cloud.attributes.get("velocity")
    if velocity is not None and velocity.shape[1] != 3:
        velocity = None
    return Particles(np.ascontiguousarray(cloud.positions, dtype=np.float32),
                     None if cloud.normals is None else np.asarray(cloud.normals, np.float32),
                     None if velocity is None else np.ascontiguousarray(velocity, np.float32),
                     sizes=_sizes(lambda name: cloud.attributes.get(name)),
                     label=os.path.basename(path))


def particle_systems(obj):
    """The object's emitter (non-hair) particle systems."""
    if obj is None or obj.type != "MESH":
        return []
    return [ps for ps in obj.particle_systems if ps.settings.type == "EMITTER"]


def resolve_kind(obj, kind):
    if kind == "AUTO":
        return "PARTICLES" if particle_systems(obj) else "VERTICES"
    return kind


def check_object(obj):
    if obj is None:
        raise SourceError("no active object: select a point cloud mesh or a particle emitter")
    if obj.type != "MESH":
        raise SourceError(f"'{obj.name}' is a {obj.type.lower()} object; particlemesh needs a mesh "
                          "(its vertices) or a particle emitter")


def read(obj, depsgraph, kind="AUTO", system_name="", need_sizes=False):
    """Particles of `obj` as evaluated in `depsgraph` (viewport or render).

    kind: 'VERTICES' (the evaluated mesh's vertices, normals from its faces or from a
    `point_normal` attribute), 'PARTICLES' (a particle system: `system_name` or the active
    one), or 'AUTO' (particles if the object has an emitter system, else vertices)."""
    check_object(obj)
    kind = resolve_kind(obj, kind)
    if kind == "PARTICLES":
        return _read_particles(obj, depsgraph, system_name, need_sizes)
    return _read_vertices(obj, depsgraph, need_sizes)


def _read_vertices(obj, depsgraph, need_sizes=False):
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        if mesh is None or len(mesh.vertices) == 0:
            raise SourceError(f"'{obj.name}' has no vertices to mesh")
        local = blender_mesh.positions(mesh)
        _check_finite(obj, local)
        normals = blender_mesh.get_point_attribute(mesh, blender_mesh.NORMAL_ATTRIBUTE)
        if normals is None and len(mesh.polygons):
            normals = blender_mesh.vertex_normals(mesh)
        velocities = blender_mesh.get_point_attribute(mesh, "velocity")
        if velocities is not None and velocities.shape[1] != 3:
            velocities = None
        sizes = _sizes(lambda name: blender_mesh.get_point_attribute(mesh, name)) if need_sizes else None
    finally:
        evaluated.to_mesh_clear()
    matrix = np.array(evaluated.matrix_world, dtype=np.float64)
    positions = mesh_arrays.transform_points(local, matrix)
    if normals is not None:
        normals = mesh_arrays.transform_normals(normals, matrix)
        if not np.all(np.isfinite(normals)):
            normals = None  # the library would reject them; the positions are what matter
    if velocities is not None:
        velocities = (velocities.astype(np.float64) @ matrix[:3, :3].T).astype(np.float32)
    if sizes is not None:
        # World units: the object's scale (the cube root of its volume scale when not uniform).
        sizes = (sizes * abs(np.linalg.det(matrix[:3, :3])) ** (1.0 / 3.0)).astype(np.float32)
    return Particles(positions, normals=normals, velocities=velocities, sizes=sizes, label=obj.name)


def _check_finite(obj, positions):
    try:
        mesh_arrays.check_finite(positions, "positions")
    except ValueError as e:
        raise SourceError(f"'{obj.name}': {e}") from None


def find_system(obj, system_name=""):
    systems = particle_systems(obj)
    if not systems:
        if len(obj.particle_systems):
            raise SourceError(f"'{obj.name}' has only hair particle systems; particlemesh meshes "
                              "emitter particles")
        raise SourceError(f"'{obj.name}' has no particle system")
    if system_name:
        for ps in systems:
            if ps.name == system_name:
                return ps
        raise SourceError(f"'{obj.name}' has no emitter particle system named '{system_name}'")
    active = obj.particle_systems.active
    return active if active in systems else systems[0]


def _read_particles(obj, depsgraph, system_name, need_sizes):
    name = find_system(obj, system_name).name
    evaluated = obj.evaluated_get(depsgraph)
    psys = evaluated.particle_systems.get(name)
    if psys is None:
        raise SourceError(f"particle system '{name}' of '{obj.name}' is not evaluated "
                          "(is the object hidden or its modifier disabled?)")
    particles = psys.particles
    n = len(particles)
    # alive_state is a short in Blender: an int16 buffer is copied in bulk, an int32 one item
    # by item (blender_mesh.INDEX says why).
    states = np.empty(n, dtype=np.int16)
    particles.foreach_get("alive_state", states)
    keep = mesh_arrays.alive_mask(states, _alive_state_values(psys.settings))
    count = int(keep.sum())
    if count == 0:
        raise SourceError(f"particle system '{name}' of '{obj.name}' has no living particles at "
                          f"frame {depsgraph.scene.frame_current}")
    location = np.empty(n * 3, dtype=np.float32)
    particles.foreach_get("location", location)
    velocity = np.empty(n * 3, dtype=np.float32)
    particles.foreach_get("velocity", velocity)
    positions = location.reshape(-1, 3)[keep]
    _check_finite(obj, positions)
    velocities = velocity.reshape(-1, 3)[keep]
    sizes = None
    if need_sizes:
        size = np.empty(n, dtype=np.float32)
        particles.foreach_get("size", size)
        sizes = size[keep]
    return Particles(positions, velocities=velocities, sizes=sizes,
                     particle_size=float(psys.settings.particle_size),
                     label=f"{obj.name}/{name}")
