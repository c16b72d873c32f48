"""Live mode's finishing timer in a real Blender window (not part of the pytest suite: timers
do not run in background mode). Needs a display, e.g. Xvfb:

    xvfb-run -a -s "-screen 0 1280x1024x24" blender --factory-startup -noaudio \
        --python tests/blender/ui_finish_frames.py -- --zip build/blender_addon/particlemesh-*.zip

A live polygonized object: a new frame shows Blender's own normals and gets the library's by
itself once frames rest; during playback new frames stay unfinished; after playback stops
the frame on screen is finished. Exits 0 when all that holds, 1 otherwise (or on a timeout);
it polls rather than waits fixed times, but it is a check by hand, not a test in the suite."""
import argparse
import os
import sys
import tempfile
import time
import traceback

import bpy

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
parser = argparse.ArgumentParser(prog="ui_finish_frames.py")
parser.add_argument("--zip", required=True)
args = parser.parse_args(argv)

os.environ["BLENDER_USER_SCRIPTS"] = tempfile.mkdtemp(prefix="pm_ui_")
os.environ.pop("PARTICLEMESH_LIBRARY", None)
bpy.ops.preferences.addon_install(filepath=os.path.abspath(args.zip), overwrite=True)
bpy.ops.preferences.addon_enable(module="particlemesh")
pm = sys.modules["particlemesh"]
name = []
start = time.monotonic()


def say(*what):
    print("ui_finish_frames:", *what, flush=True)


def context():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    return bpy.context.temp_override(window=window, screen=window.screen, area=area)


def shown():
    """(custom normals?, unfinished?) of the frame on screen."""
    mesh = pm.frame_display.shown_mesh(bpy.data.objects[name[0]])
    return mesh.has_custom_normals, pm.live.UNFINISHED_TAG in mesh


def checked(step):
    """A timer step that quits Blender with status 1 when it fails."""
    def run():
        try:
            return step()
        except Exception:  # noqa: BLE001  (report, then quit with an error status)
            traceback.print_exc()
            say("FAILED")
            os._exit(1)
    return run


@checked
def make_and_change_frame():
    with context():
        for obj in list(bpy.data.objects):
            bpy.data.objects.remove(obj)
        bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4, radius=1.0)
        emitter = bpy.context.active_object
        emitter.modifiers.new("particles", "PARTICLE_SYSTEM")
        settings = emitter.particle_systems[0].settings
        settings.count = len(emitter.data.vertices)
        settings.emit_from, settings.use_emit_random = "VERT", False
        settings.frame_start = settings.frame_end = 1
        settings.lifetime, settings.normal_factor = 1000, 1.0
        settings.effector_weights.gravity = 0.0
        assert bpy.ops.particlemesh.polygonize(live=True) == {"FINISHED"}
        name.append(bpy.context.active_object.name)
    bpy.context.scene.frame_set(4)
    assert shown() == (False, True), shown()
    assert bpy.app.timers.is_registered(pm.live.finish_frames)
    bpy.app.timers.register(checked(when_finished(play)), first_interval=0.25)


def when_finished(then):
    """A timer step that waits (polling, up to the timeout) until the frame on screen is
    finished by the add-on's own timer, then runs `then`."""
    def wait():
        if shown() != (True, False):
            return 0.25
        assert not pm.live._pending
        then()
        return None
    return wait


#: What the frame on screen was at each look during playback.
seen = []


def play():
    say("a rested frame got its normals")
    # Two frames a second: each frame stays on screen longer than the rest delay, which
    # the timer must not take for rest while playing.
    bpy.context.scene.render.fps, bpy.context.scene.render.fps_base = 2, 1.0
    with context():
        bpy.ops.screen.animation_play()
    bpy.app.timers.register(checked(stop_after_new_frames), first_interval=0.1)


def stop_after_new_frames():
    if bpy.context.scene.frame_current > 4:  # (frame 4, finished, until the first change)
        seen.append((bpy.context.scene.frame_current, round(time.monotonic() - start, 2)) + shown())
    if bpy.context.scene.frame_current < 7:
        return 0.1
    with context():
        assert bpy.context.screen.is_animation_playing
        bpy.ops.screen.animation_cancel(restore_frame=False)
    frame = bpy.context.scene.frame_current
    assert all(look[2:] == (False, True) for look in seen), seen  # never finished while playing
    say(f"playback to frame {frame} left its frames unfinished (frame, seconds, custom "
        f"normals, unfinished: {seen})")
    bpy.app.timers.register(checked(when_finished(done)), first_interval=0.25)
    return None


def done():
    say(f"the frame on screen got its normals after playback stopped; OK in "
        f"{time.monotonic() - start:.1f} s")
    bpy.ops.wm.quit_blender()


def timeout():
    say("FAILED: timed out")
    os._exit(1)


bpy.app.timers.register(make_and_change_frame, first_interval=1.0)
bpy.app.timers.register(timeout, first_interval=120.0)
