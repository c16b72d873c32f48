"""Sequences: one Dask task per frame (map_frames)."""

import glob
import os
import re
import string
import time
import uuid
from dataclasses import dataclass, field

from .. import _library, _options
from .. import (is_frame_collection, polygonize, read_frame_collection, read_points, triangulate,
                write_mesh)
from ._dask import check_client, distributed

#: What a frame can be meshed with, and the particlemesh function each runs.
COMMANDS = ("triangulate", "polygonize")
# Keywords of the functions that are not options of their C struct.
_EXTRA_KEYWORDS = {
    "triangulate": {"raw", "repair", "orient"},
    "polygonize": {"radius", "threshold", "kernel", "cell", "lattice_anchor"},
}


@dataclass
class FrameSummary:
    """What map_frames did. `done`: one dict per frame written (frame, input, output,
    seconds, vertices, triangles), in frame order; `failed`: one dict per frame
    that failed twice (frame, input, output, error: the message of its last attempt);
    `skipped`: frames whose output existed (skip_existing=True); `missing`: frames without an
    input file, as the command-line tool reports them (a gap among the files a pattern
    matches, a frame asked for whose file does not exist, a file a collection lists that
    does not exist), not run and not a failure; `seconds`: wall time of the whole run."""

    done: list = field(default_factory=list)
    failed: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    missing: list = field(default_factory=list)
    seconds: float = 0.0

    @property
    def ok(self):
        """True when no frame failed."""
        return not self.failed

    def __str__(self):
        text = (f"{len(self.done)} frames meshed, {len(self.failed)} failed, "
                f"{len(self.skipped)} skipped, in {self.seconds:.1f} s")
        if self.missing:
            shown = ", ".join(map(str, self.missing[:10]))
            more = f" and {len(self.missing) - 10} more" if len(self.missing) > 10 else ""
            text += f"\n  {len(self.missing)} missing (no file): {shown}{more}"
        for f in self.failed:
            text += f"\n  frame {f['frame']}: {f['error']}"
        return text


def _pattern_field(pattern, name):
    """The one replacement field of a frame pattern ('{}' or '{:04d}'), as (prefix, spec,
    suffix); ValueError unless there is exactly one."""
    parts = list(string.Formatter().parse(str(pattern)))
    fields = [(i, p) for i, p in enumerate(parts) if p[1] is not None]
    if len(fields) != 1 or fields[0][1][1] not in ("", "0"):
        raise ValueError(f"{name} {str(pattern)!r} must hold one frame field, '{{}}' or a "
                         "format such as '{:04d}' (e.g. 'fluid_{:04d}.xyz')")
    return fields[0][1][2]


def frame_path(pattern, frame):
    """The file of `frame` under a pattern with one '{}' (or '{:04d}') field."""
    return str(pattern).format(frame)


def find_frames(input_pattern):
    """The frame numbers of the files that match a pattern, ascending: 'in/f_{:04d}.ply'
    finds in/f_0001.ply, in/f_0002.ply, ... (a name that the pattern would not write for its
    number, e.g. f_1.ply for '{:04d}', is not a frame)."""
    _pattern_field(input_pattern, "input_pattern")
    pattern = str(input_pattern)
    prefix, _, rest = pattern.partition("{")
    spec, _, suffix = rest.partition("}")
    regex = re.compile(re.escape(prefix) + r"(-?\d+)" + re.escape(suffix) + r"\Z")
    frames = set()
    for path in glob.glob(glob.escape(prefix) + "*" + glob.escape(suffix)):
        m = regex.match(path)
        if m and frame_path(pattern, int(m.group(1))) == path:
            frames.add(int(m.group(1)))
    return sorted(frames)


def check_options(command, options):
    """TypeError for a keyword `command`'s function does not take (before any task runs)."""
    spec = _options.SPECS[command]
    allowed = set(spec.keywords) | _EXTRA_KEYWORDS[command]
    for key in options:
        if key not in allowed:
            raise TypeError(f"map_frames({command!r}) got an unexpected option {key!r}; "
                            f"{command} takes {', '.join(sorted(allowed))}")


def mesh_file(command, input_path, output_path, options):
    """One frame, on a worker: read the particles, mesh them, write the mesh atomically through
    the library (the bytes the command-line tool writes for the same file and options).
    Returns what the summary lists."""
    t0 = time.perf_counter()
    points = read_points(input_path)
    if command == "polygonize":  # the command-line tool anchors the lattice in space
        options = {"lattice_anchor": "space", **options}
    mesh = {"triangulate": triangulate, "polygonize": polygonize}[command](points, **options)
    folder = os.path.dirname(output_path)
    if folder:
        os.makedirs(folder, exist_ok=True)
    write_mesh(mesh, output_path)
    return {"vertices": mesh.vertex_count, "triangles": mesh.triangle_count,
            "seconds": time.perf_counter() - t0}


def map_frames(client, command, input_pattern, output_pattern, frames=None, *, retries=1,
               skip_existing=False, progress=None, **options):
    """Mesh a sequence of particle files, one Dask task per frame.

    command: "triangulate" or "polygonize" (or a function f(input_path, output_path) run per
    frame); input_pattern / output_pattern: paths with one frame field, '{}' or a format such
    as '{:04d}' ("sim/fluid_{:04d}.xyz", "out/fluid_{:04d}.ply"); input_pattern may also be a
    ParaView collection (.pvd, .series), frame n its n-th file by time (read_frame_collection);
    frames: the frame numbers (default: from the first file matching input_pattern to the
    last, or every file the collection lists); a frame whose input file does not exist is
    not run and is listed in the summary's `missing`, as the command-line tool skips and
    names it. Options are those of particlemesh.triangulate
    / polygonize (spacing=, radius=, threshold=, raw=, threads= ...; polygonize's lattice_anchor
    defaults to "space" here, as in the command-line tool). Each output is exactly the
    file `particlemesh triangulate|polygonize IN -o OUT` writes with the same options, written
    under a temporary name and renamed when complete. A frame that fails is retried once
    (`retries`), then reported with its error while the other frames go on.
    skip_existing=True leaves frames whose output exists (resuming a run). progress(finished,
    total) is called as frames end. Returns a FrameSummary (its `ok` is False when a frame
    failed; str() of it is a report)."""
    dd = distributed()
    check_client(client)
    if callable(command):
        task, label = command, getattr(command, "__name__", "frame")
    else:
        if command not in COMMANDS:
            raise ValueError(f"command must be one of {', '.join(COMMANDS)} or a function, "
                             f"not {command!r}")
        check_options(command, options)
        _library.load()  # a missing library is one error here, not one per frame
        task, label = None, command
    if options and task is not None:
        raise TypeError("options are for 'triangulate' and 'polygonize'; a function takes its "
                        "own arguments (use functools.partial)")
    _pattern_field(output_pattern, "output_pattern")
    present = os.path.isfile if task is None else os.path.exists  # a function may take folders
    if is_frame_collection(input_pattern):
        listed = [p for _, p in read_frame_collection(input_pattern)]
        source_of = listed.__getitem__
        if frames is None:
            frames = range(len(listed))
        else:
            frames = list(frames)
            for f in frames:
                if not 0 <= f < len(listed):
                    raise ValueError(f"frame {f} is not one of the {len(listed)} frames "
                                     f"{str(input_pattern)!r} lists (0..{len(listed) - 1})")
    elif frames is None:
        found = find_frames(input_pattern)
        if not found:
            raise FileNotFoundError(f"no file matches input_pattern {str(input_pattern)!r}")
        frames = range(found[0], found[-1] + 1)  # the gaps among them are missing frames
        source_of = lambda f: frame_path(input_pattern, f)  # noqa: E731
    else:
        _pattern_field(input_pattern, "input_pattern")
        frames = list(frames)
        source_of = lambda f: frame_path(input_pattern, f)  # noqa: E731
    # A frame without its input file is missing, as the command-line tool says: reported, not
    # sent to a worker to fail there.
    missing = [f for f in frames if not present(source_of(f))]
    if len(missing) == len(frames):
        what = ("none of the files {!r} lists exists" if is_frame_collection(input_pattern)
                else "no input file exists for the frames asked of {!r}")
        raise FileNotFoundError(what.format(str(input_pattern)))
    absent = set(missing)
    frames = [f for f in frames if f not in absent]
    outputs = [frame_path(output_pattern, f) for f in frames]
    if len(set(outputs)) != len(outputs):
        raise ValueError(f"output_pattern {str(output_pattern)!r} names the same file for two "
                         "frames")

    t0 = time.perf_counter()
    summary = FrameSummary(missing=missing)
    jobs = {}
    token = uuid.uuid4().hex[:12]  # this run's task names
    for frame, output in zip(frames, outputs):
        source = source_of(frame)
        if skip_existing and os.path.exists(output):
            summary.skipped.append(frame)
            continue
        key = f"particlemesh-{label}-frame-{frame}-{token}"
        if task is None:
            future = client.submit(mesh_file, command, source, output, options, key=key,
                                   retries=retries, pure=False)
        else:
            future = client.submit(task, source, output, key=key, retries=retries, pure=False)
        jobs[future.key] = (future, frame, source, output)

    records = {}
    finished = 0
    for future in dd.as_completed([j[0] for j in jobs.values()]):
        _, frame, source, output = jobs[future.key]
        record = {"frame": frame, "input": source, "output": output}
        if future.status == "error":
            error = future.exception()
            record["error"] = f"{type(error).__name__}: {error}"
        else:
            result = future.result()
            if isinstance(result, dict):
                record.update(result)
        records[frame] = record
        finished += 1
        if progress is not None:
            progress(finished, len(jobs))
    for frame in frames:
        record = records.get(frame)
        if record is None:
            continue
        (summary.failed if "error" in record else summary.done).append(record)
    summary.seconds = time.perf_counter() - t0
    return summary


__all__ = ["map_frames", "FrameSummary", "find_frames", "frame_path", "mesh_file"]
