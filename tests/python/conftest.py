"""pytest fixtures for the add-on's bpy-free binding (blender_addon/particlemesh/native.py).

native.py is loaded straight from its file so that the package's __init__ (which needs bpy)
is never imported: that is the point of keeping the binding bpy-free."""
import importlib.util
import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
NATIVE_PY = ROOT / "blender_addon" / "particlemesh" / "native.py"


def load_native_module(name="pm_native_under_test"):
    spec = importlib.util.spec_from_file_location(name, NATIVE_PY)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def native():
    if not os.environ.get("PARTICLEMESH_LIBRARY"):
        pytest.skip("PARTICLEMESH_LIBRARY is not set to the built libparticlemesh")
    return load_native_module()


@pytest.fixture(scope="session")
def data_dir():
    d = os.environ.get("PM_TEST_DATA")
    if not d or not Path(d).is_dir():
        pytest.skip("shared test data not found (set PM_TEST_DATA to the shared/data folder)")
    return Path(d)
