//! USD text layers (`.usda`, OpenUSD's text format): a frame's mesh as one `UsdGeomMesh` prim,
//! its arrays formatted on all threads like the other text writers.
//!
//! The prim is [`USD_PRIM`] with `points`, `faceVertexCounts`, `faceVertexIndices`, `extent`,
//! `normals` (vertex interpolation), `velocities` (the `velocity` attribute, units per second
//! as the schema reads them) and every other attribute as a vertex primvar
//! (`primvars:density`). Triangles keep splash's outward counter-clockwise order, the schema's
//! default `rightHanded` orientation; `subdivisionScheme` is `none`, so that importers do not
//! subdivide the triangles (the schema's default is Catmull-Clark). A frame with a time code
//! holds its values as time samples at that time, as a value clip must (clips ignore default
//! values), else as default values. Every attribute is declared, without a value, at the top
//! of the prim, ahead of the arrays, so that a sequence stage can read the declarations of a
//! frame from its first few lines ([`declarations`]).

use std::io::{self, BufRead, Write};
use std::ops::Range;

use glam::Vec3;

use super::failure::invalid_input;
use super::vertex_attributes::{AttributeValues, VertexAttributes};
use crate::data::TriMesh;
use crate::data::UpAxis;
use crate::io::text::float_text::{F32Text, IntText, push_f32, push_f32_row};
use crate::io::text::text_records::{each_record, write_chunks, write_records};

/// The path of the mesh prim in every layer splash writes: `/Surface`, the default prim.
pub const USD_PRIM: &str = "Surface";

/// How a frame's layer is placed in time and space.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UsdFrame {
    /// The time code of the frame (its frame number): values as time samples at this time,
    /// for a sequence stage's value clips; None: as default values.
    pub time: Option<u64>,
    /// The axis the mesh was turned to (`--up-axis`), written as the layer's `upAxis`; None:
    /// not written (USD then takes Y).
    pub up_axis: Option<UpAxis>,
}

/// `upAxis` metadata for a turned mesh.
pub(super) fn up_axis_token(axis: UpAxis) -> &'static str {
    match axis {
        UpAxis::Y => "Y",
        UpAxis::Z => "Z",
    }
}

/// One attribute to write: its declaration (`point3f[] points`), whether it is a vertex
/// primvar (interpolation metadata), and its values.
struct Declared<'a> {
    declaration: String,
    vertex_interpolation: bool,
    values: Values<'a>,
}

enum Values<'a> {
    Vectors(&'a [Vec3]),
    Scalars(&'a [f32]),
    Extent([Vec3; 2]),
    Counts(usize),
    Indices(&'a [[u32; 3]]),
}

/// Writes `mesh` and `attributes` as a USD text layer; see the module header.
pub(super) fn write(
    mesh: &TriMesh,
    attributes: &VertexAttributes,
    frame: UsdFrame,
    out: &mut impl Write,
) -> io::Result<()> {
    let declared = declared(mesh, attributes)?;
    writeln!(out, "#usda 1.0\n(")?;
    writeln!(out, "    defaultPrim = \"{USD_PRIM}\"")?;
    writeln!(
        out,
        "    doc = \"splash mesh: {} vertices, {} triangles\"",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    if let Some(t) = frame.time {
        writeln!(out, "    endTimeCode = {t}")?;
    }
    writeln!(out, "    metersPerUnit = 1")?;
    if let Some(t) = frame.time {
        writeln!(out, "    startTimeCode = {t}")?;
    }
    if let Some(axis) = frame.up_axis {
        writeln!(out, "    upAxis = \"{}\"", up_axis_token(axis))?;
    }
    writeln!(out, ")\n\ndef Mesh \"{USD_PRIM}\"\n{{")?;
    for d in &declared {
        declare(out, d)?;
    }
    writeln!(out, "    uniform token subdivisionScheme = \"none\"")?;
    for d in &declared {
        match frame.time {
            Some(t) => write!(out, "    {}.timeSamples = {{\n        {t}: ", d.declaration)?,
            None => write!(out, "    {} = ", d.declaration)?,
        }
        values(out, &d.values)?;
        match frame.time {
            Some(_) => writeln!(out, ",\n    }}")?,
            None => writeln!(out)?,
        }
    }
    writeln!(out, "}}")
}

/// An attribute's declaration without a value, with its interpolation where it has one.
fn declare(out: &mut impl Write, d: &Declared) -> io::Result<()> {
    if d.vertex_interpolation {
        writeln!(
            out,
            "    {} (\n        interpolation = \"vertex\"\n    )",
            d.declaration
        )
    } else {
        writeln!(out, "    {}", d.declaration)
    }
}

/// The attributes of the prim in the schema's (alphabetical) order, primvars by their
/// sanitised names; two attributes whose names sanitise alike are refused.
fn declared<'a>(
    mesh: &'a TriMesh,
    attributes: &VertexAttributes<'a>,
) -> io::Result<Vec<Declared<'a>>> {
    let plain = |declaration: &str, values| Declared {
        declaration: declaration.to_string(),
        vertex_interpolation: false,
        values,
    };
    let mut out = Vec::new();
    if let Some(extent) = extent(&mesh.vertices) {
        out.push(plain("float3[] extent", Values::Extent(extent)));
    }
    out.push(plain(
        "int[] faceVertexCounts",
        Values::Counts(mesh.triangles.len()),
    ));
    out.push(plain(
        "int[] faceVertexIndices",
        Values::Indices(&mesh.triangles),
    ));
    if !mesh.normals.is_empty() {
        out.push(Declared {
            declaration: "normal3f[] normals".into(),
            vertex_interpolation: true,
            values: Values::Vectors(&mesh.normals),
        });
    }
    out.push(plain("point3f[] points", Values::Vectors(&mesh.vertices)));
    let mut velocities = None;
    let mut primvars: Vec<Declared> = Vec::new();
    for (name, values) in attributes.arrays() {
        match (name, values) {
            ("velocity", AttributeValues::Vector(v)) => {
                velocities = Some(plain("vector3f[] velocities", Values::Vectors(v)));
            }
            (name, values) => {
                let (kind, values) = match values {
                    AttributeValues::Scalar(s) => ("float[]", Values::Scalars(s)),
                    AttributeValues::Vector(v) => ("vector3f[]", Values::Vectors(v)),
                };
                let declaration = format!("{kind} primvars:{}", identifier(name));
                let clash = primvars
                    .iter()
                    .find(|p| p.declaration.split(' ').nth(1) == declaration.split(' ').nth(1));
                if clash.is_some() {
                    return Err(invalid_input(format!(
                        "two vertex attributes are both named '{}' in USD, which allows \
                         letters, digits and '_' only: rename one",
                        identifier(name)
                    )));
                }
                primvars.push(Declared {
                    declaration,
                    vertex_interpolation: true,
                    values,
                });
            }
        }
    }
    primvars.sort_by(|a, b| {
        a.declaration
            .split(' ')
            .nth(1)
            .cmp(&b.declaration.split(' ').nth(1))
    });
    out.extend(primvars);
    out.extend(velocities);
    Ok(out)
}

/// `name` as a USD identifier: letters, digits and `_`, not starting with a digit.
fn identifier(name: &str) -> String {
    let mut id: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if !id.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') {
        id.insert(0, '_');
    }
    id
}

/// The bounding box's corners, None without vertices.
fn extent(vertices: &[Vec3]) -> Option<[Vec3; 2]> {
    let first = *vertices.first()?;
    Some(
        vertices
            .iter()
            .fold([first, first], |[lo, hi], &v| [lo.min(v), hi.max(v)]),
    )
}

/// Writes an array value: vectors one a line, triangles' indices three a line, the counts 32
/// a line.
fn values(out: &mut impl Write, values: &Values) -> io::Result<()> {
    match *values {
        Values::Extent([lo, hi]) => {
            let mut line = b"[".to_vec();
            push_tuple(&mut line, lo);
            line.extend_from_slice(b", ");
            push_tuple(&mut line, hi);
            line.push(b']');
            out.write_all(&line)
        }
        Values::Vectors(v) => {
            let values = bytemuck::cast_slice(v);
            array_chunks(out, v.len(), |rows, buffer| {
                let mut text = F32Text::new(values);
                each_record(rows, buffer, |i, line| {
                    text.push_row(line, b"(", i, b", ", b")");
                    item_end(line, i, v.len());
                });
            })
        }
        Values::Scalars(s) => array(out, s.len(), |i, line| push_f32(line, s[i])),
        Values::Indices(t) => {
            let corners = bytemuck::cast_slice(t);
            array_chunks(out, t.len(), |rows, buffer| {
                let mut text = IntText::new(corners, 0);
                each_record(rows, buffer, |i, line| {
                    text.push_row(line, b"", i, b", ", None, b"");
                    item_end(line, i, t.len());
                });
            })
        }
        Values::Counts(n) => {
            out.write_all(b"[")?;
            write_records(out, n, |i, line| {
                line.push(b'3');
                if i + 1 < n {
                    line.extend_from_slice(if i % 32 == 31 { b",\n" } else { b", " });
                }
            })?;
            out.write_all(b"]")
        }
    }
}

/// `[` then `count` items one a line, comma-separated, then `]`.
fn array(
    out: &mut impl Write,
    count: usize,
    item: impl Fn(usize, &mut Vec<u8>) + Sync,
) -> io::Result<()> {
    array_chunks(out, count, |items, buffer| {
        each_record(items, buffer, |i, line| {
            item(i, line);
            item_end(line, i, count);
        });
    })
}

/// [`array`] a chunk at a time, as [`write_chunks`] formats it: each item ended by
/// [`item_end`].
fn array_chunks(
    out: &mut impl Write,
    count: usize,
    chunk: impl Fn(Range<usize>, &mut Vec<u8>) + Sync,
) -> io::Result<()> {
    if count == 0 {
        return out.write_all(b"[]");
    }
    out.write_all(b"[\n")?;
    write_chunks(out, count, chunk)?;
    out.write_all(b"]")
}

/// Ends item `i` of `count` in an array: a comma but after the last, and a new line.
fn item_end(line: &mut Vec<u8>, i: usize, count: usize) {
    line.extend_from_slice(if i + 1 < count { b",\n" } else { b"\n" });
}

/// `(x, y, z)`, each the shortest text that reads back as the same `f32`.
fn push_tuple(line: &mut Vec<u8>, v: Vec3) {
    push_f32_row(line, b"(", v.to_array(), b", ", b")");
}

/// The attribute declarations at the top of a frame layer splash wrote (each line of them, the
/// metadata lines included), up to the first value: what a sequence stage declares for its
/// clips. Reads no further than the declarations; None if `layer` is not such a layer.
pub(super) fn declarations(layer: &mut impl BufRead) -> io::Result<Option<Vec<String>>> {
    let mut lines = Vec::new();
    let mut line = String::new();
    let mut in_prim = false;
    // A layer's head is a few hundred bytes; a longer one is not splash's.
    for _ in 0..200 {
        line.clear();
        if layer.read_line(&mut line)? == 0 {
            return Ok(None);
        }
        let text = line.trim_end();
        if !in_prim {
            in_prim = text == format!("def Mesh \"{USD_PRIM}\"");
            continue;
        }
        if text == "{" {
            continue;
        }
        if text.contains(" = ") && !text.contains("interpolation") || text == "}" {
            return Ok(Some(lines));
        }
        lines.push(text.to_string());
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::Attribute;

    /// A tetrahedron with normals, a velocity and a scalar and a vector attribute.
    fn tetrahedron() -> TriMesh {
        let vertices = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::new(0.0, 0.0, 1.000_000_1),
        ];
        TriMesh {
            normals: vertices.iter().map(|v| -v.normalize_or_zero()).collect(),
            vertices,
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    fn written(mesh: &TriMesh, named: &[(String, Attribute)], frame: UsdFrame) -> String {
        let attributes = VertexAttributes {
            named,
            ..Default::default()
        };
        let mut out = Vec::new();
        write(mesh, &attributes, frame, &mut out).unwrap();
        String::from_utf8(out).unwrap()
    }

    /// The numbers between the first `[` after `key` and the next `]`.
    fn numbers(text: &str, key: &str) -> Vec<f32> {
        let at = text.rfind(key).unwrap() + key.len();
        let open = at + text[at..].find('[').unwrap();
        let close = open + text[open..].find(']').unwrap();
        text[open + 1..close]
            .split(|c: char| c == ',' || c == '(' || c == ')' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .map(|s| s.parse().unwrap())
            .collect()
    }

    /// Parsed back, the arrays are the mesh's, exactly (f32 for f32), the counts one 3 per
    /// triangle, the extent the box; with a time every value is a sample at it.
    #[test]
    fn a_frame_reads_back_as_the_mesh() {
        let mesh = tetrahedron();
        let velocity: Vec<Vec3> = mesh.vertices.iter().map(|v| *v * 2.5).collect();
        let density = vec![1000.0, 999.5, 0.1, 1.0e-7];
        let named = [
            ("velocity".to_string(), Attribute::Vector(velocity.clone())),
            ("density".to_string(), Attribute::Scalar(density.clone())),
        ];
        let frame = UsdFrame {
            time: Some(40),
            up_axis: Some(UpAxis::Z),
        };
        let text = written(&mesh, &named, frame);
        let flat = |v: &[Vec3]| v.iter().flat_map(|v| v.to_array()).collect::<Vec<f32>>();
        assert_eq!(
            numbers(&text, "point3f[] points.timeSamples"),
            flat(&mesh.vertices)
        );
        assert_eq!(
            numbers(&text, "normal3f[] normals.timeSamples"),
            flat(&mesh.normals)
        );
        assert_eq!(
            numbers(&text, "vector3f[] velocities.timeSamples"),
            flat(&velocity)
        );
        assert_eq!(
            numbers(&text, "float[] primvars:density.timeSamples"),
            density
        );
        let indices: Vec<f32> = mesh.triangles.iter().flatten().map(|&i| i as f32).collect();
        assert_eq!(numbers(&text, "faceVertexIndices.timeSamples"), indices);
        assert_eq!(numbers(&text, "faceVertexCounts.timeSamples"), [3.0; 4]);
        assert_eq!(
            numbers(&text, "extent.timeSamples"),
            [0.0, 0.0, 0.0, 1.0, 1.0, 1.000_000_1]
        );
        assert_eq!(text.matches("        40: [").count(), 7, "{text}");
        for line in [
            "    startTimeCode = 40",
            "    upAxis = \"Z\"",
            "    metersPerUnit = 1",
        ] {
            assert!(text.lines().any(|l| l == line), "{line}");
        }
        // Without a time: default values, no time metadata.
        let text = written(&mesh, &[], UsdFrame::default());
        assert!(!text.contains("timeSamples") && !text.contains("TimeCode"));
        assert_eq!(numbers(&text, "point3f[] points = "), flat(&mesh.vertices));
        assert!(!text.contains("velocities"));
    }

    /// The declarations a stage reads are every attribute's, in order, metadata included, and
    /// nothing of the values.
    #[test]
    fn declarations_are_read_from_the_head() {
        let mesh = tetrahedron();
        let named = [(
            "velocity".to_string(),
            Attribute::Vector(mesh.vertices.clone()),
        )];
        let text = written(
            &mesh,
            &named,
            UsdFrame {
                time: Some(3),
                up_axis: None,
            },
        );
        let read = declarations(&mut text.as_bytes()).unwrap().unwrap();
        assert_eq!(
            read,
            [
                "    float3[] extent",
                "    int[] faceVertexCounts",
                "    int[] faceVertexIndices",
                "    normal3f[] normals (",
                "        interpolation = \"vertex\"",
                "    )",
                "    point3f[] points",
                "    vector3f[] velocities",
            ]
        );
        assert_eq!(declarations(&mut &b"#usda 1.0\n"[..]).unwrap(), None);
    }

    /// An empty mesh has empty arrays and no extent; attribute names become identifiers, and
    /// two that become the same one are refused.
    #[test]
    fn empty_meshes_and_odd_names() {
        let named = [("2nd-phase".to_string(), Attribute::Scalar(Vec::new()))];
        let text = written(&TriMesh::default(), &named, UsdFrame::default());
        assert!(text.contains("point3f[] points = []") && !text.contains("extent"));
        assert!(text.contains("float[] primvars:_2nd_phase = []"), "{text}");
        let clash = [
            ("a-b".to_string(), Attribute::Scalar(Vec::new())),
            ("a.b".to_string(), Attribute::Scalar(Vec::new())),
        ];
        let attributes = VertexAttributes {
            named: &clash,
            ..Default::default()
        };
        let e = write(
            &TriMesh::default(),
            &attributes,
            UsdFrame::default(),
            &mut Vec::new(),
        );
        assert!(e.unwrap_err().to_string().contains("'a_b'"));
    }
}
