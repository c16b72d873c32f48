"""Progress reports, cancellation and Ctrl-C for the long calls.

ctypes releases the GIL for the whole native call (the library is a CDLL), so other Python
threads run meanwhile. The library calls its progress callback on the calling thread (about
every 50 ms and once per stage); a non-zero return cancels the call, which then returns
PM_STATUS_CANCELLED promptly with its outputs untouched. Every call installs such a callback,
even without a `progress` argument, because it is the only point where Python code runs
during the call:

  - Ctrl-C: while a call runs on the main thread with Python's default SIGINT handler, the
    handler is swapped for one that only records the signal; the callback then cancels the
    call, and KeyboardInterrupt is raised once the library has returned (a KeyboardInterrupt
    raised inside a ctypes callback would be printed and ignored, and the call would go on).
  - Progress.cancel(), from any thread (Esc in Blender), cancels at the next report.
  - The user's callback returning False cancels (CancelledError); an exception in it cancels
    too and is re-raised after the call (it never unwinds through C)."""

import signal
import threading

from . import _abi


class Progress:
    """Progress and cancellation of one call, shareable between threads.

    `callback(stage, fraction)` (optional) is called on the calling thread with the stage's
    name and the overall fraction done (0..1); it returns False to cancel. `stage` and
    `fraction` hold the last report (a UI thread may poll them); `cancel()` may be called from
    any thread and stops the call at its next report."""

    def __init__(self, callback=None):
        if callback is not None and not callable(callback):
            raise TypeError("the progress callback must be callable as callback(stage, fraction)")
        self.callback = callback
        self.stage = ""
        self.fraction = 0.0
        self._cancel = threading.Event()

    def cancel(self):
        self._cancel.set()

    @property
    def cancelled(self):
        return self._cancel.is_set()

    def __repr__(self):
        state = ", cancelled" if self.cancelled else ""
        return f"<particlemesh.Progress {self.stage!r} {100 * self.fraction:.0f}%{state}>"


def as_progress(progress):
    if progress is None:
        return Progress()
    if isinstance(progress, Progress):
        return progress
    if callable(progress):
        return Progress(progress)
    raise TypeError("progress must be None, a callable (stage, fraction) or a "
                    f"particlemesh.Progress, not {type(progress).__name__!r}")


class Hook:
    """The progress callback of one native call, as a context manager:

        with Hook(progress) as hook:
            options.progress = hook.c_function
            status = lib.pm_triangulate(...)
        hook.finish(lib, status)  # the caller frees the outputs if this raises

    finish() raises KeyboardInterrupt after Ctrl-C (even when the call had finished), the
    callback's own exception, or the library's error (CancelledError when cancelled)."""

    def __init__(self, progress):
        self.progress = as_progress(progress)
        self.error = None
        self.interrupted = False
        self._previous_handler = None
        self.c_function = _abi.pm_progress_fn(self._report)

    def _report(self, _user_data, stage, fraction):
        try:
            p = self.progress
            p.stage = stage.decode(errors="replace") if stage else ""
            p.fraction = float(fraction)
            if self.interrupted or p.cancelled:
                return 1
            if p.callback is not None and p.callback(p.stage, p.fraction) is False:
                p.cancel()
                return 1
            return 0
        except BaseException as e:  # noqa: BLE001 - never let an exception unwind through C
            self.error = e
            return 1

    def _on_sigint(self, _signum, _frame):
        self.interrupted = True

    def __enter__(self):
        if (threading.current_thread() is threading.main_thread()
                and signal.getsignal(signal.SIGINT) is signal.default_int_handler):
            self._previous_handler = signal.signal(signal.SIGINT, self._on_sigint)
        return self

    def __exit__(self, *exc):
        if self._previous_handler is not None:
            signal.signal(signal.SIGINT, self._previous_handler)
            self._previous_handler = None
        return False

    def finish(self, lib, status):
        if self.interrupted:
            raise KeyboardInterrupt
        if self.error is not None:
            error, self.error = self.error, None
            raise error
        lib.check(status)  # CancelledError after a cancel, else the library's error
