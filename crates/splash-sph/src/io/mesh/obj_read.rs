//! Wavefront OBJ mesh input: the `v`, `vn` and triangular `f` lines of a file as
//! `obj_write::write` writes it (`f a b c`, `a//n`, `a/t/n`; negative indices count back from
//! the last vertex), every other line skipped. Normals are per vertex, so `vn` lines must be
//! none or one per `v`.

use glam::Vec3;

use super::failure::Result;
use crate::data::TriMesh;

/// Parses the whole file's bytes.
pub(super) fn parse(data: &[u8]) -> Result<TriMesh> {
    // Every value pushed is a line of the file: memory stays a multiple of its size.
    let mut mesh = TriMesh::default();
    for (index, line) in data.split(|&b| b == b'\n').enumerate() {
        let n = index + 1;
        let Ok(line) = std::str::from_utf8(line) else {
            bail_format!("line {n} is not UTF-8 text: not an OBJ file");
        };
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            Some("v") => mesh.vertices.push(point(words, n, "v")?),
            Some("vn") => mesh.normals.push(point(words, n, "vn")?),
            Some("f") => {
                let corners: Vec<&str> = words.collect();
                if corners.len() != 3 {
                    bail_format!(
                        "line {n}: the face has {} corners: only triangles are read (an 'f' line \
                         of 3 corners)",
                        corners.len()
                    );
                }
                let mut triangle = [0u32; 3];
                for (slot, corner) in triangle.iter_mut().zip(&corners) {
                    *slot = vertex_index(corner, mesh.vertices.len(), n)?;
                }
                mesh.triangles.push(triangle);
            }
            _ => {}
        }
    }
    if !mesh.normals.is_empty() && mesh.normals.len() != mesh.vertices.len() {
        bail_format!(
            "{} 'vn' lines for {} 'v' lines: normals are read one per vertex, as splash writes \
             them",
            mesh.normals.len(),
            mesh.vertices.len()
        );
    }
    Ok(mesh)
}

/// The three numbers of a `v` or `vn` line (a fourth, `w`, is allowed and ignored).
fn point<'a>(mut words: impl Iterator<Item = &'a str>, n: usize, what: &str) -> Result<Vec3> {
    let mut xyz = [0f32; 3];
    for slot in &mut xyz {
        let Some(word) = words.next() else {
            bail_format!("line {n}: a '{what}' line with fewer than 3 numbers");
        };
        let Ok(value) = word.parse::<f32>() else {
            bail_format!(
                "line {n}: '{}' in a '{what}' line is not a number",
                super::short(word)
            );
        };
        *slot = value;
    }
    Ok(Vec3::from_array(xyz))
}

/// The 0-based vertex index of a face corner `a`, `a/t`, `a//n` or `a/t/n`; `vertices` are
/// those read so far, which a negative index counts back from.
fn vertex_index(corner: &str, vertices: usize, n: usize) -> Result<u32> {
    let text = corner.split('/').next().unwrap_or_default();
    let index = match text.parse::<i64>() {
        Ok(i) if i > 0 => i - 1,
        Ok(i) if i < 0 => vertices as i64 + i,
        _ => bail_format!(
            "line {n}: the face corner '{}' does not start with a vertex number (1, 2, … or -1, \
             -2, …)",
            super::short(corner)
        ),
    };
    match u32::try_from(index) {
        Ok(i) => Ok(i),
        Err(_) => bail_format!(
            "line {n}: the face corner '{}' refers to no vertex",
            super::short(corner)
        ),
    }
}
