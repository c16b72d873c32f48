"""The meshing pipelines behind the operators and live mode: particles (numpy arrays) and a
flat settings dict in, a particlemesh.Mesh out. bpy-free, so it runs in a worker thread and in
tests outside Blender.

Settings keys (the operators' and the generated objects' property names):
  triangulate: auto_spacing, spacing, max_edge_factor, local_spacing, thin, raw, normal_angle (radians),
               fill_holes, fill_edge_factor, min_component_triangles, normal_source, repair, orient;
               viewport_budget
               (live mode adds it in the viewport: thin out bigger systems to about that many)
  polygonize:  kernel, anisotropic, radius_mode, radius, radius_factor, threshold, auto_cell,
               cell_size, clean_slivers
  both:        smooth ('NONE' | 'LOOP' | 'BUTTERFLY'), smooth_levels, threads
"""

import hashlib
import math

import numpy as np

from . import mesh_arrays
from . import particlemesh as pm


class Particles:
    """What the source gives: positions (N, 3) float32 in world space, optional normals,
    velocities (N, 3) and sizes (N,), and the particle system's particle size if any."""

    __slots__ = ("positions", "normals", "velocities", "sizes", "particle_size", "label")

    def __init__(self, positions, normals=None, velocities=None, sizes=None, particle_size=0.0,
                 label=""):
        self.positions = positions
        self.normals = normals
        self.velocities = velocities
        self.sizes = sizes
        self.particle_size = particle_size
        self.label = label

    def subset(self, indices):
        """The particles at `indices` (their channels with them)."""
        pick = (lambda a: None if a is None else a[indices])
        return Particles(self.positions[indices], pick(self.normals), pick(self.velocities),
                         pick(self.sizes), self.particle_size, self.label)

    def digest(self):
        return mesh_arrays.content_hash(self.positions, self.normals, self.velocities, self.sizes)


class EmptyResult(pm.Error):
    """The library succeeded but produced no triangles (a parameter far off the data)."""

    def __init__(self, message):
        super().__init__(message, pm.STATUS_INVALID_ARGUMENT)


def library_status():
    """(True, the library's version) if it loads, else (False, why not)."""
    try:
        return True, pm.version()
    except pm.Error as e:
        return False, str(e)


def pcd_status():
    """(True, the PCL bridge's path) if .pcd files can be read, else (False, why not)."""
    try:
        return True, pm.pcl_bridge_path()
    except pm.Error as e:
        return False, str(e)


def _attributes(particles):
    attrs = {}
    if particles.velocities is not None:
        attrs["velocity"] = particles.velocities
    return attrs


def _smooth(mesh, settings, progress, reuse=None):
    scheme = settings.get("smooth", "NONE")
    levels = int(settings.get("smooth_levels", 1))
    if scheme == "NONE" or levels <= 0:
        return mesh
    threads = int(settings.get("threads", 0))
    out = None
    if reuse is not None and scheme == "LOOP":
        out = _smooth_again(mesh, levels, threads, reuse, progress)
    if out is None:
        out = pm.smooth(mesh, scheme=scheme, levels=levels, threads=threads, progress=progress)
    out.stats = dict(mesh.stats, smooth_levels=levels)
    out.stats.pop("normals_are_face_weighted", None)  # Loop / butterfly normals are their own
    return out


#: What a pm.Smoother keeps per output triangle (OpenSubdiv's refinement and its weights).
SMOOTHER_BYTES_PER_TRIANGLE = 60


def _smooth_again(mesh, levels, threads, reuse, progress):
    """Loop smoothing through a kept pm.Smoother (refine once, evaluate many: the same mesh as
    pm.smooth, several times cheaper) while the triangles stay those of the frame before (a
    system that moves without changing its triangles); None where a plain smooth is due. The Smoother is made
    when the same triangles come a second time, so changing triangles cost nothing extra
    but a hash. `reuse`: a dict kept by the caller from frame to frame (live mode's cache);
    reuse["reused"] is set when the Smoother gave the mesh; reuse["max_bytes"], if given, is
    the memory a Smoother may take (about SMOOTHER_BYTES_PER_TRIANGLE per output triangle)."""
    if SMOOTHER_BYTES_PER_TRIANGLE * len(mesh.triangles) * 4 ** levels > reuse.get("max_bytes", math.inf):
        release(reuse)
        return None
    key = (levels, threads)
    smoother = reuse.get("smoother")
    if smoother is not None and reuse.get("smoother_key") == key and smoother.matches(mesh):
        reuse["reused"] = True
        return smoother.evaluate(mesh)
    triangles = np.ascontiguousarray(mesh.triangles)
    seen = (key, len(mesh.vertices), triangles.dtype.str,
            hashlib.blake2b(triangles.tobytes(), digest_size=16).digest())
    if reuse.get("last") != seen:
        reuse["last"] = seen
        return None
    release(reuse)
    smoother = pm.Smoother(mesh, "loop", levels, threads=threads, progress=progress)
    reuse.update(smoother=smoother, smoother_key=key, reused=True)
    return smoother.evaluate(mesh)


def release(reuse):
    """Free what _smooth_again keeps in `reuse` (its Smoother)."""
    smoother = reuse.pop("smoother", None)
    reuse.pop("smoother_key", None)
    if smoother is not None:
        smoother.close()


#: Particles sampled for the spacing that Thin Out is measured in.
THIN_SPACING_SAMPLES = 8192


def thin(particles, settings):
    """The particles thinned to no two closer than `thin` spacings (the spacing given, or the
    estimated one), or the particles themselves when thin is 1. The subset is evenly spaced
    again (every nearest-neighbour distance between one and two thinning distances), so the
    triangulation always estimates its spacing afresh: a given spacing scaled by the factor
    left holes where the subset's gaps reach twice the thinning distance.

    With `viewport_budget` (live mode in the viewport) more particles than that are thinned
    too, by at least budget_thin()'s factor. Returns (particles, thin distance or None,
    factor used)."""
    factor = float(settings.get("thin", 1.0))
    budget = int(settings.get("viewport_budget", 0))
    count = len(particles.positions)
    over_budget = 0 < budget < count
    if over_budget:
        factor = max(factor, budget_thin(count, budget))
    if factor <= 1.0:
        return particles, None, 1.0
    if settings.get("auto_spacing", True):
        # A sampled estimate: the thinning needs the spacing only roughly (within ~1 % here),
        # and the exact one was a third of the preview's library time at 100k particles.
        r0 = pm.estimate_spacing(particles.positions, threads=int(settings.get("threads", 0)),
                                 max_samples=THIN_SPACING_SAMPLES)
    else:
        r0 = float(settings["spacing"])
    kept = pm.thin(particles.positions, factor * r0)
    for _ in range(3):
        if not over_budget or len(kept) <= BUDGET_SLACK * budget:
            break
        # The count goes as 1 / factor^2 only on evenly spaced surface particles; parts
        # sparser than the median spacing (a scan's far side) keep up to ~1.6x more at the
        # same factor (bench/RESULTS.md): correct by the measured count.
        factor *= math.sqrt(len(kept) / budget)
        kept = pm.thin(particles.positions, factor * r0)
    return particles.subset(kept), factor * r0, factor


#: How far over the viewport budget a thinned preview may be before it is thinned again.
BUDGET_SLACK = 1.1


def budget_thin(count, budget):
    """The Thin Out factor that leaves at most about `budget` of `count` evenly spaced surface
    particles: the greedy thinning at f spacings keeps 0.77-0.95 / f^2 of them (Poisson-disk
    and Fibonacci spheres at f = 2..4; a mesh's vertices ~0.7; bench/RESULTS.md)."""
    return math.sqrt(count / budget) if 0 < budget < count else 1.0


def triangulate(particles, settings, progress=None, reuse=None):
    everything = len(particles.positions)
    particles, thin_distance, thin_factor = thin(particles, settings)
    auto = settings.get("auto_spacing", True) or thin_distance is not None
    spacing = 0.0 if auto else float(settings["spacing"])
    raw = bool(settings.get("raw", False))
    mesh = pm.triangulate(
        particles.positions, normals=particles.normals, spacing=spacing,
        max_edge_factor=settings.get("max_edge_factor"),
        threads=int(settings.get("threads", 0)), raw=raw,
        normal_angle=(math.degrees(settings["normal_angle"]) if "normal_angle" in settings
                      else None),
        fill_holes=settings.get("fill_holes"),
        fill_edge_factor=settings.get("fill_edge_factor"),
        min_component_triangles=settings.get("min_component_triangles"),
        normal_source=settings.get("normal_source"),
        repair=settings.get("repair"), orient=settings.get("orient"),
        local_spacing=bool(settings.get("local_spacing", True)), progress=progress)
    mesh.stats["raw"] = raw
    mesh.stats["global_spacing"] = not bool(settings.get("local_spacing", True))
    if mesh.triangle_count == 0 and mesh.stats.get("components_removed"):
        raise EmptyResult(
            f"no triangles: every piece of the surface ({mesh.stats['component_triangles_removed']} triangles in "
            f"{mesh.stats['components_removed']} pieces) has fewer than Min Piece Triangles "
            f"({settings.get('min_component_triangles')}): lower it")
    if mesh.triangle_count == 0:
        raise EmptyResult(
            f"no triangles: with spacing {mesh.stats['spacing']:.6g} the longest edge is "
            f"{mesh.stats['max_edge']:.6g}, shorter than the gaps between the "
            f"{len(particles.positions)} particles (raise the spacing or the edge factor)")
    if raw:
        # The raw test's triangles are not oriented (canonical a < b < c): wind them to agree
        # with the particles' normals where there are some.
        if mesh.normals is not None:
            mesh.triangles, _ = mesh_arrays.orient_by_normals(mesh.triangles, mesh.normals,
                                                              mesh.vertices)
    else:
        # The finished surface's normals are angle-weighted face normals: exactly what
        # Blender computes itself for smooth shading, so they need not be custom normals.
        mesh.stats["normals_are_face_weighted"] = True
    # Output vertex i is particle i (of the thinned subset): the particles' channels are the
    # mesh's.
    mesh.attributes.update(_attributes(particles))
    if thin_distance is not None:
        mesh.stats.update(thinned_from=everything, thin_distance=thin_distance,
                          thin_factor=thin_factor)
    return _smooth(mesh, settings, progress, reuse)


def uneven_spacing_warning(stats):
    """A warning when over 5 % of the particles are in no triangle of the finished surface:
    their spacing varies more than the longest edges follow (with one for all particles, any
    unevenness does; with each one's own, sparser than 3 spacings), which Local Spacing, Thin
    Out (an even subset) or a larger edge factor helps. None otherwise."""
    points, unused = stats.get("points", 0), stats.get("unused_points", 0)
    if stats.get("raw") or not points or unused * 20 <= points:
        return None
    advice = "turn on Local Spacing, or " if stats.get("global_spacing") else ""
    return (f"{unused} of {points} particles are in no triangle: they are unevenly spaced "
            f"for the longest edge; {advice}try Thin Out 2 or a larger Edge Factor")


def narrow_holes_warning(stats, settings):
    """A warning when holes were left open that the fill did not try for the Fill Edge Factor
    or Fill Holes set, though a patch of short edges spans them (the library's narrow_loops:
    at most 3 longest edges across): gaps in the sampling (a model's vertices leave such),
    with the settings that reach them. None otherwise."""
    count = stats.get("narrow_loops", 0)
    if stats.get("raw") or not count:
        return None
    factor = max(float(settings.get("fill_edge_factor", 1.5)),
                 math.ceil(stats.get("narrow_loop_width", 0.0) * 10.0 + 1e-9) / 10.0)  # as the CLI's hint
    edges = int(stats.get("narrow_loop_edges", 0))
    more = (f" and Fill Holes to {edges}" if edges > int(settings.get("fill_holes", 100)) else "")
    left = stats.get("holes_left", count)
    which = ("the hole left open is a narrow gap" if left == 1 else
             f"all {count} holes left open are narrow gaps" if count == left else
             f"{count} of the {left} holes left open are narrow gaps")
    return (f"{which} in the sampling (or small openings): set Fill Edge Factor to "
            f"{factor:g}{more} to fill {'it' if left == 1 else 'them'}")


def stray_pieces_warning(stats, settings, triangles):
    """A warning when at least 5 pieces of fewer than 10 triangles lie apart from the rest and
    hold under 5 % of the `triangles` (the library's stray_pieces: a scan's stray triangles),
    with the Min Piece Triangles that removes just them (as the CLI's hint). None otherwise,
    or when Min Piece Triangles is set already."""
    count = int(stats.get("stray_pieces", 0))
    if stats.get("raw") or int(settings.get("min_component_triangles", 0) or 0) > 0 or count < 5:
        return None
    if int(stats.get("stray_piece_triangles", 0)) * 20 > triangles:
        return None
    largest = int(stats.get("stray_piece_largest", 0))
    what = "lone triangles" if largest == 1 else f"pieces of at most {largest} triangles"
    return f"{count} {what} lie apart from the rest: set Min Piece Triangles to {largest + 1} to remove them"


def jittered_emission_warning(stats, settings, emission):
    """A warning when holes were left open and the particles come from a system emitting from
    faces with Distribution Jittered (Blender's default): each face gets a jitter pattern with
    gaps wider than the particles' spacing, repeated on faces that get many particles (8-40 %
    exact copies), which an Edge Factor of 3 spans (measured on 1000-20 000 particles from a
    cube, UV spheres, a torus, a cylinder and an icosphere: every one closed; at 2, up to 6
    pieces and 99 holes), as does Distribution Random (the library lengthens the reach for
    particles at random). `emission`: the source system's (emit_from, distribution), or None
    for vertices. None otherwise."""
    if stats.get("raw") or not stats.get("holes_left") or emission != ("FACE", "JIT"):
        return None
    if float(settings.get("max_edge_factor", 2.0)) >= 3.0:
        return None
    return ("the particle system emits from faces with Distribution Jittered, which leaves gaps wider than "
            "the particles' spacing: set Edge Factor to 3, or the system's Distribution to Random")


def volume_particles_warning(stats):
    """A warning when the library says the particles look like a volume's (the triangulation
    statistic looks_like_volume: co-normality dropped most raw triangles and loops were left
    open), which Polygonize meshes. None otherwise."""
    if stats.get("raw") or not stats.get("looks_like_volume"):
        return None
    kept, dropped = stats.get("kept", 0), stats.get("rejected_conormal", 0)
    return (f"{100 * dropped / kept:.0f}% of the smallest-sphere test's triangles join particles facing opposite "
            "ways: if the particles fill a volume (a fluid simulation's), use Polygonize")


def enclosure_warning(stats):
    """A warning when most particles end up outside the polygonized surface (the library's
    enclosed_fraction: F below the threshold at their centres), which then shows only their
    densest clumps: the radius is small for how sparsely they are packed (a Fixed radius or one
    from the particle sizes; the automatic radius follows the packing), with the radius their
    packing suggests; or when the radius is over 3 x what their packing asks for. None
    otherwise."""
    share = stats.get("enclosed_fraction")
    suggested = stats.get("density_radius", 0.0)
    radius = stats.get("radius", 0.0)
    if share is not None and share >= 0.5 and 0 < suggested and 3 * suggested < radius:
        # The other way round: over 6 spacings of a lattice as dense (the library reads at
        # most 8: then it suggests R / 4).
        return (f"the radius {radius:.4g} is large for how densely the particles are packed (their packing "
                f"suggests a Fixed radius of {suggested:.3g}): every detail smaller than it melts into one blob")
    if share is None or share >= 0.5:
        return None
    advice = (f"; their packing suggests a Fixed radius of {suggested:.3g}"
              if suggested > radius else "; raise the radius or lower the threshold")
    return (f"the surface encloses only {100 * share:.0f}% of the particles: the radius "
            f"{radius:.4g} is small for how sparsely they are packed{advice}")


#: More pieces than one for every this many particles (and at least PIECES_MIN) make
#: pieces_warning speak (as the command-line tool's polygonize).
PARTICLES_PER_PIECE = 10
PIECES_MIN = 100


def pieces_warning(pieces, particles):
    """A warning when the polygonized surface fell into about as many pieces as there are
    particles: one layer of particles (a surface's samples, not a fluid's volume) gives a blob
    around each few, since the automatic threshold is half the field inside a packed volume;
    Triangulate meshes such particles. None otherwise."""
    if pieces < PIECES_MIN or pieces * PARTICLES_PER_PIECE <= particles:
        return None
    return (f"the surface fell into {pieces} pieces, one for every {particles / pieces:.1f} particles: particles "
            "that sample a surface rather than fill a volume give a blob around each few: use Triangulate (or "
            "raise the radius to join the blobs)")


def polygonize_radii(particles, settings):
    """(radius, radii): one radius for all (0 = the library's default from the packing), or
    per-particle radii from the particles' sizes."""
    mode = settings.get("radius_mode", "AUTO")
    if mode == "FIXED":
        return float(settings["radius"]), None
    if mode == "PARTICLE_SIZE":
        factor = float(settings.get("radius_factor", 2.0))
        if particles.sizes is not None:
            return 0.0, particles.sizes.astype(np.float64) * factor
        if particles.particle_size > 0:
            return particles.particle_size * factor, None
    return 0.0, None


def polygonize_threshold(settings, from_sizes):
    """The iso level T; 0 = the library's default, which assumes R = 2 particle spacings. With
    radii from the particles' sizes the size says the spacing instead: particles of size
    (radius) s packed touching are 2 s apart, and T is half the field inside such a packing,
    0.5 x lattice_field(kernel, factor x s, 2 s), which depends on the kernel and the factor
    only (at the default factor 2 it is 0.5: an isolated particle becomes a ball of about its
    size, touching ones merge). With anisotropic kernels 0 is kept: the library calibrates its
    threshold on the particles themselves (the median radius stands for their sizes)."""
    threshold = float(settings.get("threshold", 0.0))
    if threshold > 0 or not from_sizes or settings.get("anisotropic", False):
        # Anisotropic kernels: 0 lets the library calibrate the threshold on the particles.
        return threshold
    factor = float(settings.get("radius_factor", 2.0))
    return 0.5 * pm.lattice_field(settings.get("kernel", "WYVILL"), factor, 2.0)


#: Clean Slivers: edges shorter than this many cells are collapsed (the library's
#: collapse_edges; 0.3 takes out nine in ten of marching cubes' triangles with an angle under
#: 10 degrees).
CLEAN_SLIVERS_EDGE = 0.3


def polygonize(particles, settings, progress=None, reuse=None, defer_attributes=False):
    """The polygonized surface. `defer_attributes`: leave the particles' channels (velocity)
    for finish_attributes() (live mode's viewport frames, until frames rest): their
    interpolation is a fifth of the library's time on a 100k-particle frame. Not with
    smoothing (it carries the channels: they would have to be smoothed again)."""
    radius, radii = polygonize_radii(particles, settings)
    from_sizes = settings.get("radius_mode") == "PARTICLE_SIZE" and (radius > 0 or radii is not None)
    # 0 is the library's "automatic" for radius, threshold and cell.
    arguments = dict(
        radii=radii, kernel=settings.get("kernel"),
        radius=radius, threshold=polygonize_threshold(settings, from_sizes),
        cell=0.0 if settings.get("auto_cell", True) else float(settings["cell_size"]),
        threads=int(settings.get("threads", 0)),
        anisotropic=bool(settings.get("anisotropic", False)),
        collapse_edges=CLEAN_SLIVERS_EDGE if settings.get("clean_slivers", False) else 0.0)
    attributes = _attributes(particles)
    later = bool(defer_attributes and attributes and not _smooths(settings))
    mesh = pm.polygonize(particles.positions, attributes=None if later else attributes,
                         progress=progress, **arguments)
    mesh.stats["global_spacing"] = not bool(settings.get("local_spacing", True))
    if mesh.triangle_count == 0:
        raise EmptyResult("no surface: the summed field stays below the threshold everywhere "
                          "(raise the radius or lower the threshold)")
    if later:
        mesh.stats[PENDING_ATTRIBUTES] = _PendingAttributes(particles.positions, attributes,
                                                            arguments, mesh.vertices)
    return _smooth(mesh, settings, progress, reuse)


def _smooths(settings):
    return settings.get("smooth", "NONE") != "NONE" and int(settings.get("smooth_levels", 1)) > 0


#: The stats key of a mesh whose channels wait (polygonize(defer_attributes=True)).
PENDING_ATTRIBUTES = "pending_attributes"


class _PendingAttributes:
    """What pm.polygonize_attributes needs to give a mesh the channels polygonize would have
    given it: the particles, their channels, polygonize's arguments and the library's own
    float64 vertices (the float32 ones Blender keeps are other points: their values would
    differ in the last bits)."""

    __slots__ = ("positions", "attributes", "arguments", "vertices")

    def __init__(self, positions, attributes, arguments, vertices):
        self.positions, self.attributes = positions, attributes
        self.arguments, self.vertices = arguments, vertices

    @property
    def nbytes(self):
        arrays = [self.positions, self.vertices, self.arguments.get("radii"),
                  *self.attributes.values()]
        return sum(np.asarray(a).nbytes for a in arrays if a is not None)

    def finished_nbytes(self):
        """The bytes of the channels once interpolated (float32, per vertex)."""
        return sum(4 * len(self.vertices) * (np.asarray(a).size // max(len(a), 1))
                   for a in self.attributes.values())


def attributes_pending(mesh):
    """The names of the channels `mesh` still waits for (finish_attributes), or ()."""
    pending = mesh.stats.get(PENDING_ATTRIBUTES)
    return tuple(pending.attributes) if pending is not None else ()


def pending_nbytes(mesh):
    """Bytes `mesh` holds or will hold beyond mesh.nbytes for its waiting channels: the
    larger of what waits (particles, float64 vertices) and the channels it will get."""
    pending = mesh.stats.get(PENDING_ATTRIBUTES)
    return 0 if pending is None else max(pending.nbytes, pending.finished_nbytes())


def pending_finished_nbytes(mesh):
    """Bytes the channels `mesh` waits for will hold (0 when none wait)."""
    pending = mesh.stats.get(PENDING_ATTRIBUTES)
    return 0 if pending is None else pending.finished_nbytes()


def finish_attributes(mesh):
    """Give `mesh` the channels it waits for (polygonize(defer_attributes=True)): the values
    pm.polygonize would have given it, bit for bit. Returns the names set (() when nothing
    waited)."""
    pending = mesh.stats.get(PENDING_ATTRIBUTES)
    if pending is None:
        return ()
    values = pm.polygonize_attributes(pending.positions, pending.vertices,
                                      attributes=pending.attributes, **pending.arguments)
    mesh.attributes.update(values)
    del mesh.stats[PENDING_ATTRIBUTES]
    return tuple(values)


METHODS = {"TRIANGULATE": triangulate, "POLYGONIZE": polygonize}


def run(method, particles, settings, progress=None, reuse=None, defer_attributes=False):
    """The mesh of `particles` by `method` with `settings`. `reuse`: a dict the caller keeps
    from one call to the next on the same object (live mode), where Loop smoothing keeps its
    refinement while the triangles stay the same; the result is the same without it.
    `defer_attributes`: polygonize may leave the channels for finish_attributes() (a
    triangulation's channels are the particles' own: nothing to wait for)."""
    if method == "POLYGONIZE":
        mesh = polygonize(particles, settings, progress=progress, reuse=reuse,
                          defer_attributes=defer_attributes)
    else:
        mesh = METHODS[method](particles, settings, progress=progress, reuse=reuse)
    # Blender stores float32: convert once here (it also halves the live cache's memory).
    mesh.vertices = mesh.vertices.astype(np.float32)
    if mesh.normals is not None:
        mesh.normals = mesh.normals.astype(np.float32)
    return mesh
