//! Ascii PLY payload: one record per line.

use std::fs::File;
use std::io::BufReader;

use glam::Vec3;

use super::attribute_columns::AttributeColumns;
use super::failure::Result;
use super::ply_layout::{Element, Kind, Layout, Property};
use crate::io::text::lines::Lines;

/// Reads the payload, `remaining_bytes` long, skipping blank lines.
pub(super) fn read(
    mut lines: Lines<BufReader<File>>,
    layout: &Layout,
    attributes: &mut AttributeColumns,
    remaining_bytes: u64,
) -> Result<Vec<Vec3>> {
    let (vertex, xyz) = (&layout.vertex, layout.xyz_indices());
    // Records of an element without properties would be empty lines, which are skipped anyway.
    for element in layout.before.iter().filter(|e| !e.props.is_empty()) {
        for index in 0..element.count {
            if lines.next_non_blank()?.is_none() {
                bail_format!(
                    "the file ends at line {} inside element '{}', after {index} of {} records",
                    lines.line(),
                    element.name,
                    element.count
                );
            }
        }
    }
    // Each property takes at least two bytes ("0 "), which bounds the allocation.
    let shortest = 2 * vertex.props.len() as u64;
    let fit = usize::try_from(remaining_bytes / shortest).unwrap_or(usize::MAX);
    let mut out = Vec::with_capacity(vertex.count.min(fit));
    attributes.reserve(vertex.count.min(fit));
    let last = xyz.iter().copied().max().unwrap_or_default();
    let last = last.max(attributes.last());
    for index in 0..vertex.count {
        let Some((line, text)) = lines.next_non_blank()? else {
            bail_format!(
                "the file ends at line {} after {index} of {} vertices",
                lines.line(),
                vertex.count
            );
        };
        let p = parse_vertex(text, vertex, xyz, last, attributes)
            .map_err(|e| format_failure!("line {line} (vertex {index}): {e}"))?;
        out.push(super::failure::finite(p, || {
            format!("line {line} (vertex {index})")
        })?);
    }
    if layout.vertex_is_last
        && let Some((line, _)) = lines.next_non_blank()?
    {
        bail_format!(
            "line {line}: more data after the {} vertices the header declares (the vertex \
             count is too small)",
            vertex.count
        );
    }
    Ok(out)
}

/// Parses one vertex line up to property `last`: the coordinates, returned, and the
/// attributes, appended.
fn parse_vertex(
    text: &str,
    vertex: &Element,
    xyz: [usize; 3],
    last: usize,
    attributes: &mut AttributeColumns,
) -> Result<Vec3, String> {
    let mut tokens = text.split_ascii_whitespace();
    let too_few = || {
        format!(
            "too few values for the {} properties of the 'vertex' element",
            vertex.props.len()
        )
    };
    let mut coordinates = [0.0; 3];
    attributes.push();
    for (i, prop) in vertex.props.iter().enumerate() {
        let token = tokens.next().ok_or_else(too_few)?;
        if i > last {
            // Past the properties read: only counted, so that a short or long line is caught.
            skip_list(prop, token, &mut tokens, too_few)?;
            continue;
        }
        match prop.kind {
            Kind::Scalar(_) => {
                let coordinate = xyz.iter().position(|&j| j == i);
                if coordinate.is_none() && !attributes.reads(i) {
                    continue;
                }
                let value = token.parse().map_err(|_| {
                    let token = super::failure::short(token);
                    let name = super::failure::short(&prop.name);
                    format!("cannot parse '{token}' as property '{name}'")
                })?;
                match coordinate {
                    Some(c) => coordinates[c] = value,
                    None => attributes.set_last(i, value),
                }
            }
            Kind::List { .. } => skip_list(prop, token, &mut tokens, too_few)?,
        }
    }
    if let Some(extra) = tokens.next() {
        return Err(format!(
            "more values than the {} properties of the 'vertex' element (from '{}' on)",
            vertex.props.len(),
            super::failure::short(extra)
        ));
    }
    Ok(Vec3::from_array(coordinates))
}

/// Skips the rest of property `prop`, whose first token is `token`: nothing for a scalar, the
/// entries of a list.
fn skip_list<'a>(
    prop: &Property,
    token: &str,
    tokens: &mut impl Iterator<Item = &'a str>,
    too_few: impl Fn() -> String,
) -> Result<(), String> {
    if let Kind::List { .. } = prop.kind {
        let n: usize = token.parse().map_err(|_| {
            let token = super::failure::short(token);
            let name = super::failure::short(&prop.name);
            format!("invalid list length '{token}' for property '{name}'")
        })?;
        if n > 0 {
            tokens.nth(n - 1).ok_or_else(too_few)?;
        }
    }
    Ok(())
}
