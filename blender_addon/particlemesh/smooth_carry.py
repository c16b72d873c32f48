"""What a Blender mesh holds beyond its positions, carried through the Smooth operator's
subdivision, and what cannot be, named.

The library subdivides positions, per-vertex channels and per-corner values; the rest follows
the order both schemes give the triangles (smooth/subdivide.h): the children of input
triangle f are output triangles f * 4^levels onward.

- Shape keys and vertex-group weights are per-vertex values: subdivided by the same scheme
  as the positions (both schemes are affine, so a key that moves every vertex by d still does),
  as extra channels of the library call.
- Face data (material indices, FACE attributes) is each child's parent's.
- Corner data (UV maps, float CORNER attributes such as colour) goes as the library's corner
  attributes, linear over each input triangle (Blender's Subdivision Surface with UV Smooth
  None): a seam stays where it was.
- Edge creases are Loop's creases (OpenSubdiv's sharpness 10 c^2, as Blender's Subdivision
  Surface converts them); seams and sharp edges mark the output edges that lie on them. They
  go as corner values too, one per triangle edge: 1 at the flagged edge's two corners, 0 at
  the third. Interpolated linearly, a value is 1 exactly where the third corner has no
  weight, so an output edge lies on a flagged input edge where both its ends hold 1.
- Loose vertices and loose edges (in no face), which the library's meshes do not hold, are
  put back as they were, as Blender's Subdivision Surface keeps them: a loose vertex keeps its
  position, shape keys, weights and attributes; a loose edge is not subdivided, and an end it
  shares with a face follows that vertex to its new place.
- Other EDGE attributes, bevel weights, and integer or boolean vertex and corner attributes
  have no subdivision rule here: named in the operator's report."""
import numpy as np

from . import blender_mesh

_KEY = ".pm_shape_key_{}"
_GROUP = ".pm_vertex_group_{}"
_CORNER = ".pm_corner_{}"
_EDGE = ".pm_edge_{}"
# _ENDS[c, e]: corner c is an end of triangle edge e (corner e to e + 1).
_ENDS = np.eye(3, dtype=bool) | np.roll(np.eye(3, dtype=bool), 1, axis=0)
# Blender's attribute types this module interpolates, and their foreach field and width.
_FLOAT_TYPES = {"FLOAT": ("value", 1), "FLOAT2": ("vector", 2), "FLOAT_VECTOR": ("vector", 3),
                "FLOAT_COLOR": ("color", 4), "BYTE_COLOR": ("color", 4)}
_FACE_TYPES = dict(_FLOAT_TYPES, INT=("value", 1), BOOLEAN=("value", 1), INT8=("value", 1))
_DTYPES = {"INT": np.int32, "BOOLEAN": bool, "INT8": np.int32}


def _read(collection, field, count, width, dtype=np.float32):
    out = np.empty(count * width, dtype=dtype)
    collection.foreach_get(field, out)
    return out.reshape(count, width) if width > 1 else out.reshape(count, 1)


class Carried:
    """Gathered before the library call (gather()); put back after the write (restore())."""

    def __init__(self):
        self.channels = {}       # extra per-vertex channels for the library: {name: (V, C)}
        self.shape_keys = []     # (name, settings) in order; values in channels
        self.key_settings = None
        self.groups = []         # (name, lock_weight); values in channels
        self.active_group = -1
        self.faces = []          # (name or None for material_index, type, (F, C) per input triangle)
        self.corners = []        # (name, type, (F, 3, C) per input corner, is_uv, active, render)
        self.not_carried = []    # what no rule here carries, named
        self.crease_edges = None     # (K, 2) vertex pairs and their sharpness, for Loop
        self.crease_sharpness = None
        # {"use_seam" / "use_edge_sharp": (F, 3 corners, 3 edges) corner values, see above}
        self.edge_flags = {}
        # Loose geometry: the face vertices in input order (output vertex i is the image of
        # face_vertices[i]), the loose vertices, their positions and per-vertex values
        # {name: (K, C)}, the loose edges' input ends (M, 2) and their seam and sharp flags.
        self.face_vertices = None
        self.loose_vertices = np.zeros(0, dtype=np.int64)
        self.loose_positions = np.zeros((0, 3), dtype=np.float32)
        self.loose_values = {}
        self.loose_edges = np.zeros((0, 2), dtype=np.int64)
        self.loose_edge_flags = {}


def gather(obj, mesh, loops, polygon):
    """What `mesh` (obj's data) holds beyond positions and float POINT attributes."""
    c = Carried()
    nv = len(mesh.vertices)
    keys = mesh.shape_keys
    if keys is not None and len(keys.key_blocks):
        c.key_settings = {"use_relative": keys.use_relative,
                          "action": keys.animation_data.action if keys.animation_data else None}
        for i, block in enumerate(keys.key_blocks):
            c.channels[_KEY.format(i)] = _read(block.data, "co", nv, 3)
            c.shape_keys.append((block.name, {
                "relative_key": block.relative_key.name, "value": block.value,
                "slider_min": block.slider_min, "slider_max": block.slider_max, "mute": block.mute,
                "vertex_group": block.vertex_group, "interpolation": block.interpolation}))
    if len(obj.vertex_groups):
        weights = np.zeros((nv, len(obj.vertex_groups)), dtype=np.float32)
        for v in mesh.vertices:  # no bulk access to weights in Blender's API
            for g in v.groups:
                if g.group < weights.shape[1]:
                    weights[v.index, g.group] = g.weight
        for i, group in enumerate(obj.vertex_groups):
            c.channels[_GROUP.format(i)] = weights[:, i:i + 1].copy()
            c.groups.append((group.name, group.lock_weight))
        c.active_group = obj.vertex_groups.active_index
    if len(mesh.polygons):
        material = _read(mesh.polygons, "material_index", len(mesh.polygons), 1, np.int32)
        if material.any():
            c.faces.append((None, "INT", material[polygon]))
    uv_names = set()
    for layer in mesh.uv_layers:
        uv_names.add(layer.name)
        uv = _read(layer.data, "uv", len(mesh.loops), 2)
        c.corners.append((layer.name, "FLOAT2", uv[loops], True, layer.active, layer.active_render))
    skipped = {"int or boolean vertex attributes": [], "edge attributes": [], "corner attributes": []}
    for attribute in mesh.attributes:
        name, kind, domain = attribute.name, attribute.data_type, attribute.domain
        # (sharp_face: the shading, which the operator sets smooth)
        if name.startswith(".") or name in uv_names or name in ("position", "material_index", "sharp_face"):
            continue
        if domain == "FACE" and kind in _FACE_TYPES:
            field, width = _FACE_TYPES[kind]
            values = _read(attribute.data, field, len(mesh.polygons), width, _DTYPES.get(kind, np.float32))
            c.faces.append((name, kind, values[polygon]))
        elif domain == "CORNER" and kind in _FLOAT_TYPES:
            field, width = _FLOAT_TYPES[kind]
            values = _read(attribute.data, field, len(mesh.loops), width)
            c.corners.append((name, kind, values[loops], False, False, False))
        elif domain == "POINT" and kind not in _FLOAT_TYPES:
            skipped["int or boolean vertex attributes"].append(name)
        elif domain == "EDGE" and name not in ("crease_edge", "sharp_edge"):  # (4.x: read below)
            skipped["edge attributes"].append(name)
        elif domain == "CORNER":
            skipped["corner attributes"].append(name)
    for what, names in skipped.items():
        if names:
            c.not_carried.append(f"{what} ({', '.join(sorted(names))})")
    if len(mesh.edges):
        _gather_edges(mesh, loops, c)
    return c


def _gather_loose_vertices(mesh, triangles, positions, values, c):
    """The vertices of no face, with what a vertex holds (`values`: every per-vertex channel
    of the library call). (The loose edges: _gather_edges.)"""
    in_faces = np.zeros(len(mesh.vertices), dtype=bool)
    in_faces[triangles.ravel()] = True
    c.face_vertices = np.flatnonzero(in_faces)
    c.loose_vertices = np.flatnonzero(~in_faces)
    c.loose_positions = positions[c.loose_vertices]
    c.loose_values = {name: v[c.loose_vertices] for name, v in values.items()}


def append_loose(result, channels, c):
    """The loose vertices appended to the subdivided `result` (positions, normals, attributes)
    and to `channels` (take_channels()), before the write."""
    k = len(c.loose_vertices)
    if k == 0:
        return
    result.vertices = np.concatenate([np.asarray(result.vertices), c.loose_positions.astype(np.float64)])
    if result.normals is not None:
        result.normals = np.concatenate([np.asarray(result.normals), np.zeros((k, 3))])
    for values in (result.attributes, channels):
        for name in list(values):
            values[name] = np.concatenate([values[name], c.loose_values[name].astype(values[name].dtype)])


def _restore_loose_edges(mesh, c):
    """The loose edges, their ends renumbered: a face vertex to its image, a loose vertex to
    its place after the subdivided vertices."""
    if len(c.loose_edges) == 0:
        return
    image = np.empty(len(c.face_vertices) + len(c.loose_vertices), dtype=np.int64)  # (every input vertex)
    image[c.face_vertices] = np.arange(len(c.face_vertices))
    first_loose = len(mesh.vertices) - len(c.loose_vertices)
    image[c.loose_vertices] = first_loose + np.arange(len(c.loose_vertices))
    start = len(mesh.edges)
    mesh.edges.add(len(c.loose_edges))
    ends = np.empty(2 * len(mesh.edges), dtype=blender_mesh.INDEX)
    mesh.edges.foreach_get("vertices", ends)
    ends[2 * start:] = image[c.loose_edges].ravel()
    mesh.edges.foreach_set("vertices", ends)
    for field, flags in c.loose_edge_flags.items():
        if flags.any():
            values = np.empty(len(mesh.edges), dtype=bool)
            mesh.edges.foreach_get(field, values)
            values[start:] = flags
            mesh.edges.foreach_set(field, values)


def _gather_edges(mesh, loops, c):
    """Edge creases (for Loop), seams and sharp edges per input triangle edge, and the loose
    edges (in no face) with their seam and sharp flags."""
    ne = len(mesh.edges)
    ends = _read(mesh.edges, "vertices", ne, 2, np.int64)
    loop_edge = _read(mesh.loops, "edge_index", len(mesh.loops), 1, np.int64)[:, 0]
    loop_vertex = _read(mesh.loops, "vertex_index", len(mesh.loops), 1, np.int64)[:, 0]
    in_faces = np.zeros(ne, dtype=bool)
    in_faces[loop_edge] = True
    loose = np.flatnonzero(~in_faces)
    if len(loose):
        c.loose_edges = ends[loose]
    # Triangle edge e (corner e to e + 1) is a mesh edge when loop e's edge joins the two
    # corners (not a diagonal a tessellated polygon added).
    edge = loop_edge[loops]
    a, b = loop_vertex[loops], loop_vertex[np.roll(loops, -1, axis=1)]
    real = ((ends[edge, 0] == a) & (ends[edge, 1] == b)) | ((ends[edge, 0] == b) & (ends[edge, 1] == a))
    for field in ("use_seam", "use_edge_sharp"):
        values = _read(mesh.edges, field, ne, 1, bool)[:, 0]
        if len(loose):
            c.loose_edge_flags[field] = values[loose]
        if values.any():
            flagged = values[edge] & real                       # (F, 3): triangle edge e
            c.edge_flags[field] = (flagged[:, None, :] & _ENDS[None]).astype(np.float32)
    crease = None
    if hasattr(mesh.edges[0], "crease"):  # Blender 3.x; 4.x keeps them as the EDGE attribute crease_edge
        crease = _read(mesh.edges, "crease", ne, 1)[:, 0]
    elif mesh.attributes.get("crease_edge") is not None:
        crease = _read(mesh.attributes["crease_edge"].data, "value", ne, 1)[:, 0]
    if crease is not None and crease.any():
        # (an edge of no face, a loose one, is no edge of the library's mesh)
        keep = np.flatnonzero((crease > 0) & in_faces)
        c.crease_edges = ends[keep].astype(np.int32)
        c.crease_sharpness = np.minimum(10.0 * crease[keep].astype(np.float64) ** 2, 10.0)
    bevel = None
    if hasattr(mesh.edges[0], "bevel_weight"):
        bevel = _read(mesh.edges, "bevel_weight", ne, 1)[:, 0]
    if bevel is not None and bevel.any():
        c.not_carried.append("edge bevel weights")


def before_write(obj):
    """Shape keys go before the geometry is replaced: a key must hold one point per vertex."""
    if obj.data.shape_keys is not None:
        obj.shape_key_clear()


def take_channels(result, c):
    """The extra channels of the subdivided `result`, taken out of its attributes before it
    is written (they are shape keys and weights, not attributes)."""
    return {name: result.attributes.pop(name) for name in list(result.attributes) if name in c.channels}


def restore(obj, mesh, c, result, channels, levels):
    """Put back what gather() found on the subdivided `result`, already written into `mesh`;
    `channels` from take_channels()."""
    k = 4 ** levels
    nt = result.triangle_count
    parent = np.arange(nt) // k
    for name, kind, per_triangle in c.faces:
        values = per_triangle[parent]
        if name is None:
            mesh.polygons.foreach_set("material_index", values.ravel().astype(np.int32))
            continue
        field, _ = _FACE_TYPES[kind]
        attribute = mesh.attributes.new(name, kind, "FACE")
        if attribute is not None:
            attribute.data.foreach_set(field, values.ravel())
    if c.edge_flags:
        _restore_edge_flags(mesh, result)
    _restore_loose_edges(mesh, c)
    for i, (name, kind, _, is_uv, active, render) in enumerate(c.corners):
        values = result.corner_attributes[_CORNER.format(i)]
        if is_uv:
            layer = mesh.uv_layers.new(name=name)
            if layer is None:
                continue
            layer.data.foreach_set("uv", values.ravel())
            if active:
                mesh.uv_layers.active = layer
            if render:
                layer.active_render = True
        else:
            attribute = mesh.attributes.new(name, kind, "CORNER")
            if attribute is not None:
                attribute.data.foreach_set(_FLOAT_TYPES[kind][0], values.ravel())
    for i, (name, lock) in enumerate(c.groups):
        group = obj.vertex_groups.new(name=name)
        group.lock_weight = lock
        weights = np.clip(channels[_GROUP.format(i)][:, 0], 0.0, 1.0)
        for value in np.unique(weights[weights > 0]):  # one call per distinct weight
            group.add(np.flatnonzero(weights == value).tolist(), float(value), "REPLACE")
    if c.groups:
        obj.vertex_groups.active_index = c.active_group
    if c.shape_keys:
        blocks = []
        for i, (name, _) in enumerate(c.shape_keys):
            block = obj.shape_key_add(name=name, from_mix=False)
            block.data.foreach_set("co", channels[_KEY.format(i)].astype(np.float32).ravel())
            blocks.append(block)
        keys = mesh.shape_keys
        keys.use_relative = c.key_settings["use_relative"]
        for block, (_, settings) in zip(blocks, c.shape_keys):
            block.relative_key = keys.key_blocks.get(settings["relative_key"], blocks[0])
            for field in ("slider_min", "slider_max", "value", "mute", "vertex_group", "interpolation"):
                setattr(block, field, settings[field])
        if c.key_settings["action"] is not None:
            keys.animation_data_create().action = c.key_settings["action"]
    mesh.update()


def _restore_edge_flags(mesh, result):
    """Seams and sharp edges on the output edges whose ends both hold 1 for a flagged input
    triangle edge."""
    out_edge = _read(mesh.loops, "edge_index", len(mesh.loops), 1, np.int64)[:, 0].reshape(-1, 3)
    for field in ("use_seam", "use_edge_sharp"):
        values = result.corner_attributes.get(_EDGE.format(field))
        if values is None:
            continue
        on = values == 1                                           # (T, 3 corners, 3 input edges)
        flag = (on & np.roll(on, -1, axis=1)).any(axis=2)          # output edge j: corners j, j + 1
        marked = np.zeros(len(mesh.edges), dtype=bool)
        marked[out_edge[flag]] = True
        mesh.edges.foreach_set(field, marked)


def prepare(obj, mesh):
    """(triangles, per-vertex channels, per-corner values, Carried) for the library call."""
    triangles, loops, polygon = blender_mesh.triangle_corners(mesh)
    c = gather(obj, mesh, loops, polygon)
    attributes = blender_mesh.float_point_attributes(mesh)
    attributes.update(c.channels)
    _gather_loose_vertices(mesh, triangles, blender_mesh.positions(mesh), attributes, c)
    corners = {_CORNER.format(i): entry[2] for i, entry in enumerate(c.corners)}
    corners.update({_EDGE.format(field): values for field, values in c.edge_flags.items()})
    return triangles, attributes, corners, c
