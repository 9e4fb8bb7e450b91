//! PLY mesh input, binary (either byte order) or ascii: a `vertex` element of scalar properties
//! (`x y z`, the others attributes named as for particles: `nx ny nz` the normals, `vx vy vz`
//! `velocity`), then an optional `face` element whose one list property `vertex_indices`
//! (or `vertex_index`) holds triangles. The header is read as for particles.

use std::collections::BTreeMap;

use glam::Vec3;
use ply_rs_bw::ply::Encoding;

use super::failure::Result;
use crate::data::{Attribute, TriMesh};
use crate::io::particles::attribute_columns::AttributeColumns;
use crate::io::particles::ply_layout::{Element, Kind, Layout, Scalar};
use crate::io::particles::ply_read::read_header;

/// Parses the whole file's bytes; the normals are still the attribute `normal`.
pub(super) fn parse(data: &[u8]) -> Result<(TriMesh, BTreeMap<String, Attribute>)> {
    let (header, header_len, header_lines) = read_header(&mut &data[..])?;
    let names: Vec<&str> = header.elements.keys().map(String::as_str).collect();
    if names != ["vertex", "face"] && names != ["vertex"] {
        bail_format!(
            "expected the elements 'vertex' and 'face' of a mesh, found {}",
            super::listed(names.iter().copied())
        );
    }
    let layout = Layout::new(&header)?;
    let vertex = &layout.vertex;
    if let Some(p) = vertex
        .props
        .iter()
        .find(|p| matches!(p.kind, Kind::List { .. }))
    {
        bail_format!(
            "the 'vertex' property '{}' is a list: a mesh's vertices have numbers only",
            super::short(&p.name)
        );
    }
    let face = match header.elements.get("face") {
        Some(def) => Some(Element::new(def)?),
        None => None,
    };
    let corners = match face.as_ref().map(|f| f.props.as_slice()) {
        None => None,
        Some([p]) if p.name == "vertex_indices" || p.name == "vertex_index" => match p.kind {
            Kind::List { len, item } => Some((len, item)),
            Kind::Scalar(_) => None,
        },
        Some(_) => None,
    };
    let faces = face.as_ref().map_or(0, |f| f.count);
    if face.is_some() && corners.is_none() {
        bail_format!(
            "the faces must have the single list property 'vertex_indices' (a count, then the \
             corners' vertex numbers)"
        );
    }
    let names: Vec<&str> = vertex.props.iter().map(|p| p.name.as_str()).collect();
    let mut attributes = AttributeColumns::new(&names, layout.xyz_indices(), |_| true, false);
    let body = usize::try_from(header_len)
        .ok()
        .and_then(|start| data.get(start..))
        .unwrap_or_default();
    let (vertices, triangles) = match header.encoding {
        Encoding::Ascii => ascii(body, header_lines, &layout, &mut attributes, faces)?,
        Encoding::BinaryLittleEndian | Encoding::BinaryBigEndian => {
            let big_endian = header.encoding == Encoding::BinaryBigEndian;
            let (vertices, rest) = binary_vertices(body, &layout, &mut attributes, big_endian)?;
            let triangles = match corners {
                Some((len, item)) => binary_faces(rest, faces, len, item, big_endian)?,
                None => Vec::new(),
            };
            (vertices, triangles)
        }
    };
    let mesh = TriMesh {
        vertices,
        normals: Vec::new(),
        triangles,
    };
    Ok((mesh, attributes.into_map()))
}

/// The vertices, with their attributes, and the bytes after them.
fn binary_vertices<'d>(
    body: &'d [u8],
    layout: &Layout,
    attributes: &mut AttributeColumns,
    big_endian: bool,
) -> Result<(Vec<Vec3>, &'d [u8])> {
    let vertex = &layout.vertex;
    // Scalar properties only (checked above): a fixed record size, at least 3 bytes (x y z).
    let stride = vertex.fixed_stride().unwrap_or(usize::MAX);
    let Some(bytes) = vertex
        .count
        .checked_mul(stride)
        .filter(|&b| b <= body.len())
    else {
        bail_format!(
            "the file is too short for its {} vertices of {stride} bytes: {} bytes follow the \
             header",
            vertex.count,
            body.len()
        );
    };
    let (records, rest) = body.split_at(bytes);
    let at = |i: usize| vertex.scalar_offset(i);
    let xyz = layout.xyz.map(|(i, scalar)| (at(i), scalar));
    let mut vertices = Vec::with_capacity(vertex.count);
    for (index, record) in records.chunks_exact(stride).enumerate() {
        let mut p = [0f32; 3];
        for (slot, &(offset, scalar)) in p.iter_mut().zip(&xyz) {
            *slot = scalar
                .to_f32(&record[offset..], big_endian)
                .unwrap_or(f32::NAN);
        }
        vertices.push(finite_vertex(Vec3::from_array(p), index)?);
    }
    attributes.resize(vertex.count);
    for (i, p) in vertex.props.iter().enumerate() {
        if let (true, Kind::Scalar(scalar)) = (attributes.reads(i), p.kind) {
            let offset = at(i);
            let values = records.chunks_exact(stride);
            attributes.fill(
                i,
                0,
                values.map(|r| scalar.to_f32(&r[offset..], big_endian)),
            );
        }
    }
    Ok((vertices, rest))
}

/// `count` triangles of a count of type `len` and three indices of type `item` each.
fn binary_faces(
    body: &[u8],
    count: usize,
    len: Scalar,
    item: Scalar,
    big_endian: bool,
) -> Result<Vec<[u32; 3]>> {
    let stride = len.size() + 3 * item.size();
    if count.checked_mul(stride).is_none_or(|b| b > body.len()) {
        bail_format!(
            "the file is too short for its {count} triangles of {stride} bytes (or a face is not \
             a triangle): {} bytes follow the vertices",
            body.len()
        );
    }
    let mut triangles = Vec::with_capacity(count);
    for (index, record) in body.chunks_exact(stride).take(count).enumerate() {
        let corners = len.to_len(record, big_endian);
        if corners != Some(3) {
            bail_format!(
                "face {index} has {} corners: only triangles are read",
                corners.map_or("a negative number of".to_string(), |c| c.to_string())
            );
        }
        let mut triangle = [0u32; 3];
        for (k, slot) in triangle.iter_mut().enumerate() {
            let at = len.size() + k * item.size();
            *slot = index_of(item.to_len(&record[at..], big_endian), index)?;
        }
        triangles.push(triangle);
    }
    Ok(triangles)
}

/// Ascii payload: one record per line, blank lines skipped; `lines_before` are the header's.
fn ascii(
    body: &[u8],
    lines_before: usize,
    layout: &Layout,
    attributes: &mut AttributeColumns,
    faces: usize,
) -> Result<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let vertex = &layout.vertex;
    let mut lines = body
        .split(|&b| b == b'\n')
        .enumerate()
        .map(|(i, line)| (lines_before + i + 1, line))
        .filter(|(_, line)| !line.trim_ascii().is_empty());
    let mut next = |what: &str, index: usize, count: usize| {
        let Some((n, line)) = lines.next() else {
            bail_format!("the file ends after {index} of its {count} {what}");
        };
        match std::str::from_utf8(line) {
            Ok(text) => Ok((n, text)),
            Err(_) => bail_format!("line {n} is not text"),
        }
    };
    // A record takes 2 bytes a number at least ("0 "): bounds what is reserved.
    let fit = |count: usize, numbers: usize| count.min(body.len() / (2 * numbers.max(1)));
    let xyz = layout.xyz_indices();
    let mut vertices = Vec::with_capacity(fit(vertex.count, vertex.props.len()));
    attributes.reserve(fit(vertex.count, vertex.props.len()));
    let mut values = Vec::with_capacity(vertex.props.len());
    for index in 0..vertex.count {
        let (n, text) = next("vertices", index, vertex.count)?;
        values.clear();
        for word in text.split_ascii_whitespace() {
            match word.parse::<f32>() {
                Ok(v) => values.push(v),
                Err(_) => bail_format!(
                    "line {n} (vertex {index}): '{}' is not a number",
                    super::short(word)
                ),
            }
        }
        if values.len() != vertex.props.len() {
            bail_format!(
                "line {n} (vertex {index}) has {} numbers, but the header declares {} properties",
                values.len(),
                vertex.props.len()
            );
        }
        vertices.push(finite_vertex(
            Vec3::new(values[xyz[0]], values[xyz[1]], values[xyz[2]]),
            index,
        )?);
        attributes.push();
        for (i, &v) in values.iter().enumerate() {
            attributes.set_last(i, v);
        }
    }
    let mut triangles = Vec::with_capacity(fit(faces, 4));
    for index in 0..faces {
        let (n, text) = next("faces", index, faces)?;
        let words: Vec<&str> = text.split_ascii_whitespace().collect();
        if words.first() != Some(&"3") || words.len() != 4 {
            bail_format!(
                "line {n} (face {index}) is not a triangle ('3' and three vertex numbers): '{}'",
                super::short(text)
            );
        }
        let mut triangle = [0u32; 3];
        for (slot, word) in triangle.iter_mut().zip(&words[1..]) {
            *slot = index_of(word.parse::<u64>().ok(), index)?;
        }
        triangles.push(triangle);
    }
    Ok((vertices, triangles))
}

fn finite_vertex(p: Vec3, index: usize) -> Result<Vec3> {
    super::failure::finite(p, || format!("vertex {index}"))
}

/// A corner's vertex number as an index; `None` when the file's value is not one.
fn index_of(value: Option<u64>, face: usize) -> Result<u32> {
    match value.and_then(|v| u32::try_from(v).ok()) {
        Some(i) => Ok(i),
        None => bail_format!("face {face} has a corner that is not a vertex number"),
    }
}
