"""pytest fixtures for the particlemesh Python package and the add-on's bpy-free modules.

The package under test is the one the build staged (build/python/particlemesh: the source
files and lib/ with libparticlemesh and what it needs), named by $PM_PYTHON_PATH, which
CTest sets; without it the source folder python/ is used with $PARTICLEMESH_LIBRARY. A
package that does not load fails the tests (it never skips them)."""
import importlib
import os
import sys
import types
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE_PARENT = Path(os.environ.get("PM_PYTHON_PATH") or ROOT / "python")
ADDON_SOURCE = ROOT / "blender_addon" / "particlemesh"

sys.path.insert(0, str(PACKAGE_PARENT))
sys.path.insert(0, str(Path(__file__).resolve().parent))  # c_header


@pytest.fixture(scope="session")
def pm():
    import particlemesh
    assert Path(particlemesh.__file__).resolve().parent == (PACKAGE_PARENT / "particlemesh").resolve()
    try:
        particlemesh.version()
    except particlemesh.LibraryNotFoundError as e:
        pytest.fail(f"the particlemesh package does not load its library: {e} (run through "
                    "ctest, or set PM_PYTHON_PATH to build/python)")
    return particlemesh


@pytest.fixture(scope="session")
def pm_abi(pm):
    return importlib.import_module("particlemesh._abi")


@pytest.fixture(scope="session")
def pm_library(pm):
    return importlib.import_module("particlemesh._library")


@pytest.fixture(scope="session")
def pm_options(pm):
    return importlib.import_module("particlemesh._options")


@pytest.fixture(scope="session")
def data_dir():
    d = os.environ.get("PM_TEST_DATA")
    if not d or not Path(d).is_dir():
        pytest.skip("shared test data not found (set PM_TEST_DATA to the shared/data folder)")
    return Path(d)


@pytest.fixture(scope="session")
def addon_zip():
    path = os.environ.get("PM_ADDON_ZIP")
    assert path and os.path.isfile(path), f"PM_ADDON_ZIP is not the built add-on zip: {path!r}"
    return Path(path)


@pytest.fixture(scope="session")
def unpacked_addon(addon_zip, tmp_path_factory):
    """The add-on zip unpacked as Blender does: <folder>/particlemesh/..."""
    folder = tmp_path_factory.mktemp("addon")
    with zipfile.ZipFile(addon_zip) as z:
        z.extractall(folder)
    return folder / "particlemesh"


BPY_FREE = ("mesh_arrays", "jobs", "generate")


@pytest.fixture(scope="session")
def addon(unpacked_addon):
    """The add-on's bpy-free modules as the zip ships them (with its own copy of the package
    in particlemesh/particlemesh), imported under a stand-in package name because the
    add-on's __init__ needs bpy."""
    name = "pm_addon_bpy_free"
    package = types.ModuleType(name)
    package.__path__ = [str(unpacked_addon)]
    sys.modules[name] = package
    modules = {m: importlib.import_module(f"{name}.{m}") for m in BPY_FREE}
    modules["pm"] = importlib.import_module(f"{name}.particlemesh")
    return types.SimpleNamespace(**modules)
