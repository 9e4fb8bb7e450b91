"""Reading back the meshes ``splash recon`` and ``Mesh.write`` write, as numpy arrays.

OBJ (``v``, ``vn``, ``f a//a``), PLY (binary either byte order, or ascii; ``float x y z``,
optional ``nx ny nz`` and attribute properties, triangle ``vertex_indices``) and VTK XML
(``.vtu``, ``.vtp``: binary, zlib-compressed or raw, ``UInt32`` or ``UInt64`` headers).
Whole arrays are decoded at once by numpy: no Python loop runs per vertex or per line, so
a frame of a million triangles reads in well under a second. Every size is checked against
the file's length before anything is allocated from it, and errors name the file.

Only what these writers produce is read: faces must be triangles, and other elements,
cells and arrays are refused or skipped as the messages say.
"""

import base64
import os
import re
import warnings
import zlib
from typing import NamedTuple
from xml.etree import ElementTree

import numpy as np

__all__ = ["MESH_EXTENSIONS", "MeshArrays", "read_mesh"]

#: The extensions ``read_mesh`` reads.
MESH_EXTENSIONS = (".obj", ".ply", ".vtu", ".vtp")


class MeshArrays(NamedTuple):
    """A triangle mesh read from a file."""

    #: Vertex positions, shape (V, 3), float32.
    vertices: np.ndarray
    #: Triangles as vertex indices, shape (F, 3), uint32.
    faces: np.ndarray
    #: Unit vertex normals, shape (V, 3), float32; shape (0, 3) when the file has none.
    normals: np.ndarray
    #: Per-vertex attributes by name (``velocity``: shape (V, 3); scalars: shape (V,)),
    #: float32.
    attributes: dict[str, np.ndarray]


def read_mesh(path) -> MeshArrays:
    """Reads a mesh written by ``splash recon`` or ``Mesh.write``: ``.obj``, ``.ply``,
    ``.vtu`` or ``.vtp`` (by extension).

    PLY properties ``vx vy vz`` become the attribute ``velocity``, ``{name}_x {name}_y
    {name}_z`` the vector ``{name}``, other vertex properties scalars; VTK point data arrays
    keep their names (``Normals`` are the normals). Raises FileNotFoundError for a missing
    file, OSError when it cannot be read, and ValueError naming the file when its content is
    not such a mesh.
    """
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower()
    readers = {".obj": _read_obj, ".ply": _read_ply, ".vtu": _read_vtk_xml, ".vtp": _read_vtk_xml}
    if ext not in readers:
        raise ValueError(
            f"{path}: cannot tell the mesh format from the extension: "
            f"expected one of {', '.join(MESH_EXTENSIONS)}"
        )
    with open(path, "rb") as f:
        data = f.read()
    try:
        mesh = readers[ext](data)
    except _Bad as e:
        raise ValueError(f"{path}: {e}") from None
    _check(mesh)
    return mesh


class _Bad(Exception):
    """What is wrong with a file; read_mesh adds its name."""


def _check(mesh: MeshArrays) -> None:
    n = len(mesh.vertices)
    if len(mesh.faces) and int(mesh.faces.max()) >= n:
        raise _Bad(f"a triangle refers to vertex {int(mesh.faces.max())} of {n}")
    if len(mesh.normals) not in (0, n):
        raise _Bad(f"{len(mesh.normals)} normals for {n} vertices")
    if not np.isfinite(mesh.vertices).all():
        raise _Bad("a vertex has a non-finite coordinate")


def _mesh(vertices, faces, normals, attributes) -> MeshArrays:
    vertices = np.ascontiguousarray(vertices, dtype=np.float32).reshape(-1, 3)
    faces = np.asarray(faces)
    if faces.size and (faces.min() < 0):
        raise _Bad("a triangle has a negative vertex index")
    faces = np.ascontiguousarray(faces, dtype=np.uint32).reshape(-1, 3)
    normals = (
        np.zeros((0, 3), np.float32)
        if normals is None
        else np.ascontiguousarray(normals, dtype=np.float32).reshape(-1, 3)
    )
    attributes = {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in attributes.items()}
    for name, values in attributes.items():
        if len(values) != len(vertices):
            raise _Bad(f"{len(values)} values of '{name}' for {len(vertices)} vertices")
    mesh = MeshArrays(vertices, faces, normals, attributes)
    _check(mesh)
    return mesh


# --- OBJ -------------------------------------------------------------------------------------


_OBJ_V = re.compile(rb"^v[ \t]+(\S+)[ \t]+(\S+)[ \t]+(\S+)[ \t]*\r?$", re.MULTILINE)
_OBJ_VN = re.compile(rb"^vn[ \t]+(\S+)[ \t]+(\S+)[ \t]+(\S+)[ \t]*\r?$", re.MULTILINE)
# A corner is `a`, `a//n` or `a/t/n`: its vertex index is the first number.
_OBJ_F = re.compile(rb"^f[ \t]+(\d+)\S*[ \t]+(\d+)\S*[ \t]+(\d+)\S*[ \t]*\r?$", re.MULTILINE)


def _obj_lines(data: bytes, pattern, keyword: bytes, what: str, dtype) -> np.ndarray:
    """The numbers of every `keyword` line, three per line (the first number of each corner
    for `f`), decoded by numpy at once. `data` starts with a line break."""
    tag = b"\n" + keyword + b" "
    lines = data.count(tag) + data.count(b"\n" + keyword + b"\t")
    if lines == 0:
        return np.zeros((0, 3), dtype)
    first, last = data.find(tag), data.rfind(tag)
    block = data[first + 1 : data.find(b"\n", last + 1) % (len(data) + 1)]
    if first >= 0 and block.count(b"\n") + 1 == lines:
        numbers = _block_numbers(block.replace(tag, b"\n ")[len(keyword) :], lines, dtype)
        if numbers is not None:
            return numbers
    rows = pattern.findall(data)
    if len(rows) != lines:
        raise _Bad(f"{lines - len(rows)} of the {lines} '{what}' lines do not hold 3 numbers")
    try:
        return np.array(rows, dtype=np.bytes_).astype(dtype)
    except ValueError:
        raise _Bad(f"a '{what}' line holds something other than numbers") from None


def _block_numbers(block: bytes, lines: int, dtype):
    """The (lines, 3) numbers of a block of `lines` lines of three words each, `a` or `a//n`
    (splash's `f` lines) parsed by numpy at once; None when the block is not that regular,
    for the line-by-line parse to judge."""
    b = np.frombuffer(block, np.uint8)
    newline = b == ord("\n")
    gap = newline | (b == ord(" ")) | (b == ord("\t")) | (b == ord("\r"))
    starts = ~gap & np.concatenate(([True], gap[:-1]))
    words = np.bincount(np.cumsum(newline)[starts], minlength=lines)
    if len(words) != lines or (words != 3).any():
        return None
    pairs = block.count(b"//")
    if pairs not in (0, 3 * lines) or block.count(b"/") != 2 * pairs:
        return None
    with warnings.catch_warnings():
        # numpy 1.x warns, 2.x raises, when the text does not parse to its end.
        warnings.simplefilter("error", DeprecationWarning)
        try:
            numbers = np.fromstring(block.replace(b"//", b" "), dtype=dtype, sep=" ")
        except (ValueError, DeprecationWarning):
            return None
    per_line = 6 if pairs else 3
    if numbers.size != per_line * lines:
        return None
    return numbers.reshape(lines, per_line)[:, :: per_line // 3]


def _read_obj(data: bytes) -> MeshArrays:
    data = b"\n" + data
    vertices = _obj_lines(data, _OBJ_V, b"v", "v", np.float32)
    normals = _obj_lines(data, _OBJ_VN, b"vn", "vn", np.float32)
    faces = _obj_lines(data, _OBJ_F, b"f", "f (triangle)", np.int64) - 1
    if len(normals) not in (0, len(vertices)):
        raise _Bad(
            f"{len(normals)} 'vn' lines for {len(vertices)} 'v' lines: splash writes one "
            "normal per vertex"
        )
    return _mesh(vertices, faces, normals if len(normals) else None, {})


# --- PLY -------------------------------------------------------------------------------------

_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}  # fmt: skip


def _read_ply(data: bytes) -> MeshArrays:
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise _Bad("not a PLY file (no 'ply' line or no 'end_header')")
    body = data.index(b"\n", end) + 1
    encoding, elements = None, []
    for line in data[:end].decode("ascii", "replace").splitlines()[1:]:
        words = line.split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format" and len(words) == 3:
            encoding = words[1]
        elif words[0] == "element" and len(words) == 3 and words[2].isdigit():
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property" and elements and len(words) >= 3:
            props = elements[-1][2]
            if words[1] == "list" and len(words) == 5:
                props.append((words[4], words[2], words[3]))
            elif len(words) == 3:
                props.append((words[2], words[1], None))
            else:
                raise _Bad(f"malformed PLY header line '{line[:60]}'")
            if any(t not in _PLY_TYPES for t in props[-1][1:] if t):
                raise _Bad(f"unknown PLY type in '{line[:60]}'")
        else:
            raise _Bad(f"malformed PLY header line '{line[:60]}'")
    if encoding not in ("binary_little_endian", "binary_big_endian", "ascii"):
        raise _Bad("the PLY header has no valid 'format' line")
    names = [e[0] for e in elements]
    if names != ["vertex", "face"] and names != ["vertex"]:
        raise _Bad(f"expected the elements 'vertex' and 'face', found {', '.join(names)}")
    (_, n, vprops), (_, t, fprops) = elements[0], (elements + [("face", 0, [])])[1]
    if any(p[2] for p in vprops):
        raise _Bad("a vertex has a list property: not a splash mesh")
    if t and (len(fprops) != 1 or fprops[0][0] != "vertex_indices" or fprops[0][2] is None):
        raise _Bad("faces must have the single list property 'vertex_indices'")
    if len({p[0] for p in vprops}) != len(vprops):
        raise _Bad("two vertex properties have the same name")
    if encoding == "ascii":
        vertex_table, faces = _ply_ascii(data[body:], n, len(vprops), t)
        columns = {p[0]: vertex_table[:, i] for i, p in enumerate(vprops)}
    else:
        order = "<" if encoding == "binary_little_endian" else ">"
        vdtype = np.dtype([(p[0], order + _PLY_TYPES[p[1]]) for p in vprops])
        if n * vdtype.itemsize > len(data) - body:
            raise _Bad(f"the file is too short for its {n} vertices")
        vertex_table = np.frombuffer(data, vdtype, n, body)
        columns = {name: vertex_table[name] for name in vdtype.names or ()}
        faces = np.zeros((0, 3), np.int64)
        if t:
            _, count_type, index_type = fprops[0]
            fdtype = np.dtype(
                [("n", order + _PLY_TYPES[count_type]), ("i", order + _PLY_TYPES[index_type], 3)]
            )
            start = body + n * vdtype.itemsize
            if t * fdtype.itemsize > len(data) - start:
                raise _Bad(f"the file is too short for its {t} triangles (or a face is not one)")
            table = np.frombuffer(data, fdtype, t, start)
            if (table["n"] != 3).any():
                raise _Bad("a face is not a triangle")
            faces = table["i"]
    for axis in "xyz":
        if axis not in columns:
            raise _Bad(f"the vertices have no '{axis}' property")
    vertices = np.stack([columns.pop(a) for a in "xyz"], axis=1)
    normals = None
    if all(k in columns for k in ("nx", "ny", "nz")):
        normals = np.stack([columns.pop(k) for k in ("nx", "ny", "nz")], axis=1)
    attributes = {}
    if all(k in columns for k in ("vx", "vy", "vz")):
        attributes["velocity"] = np.stack([columns.pop(k) for k in ("vx", "vy", "vz")], axis=1)
    for name in [k[:-2] for k in list(columns) if k.endswith("_x")]:
        keys = [f"{name}_{a}" for a in "xyz"]
        if all(k in columns for k in keys):
            attributes[name] = np.stack([columns.pop(k) for k in keys], axis=1)
    attributes.update(columns)
    return _mesh(vertices, faces, normals, attributes)


def _ply_ascii(body: bytes, n: int, width: int, t: int):
    lines = body.split(b"\n", n + t)
    if len(lines) < n + t:
        raise _Bad(f"the file is too short for its {n} vertices and {t} faces")
    try:
        table = np.array(b" ".join(lines[:n]).split(), dtype=np.float64)
        faces = np.array(b" ".join(lines[n : n + t]).split(), dtype=np.int64)
    except ValueError:
        raise _Bad("a vertex or face line holds something other than numbers") from None
    if table.size != n * width or faces.size != 4 * t:
        raise _Bad("a vertex line has the wrong number of values, or a face is not a triangle")
    faces = faces.reshape(t, 4)
    if t and (faces[:, 0] != 3).any():
        raise _Bad("a face is not a triangle")
    return table.reshape(n, width), faces[:, 1:]


# --- VTK XML ---------------------------------------------------------------------------------

_VTK_TYPES = {
    "Int8": "i1", "UInt8": "u1", "Int16": "i2", "UInt16": "u2", "Int32": "i4",
    "UInt32": "u4", "Int64": "i8", "UInt64": "u8", "Float32": "f4", "Float64": "f8",
}  # fmt: skip


def _read_vtk_xml(data: bytes) -> MeshArrays:
    if b'format="appended"' in data:
        raise _Bad('appended VTK XML data is not read here: splash writes format="binary"')
    try:
        root = ElementTree.fromstring(data)
    except ElementTree.ParseError as e:
        raise _Bad(f"not a VTK XML file ({e})") from None
    if root.tag != "VTKFile":
        raise _Bad("not a VTK XML file (no VTKFile element)")
    order = "<" if root.get("byte_order", "LittleEndian") == "LittleEndian" else ">"
    header = order + ("u8" if root.get("header_type") == "UInt64" else "u4")
    compressed = root.get("compressor") == "vtkZLibDataCompressor"
    if root.get("compressor") not in (None, "vtkZLibDataCompressor"):
        raise _Bad(f"the compressor {root.get('compressor')} is not read here (zlib only)")
    pieces = root.findall("./*/Piece")
    if len(pieces) != 1:
        raise _Bad(f"expected one Piece, found {len(pieces)}")
    piece = pieces[0]
    n = int(piece.get("NumberOfPoints", "0"))

    def array(node, what, components=None):
        if node is None:
            raise _Bad(f"no {what} array")
        if node.get("format") != "binary":
            raise _Bad(f'the {what} array is not format="binary"')
        ty = _VTK_TYPES.get(node.get("type", ""))
        if ty is None:
            raise _Bad(f"the {what} array has an unknown type {node.get('type')}")
        raw = _vtk_binary(node.text or "", header, compressed, what)
        values = np.frombuffer(raw, order + ty)
        k = int(node.get("NumberOfComponents", "1"))
        if components is not None and k != components:
            raise _Bad(f"the {what} array has {k} components, expected {components}")
        if values.size % k:
            raise _Bad(f"the {what} array's length is not a multiple of its components")
        return values.reshape(-1, k) if k > 1 else values

    vertices = array(piece.find("Points/DataArray"), "Points", 3)
    if len(vertices) != n:
        raise _Bad(f"{len(vertices)} points for NumberOfPoints {n}")
    cells = piece.find("Cells") if piece.find("Cells") is not None else piece.find("Polys")
    faces = np.zeros((0, 3), np.int64)
    if cells is not None:
        by_name = {a.get("Name"): a for a in cells.findall("DataArray")}
        connectivity = array(by_name.get("connectivity"), "connectivity", 1)
        offsets = array(by_name.get("offsets"), "offsets", 1)
        if len(offsets) * 3 != len(connectivity) or (
            len(offsets) and (np.diff(offsets, prepend=0) != 3).any()
        ):
            raise _Bad("a cell is not a triangle")
        if "types" in by_name and (array(by_name["types"], "types", 1) != 5).any():
            raise _Bad("a cell is not a triangle (VTK type 5)")
        faces = connectivity.reshape(-1, 3)
    normals, attributes = None, {}
    for node in piece.findall("PointData/DataArray"):
        name = node.get("Name", "")
        values = array(node, f"point data '{name}'")
        if name == "Normals":
            normals = values
        else:
            attributes[name] = values
    return _mesh(vertices, faces, normals, attributes)


def _vtk_binary(text: str, header: str, compressed: bool, what: str) -> bytes:
    """The bytes of one `format="binary"` array: base64 of a header then of the data (VTK
    encodes the two separately when compressed, together when not)."""
    text = "".join(text.split())
    word = np.dtype(header).itemsize
    try:
        if not compressed:
            raw = base64.b64decode(text)
            size = int(np.frombuffer(raw[:word], header)[0])
            if size > len(raw) - word:
                raise _Bad(f"the {what} array is shorter than its header says")
            return raw[word : word + size]
        first = base64.b64decode(text[: 4 * -(-3 * word // 3)])[: 3 * word]
        blocks, block, last = (int(x) for x in np.frombuffer(first, header, 3))
        head_bytes = (3 + blocks) * word
        head_chars = 4 * -(-head_bytes // 3)
        if head_chars > len(text):
            raise _Bad(f"the {what} array is shorter than its header says")
        sizes = np.frombuffer(base64.b64decode(text[:head_chars])[:head_bytes], header)[3:]
        payload = base64.b64decode(text[head_chars:])
    except (ValueError, IndexError, base64.binascii.Error):
        raise _Bad(f"the {what} array is not valid base64 binary data") from None
    if int(sizes.sum()) > len(payload):
        raise _Bad(f"the {what} array is shorter than its header says")
    out, start = [], 0
    for k, size in enumerate(sizes.tolist()):
        expected = last if (k == blocks - 1 and last) else block
        inflater = zlib.decompressobj()
        try:
            chunk = inflater.decompress(payload[start : start + size], expected)
        except zlib.error:
            raise _Bad(f"the {what} array's compressed data is corrupt") from None
        if len(chunk) != expected:
            raise _Bad(f"the {what} array inflates to another size than its header says")
        out.append(chunk)
        start += size
    return b"".join(out)
