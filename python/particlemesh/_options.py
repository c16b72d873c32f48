"""Options structs as keyword arguments.

Each options struct of the C ABI (pm_triangulate_options, pm_polygonize_options,
pm_smooth_options) becomes keyword arguments named as its fields, with the library's own
defaults: the struct is filled by pm_<x>_options_init and only the keywords given (not None)
are written over it, so no default is repeated in Python. A field appended to the header
(and to _abi.py) is a keyword at once. Fields the Python function sets itself (struct_size,
the progress callback, flags and arrays) are not keywords; a few are renamed where the
field's name is taken by an argument (pm_triangulate_options.normals, the normals source,
is `normal_source` because `normals` is the particles' normals).

Values are checked before they reach C, since ctypes would silently wrap an out-of-range
integer: an unknown keyword or a value of the wrong type is a TypeError naming it, an integer
out of its field's range or an unknown enum name an Error (invalid argument) naming it. Enum
fields take the constant's name (case-insensitive, '-' or '_') or its integer value."""

import ctypes
import numbers

from . import _abi
from ._errors import Error

_INTEGER_RANGES = {
    ctypes.c_int32: (-2 ** 31, 2 ** 31 - 1),
    ctypes.c_uint32: (0, 2 ** 32 - 1),
    ctypes.c_int64: (-2 ** 63, 2 ** 63 - 1),
    ctypes.c_uint64: (0, 2 ** 64 - 1),
    ctypes.c_size_t: (0, 2 ** (8 * ctypes.sizeof(ctypes.c_size_t)) - 1),
}
_REALS = (ctypes.c_double, ctypes.c_float)


def enum_names(prefix):
    """{name: value} of the integer #defines PM_<prefix>_*: 'PM_KERNEL_POLY6' -> 'poly6',
    'PM_BOUNDARY_EDGE_AND_CORNER' -> 'edge-and-corner'."""
    out = {}
    for key, value in vars(_abi).items():
        if key.startswith(prefix) and isinstance(value, int) and not isinstance(value, bool):
            out[key[len(prefix):].lower().replace("_", "-")] = value
    return out


class OptionsSpec:
    """The keyword arguments of one options struct."""

    def __init__(self, function, struct, init, *, internal=(), renamed=None, enums=None):
        self.function = function  # the Python function's name, for messages
        self.struct = struct
        self.init = init          # name of pm_<x>_options_init
        self.internal = {"struct_size", "progress", "progress_user_data", *internal}
        self.renamed = dict(renamed or {})           # C field -> keyword
        self.enums = dict(enums or {})               # C field -> {name: value}
        self.fields = {name: ctype for name, ctype in struct._fields_}
        # keyword -> C field, in the struct's order
        self.keywords = {self.renamed.get(name, name): name
                         for name in self.fields if name not in self.internal}

    def new(self, lib):
        options = self.struct()
        getattr(lib, self.init)(ctypes.byref(options))
        return options

    def _enum_name(self, field, value):
        for name, v in self.enums[field].items():
            if v == value:
                return name
        return value

    def defaults(self, lib):
        """{keyword: the library's default}, enum fields by name."""
        options = self.new(lib)
        out = {}
        for keyword, field in self.keywords.items():
            value = getattr(options, field)
            out[keyword] = self._enum_name(field, value) if field in self.enums else value
        return out

    def build(self, lib, given):
        """A struct filled by the library's init, then with the keywords in `given` that are
        not None."""
        options = self.new(lib)
        for keyword, value in given.items():
            field = self.keywords.get(keyword)
            if field is None:
                raise TypeError(f"{self.function}() got an unexpected keyword argument "
                                f"'{keyword}'")
            if value is None:
                continue
            setattr(options, field, self.convert(keyword, field, value))
        return options

    def convert(self, keyword, field, value):
        ctype = self.fields[field]
        if field in self.enums:
            names = self.enums[field]
            if isinstance(value, str):
                key = value.strip().lower().replace("_", "-")
                if key not in names:
                    raise Error(f"{keyword} is '{value}'; it must be one of "
                                f"{', '.join(names)}", _abi.PM_STATUS_INVALID_ARGUMENT)
                return names[key]
            if isinstance(value, numbers.Integral) and not isinstance(value, bool):
                if int(value) not in names.values():
                    raise Error(f"{keyword} is {value}; it must be one of "
                                f"{', '.join(f'{n} ({v})' for n, v in names.items())}",
                                _abi.PM_STATUS_INVALID_ARGUMENT)
                return int(value)
            raise TypeError(f"{keyword} must be a name ({', '.join(names)}), not "
                            f"{type(value).__name__!r}")
        if ctype in _INTEGER_RANGES:
            if not isinstance(value, numbers.Integral):
                if isinstance(value, numbers.Real) and float(value).is_integer():
                    value = int(value)
                else:
                    raise TypeError(f"{keyword} must be an integer, not {type(value).__name__!r}")
            low, high = _INTEGER_RANGES[ctype]
            if not low <= int(value) <= high:
                raise Error(f"{keyword} is {value}; it must be {low}..{high}",
                            _abi.PM_STATUS_INVALID_ARGUMENT)
            return int(value)
        if ctype in _REALS:
            if not isinstance(value, numbers.Real):
                raise TypeError(f"{keyword} must be a number, not {type(value).__name__!r}")
            return float(value)
        raise TypeError(f"{self.struct.__name__}.{field} ({ctype.__name__}) cannot be given "
                        "as a keyword")  # a pointer field: the function must handle it


TRIANGULATE = OptionsSpec(
    "triangulate", _abi.pm_triangulate_options, "pm_triangulate_options_init",
    internal=("flags", "viewpoint"),  # raw=, repair=, orient=, local_spacing=, viewpoint=
    renamed={"normals": "normal_source"},
    enums={"normals": enum_names("PM_NORMALS_")})

POLYGONIZE = OptionsSpec(
    "polygonize", _abi.pm_polygonize_options, "pm_polygonize_options_init",
    internal=("flags", "domain_min", "cell_min", "cell_max"),  # domain_min=, cells=
    enums={"kernel": enum_names("PM_KERNEL_")})

SMOOTH = OptionsSpec(
    "smooth", _abi.pm_smooth_options, "pm_smooth_options_init",
    internal=("crease_count", "crease_edges", "crease_sharpness"),  # arrays: smooth() sets them
    enums={"scheme": enum_names("PM_SMOOTH_"), "boundary": enum_names("PM_BOUNDARY_"),
           "crease_method": enum_names("PM_CREASE_")})

PCL_PREPROCESS = OptionsSpec(  # the PCL bridge's: its init is libparticlemesh_pcl's
    "preprocess_scan", _abi.pm_pcl_preprocess_options, "pm_pcl_preprocess_options_init",
    internal=("viewpoint",),  # viewpoint=
    enums={"downsampling": enum_names("PM_PCL_DOWNSAMPLE_")})

SPECS = {spec.function: spec for spec in (TRIANGULATE, POLYGONIZE, SMOOTH, PCL_PREPROCESS)}
