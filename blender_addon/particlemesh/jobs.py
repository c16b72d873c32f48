"""Native work in a worker thread, so that Blender's UI stays live and Esc can cancel.

bpy-free: the thread only runs library calls on numpy arrays prepared on the main thread;
everything that touches Blender data happens on the main thread before and after."""

import threading

from . import particlemesh as pm


class Job:
    """Runs fn(*args, progress=<particlemesh.Progress>, **kwargs) in a daemon thread.

    The main thread polls `done`, shows `progress.stage` / `progress.fraction`, may call
    `cancel()` (the library stops at its next progress report and the job ends with a
    particlemesh.CancelledError in `error`), and takes `result` or `error` once done."""

    def __init__(self, fn, *args, **kwargs):
        self.progress = pm.Progress()
        self.result = None
        self.error = None
        self._fn = fn
        self._args = args
        self._kwargs = kwargs
        self._thread = threading.Thread(target=self._run, name="particlemesh-job", daemon=True)

    def _run(self):
        try:
            self.result = self._fn(*self._args, progress=self.progress, **self._kwargs)
        except BaseException as e:  # handed to the main thread, which reports it
            self.error = e

    def start(self):
        self._thread.start()
        return self

    @property
    def done(self):
        return not self._thread.is_alive()

    def cancel(self):
        self.progress.cancel()

    def wait(self, timeout=None):
        self._thread.join(timeout)
        return self.done

    def status_text(self):
        stage = self.progress.stage or "starting"
        return f"particlemesh: {stage} {100.0 * self.progress.fraction:.0f}%  (Esc to cancel)"
