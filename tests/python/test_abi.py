"""The ctypes mirror (python/particlemesh/_abi.py) agrees with the C headers, checked against
the compiler and the headers themselves, never by hand: every struct's size and alignment,
every field's name, order, offset, size and type, every constant's value, and every
function's argument and result types. A mismatch fails; nothing here skips."""
import ctypes
import os
import re
import subprocess
from ctypes import (POINTER, c_char_p, c_double, c_float, c_int, c_int32, c_int64, c_size_t,
                    c_uint32, c_uint64, c_void_p)

import pytest

import c_header

SCALARS = {"uint32_t": c_uint32, "int32_t": c_int32, "uint64_t": c_uint64, "int64_t": c_int64,
           "size_t": c_size_t, "double": c_double, "float": c_float, "int": c_int,
           "pm_status": c_int}
OPAQUE = {"pm_cloud", "pm_mesh", "pm_field", "pm_ray_hits", "pm_smoother", "pm_frame_collection"}


def expected_ctype(abi, structs, text, array=None):
    """The ctypes type a C type must be bound as."""
    if array is not None:
        return expected_ctype(abi, structs, text) * array
    if text == "void":
        return None
    special = {"char*": c_char_p, "char**": POINTER(c_char_p), "void*": c_void_p,
               "pm_progress_fn": abi.pm_progress_fn}
    if text in special:
        return special[text]
    base, stars = text.rstrip("*"), len(text) - len(text.rstrip("*"))
    if base in OPAQUE:  # handles are void pointers
        base_type, stars = c_void_p, stars - 1
    elif base in structs:
        base_type = getattr(abi, base)
    elif base in SCALARS:
        base_type = SCALARS[base]
    else:
        raise AssertionError(f"no ctypes mapping for the C type {text!r}: extend test_abi.py")
    for _ in range(stars):
        base_type = POINTER(base_type)
    return base_type


@pytest.fixture(scope="module")
def headers():
    return c_header.read_all()


@pytest.fixture(scope="module")
def layout():
    """What the compiler says: {('struct', name): (size, align), ('field', s, f): (offset,
    size), ('constant', name): value, ('type', name): size}."""
    program = os.environ.get("PM_ABI_LAYOUT")
    assert program and os.path.isfile(program), (
        "PM_ABI_LAYOUT must name the pm_abi_layout program built with the tests "
        f"(got {program!r}); run this suite through ctest")
    out = subprocess.run([program], capture_output=True, text=True, check=True).stdout
    result = {}
    for line in out.splitlines():
        kind, *rest = line.split()
        if kind == "struct":
            result[("struct", rest[0])] = (int(rest[1]), int(rest[2]))
        elif kind == "field":
            result[("field", rest[0], rest[1])] = (int(rest[2]), int(rest[3]))
        elif kind == "constant":
            result[("constant", rest[0])] = float(rest[1])
        elif kind == "type":
            result[("type", rest[0])] = int(rest[1])
    return result


def test_every_struct_has_the_compilers_layout(pm_abi, headers, layout):
    structs, _, _ = headers
    assert structs, "no struct read from the headers"
    for name, fields in structs.items():
        mirror = getattr(pm_abi, name, None)
        assert mirror is not None, f"_abi.py has no mirror of {name}"
        assert [f for f, _ in mirror._fields_] == [f for f, _, _ in fields], name
        size, align = layout[("struct", name)]
        assert (ctypes.sizeof(mirror), ctypes.alignment(mirror)) == (size, align), name
        for (field, ctype_text, array), (_, bound) in zip(fields, mirror._fields_):
            offset, field_size = layout[("field", name, field)]
            descriptor = getattr(mirror, field)
            assert (descriptor.offset, descriptor.size) == (offset, field_size), f"{name}.{field}"
            assert bound == expected_ctype(pm_abi, structs, ctype_text, array), f"{name}.{field}"


def test_every_constant_has_the_headers_value(pm_abi, headers, layout):
    _, constants, _ = headers
    assert "PM_ABI_VERSION" in constants and "PM_KERNEL_WYVILL" in constants
    for name in constants:
        assert hasattr(pm_abi, name), f"_abi.py has no {name}"
        assert getattr(pm_abi, name) == layout[("constant", name)], name
    assert ctypes.sizeof(c_int) == layout[("type", "pm_status")]
    assert ctypes.sizeof(pm_abi.pm_progress_fn) == layout[("type", "pm_progress_fn")]


def test_the_header_reader_finds_every_exported_function():
    """Every PM_EXPORT / PM_PCL_EXPORT prototype is read (the reader cannot miss one
    silently)."""
    for path in c_header.HEADERS:
        text = c_header._strip_comments(path.read_text())
        exported = len(re.findall(r"^\s*PM_(?:PCL_)?EXPORT\s", text, re.M))
        assert exported == len(c_header.Header(path).functions) > 0, path.name


def test_every_function_has_the_headers_signature(pm_abi, headers):
    structs, _, functions = headers
    bound = {**pm_abi.FUNCTIONS, **pm_abi.PCL_FUNCTIONS}
    assert set(bound) == set(functions), (set(functions) - set(bound), set(bound) - set(functions))
    for name, (result, params) in functions.items():
        restype, argtypes = bound[name]
        assert restype == expected_ctype(pm_abi, structs, result), name
        assert argtypes == [expected_ctype(pm_abi, structs, p) for p in params], name


def test_the_loaded_library_has_every_signature_declared(pm, pm_abi, pm_library):
    lib = pm_library.load()
    assert lib.abi_version == pm_abi.PM_ABI_VERSION
    for name, (restype, argtypes) in pm_abi.FUNCTIONS.items():
        fn = getattr(lib, name)
        assert (fn.restype, fn.argtypes) == (restype, argtypes), name


def test_every_options_field_is_a_keyword_or_set_by_the_binding(pm, pm_options):
    """A field appended to an options struct becomes a keyword with the library's default;
    only the fields the functions fill themselves are not keywords."""
    set_by_binding = {
        "triangulate": {"struct_size", "progress", "progress_user_data", "flags", "viewpoint"},
        "polygonize": {"struct_size", "progress", "progress_user_data", "flags", "domain_min",
                       "cell_min", "cell_max"},
        "smooth": {"struct_size", "progress", "progress_user_data", "crease_count",
                   "crease_edges", "crease_sharpness"},
        "preprocess_scan": {"struct_size", "viewpoint"},
    }
    for function, spec in pm_options.SPECS.items():
        if function == "preprocess_scan" and os.environ.get("PM_WITH_PCL") != "1":
            continue  # its defaults come from the PCL bridge
        fields = [f for f, _ in spec.struct._fields_]
        assert set(spec.keywords.values()) == set(fields) - set_by_binding[function], function
        defaults = pm.defaults(function)
        assert list(defaults) == list(spec.keywords), function
        for keyword, field in spec.keywords.items():
            ctype = spec.fields[field]
            assert ctype in (c_double, c_float, c_int32, c_uint32, c_int64, c_uint64, c_size_t), (
                f"{function}: {field} is no plain number: give it a keyword of its own")
