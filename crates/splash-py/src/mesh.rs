//! The `Mesh` that `reconstruct` returns: numpy arrays, the report, and `write`; and the
//! edges of a mesh's faces, as Blender holds them (`mesh_edges`).

use std::path::PathBuf;

use ndarray::Array2;
use numpy::{PyArray1, PyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use splash_sph::io::{self, VertexAttributes};
use splash_sph::level_set::LevelSet;
use splash_sph::mesh::Edges;
use splash_sph::{Attribute, MeshFormat, TriMesh, UpAxis};

use crate::arrays;
use crate::errors::to_py;

/// A closed triangle mesh whose triangles wind counter-clockwise seen from outside the fluid.
///
/// The arrays are the mesh: edit them in place (to move or scale it, say) and ``write``
/// writes the edited mesh.
#[pyclass(frozen, module = "splash_sph")]
pub struct Mesh {
    /// Vertex positions, shape (V, 3), float32.
    #[pyo3(get)]
    vertices: Py<PyArray2<f32>>,
    /// Triangles as vertex indices, shape (F, 3), uint32.
    #[pyo3(get)]
    faces: Py<PyArray2<u32>>,
    /// Unit vertex normals pointing out of the fluid, shape (V, 3), float32; shape (0, 3)
    /// when reconstructed with ``normals="none"``.
    #[pyo3(get)]
    normals: Py<PyArray2<f32>>,
    /// Per-vertex values interpolated from the particles' ``attributes``: name -> array of
    /// shape (V, 3) or (V,), float32.
    #[pyo3(get)]
    attributes: Py<PyDict>,
    /// Counts, lengths and stage times of the reconstruction (see ``reconstruct``).
    #[pyo3(get)]
    report: Py<PyDict>,
    /// The configuration's `[output]` choices, the defaults of `write`.
    format: Option<MeshFormat>,
    up_axis: Option<UpAxis>,
}

impl Mesh {
    pub fn new(
        py: Python<'_>,
        mesh: TriMesh,
        attributes: Bound<'_, PyDict>,
        report: Bound<'_, PyDict>,
        format: Option<MeshFormat>,
        up_axis: Option<UpAxis>,
    ) -> Mesh {
        Mesh {
            vertices: arrays::points_array(py, mesh.vertices).unbind(),
            faces: arrays::triangles_array(py, mesh.triangles).unbind(),
            normals: arrays::points_array(py, mesh.normals).unbind(),
            attributes: attributes.unbind(),
            report: report.unbind(),
            format,
            up_axis,
        }
    }

    /// The mesh as the arrays hold it now (copied: they may have been edited).
    pub fn arrays(&self, py: Python<'_>) -> PyResult<TriMesh> {
        Ok(TriMesh {
            vertices: arrays::points(self.vertices.bind(py).as_any(), "mesh.vertices")?.into_vec(),
            normals: arrays::points(self.normals.bind(py).as_any(), "mesh.normals")?.into_vec(),
            triangles: arrays::triangles(self.faces.bind(py).as_any(), "mesh.faces")?,
        })
    }

    /// The report dict (shared, not copied).
    pub fn report<'py>(&self, py: Python<'py>) -> Bound<'py, PyDict> {
        self.report.bind(py).clone()
    }

    /// The attributes dict (shared, not copied).
    pub fn attributes<'py>(&self, py: Python<'py>) -> Bound<'py, PyDict> {
        self.attributes.bind(py).clone()
    }

    /// The `[output]` choices: format and up axis.
    pub fn output(&self) -> (Option<MeshFormat>, Option<UpAxis>) {
        (self.format, self.up_axis)
    }

    /// The format `path` is written in: `format`, else the configuration's, else the one its
    /// extension implies, else OBJ; refused when it contradicts the extension (as the CLI does).
    fn format_for(&self, path: &std::path::Path, format: Option<&str>) -> PyResult<MeshFormat> {
        let format = format.map(MeshFormat::parse).transpose().map_err(to_py)?;
        let hint = MeshFormat::from_path(path);
        match (format.or(self.format), hint) {
            (Some(f), Some(h)) if f.extension() != h.extension() => {
                Err(PyValueError::new_err(format!(
                    "format {} does not match the file name's .{} extension",
                    f.extension(),
                    h.extension()
                )))
            }
            (Some(f), _) => Ok(f),
            (None, hint) => Ok(hint.unwrap_or(MeshFormat::Obj)),
        }
    }
}

#[pymethods]
impl Mesh {
    /// Writes the mesh to ``path`` atomically (a reader sees the old file or the new one),
    /// creating missing directories.
    ///
    /// ``format``: ``"obj"``, ``"ply"`` (binary), ``"ply-ascii"``, ``"pov"``, ``"vtk"``,
    /// ``"vtu"``, ``"vtp"``, ``"usd"`` (a ``.usda`` layer) or ``"vdb"``; by default the
    /// configuration's ``output.format``, else the one the extension implies (``.obj``,
    /// ``.ply``, ``.inc``, ``.vtk``, ``.vtu``, ``.vtp``, ``.usda``, ``.vdb``), else OBJ.
    /// ``up_axis``: ``"z"`` or ``"y"`` turns the written coordinates so that that axis is up
    /// (the arrays are left as they are); by default the configuration's ``output.up_axis``.
    /// PLY, VTK and USD files get every attribute of the mesh (``velocity`` as the PLY
    /// properties ``vx vy vz``, USD's ``velocities``); OBJ and POV-Ray files leave them out. A
    /// VDB file holds the mesh's level set alone (``write_vdb`` also writes grids), on voxels
    /// of edge ``voxel``: by default the cell of the reconstruction that made the mesh. The
    /// GIL is released while writing.
    ///
    /// Raises OSError when the file cannot be written, ValueError for an unknown format or
    /// one that contradicts the extension, and for a VDB file without ``voxel`` of a mesh whose
    /// report has no cell.
    #[pyo3(signature = (path, format=None, up_axis=None, voxel=None))]
    fn write(
        &self,
        py: Python<'_>,
        path: PathBuf,
        format: Option<&str>,
        up_axis: Option<&str>,
        voxel: Option<f32>,
    ) -> PyResult<()> {
        let format = self.format_for(&path, format)?;
        let up_axis = match up_axis {
            Some(a) => Some(UpAxis::parse(a).map_err(to_py)?),
            None => self.up_axis,
        };
        let mut mesh = self.arrays(py)?;
        if format == MeshFormat::Vdb {
            let cell = self.report.bind(py).get_item("cell")?;
            let cell = cell.filter(|c| !c.is_none());
            let voxel = match (voxel, cell) {
                (Some(v), _) => v,
                (None, Some(cell)) => cell.extract()?,
                (None, None) => {
                    return Err(PyValueError::new_err(
                        "a .vdb file holds the mesh's level set: give voxel=, the voxels' \
                         edge (the mesh's report has no reconstruction cell)",
                    ));
                }
            };
            return py
                .detach(|| {
                    if let Some(axis) = up_axis {
                        axis.rotate_mesh(&mut mesh, &mut []);
                    }
                    LevelSet::of_mesh(&mesh, voxel)?.write_file(&path, &[])
                })
                .map_err(to_py);
        }
        // Every attribute, where the format has room for them: (V,) arrays as numbers, (V, 3)
        // arrays as vectors.
        let mut named: Vec<(String, Attribute)> = Vec::new();
        if format.holds_attributes() {
            for (key, value) in self.attributes.bind(py).iter() {
                let name: String = key.extract()?;
                let what = format!("mesh.attributes['{name}']");
                let ndim: usize = value.getattr("ndim")?.extract()?;
                let attribute = if ndim == 1 {
                    Attribute::Scalar(arrays::scalars(&value, &what)?)
                } else {
                    Attribute::Vector(arrays::points(&value, &what)?.into_vec())
                };
                let rows = match &attribute {
                    Attribute::Scalar(s) => s.len(),
                    Attribute::Vector(v) => v.len(),
                };
                if rows != mesh.vertices.len() {
                    return Err(PyValueError::new_err(format!(
                        "{what} has {rows} rows for {} vertices",
                        mesh.vertices.len()
                    )));
                }
                named.push((name, attribute));
            }
        }
        py.detach(|| {
            if let Some(axis) = up_axis {
                axis.rotate_mesh(&mut mesh, &mut named);
            }
            let attributes = VertexAttributes {
                named: &named,
                ..Default::default()
            };
            io::write_mesh_file_with(&path, &mesh, &attributes, format)
        })
        .map_err(to_py)
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "Mesh({} vertices, {} faces)",
            self.vertices.bind(py).shape()[0],
            self.faces.bind(py).shape()[0]
        )
    }
}

/// `mesh_edges`' arrays: the edges' vertex pairs and each corner's edge.
type EdgeArrays<'py> = (Bound<'py, PyArray2<u32>>, Bound<'py, PyArray1<u32>>);

/// The edges of the triangles ``faces``, as Blender's meshes hold them beside the faces:
/// ``(edges, corner_edges)``, ``edges`` each distinct edge once as an (E, 2) uint32 array of
/// vertex indices, the lower first, and ``corner_edges`` an (3F,) uint32 array giving for
/// corner ``3 f + k`` the edge from vertex ``faces[f, k]`` to ``faces[f, (k + 1) % 3]``.
///
/// ``faces``: an (F, 3) uint32 array (``Mesh.faces``, ``MeshArrays.faces``) over
/// ``vertex_count`` vertices. A closed mesh has 3F/2 edges. The GIL is released while
/// counting. Raises ValueError when a face names a vertex beyond ``vertex_count``.
#[pyfunction]
pub fn mesh_edges<'py>(
    py: Python<'py>,
    faces: &Bound<'py, PyAny>,
    vertex_count: usize,
) -> PyResult<EdgeArrays<'py>> {
    let triangles = arrays::triangles(faces, "faces")?;
    let edges = py
        .detach(|| Edges::of(vertex_count, &triangles))
        .map_err(to_py)?;
    let pairs = Array2::from_shape_vec((edges.pairs.len(), 2), edges.pairs.concat())
        .expect("2 vertices per edge");
    Ok((
        PyArray2::from_owned_array(py, pairs),
        PyArray1::from_vec(py, edges.corners),
    ))
}
