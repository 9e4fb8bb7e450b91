//! `preview`: a ray-traced image of the metaball surface of numpy positions, as `splash
//! preview` renders it, returned as an (H, W, 3) uint8 array.

use ndarray::Array3;
use numpy::PyArray3;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use splash_sph::Vec3;
use splash_sph::preview::{
    BvhKind, Camera, Colouring, Previewer, Style, parse_colour, robust_bounds, up_vector,
};

use crate::arrays;
use crate::errors::to_py;
use crate::settings::{self, Overrides};

fn vector(v: Option<(f32, f32, f32)>) -> Option<Vec3> {
    v.map(|(x, y, z)| Vec3::new(x, y, z))
}

/// A ray-traced picture of the metaball surface of ``positions`` (an (N, 3) float array), the
/// surface ``reconstruct(..., field="metaball")`` meshes, as an (H, W, 3) uint8 RGB array.
///
/// ``spacing``: the particle spacing r (required unless the config gives it). ``size``:
/// (width, height) in pixels. Without ``camera`` the camera frames the particles' 0.5–99.5 %
/// percentile box from ``view`` (default: front, right, above; see ``splash preview --help``);
/// ``camera`` without ``look_at`` looks at that box's centre. ``up``: the image's up
/// direction, default the data's ``up_axis`` (``"y"`` or ``"z"``). ``fov``: vertical field of
/// view in degrees. ``background``, ``colour``: ``"#rrggbb"`` or ``"R,G,B"``. ``bvh``:
/// ``"fitted"`` (default) or ``"plain"``. ``config`` and ``threads`` as for ``reconstruct``;
/// ``samples``: rays per pixel, stratified; ``ao``: ambient-occlusion rays per pixel (0 off);
/// both default to the config's ``[preview]`` table. ``values``: an (N,) array, or (N, 3) for
/// its magnitude (e.g. velocities), colouring the surface through viridis, with a legend
/// unless ``legend=False``. The image does not depend on the thread count. The GIL is released
/// while rendering.
/// Raises ValueError for bad settings, cameras or sizes.
#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (positions, spacing=None, *, size=(1280, 720), camera=None, look_at=None,
    up=None, up_axis="y", view=None, fov=40.0, background="#eceef2", colour="#3a7bd5",
    shadows=true, bvh="fitted", threads=None, config=None, samples=None, ao=None, values=None,
    legend=None))]
pub fn preview<'py>(
    py: Python<'py>,
    positions: &Bound<'py, PyAny>,
    spacing: Option<f32>,
    size: (u32, u32),
    camera: Option<(f32, f32, f32)>,
    look_at: Option<(f32, f32, f32)>,
    up: Option<(f32, f32, f32)>,
    up_axis: &str,
    view: Option<(f32, f32, f32)>,
    fov: f32,
    background: &str,
    colour: &str,
    shadows: bool,
    bvh: &str,
    threads: Option<i64>,
    config: Option<&Bound<'py, PyAny>>,
    samples: Option<u32>,
    ao: Option<u32>,
    values: Option<&Bound<'py, PyAny>>,
    legend: Option<bool>,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let overrides = Overrides {
        spacing,
        threads,
        ..Overrides::default()
    };
    let mut config = settings::resolve(config, overrides)?;
    if config.spacing.is_none() {
        return Err(PyValueError::new_err(
            "the particle spacing is not set: pass spacing=r or give spacing in the config; \
             splash_sph.estimate_spacing(positions) estimates it",
        ));
    }
    let z_up = match up_axis.trim().to_ascii_lowercase().as_str() {
        "y" => false,
        "z" => true,
        _ => {
            return Err(PyValueError::new_err(format!(
                "up_axis '{up_axis}': expected y or z"
            )));
        }
    };
    let style = Style {
        background: parse_colour(background).map_err(to_py)?,
        colour: parse_colour(colour).map_err(to_py)?,
        shadows,
        samples: samples.unwrap_or(config.preview.samples),
        ao: ao.unwrap_or(config.preview.ao),
        legend: legend.unwrap_or(config.preview.legend),
    };

    let kind = BvhKind::parse(bvh).map_err(to_py)?;
    let threads = config.threads.take();
    let previewer = Previewer::new(&config).map_err(to_py)?.with_bvh(kind);
    let points = arrays::points(positions, "positions")?;
    let positions = points.as_slice();
    // (N,) values as they are, (N, 3) by magnitude.
    let colouring = match values {
        Some(v) => Some(Colouring::new(&arrays::column(
            v,
            "values",
            positions.len(),
        )?)),
        None => None,
    };
    let (w, h) = size;
    let up = vector(up).unwrap_or_else(|| up_vector(z_up));
    let (position, target, view) = (vector(camera), vector(look_at), vector(view));
    let image = py
        .detach(|| {
            let cam = match (position, target) {
                (Some(p), Some(t)) => Camera::look_at(p, t, up, fov, w, h)?,
                (Some(p), None) => {
                    if positions.is_empty() {
                        return Err(splash_sph::Error::Input(
                            "no particles to look at: give look_at".into(),
                        ));
                    }
                    let (lo, hi) = robust_bounds(positions);
                    Camera::look_at(p, 0.5 * (lo + hi), up, fov, w, h)?
                }
                (None, Some(_)) => {
                    return Err(splash_sph::Error::Input(
                        "look_at needs camera (without both the camera is framed automatically)"
                            .into(),
                    ));
                }
                (None, None) => Camera::auto(positions, previewer.margin(), up, view, fov, w, h)?,
            };
            splash_sph::install(threads, || {
                previewer.render_coloured(positions, colouring.as_ref(), &cam, &style)
            })?
        })
        .map_err(to_py)?;
    let array = Array3::from_shape_vec((h as usize, w as usize, 3), image.image.rgb)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(PyArray3::from_owned_array(py, array))
}
