#!/usr/bin/env python3
"""Regenerates fixtures/formats/: one small particle set in every input format splash reads,
each file written by an independent tool (never by splash), for the reader tests.

The particles are every 23rd vertex of fixtures/frame_0010.ply (a SPlisHSPlasH frame; 1 916
particles) with its velocity (vx vy vz), density, and id = the vertex's index in the frame.

Tools (pip install into a throwaway venv): vtk (9.7.2: legacy VTK and XML VTU/VTP writers,
every encoding), meshio (5.3.5: reads the source PLY), pysplashsurf (0.14.1.0: splashsurf's
`convert`, which writes BGEO). The SPlisHSPlasH-style VTK file is written here with struct,
byte for byte as SPlisHSPlasH's VTK exporter lays it out (binary big-endian UNSTRUCTURED_GRID,
vertex cells, FIELD point data `id velocity density`), and the raw `.xyz` with numpy's tofile.

    python3 -m venv /tmp/v && /tmp/v/bin/pip install vtk meshio pysplashsurf
    /tmp/v/bin/python scripts/make-format-fixtures.py
"""
import gzip
import os
import struct
import sys

import meshio
import numpy as np
import vtk
from vtk.util.numpy_support import numpy_to_vtk

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "fixtures", "formats")
STEP = 23

src = meshio.read(os.path.join(ROOT, "fixtures", "frame_0010.ply"))
idx = np.arange(0, len(src.points), STEP)
pos = np.asarray(src.points, dtype=np.float32)[idx]
vel = np.stack([np.asarray(src.point_data[k], dtype=np.float32)[idx] for k in ("vx", "vy", "vz")], axis=1)
density = np.asarray(src.point_data["density"], dtype=np.float32)[idx]
ids = idx.astype(np.int32)
n = len(pos)
os.makedirs(OUT, exist_ok=True)


def path(name):
    return os.path.join(OUT, name)


def array(values, name):
    a = numpy_to_vtk(np.ascontiguousarray(values), deep=True)
    a.SetName(name)
    return a


def dataset(kind, positions):
    points = vtk.vtkPoints()
    points.SetData(numpy_to_vtk(np.ascontiguousarray(positions), deep=True))
    verts = vtk.vtkCellArray()
    for i in range(n):
        verts.InsertNextCell(1)
        verts.InsertCellPoint(i)
    if kind == "poly":
        d = vtk.vtkPolyData()
        d.SetPoints(points)
        d.SetVerts(verts)
    else:
        d = vtk.vtkUnstructuredGrid()
        d.SetPoints(points)
        d.SetCells(vtk.VTK_VERTEX, verts)
    d.GetPointData().AddArray(array(vel, "velocity"))
    d.GetPointData().AddArray(array(density, "density"))
    d.GetPointData().AddArray(array(ids, "id"))
    return d


def legacy(name, kind, binary, version=None, double=False):
    d = dataset(kind, pos.astype(np.float64) if double else pos)
    w = vtk.vtkPolyDataWriter() if kind == "poly" else vtk.vtkUnstructuredGridWriter()
    w.SetFileName(path(name))
    w.SetInputData(d)
    if binary:
        w.SetFileTypeToBinary()
    else:
        w.SetFileTypeToASCII()
    if version:
        w.SetFileVersion(version)
    assert w.Write() == 1


def xml(name, kind, mode, compress=False, header64=False, encode=False, double=False):
    d = dataset(kind, pos.astype(np.float64) if double else pos)
    w = vtk.vtkXMLPolyDataWriter() if kind == "poly" else vtk.vtkXMLUnstructuredGridWriter()
    w.SetFileName(path(name))
    w.SetInputData(d)
    {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary,
     "appended": w.SetDataModeToAppended}[mode]()
    w.SetEncodeAppendedData(encode)
    if compress:
        w.SetCompressorTypeToZLib()
        w.SetBlockSize(1024)  # several blocks per array
    else:
        w.SetCompressorTypeToNone()
    w.SetHeaderTypeToUInt64() if header64 else w.SetHeaderTypeToUInt32()
    assert w.Write() == 1


# Legacy VTK: ascii and binary (big-endian), file versions 5.1 (OFFSETS/CONNECTIVITY cells) and
# 4.2, unstructured grid and polydata, float and double.
legacy("legacy_ascii.vtk", "grid", binary=False)
legacy("legacy_binary.vtk", "grid", binary=True)
legacy("legacy_binary_v42_double.vtk", "grid", binary=True, version=42, double=True)
legacy("legacy_polydata_ascii_v42.vtk", "poly", binary=False, version=42)
legacy("legacy_polydata_binary.vtk", "poly", binary=True)

# XML: every data mode and encoding, zlib blocks with 32- and 64-bit headers.
xml("xml_ascii.vtu", "grid", "ascii")
xml("xml_binary.vtu", "grid", "binary")
xml("xml_binary_zlib.vtu", "grid", "binary", compress=True)
xml("xml_binary_zlib_uint64.vtu", "grid", "binary", compress=True, header64=True)
xml("xml_appended_raw.vtu", "grid", "appended")
xml("xml_appended_raw_zlib_uint64.vtu", "grid", "appended", compress=True, header64=True)
xml("xml_appended_base64.vtu", "grid", "appended", encode=True)
xml("xml_appended_base64_zlib.vtu", "grid", "appended", compress=True, encode=True)
xml("xml_binary_zlib_uint64_double.vtp", "poly", "binary", compress=True, header64=True, double=True)
xml("xml_appended_raw.vtp", "poly", "appended")


# SPlisHSPlasH's VTK exporter: binary big-endian unstructured grid of vertex cells, the point
# data as one FIELD of `id` (unsigned_int), `velocity` (3 float) and `density` (float).
def splishsplash(name):
    with open(path(name), "wb") as f:
        f.write(b"# vtk DataFile Version 4.1\nSPlisHSPlasH particle data (4.1)\nBINARY\n")
        f.write(b"DATASET UNSTRUCTURED_GRID\n")
        f.write(b"POINTS %d float\n" % n)
        f.write(pos.astype(">f4").tobytes())
        f.write(b"\n")
        f.write(b"CELLS %d %d\n" % (n, 2 * n))
        f.write(np.stack([np.ones(n), np.arange(n)], axis=1).astype(">i4").tobytes())
        f.write(b"\n")
        f.write(b"CELL_TYPES %d\n" % n)
        f.write(np.ones(n).astype(">i4").tobytes())
        f.write(b"\n")
        f.write(b"POINT_DATA %d\n" % n)
        f.write(b"FIELD FieldData 3\n")
        f.write(b"id 1 %d unsigned_int\n" % n)
        f.write(ids.astype(">u4").tobytes())
        f.write(b"\n")
        f.write(b"velocity 3 %d float\n" % n)
        f.write(vel.astype(">f4").tobytes())
        f.write(b"\n")
        f.write(b"density 1 %d float\n" % n)
        f.write(density.astype(">f4").tobytes())
        f.write(b"\n")


splishsplash("splishsplash.vtk")

# splashsurf's .xyz: raw little-endian f32 triples; and a text .xyz of the same numbers.
pos.astype("<f4").tofile(path("raw.xyz"))
np.savetxt(path("text.xyz"), pos, fmt="%.9g")

# BGEO from splashsurf (`splashsurf convert`, positions only).
import pysplashsurf  # noqa: E402

for out in ("splashsurf.bgeo",):
    if os.path.exists(path(out)):
        os.remove(path(out))
    pysplashsurf.run_splashsurf(["splashsurf", "convert", "-q", "--particles",
                                 path("legacy_binary_v42_double.vtk"), "-o", path(out)])



# BGEO with attributes, laid out as partio's writer does (partio is not on PyPI): header,
# point attribute definitions `velocity` (vector, 3), `density` (float, 1), `id` (int, 1) with
# zero defaults, then per point x y z w and the values, big-endian, ending 0x00 0xff; gzipped
# and plain. Cross-checked with the reader pysplashsurf registers in meshio.
def partio_bgeo(name, compress):
    out = bytearray(b"BgeoV" + struct.pack(">i", 5))
    out += struct.pack(">8i", n, 0, 0, 0, 3, 0, 0, 0)
    for attr, size, kind in (("velocity", 3, 5), ("density", 1, 0), ("id", 1, 1)):
        out += struct.pack(">H", len(attr)) + attr.encode() + struct.pack(">Hi", size, kind)
        out += b"\0" * (4 * size)
    rec = np.zeros((n, 9), dtype=">f4")
    rec[:, :3] = pos
    rec[:, 3] = 1.0
    rec[:, 4:7] = vel
    rec[:, 7] = density
    records = rec.view(">u4")
    records[:, 8] = ids.astype(">u4")
    out += records.tobytes() + b"\x00\xff"
    with (gzip.GzipFile(path(name), "wb", mtime=0) if compress else open(path(name), "wb")) as f:
        f.write(bytes(out))
    m = pysplashsurf.bgeo.readbgeo_to_meshio(path(name)) if compress else None
    if m is not None:
        assert (m.points == pos).all()
        assert (m.point_data["velocity"] == vel).all()
        assert (m.point_data["density"] == density).all()
        assert (m.point_data["id"] == ids).all()


partio_bgeo("partio_attributes.bgeo.gz", True)
partio_bgeo("partio_attributes.bgeo", False)

print("wrote", sorted(os.listdir(OUT)))
