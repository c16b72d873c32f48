"""particlemesh in Blender: benchmark, run in background Blender (results: bench/RESULTS.md).

    blender --background --factory-startup -noaudio --python bench/blender_bench.py -- \
        --zip build/blender_addon/particlemesh-*-blender-addon.zip \
        [--triangles 1000000] [--particles 100000] [--frames 8] [--metaballs 1000 10000]
        [--thin 2 3]

1. A 1M-triangle result into a Blender mesh (the add-on's bulk foreach_set path), with and
   without the library's normals as custom split normals; beside Mesh.from_pydata.
2. Live mode on a 100k-particle system: the cost of a frame change (wall time, and the CPU
   time of Blender's process, all threads: the fairer figure on a shared machine) with the
   mesh regenerated from the evaluated particles (source read, triangulation, mesh write), beside the same
   frame change with live mode off, and revisiting cached frames: with every particle (Viewport
   Budget 0), with the default Viewport Budget (8 000: a bigger system is thinned to at most
   about that many while scrubbing), and with the viewport's Thin Out set by hand. A cached
   frame shows the mesh kept for it again (through its hidden holder object, where the
   add-on's frame_display can: no evaluation again); the last polygonized frame is then
   written again with and without custom split normals, and shown by a bare frame handler
   (the object's mesh swapped, or the holder shown), to show where a big frame's time goes
   (the write, and Blender's own evaluation of a mesh swapped in). Where the add-on defers a
   new viewport frame's custom split normals until frames rest (live.finish_frames), the
   frame changes are measured as in the viewport (deferred), and the finishing of a frame at
   rest (the normals set, the frame evaluated again) gets a row of its own.
3. Blender's own particle meshers on the same particles for reference: Points to Volume ->
   Volume to Mesh (geometry nodes) and metaballs (element counts given; metaballs do not
   reach 100k in reasonable time).
Prints Markdown tables."""
import argparse
import math
import os
import shutil
import statistics
import sys
import tempfile
import time

import bpy
import numpy as np

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
parser = argparse.ArgumentParser(prog="blender_bench.py")
parser.add_argument("--zip", required=True)
parser.add_argument("--triangles", type=int, default=1_000_000)
parser.add_argument("--particles", type=int, default=100_000)
parser.add_argument("--frames", type=int, default=8)
parser.add_argument("--repeat", type=int, default=3)
parser.add_argument("--metaballs", type=int, nargs="*", default=[1000, 10000])
parser.add_argument("--skip", nargs="*", default=[], choices=["write", "live", "peers"])
parser.add_argument("--thin", type=float, nargs="*", default=[2.0, 3.0],
                    help="also run live triangulation with the viewport's Thin Out at these")
args = parser.parse_args(argv)


def out(line=""):
    print(line, flush=True)


def ms(seconds):
    return f"{1000 * seconds:.0f} ms"


user_scripts = tempfile.mkdtemp(prefix="pm_bench_scripts_")
os.environ["BLENDER_USER_SCRIPTS"] = user_scripts
os.environ.pop("PARTICLEMESH_LIBRARY", None)
bpy.ops.preferences.addon_install(filepath=os.path.abspath(args.zip), overwrite=True)
bpy.ops.preferences.addon_enable(module="particlemesh")
pm = sys.modules["particlemesh"]
#: The viewport's deferral of custom normals until frames rest (add-ons that have it): off in
#: background mode unless asked for.
deferring = hasattr(pm.live, "finish_frames")
if deferring:
    pm.live.defer_in_background = True
# The add-on's default Live Cache (2048 MB) keeps every frame of these runs as a mesh.
assert pm.properties.preferences().cache_megabytes == pm.properties.CACHE_MEGABYTES
scene = bpy.context.scene
for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj)

out(f"particlemesh {pm.particlemesh.version()} in Blender {bpy.app.version_string}, "
    f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f} at start")


# ---- 1. a big result into a Blender mesh ------------------------------------------------------

def torus(triangles):
    """A closed torus grid with about `triangles` triangles and analytic normals."""
    nv = int(round(math.sqrt(triangles / 2 / 3)))
    nu = int(round(triangles / 2 / nv))
    u = np.arange(nu) * (2 * np.pi / nu)
    v = np.arange(nv) * (2 * np.pi / nv)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    R, r = 1.0, 0.3
    normals = np.stack([np.cos(uu) * np.cos(vv), np.sin(uu) * np.cos(vv), np.sin(vv)], -1)
    centre = np.stack([R * np.cos(uu), R * np.sin(uu), np.zeros_like(uu)], -1)
    positions = (centre + r * normals).reshape(-1, 3).astype(np.float32)
    i = np.arange(nu)[:, None]
    j = np.arange(nv)[None, :]
    a = i * nv + j
    b = ((i + 1) % nu) * nv + j
    c = ((i + 1) % nu) * nv + (j + 1) % nv
    d = i * nv + (j + 1) % nv
    tris = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                           np.stack([a, c, d], -1).reshape(-1, 3)]).astype(np.int32)
    return pm.particlemesh.Mesh(positions, tris, normals.reshape(-1, 3).astype(np.float32))


def time_write(data, custom_normals):
    times = []
    for _ in range(args.repeat):
        mesh = bpy.data.meshes.new("bench")
        t = time.perf_counter()
        pm.blender_mesh.write(mesh, data, custom_normals=custom_normals)
        times.append(time.perf_counter() - t)
        if _ == 0:
            assert not mesh.validate(verbose=False)
            assert len(mesh.polygons) == data.triangle_count
        bpy.data.meshes.remove(mesh)
    return min(times), statistics.median(times)


if "write" not in args.skip:
    data = torus(args.triangles)
    out()
    out(f"### {data.triangle_count} triangles, {data.vertex_count} vertices into a Blender mesh "
        f"(best / median of {args.repeat})")
    out()
    out("| path | best | median |")
    out("|---|---|---|")
    best, med = time_write(data, custom_normals=False)
    out(f"| add-on `blender_mesh.write` (foreach_set, smooth shading) | {best:.2f} s | {med:.2f} s |")
    best, med = time_write(data, custom_normals=True)
    out(f"| add-on `blender_mesh.write` + library normals as custom split normals "
        f"| {best:.2f} s | {med:.2f} s |")
    mesh = bpy.data.meshes.new("pydata")
    t = time.perf_counter()
    mesh.from_pydata(data.vertices, [], data.triangles)
    mesh.update()
    out(f"| peer: `Mesh.from_pydata` (numpy arrays in) + `update()` | {time.perf_counter() - t:.2f} s | - |")
    bpy.data.meshes.remove(mesh)
    del data


# ---- 2. live mode on a 100k-particle system ---------------------------------------------------

def fibonacci_sphere(n):
    i = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * i / n)
    theta = np.pi * (1 + 5 ** 0.5) * i
    return np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)],
                    1).astype(np.float32)


def make_emitter(count):
    """A sphere whose `count` evenly spaced vertices (a Fibonacci lattice, triangulated by the
    library so that Blender has vertex normals) each emit one particle at frame 1, flying
    outward (no gravity): evenly spaced surface particles at every frame."""
    p = fibonacci_sphere(count)
    data = pm.particlemesh.triangulate(p, normals=p)
    data.triangles, _ = pm.mesh_arrays.orient_by_normals(data.triangles, p, p)
    data.normals = None
    mesh = pm.blender_mesh.write(bpy.data.meshes.new("emitter"), data)
    emitter = bpy.data.objects.new("emitter", mesh)
    scene.collection.objects.link(emitter)
    bpy.context.view_layer.objects.active = emitter
    emitter.modifiers.new("particles", "PARTICLE_SYSTEM")
    s = emitter.particle_systems[0].settings
    s.count = count
    s.emit_from = "VERT"
    s.use_emit_random = False
    s.frame_start = s.frame_end = 1
    s.lifetime = 10000
    s.normal_factor = 0.5
    s.effector_weights.gravity = 0.0
    s.display_percentage = 100
    emitter.show_instancer_for_viewport = emitter.show_instancer_for_render = False
    return emitter


#: The CPU time (user + sys, all of Blender's threads) of every step() frame change, in order:
#: on a shared machine the fairer figure beside the wall times.
cpu_costs = []


def step(frames):
    costs = []
    for f in frames:
        t, c = time.perf_counter(), time.process_time()
        scene.frame_set(f)
        costs.append(time.perf_counter() - t)
        cpu_costs.append(time.process_time() - c)
    return costs


if "live" not in args.skip or "peers" not in args.skip:
    scene.frame_start, scene.frame_end = 1, args.frames + 10
    scene.frame_set(1)
    emitter = make_emitter(args.particles)
    frames = list(range(2, args.frames + 2))
    baseline = step(frames)  # the particle simulation alone (fills Blender's point cache)
    baseline_cpu = cpu_costs[-len(frames):]

def live_run(method, budget=0, **props):
    """Live mode with `method` on the emitter (the generated object's Viewport Budget set to
    `budget`, None = its default): per-frame costs over `frames`, then again over the same
    frames (now cached)."""
    scene.frame_set(1)
    pm.live.clear_cache()
    for obj in bpy.context.view_layer.objects:
        obj.select_set(False)
    bpy.context.view_layer.objects.active = emitter
    op = getattr(bpy.ops.particlemesh, method.lower())
    assert op(live=True, **props) == {"FINISHED"}, f"{method} failed"
    generated = bpy.context.active_object
    if budget is not None:
        generated.particlemesh.viewport_budget = budget
    name = generated.name
    pm.live.history.clear()
    live_costs = step(frames)
    run_cpu.append(statistics.median(cpu_costs[-len(frames):]))
    records = [r for n, r in pm.live.history if n == name]
    assert len(records) == len(frames) and not any("error" in r for r in records), records
    cached_costs = step(frames)
    cached = [r for n, r in list(pm.live.history)[len(records):] if n == name]
    assert all(r["cached"] for r in cached), [(r["frame"], r["cached"], r.get("particles"))
                                              for r in records + cached]
    finishing.append(time_finishing(frames))
    generated.particlemesh.live = False
    entries = pm.live.cache_for(generated).entries
    last_data[method, budget, tuple(sorted(props.items()))] = next(reversed(entries.values()))
    return live_costs, records, cached_costs, cached


last_data = {}
run_cpu = []  # per live_run, in order: the median CPU of its new frames' changes
finishing = []  # per live_run, in order: (wall, CPU) medians of finishing a frame, or None


def time_finishing(frames):
    """Finishing a frame at rest (what live.finish_frames does once frames rest: the custom
    normals set) and Blender's evaluation of it, for the last `args.repeat` frames shown
    again (cached, unfinished). (median wall, median CPU) or None when nothing waits."""
    if not deferring:
        return None
    walls, cpus = [], []
    for f in frames[-args.repeat:]:
        scene.frame_set(f)
        if not pm.live._pending:
            return None
        t, c = time.perf_counter(), time.process_time()
        pm.live.finish_pending()
        bpy.context.view_layer.update()
        walls.append(time.perf_counter() - t)
        cpus.append(time.process_time() - c)
    return statistics.median(walls), statistics.median(cpus)


def time_swaps(data, custom_normals, holders=False):
    """Frame changes (beyond the particle step) whose handler only swaps the object's mesh
    between two meshes already written (holders: shows them through their hidden holders,
    the add-on's frame_display): what a cached live frame costs Blender itself."""
    meshes = [pm.blender_mesh.write(bpy.data.meshes.new("swap"), data, custom_normals=custom_normals)
              for _ in range(2)]
    for i, mesh in enumerate(meshes):
        mesh[pm.live.FRAME_TAG] = f"bench.{i}"
    obj = bpy.data.objects.new("swap", meshes[0] if not holders else bpy.data.meshes.new("own"))
    scene.collection.objects.link(obj)
    emitter.hide_viewport = True  # no particle step in these frame changes
    live_objects = [o for o in scene.objects if o.particlemesh.live]
    for o in live_objects:
        o.particlemesh.live = False

    def swap(scene_, depsgraph=None):
        if holders:
            mesh = meshes[scene_.frame_current % 2]
            pm.frame_display.show(obj, mesh, mesh[pm.live.FRAME_TAG])
        else:
            obj.data = meshes[1] if obj.data == meshes[0] else meshes[0]

    # Only this handler: the add-on's own would sweep holders that no cache keeps.
    others = list(bpy.app.handlers.frame_change_post)
    bpy.app.handlers.frame_change_post.clear()
    bpy.app.handlers.frame_change_post.append(swap)
    try:
        # The first two evaluate (and with holders make) both.
        costs = step(list(range(2, 2 + max(5, args.repeat + 3))))[2:]
    finally:
        bpy.app.handlers.frame_change_post.remove(swap)
        bpy.app.handlers.frame_change_post.extend(others)
        emitter.hide_viewport = False
        bpy.data.objects.remove(obj)
        for holder in [o for o in bpy.data.objects if holders and pm.frame_display.HOLDER_TAG in o]:
            bpy.data.objects.remove(holder)
        for m in meshes:
            bpy.data.meshes.remove(m)
    return min(costs), statistics.median(costs)


if "live" not in args.skip:
    med = statistics.median
    columns = {"triangulate": ("TRIANGULATE", {}),
               "triangulate, default Viewport Budget": ("TRIANGULATE", {"budget": None})}
    for factor in args.thin:
        columns[f"triangulate, Thin Out {factor:g}"] = ("TRIANGULATE", {"thin": factor})
    columns["polygonize"] = ("POLYGONIZE", {})
    methods = list(columns)
    runs = {m: live_run(method, **props) for m, (method, props) in columns.items()}
    first = runs["triangulate"][1][0]
    out()
    out(f"### Live mode, {first['particles']} particles, frames {frames[0]}..{frames[-1]}, "
        f"median per frame")
    out()
    out("| what | " + " | ".join(methods) + " |")
    out("|---|" + "---|" * len(methods))

    def row(label, fn):
        out(f"| {label} | " + " | ".join(fn(*runs[m]) for m in methods) + " |")

    row("vertices (particles meshed)", lambda lc, rec, cc, cr: str(rec[0]["vertices"]))
    row("triangles", lambda lc, rec, cc, cr: str(rec[0]["triangles"]))
    row("frame change, live mode off (Blender's particle step only)", lambda *a: ms(med(baseline)))
    row("frame change, live mode on", lambda lc, rec, cc, cr: ms(med(lc)))
    cpu_of = dict(zip(methods, run_cpu))
    out("| frame change, live mode on: CPU time of Blender's process (all threads) | "
        + " | ".join(ms(cpu_of[m]) for m in methods) + " |")
    out("| frame change, live mode off: CPU time | "
        + " | ".join(ms(med(baseline_cpu)) for m in methods) + " |")
    row("- the add-on's handler", lambda lc, rec, cc, cr: ms(med([r["seconds"] for r in rec])))
    row("-- read the evaluated particles", lambda lc, rec, cc, cr: ms(med([r["source"] for r in rec])))
    row("-- mesh them (library)", lambda lc, rec, cc, cr: ms(med([r["mesh"] for r in rec])))
    row("-- write the Blender mesh", lambda lc, rec, cc, cr: ms(med([r["write"] for r in rec])))
    if deferring:
        finish_of = dict(zip(methods, finishing))
        out("| the frame at rest: custom normals set, evaluated again (wall / CPU) | "
            + " | ".join(f"{ms(finish_of[m][0])} / {ms(finish_of[m][1])}" if finish_of[m]
                         else "nothing to do" for m in methods) + " |")
    row("frame change, frame already in the cache", lambda lc, rec, cc, cr: ms(med(cc)))
    row("- the add-on's handler (cached)", lambda lc, rec, cc, cr: ms(med([r["seconds"] for r in cr])))
    row("-- show the cached frame (its kept mesh again)",
        lambda lc, rec, cc, cr: ms(med([r["write"] for r in cr])) + ("" if all(r["swapped"] for r in cr)
                                                                      else " (not all swapped)"))

    # Where a live write's time goes: the last polygonized frame into a new mesh, with and
    # without the library's normals as custom split normals.
    poly = last_data.get(("POLYGONIZE", 0, ()))
    if poly is not None:
        out()
        out(f"### The last polygonized frame ({poly.triangle_count} triangles, {poly.vertex_count} "
            f"vertices) into a new Blender mesh (best / median of {args.repeat})")
        out()
        out("| path | best | median |")
        out("|---|---|---|")
        best, median = time_write(poly, custom_normals=False)
        out(f"| geometry only (Blender's own smooth normals) | {best:.2f} s | {median:.2f} s |")
        best, median = time_write(poly, custom_normals=True)
        out(f"| + the field's gradient normals as custom split normals (the live default) "
            f"| {best:.2f} s | {median:.2f} s |")
        for custom in (False, True):
            best, median = time_swaps(poly, custom)
            out(f"| a frame change that only swaps in a kept mesh of it ({'custom' if custom else 'own'} "
                f"normals; Blender evaluates the object again) | {best:.2f} s | {median:.2f} s |")
        for custom in (False, True):
            if hasattr(pm, "frame_display"):
                best, median = time_swaps(poly, custom, holders=True)
                out(f"| a frame change that shows a kept mesh through its hidden holder "
                    f"({'custom' if custom else 'own'} normals; nothing evaluated again) "
                    f"| {best:.2f} s | {median:.2f} s |")



# ---- 3. Blender's own volume meshers on the same particles ------------------------------------

def particles_now():
    depsgraph = bpy.context.evaluated_depsgraph_get()
    return pm.sources.read(emitter, depsgraph, "PARTICLES")


def points_to_volume(points, radius, voxel):
    mesh = bpy.data.meshes.new("points")
    mesh.vertices.add(len(points))
    mesh.vertices.foreach_set("co", points.ravel())
    obj = bpy.data.objects.new("points_to_volume", mesh)
    scene.collection.objects.link(obj)
    tree = bpy.data.node_groups.new("points_to_volume", "GeometryNodeTree")
    if hasattr(tree, "interface"):  # Blender 4.0+
        tree.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
        tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    else:
        tree.inputs.new("NodeSocketGeometry", "Geometry")
        tree.outputs.new("NodeSocketGeometry", "Geometry")
    n_in = tree.nodes.new("NodeGroupInput")
    n_out = tree.nodes.new("NodeGroupOutput")
    to_points = tree.nodes.new("GeometryNodeMeshToPoints")
    to_volume = tree.nodes.new("GeometryNodePointsToVolume")
    to_volume.resolution_mode = "VOXEL_SIZE"
    to_volume.inputs["Voxel Size"].default_value = voxel
    to_volume.inputs["Radius"].default_value = radius
    to_mesh = tree.nodes.new("GeometryNodeVolumeToMesh")
    tree.links.new(n_in.outputs[0], to_points.inputs["Mesh"])
    tree.links.new(to_points.outputs["Points"], to_volume.inputs["Points"])
    tree.links.new(to_volume.outputs["Volume"], to_mesh.inputs["Volume"])
    tree.links.new(to_mesh.outputs["Mesh"], n_out.inputs[0])
    modifier = obj.modifiers.new("points_to_volume", "NODES")
    modifier.node_group = tree
    times = []
    for _ in range(args.repeat):
        mesh.vertices.foreach_set("co", (points * (1 + 1e-6 * _)).ravel())  # a "new frame"
        mesh.update()
        t = time.perf_counter()
        evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
        times.append(time.perf_counter() - t)
    triangles = len(evaluated.data.loops) - 2 * len(evaluated.data.polygons)
    bpy.data.objects.remove(obj)
    return statistics.median(times), triangles


def metaballs(points, radius, resolution, limit_seconds=120.0):
    mb = bpy.data.metaballs.new("metaballs")
    mb.resolution = mb.render_resolution = resolution
    mb.update_method = "UPDATE_ALWAYS"
    for p in points:  # Blender has no bulk way to add metaball elements
        e = mb.elements.new()
        e.co = p
        e.radius = radius
    obj = bpy.data.objects.new("metaballs", mb)
    scene.collection.objects.link(obj)
    t = time.perf_counter()
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    seconds = time.perf_counter() - t
    faces = len(mesh.polygons)
    evaluated.to_mesh_clear()
    bpy.data.objects.remove(obj)
    bpy.data.metaballs.remove(mb)
    return seconds, faces


if "peers" not in args.skip:
    scene.frame_set(frames[-1])
    particles = particles_now()
    points = particles.positions
    spacing = pm.particlemesh.estimate_spacing(points)
    # The library's polygonize defaults: R = 2 x spacing, cell = R / 4.
    radius, voxel = 2.0 * spacing, 0.5 * spacing
    out()
    out(f"### Blender's volume meshers on the same {len(points)} particles "
        f"(spacing {spacing:.4g}; radius {radius:.4g}, voxel/resolution {voxel:.4g})")
    out()
    out("| method | per frame | faces |")
    out("|---|---|---|")
    t = time.perf_counter()
    tri = pm.particlemesh.triangulate(points)
    out(f"| particlemesh triangulation (library call only) | {ms(time.perf_counter() - t)} "
        f"| {tri.triangle_count} |")
    t = time.perf_counter()
    poly = pm.particlemesh.polygonize(points, radius=radius, cell=voxel)
    out(f"| particlemesh polygonize (library call only) | {ms(time.perf_counter() - t)} "
        f"| {poly.triangle_count} |")
    seconds, faces = points_to_volume(points, radius, voxel)
    out(f"| Points to Volume -> Volume to Mesh (geometry nodes) | {ms(seconds)} | {faces} |")
    rng = np.random.default_rng(1)
    for count in args.metaballs:
        subset = points[rng.choice(len(points), size=min(count, len(points)), replace=False)]
        # Same density as the full set: scale the radius with the subset's own spacing.
        sub_spacing = pm.particlemesh.estimate_spacing(subset)
        seconds, faces = metaballs(subset, 2.0 * sub_spacing, 0.5 * sub_spacing)
        out(f"| metaballs, {len(subset)} elements (radius 2 x their spacing) "
            f"| {ms(seconds)} | {faces} |")

out()
out(f"load average {os.getloadavg()[0]:.2f} at the end")
bpy.ops.preferences.addon_disable(module="particlemesh")
shutil.rmtree(user_scripts, ignore_errors=True)
