"""The exceptions of the particlemesh package."""

from . import _abi

_STATUS_NAMES = {
    _abi.PM_OK: "ok",
    _abi.PM_STATUS_INVALID_ARGUMENT: "invalid argument",
    _abi.PM_STATUS_INVALID_INPUT: "invalid input",
    _abi.PM_STATUS_IO_ERROR: "I/O error",
    _abi.PM_STATUS_FORMAT_ERROR: "format error",
    _abi.PM_STATUS_OUT_OF_MEMORY: "out of memory",
    _abi.PM_STATUS_CANCELLED: "cancelled",
    _abi.PM_STATUS_LIMIT_EXCEEDED: "limit exceeded",
    _abi.PM_STATUS_INTERNAL: "internal error",
}


class Error(Exception):
    """A particlemesh call failed. str(e) is the library's message (it names the argument, the
    point index or the file); `status` is the C ABI's pm_status (see the STATUS_* constants)."""

    def __init__(self, message, status=_abi.PM_STATUS_INTERNAL):
        super().__init__(message)
        self.status = status

    @property
    def status_name(self):
        return _STATUS_NAMES.get(self.status, f"status {self.status}")


class CancelledError(Error):
    """The call was cancelled: the progress callback returned False, or Progress.cancel() was
    called (from any thread). Ctrl-C raises KeyboardInterrupt instead."""

    def __init__(self, message="cancelled"):
        super().__init__(message, _abi.PM_STATUS_CANCELLED)


class LibraryNotFoundError(Error):
    """The native library libparticlemesh could not be found or loaded (the message says where
    it was looked for and why it did not load)."""

    def __init__(self, message):
        super().__init__(message, _abi.PM_STATUS_IO_ERROR)


class PclBridgeNotFoundError(Error):
    """Reading .pcd needs the PCL bridge library (libparticlemesh_pcl), which could not be
    found or loaded; everything else works without it."""

    def __init__(self, message):
        super().__init__(message, _abi.PM_STATUS_IO_ERROR)


class NotReadWarning(UserWarning):
    """read_points found data per particle in the file that it does not read (a string
    attribute, a list property, a LAS file's other fields), or read_mesh data the mesh does
    not carry (texture coordinates, face properties); the message names it, and the Points'
    info["not_read"] (the Mesh's stats["not_read"]) lists it. Silence it with warnings.simplefilter("ignore",
    NotReadWarning)."""


class NotWrittenWarning(UserWarning):
    """write_mesh wrote a format that cannot hold some of the mesh's channels (an .obj holds a
    colour per vertex only); the message names them."""
