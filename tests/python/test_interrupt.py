"""Ctrl-C during a long call: a Python process sent SIGINT while the library works stops
promptly with KeyboardInterrupt (through the library's cancellation), not after the call
and not with a crash; the same process can call again afterwards."""
import os
import signal
import subprocess
import sys
import time

import pytest

CHILD = r"""
import sys, time
import numpy as np
import particlemesh as pm

n = 1_500_000
i = np.arange(n) + 0.5
phi = np.arccos(1 - 2 * i / n)
theta = np.pi * (1 + 5 ** 0.5) * i
p = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], 1)
reported = []

def progress(stage, fraction):
    if not reported:
        print("working", flush=True)
    reported.append(stage)

kwargs = {"progress": progress} if sys.argv[1] == "callback" else {}
if sys.argv[1] == "silent":
    print("working", flush=True)
start = time.perf_counter()
try:
    pm.triangulate(p, **kwargs)
    print("finished", flush=True)
except KeyboardInterrupt:
    print(f"interrupted {time.perf_counter() - start:.3f}", flush=True)
    # The library is fine afterwards, and Ctrl-C works as usual again outside calls.
    assert pm.triangulate(p[:2000]).triangle_count > 0
    print("again ok", flush=True)
    raise
"""


@pytest.mark.parametrize("mode", ["callback", "silent"])
def test_sigint_during_a_call_raises_keyboardinterrupt_promptly(pm, mode):
    env = dict(os.environ, PYTHONPATH=os.path.dirname(os.path.dirname(pm.__file__)))
    child = subprocess.Popen([sys.executable, "-c", CHILD, mode], env=env, text=True,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        assert child.stdout.readline().strip() == "working"
        time.sleep(0.3)  # well inside the call: 1.5M points take several seconds
        sent = time.perf_counter()
        child.send_signal(signal.SIGINT)
        first = child.stdout.readline()  # "interrupted ..." as soon as the call has stopped
        latency = time.perf_counter() - sent
        out, err = child.communicate(timeout=60)
        out = first + out
    finally:
        if child.poll() is None:
            child.kill()
    assert "finished" not in out, "the call ran to its end despite Ctrl-C"
    assert first.startswith("interrupted") and "again ok" in out, (out, err)
    assert err.rstrip().endswith("KeyboardInterrupt"), err
    # An uncaught KeyboardInterrupt: Python prints it, then ends by SIGINT as Ctrl-C does.
    assert child.returncode == -signal.SIGINT
    # 14-20 ms measured (the library reports progress about every 50 ms); 2 s leaves room for a
    # loaded machine.
    assert latency < 2.0, f"the call stopped {latency:.2f} s after SIGINT"
