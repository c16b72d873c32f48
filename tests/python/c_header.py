"""A reader of the C ABI headers (particlemesh.h, particlemesh_pcl_c.h) for the binding's
layout test: structs and their fields with types, #define and enum constants, and the
exported functions' prototypes. The headers are written in a plain style (one typedef'd
struct per block, PM_EXPORT prototypes); anything this reader does not understand raises,
so a new construct fails the test instead of slipping past it."""
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HEADERS = [ROOT / "native/include/particlemesh/particlemesh.h",
           ROOT / "pcl_bridge/include/particlemesh_pcl/particlemesh_pcl_c.h"]


def _strip_comments(text):
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    return re.sub(r"//[^\n]*", " ", text)


def _type(text):
    """'const double *' -> 'double*' (const dropped, no spaces before stars)."""
    t = re.sub(r"\bconst\b", " ", text)
    t = re.sub(r"\s*\*\s*", "*", t)
    return " ".join(t.split())


class Header:
    def __init__(self, path):
        self.path = Path(path)
        raw = self.path.read_text()
        text = _strip_comments(raw)
        self.structs = {}    # name -> [(field, type, array length or None)]
        self.constants = {}  # name -> int or float
        self.functions = {}  # name -> (return type, [parameter types])
        for m in re.finditer(r"typedef\s+struct\s+(\w+)\s*\{(.*?)\}\s*(\w+)\s*;", text, re.S):
            if m.group(1) != m.group(3):
                raise ValueError(f"{path}: typedef struct {m.group(1)} is named {m.group(3)}")
            self.structs[m.group(1)] = self._fields(m.group(1), m.group(2))
        for m in re.finditer(r"typedef\s+enum\s+(\w+)\s*\{(.*?)\}\s*(\w+)\s*;", text, re.S):
            for item in m.group(2).split(","):
                if item.strip():
                    name, value = (s.strip() for s in item.split("="))
                    self.constants[name] = int(value, 0)
        for m in re.finditer(r"^\s*#\s*define\s+(PM_\w+)[ \t]+([^\n]+)$", text, re.M):
            value = m.group(2).strip()
            number = re.fullmatch(r"(0[xX][0-9a-fA-F]+|\d+)[uU]?", value)
            real = re.fullmatch(r"(\d+\.\d*)[fF]?", value)
            if number:
                self.constants[m.group(1)] = int(number.group(1), 0)
            elif real:
                self.constants[m.group(1)] = float(real.group(1))
            elif not value.startswith("__"):  # PM_EXPORT's attribute, not a constant
                raise ValueError(f"{path}: cannot read #define {m.group(1)} {value}")
        exports = re.findall(r"PM_(?:PCL_)?EXPORT\s+([^;]*?)\s*\(([^;]*?)\)\s*;", text, re.S)
        for head, params in exports:
            if head.startswith("__") or "define" in head:
                continue
            m = re.fullmatch(r"(.*?[\s*])(\w+)", " ".join(head.split()))
            if not m:
                raise ValueError(f"{path}: cannot read the prototype {head}({params})")
            args = [] if params.strip() == "void" else [self._param(p) for p in params.split(",")]
            self.functions[m.group(2)] = (_type(m.group(1)), args)

    @staticmethod
    def _param(text):
        m = re.fullmatch(r"(.*?[\s*])(\w+)", " ".join(text.split()))
        if not m:
            raise ValueError(f"cannot read the parameter {text!r}")
        return _type(m.group(1))

    @staticmethod
    def _fields(struct, body):
        fields = []
        for decl in body.split(";"):
            decl = " ".join(decl.split())
            if not decl:
                continue
            m = re.fullmatch(r"((?:const )?\w+(?: ?\*+ ?| ))(\w+(?:\[\d+\])?(?:, ?\w+(?:\[\d+\])?)*)",
                             decl)
            if not m:
                raise ValueError(f"{struct}: cannot read the field declaration {decl!r}")
            ctype = _type(m.group(1))
            for name in m.group(2).split(","):
                name = name.strip()
                array = re.fullmatch(r"(\w+)\[(\d+)\]", name)
                if array:
                    fields.append((array.group(1), ctype, int(array.group(2))))
                else:
                    fields.append((name, ctype, None))
        return fields


def read_all():
    """(structs, constants, functions) of every header, merged."""
    structs, constants, functions = {}, {}, {}
    for path in HEADERS:
        h = Header(path)
        structs.update(h.structs)
        constants.update(h.constants)
        functions.update(h.functions)
    return structs, constants, functions
