//! VTK XML output: `.vtu` (`UnstructuredGrid`, triangles as cell type 5) and `.vtp`
//! (`PolyData`, triangles as `Polys`), every array `format="binary"` (base64) and compressed by
//! `vtkZLibDataCompressor` in 32 KiB blocks with `UInt64` headers, the encoding ParaView writes
//! by default. Points and attributes are `Float32` (vectors with 3 components), normals are the
//! point data `Normals`, connectivity and offsets `Int64`.
//!
//! Each array is laid out as VTK's compressed binary data: a header of `u64`s (block count,
//! block size, size of the last block before compression, compressed size of each block),
//! base64-encoded on its own, followed by the compressed blocks, base64-encoded together.
//! The blocks are compressed in parallel.

use std::io::{self, Write};

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;
use flate2::Compression;
use flate2::write::ZlibEncoder;
use rayon::prelude::*;

use super::failure::invalid_input;
use super::vertex_attributes::{AttributeValues, VertexAttributes};
use crate::data::TriMesh;

/// Uncompressed bytes per block (VTK's default).
const BLOCK: usize = 1 << 15;

/// Which XML data set to write.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    /// `.vtu`.
    UnstructuredGrid,
    /// `.vtp`.
    PolyData,
}

/// `mesh` and `attributes` have been checked (one entry per vertex, indices in range).
pub(super) fn write(
    mesh: &TriMesh,
    attributes: &VertexAttributes,
    kind: Kind,
    out: &mut impl Write,
) -> io::Result<()> {
    let arrays = attributes.arrays();
    for (name, _) in &arrays {
        if name.is_empty()
            || name
                .chars()
                .any(|c| matches!(c, '"' | '<' | '>' | '&') || c.is_control())
        {
            return Err(invalid_input(format!(
                "a VTK XML array name cannot be empty or hold quotes, <, > or &: '{name}'"
            )));
        }
    }
    let (n, t) = (mesh.vertices.len(), mesh.triangles.len());
    let ty = match kind {
        Kind::UnstructuredGrid => "UnstructuredGrid",
        Kind::PolyData => "PolyData",
    };
    writeln!(out, "<?xml version=\"1.0\"?>")?;
    writeln!(
        out,
        "<VTKFile type=\"{ty}\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">"
    )?;
    writeln!(out, "  <{ty}>")?;
    match kind {
        Kind::UnstructuredGrid => writeln!(
            out,
            "    <Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{t}\">"
        )?,
        Kind::PolyData => writeln!(
            out,
            "    <Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"0\" NumberOfLines=\"0\" \
             NumberOfStrips=\"0\" NumberOfPolys=\"{t}\">"
        )?,
    }
    let mut attrs = Vec::new();
    if !mesh.normals.is_empty() {
        attrs.push("Normals=\"Normals\"".to_owned());
    }
    if let Some((name, _)) = arrays
        .iter()
        .find(|(_, v)| matches!(v, AttributeValues::Scalar(_)))
    {
        attrs.push(format!("Scalars=\"{name}\""));
    }
    if let Some((name, _)) = arrays
        .iter()
        .find(|(_, v)| matches!(v, AttributeValues::Vector(_)))
    {
        attrs.push(format!("Vectors=\"{name}\""));
    }
    writeln!(out, "      <PointData {}>", attrs.join(" "))?;
    if !mesh.normals.is_empty() {
        array(
            out,
            "Float32",
            "Normals",
            3,
            &f32_bytes(bytemuck::cast_slice(&mesh.normals)),
        )?;
    }
    for (name, values) in &arrays {
        match values {
            AttributeValues::Scalar(s) => array(out, "Float32", name, 1, &f32_bytes(s))?,
            AttributeValues::Vector(v) => {
                array(out, "Float32", name, 3, &f32_bytes(bytemuck::cast_slice(v)))?
            }
        }
    }
    writeln!(out, "      </PointData>")?;
    writeln!(out, "      <Points>")?;
    array(
        out,
        "Float32",
        "Points",
        3,
        &f32_bytes(bytemuck::cast_slice(&mesh.vertices)),
    )?;
    writeln!(out, "      </Points>")?;
    let cells = match kind {
        Kind::UnstructuredGrid => "Cells",
        Kind::PolyData => "Polys",
    };
    writeln!(out, "      <{cells}>")?;
    let connectivity: Vec<u8> = mesh
        .triangles
        .iter()
        .flatten()
        .flat_map(|&i| i64::from(i).to_le_bytes())
        .collect();
    array(out, "Int64", "connectivity", 1, &connectivity)?;
    drop(connectivity);
    let offsets: Vec<u8> = (1..=t as i64).flat_map(|k| (3 * k).to_le_bytes()).collect();
    array(out, "Int64", "offsets", 1, &offsets)?;
    drop(offsets);
    if kind == Kind::UnstructuredGrid {
        // VTK_TRIANGLE.
        array(out, "UInt8", "types", 1, &vec![5u8; t])?;
    }
    writeln!(out, "      </{cells}>")?;
    writeln!(out, "    </Piece>")?;
    writeln!(out, "  </{ty}>")?;
    writeln!(out, "</VTKFile>")
}

/// Little-endian bytes of `values`.
fn f32_bytes(values: &[f32]) -> Vec<u8> {
    if cfg!(target_endian = "little") {
        bytemuck::cast_slice(values).to_vec()
    } else {
        values.iter().flat_map(|x| x.to_le_bytes()).collect()
    }
}

/// One `DataArray` of `bytes` (little-endian values of `ty`), compressed and base64-encoded.
fn array(
    out: &mut impl Write,
    ty: &str,
    name: &str,
    components: usize,
    bytes: &[u8],
) -> io::Result<()> {
    write!(
        out,
        "        <DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{components}\" \
         format=\"binary\">\n          "
    )?;
    let blocks: Vec<Vec<u8>> = bytes
        .par_chunks(BLOCK)
        .map(|chunk| {
            let mut z = ZlibEncoder::new(Vec::with_capacity(chunk.len() / 2), Compression::fast());
            z.write_all(chunk)?;
            z.finish()
        })
        .collect::<io::Result<_>>()?;
    // As VTK writes it: 0 when the last block is full.
    let last = bytes.len() % BLOCK;
    let mut header: Vec<u8> = Vec::with_capacity(8 * (3 + blocks.len()));
    for x in [blocks.len(), BLOCK, last]
        .into_iter()
        .chain(blocks.iter().map(Vec::len))
    {
        header.extend_from_slice(&(x as u64).to_le_bytes());
    }
    out.write_all(BASE64.encode(&header).as_bytes())?;
    let compressed = blocks.concat();
    drop(blocks);
    out.write_all(BASE64.encode(&compressed).as_bytes())?;
    writeln!(out, "\n        </DataArray>")
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use glam::Vec3;

    use crate::data::TriMesh;
    use crate::io::{Attribute, MeshFormat, Particles, VertexAttributes, write_mesh_with};

    fn triangle() -> TriMesh {
        TriMesh {
            vertices: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z; 3],
            triangles: vec![[0, 1, 2]],
        }
    }

    fn written(named: &[(String, Attribute)], format: MeshFormat) -> std::io::Result<Vec<u8>> {
        let mut out = Vec::new();
        let attributes = VertexAttributes {
            named,
            ..Default::default()
        };
        write_mesh_with(&triangle(), &attributes, format, &mut out).map(|()| out)
    }

    #[test]
    fn ply_names_attributes_and_formats_without_room_refuse() {
        let named = vec![
            ("velocity".to_string(), Attribute::Vector(vec![Vec3::X; 3])),
            ("density".to_string(), Attribute::Scalar(vec![1000.0; 3])),
            ("vorticity".to_string(), Attribute::Vector(vec![Vec3::Y; 3])),
        ];
        let text = String::from_utf8(written(&named, MeshFormat::PlyAscii).unwrap()).unwrap();
        let properties: Vec<&str> = text
            .lines()
            .filter_map(|l| l.strip_prefix("property float "))
            .collect();
        assert_eq!(
            properties,
            ["x", "y", "z", "nx", "ny", "nz", "vx", "vy", "vz", "density"]
                .into_iter()
                .chain(["vorticity_x", "vorticity_y", "vorticity_z"])
                .collect::<Vec<_>>()
        );
        assert!(text.contains("\n1 0 0 0 0 1 1 0 0 1000 0 1 0\n"), "{text}");
        for format in [MeshFormat::Obj, MeshFormat::Pov] {
            let e = written(&named, format).unwrap_err().to_string();
            assert!(e.contains("cannot hold vertex attributes (velocity, density, vorticity)"));
        }
        let short = vec![("density".to_string(), Attribute::Scalar(vec![1.0]))];
        let e = written(&short, MeshFormat::Vtu).unwrap_err().to_string();
        assert!(e.contains("1 values of 'density' for 3 vertices"), "{e}");
        let spaced = vec![("a b".to_string(), Attribute::Scalar(vec![1.0; 3]))];
        for format in [MeshFormat::PlyBinary, MeshFormat::Vtk] {
            assert!(written(&spaced, format).is_err());
        }
        let clash = vec![("nx".to_string(), Attribute::Scalar(vec![1.0; 3]))];
        assert!(written(&clash, MeshFormat::PlyBinary).is_err());
    }

    #[test]
    fn xml_arrays_are_compressed_blocks_with_their_header() {
        use base64::Engine as _;
        use std::io::Read;
        let out = String::from_utf8(written(&[], MeshFormat::Vtp).unwrap()).unwrap();
        let points = out.split("Name=\"Points\"").nth(1).unwrap();
        let data = points
            .split('>')
            .nth(1)
            .unwrap()
            .split('<')
            .next()
            .unwrap()
            .trim();
        // A header of 4 u64s is 32 bytes, 44 base64 characters.
        let header = super::BASE64.decode(&data[..44]).unwrap();
        let h: Vec<u64> = header
            .chunks(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(h[..3], [1, super::BLOCK as u64, 36]);
        let block = super::BASE64.decode(&data[44..]).unwrap();
        assert_eq!(block.len() as u64, h[3]);
        let mut raw = Vec::new();
        flate2::read::ZlibDecoder::new(&block[..])
            .read_to_end(&mut raw)
            .unwrap();
        let expected: Vec<u8> = bytemuck::cast_slice(&triangle().vertices).to_vec();
        assert_eq!(raw, expected);
    }

    #[test]
    fn a_box_keeps_the_particles_inside_with_their_attributes() {
        let mut p = Particles {
            positions: vec![
                Vec3::ZERO,
                Vec3::splat(1e30),
                Vec3::ONE,
                Vec3::splat(f32::NAN),
            ],
            attributes: BTreeMap::from([
                ("id".into(), Attribute::Scalar(vec![0.0, 1.0, 2.0, 3.0])),
                (
                    "v".into(),
                    Attribute::Vector(vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE]),
                ),
            ]),
        };
        assert_eq!(p.retain_in_box([0.0, 0.0, 0.0, 1.0, 1.0, 1.0]), 2);
        assert_eq!(p.positions, [Vec3::ZERO, Vec3::ONE]);
        assert_eq!(p.attributes["id"], Attribute::Scalar(vec![0.0, 2.0]));
        assert_eq!(p.attributes["v"], Attribute::Vector(vec![Vec3::X, Vec3::Z]));
        assert_eq!(p.retain_in_box([0.0, 0.0, 0.0, 1.0, 1.0, 1.0]), 0);
    }
}
