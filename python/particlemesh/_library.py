"""Finding and loading the native libraries, with every signature declared.

libparticlemesh is looked for, in order: $PARTICLEMESH_LIBRARY (a file); the package's own
lib/ folder (the Blender add-on's zip, `pip install`, `cmake --install`); the system's library
path (ctypes.util.find_library). It is loaded on the first call, not on import, so that
`import particlemesh` always works and a missing library is one clear message naming where it
was looked for.

.pcd files are read by the PCL bridge, libparticlemesh_pcl, loaded on the first .pcd:
$PARTICLEMESH_PCL_LIBRARY, else next to the loaded libparticlemesh, the package's lib/ and the
system's library path. It binds to the libparticlemesh already loaded (the dynamic loader
matches its soname)."""

import ctypes
import ctypes.util
import glob
import os
import sys
import threading

from . import _abi
from ._errors import Error, LibraryNotFoundError, PclBridgeNotFoundError

LIBRARY_ENV = "PARTICLEMESH_LIBRARY"
PCL_LIBRARY_ENV = "PARTICLEMESH_PCL_LIBRARY"

#: The package's own folder of native libraries.
LIB_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib")


def _file_patterns(stem):
    if sys.platform == "win32":
        return [f"{stem}.dll"]
    if sys.platform == "darwin":
        return [f"lib{stem}.dylib", f"lib{stem}.*.dylib"]
    return [f"lib{stem}.so", f"lib{stem}.so.*"]


def _in_folders(stem, folders):
    paths = []
    for folder in dict.fromkeys(folders):
        for pattern in _file_patterns(stem):
            paths.extend(sorted(glob.glob(os.path.join(folder, pattern))))
    return paths


def _declare(cdll, table, path, error):
    missing = [name for name in table if not hasattr(cdll, name)]
    if missing:
        raise error(f"{path} is not a usable library for this particlemesh package "
                    f"(missing {', '.join(missing)}); install the matching build")
    for name, (restype, argtypes) in table.items():
        fn = getattr(cdll, name)
        fn.restype = restype
        fn.argtypes = argtypes


class Library:
    """libparticlemesh, loaded, with every function of particlemesh.h declared
    (_abi.FUNCTIONS) and its ABI version checked. Functions are its attributes (lib.pm_...)."""

    def __init__(self, path):
        try:
            cdll = ctypes.CDLL(path)
        except OSError as e:
            raise LibraryNotFoundError(f"cannot load the particlemesh library {path}: {e}") from e
        _declare(cdll, _abi.FUNCTIONS, path, LibraryNotFoundError)
        abi = int(cdll.pm_abi_version())
        if abi != _abi.PM_ABI_VERSION:
            raise LibraryNotFoundError(
                f"{path} has particlemesh ABI version {abi}; this package needs version "
                f"{_abi.PM_ABI_VERSION} (install the matching build)")
        self.cdll = cdll
        self.path = path
        self.abi_version = abi
        self.version = cdll.pm_version_string().decode()
        for name in _abi.FUNCTIONS:
            setattr(self, name, getattr(cdll, name))

    def check(self, status):
        """Raise the library's error for a non-OK pm_status."""
        if status == _abi.PM_OK:
            return
        message = self.pm_last_error_message().decode(errors="replace")
        if not message:
            message = self.pm_status_string(status).decode()
        if status == _abi.PM_STATUS_CANCELLED:
            from ._errors import CancelledError
            raise CancelledError(message)
        raise Error(message, status)


class PclBridge:
    """libparticlemesh_pcl with its functions declared and its ABI version checked."""

    def __init__(self, path):
        try:
            cdll = ctypes.CDLL(path)
        except OSError as e:
            raise PclBridgeNotFoundError(
                "reading .pcd and preprocess_scan need the PCL bridge library, and "
                f"{path} does not load: {e} "
                f"(it needs PCL 1.13's libraries, e.g. Debian's libpcl-io1.13)") from e
        _declare(cdll, _abi.PCL_FUNCTIONS, path, PclBridgeNotFoundError)
        abi = int(cdll.pm_pcl_abi_version())
        if abi != _abi.PM_PCL_ABI_VERSION:
            raise PclBridgeNotFoundError(
                f"{path} has PCL bridge ABI version {abi}; this package needs version "
                f"{_abi.PM_PCL_ABI_VERSION}")
        self.cdll = cdll
        self.path = path
        self.abi_version = abi
        for name in _abi.PCL_FUNCTIONS:
            setattr(self, name, getattr(cdll, name))


def candidate_paths():
    """Where libparticlemesh is looked for, in order."""
    env = os.environ.get(LIBRARY_ENV)
    if env:
        return [env]
    paths = _in_folders("particlemesh", [LIB_DIR])
    system = ctypes.util.find_library("particlemesh")
    if system:
        paths.append(system)
    return paths


def _load_first(paths, make, error, not_found):
    errors = []
    for candidate in paths:
        if os.sep in candidate and not os.path.exists(candidate):
            errors.append(f"{candidate} does not exist")
            continue
        try:
            return make(candidate)
        except error as e:
            errors.append(str(e))
    raise error("; ".join(errors) if errors else not_found)


_lock = threading.Lock()
_library = None
_bridges = {}


def load(path=None):
    """The loaded libparticlemesh (loaded once). `path` loads that file instead (not cached)."""
    global _library
    if path is not None:
        return Library(os.fspath(path))
    with _lock:
        if _library is None:
            _library = _load_first(
                candidate_paths(), Library, LibraryNotFoundError,
                f"the particlemesh native library was not found (looked in {LIB_DIR} and the "
                f"system library path; set {LIBRARY_ENV} to the library file)")
        return _library


def pcl_candidate_paths(core_path):
    """(paths, folders looked in) for the PCL bridge."""
    env = os.environ.get(PCL_LIBRARY_ENV)
    if env:
        return [env], []
    folders = []
    if core_path and os.sep in core_path:
        folders.append(os.path.dirname(os.path.abspath(core_path)))
    folders.append(LIB_DIR)
    paths = _in_folders("particlemesh_pcl", folders)
    system = ctypes.util.find_library("particlemesh_pcl")
    if system:
        paths.append(system)
    return paths, folders


def load_pcl(path=None):
    """The loaded PCL bridge (once per core library); PclBridgeNotFoundError saying what .pcd
    needs and where it was looked for when it is absent or does not load."""
    core = load()
    if path is not None:
        return PclBridge(os.fspath(path))
    with _lock:
        if core.path not in _bridges:
            paths, folders = pcl_candidate_paths(core.path)
            _bridges[core.path] = _load_first(
                paths, PclBridge, PclBridgeNotFoundError,
                "reading .pcd and preprocess_scan need the PCL bridge library "
                "libparticlemesh_pcl, which was not "
                f"found (looked in {', '.join(folders)} and the system library path; set "
                f"{PCL_LIBRARY_ENV} to the library file)")
        return _bridges[core.path]
