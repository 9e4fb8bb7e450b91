//! A pinhole camera: explicit (position, target, up, vertical field of view) or framed
//! automatically around the particles.

use glam::Vec3;

use crate::error::Result;

/// Largest image side, and largest pixel count, that a preview accepts.
pub const MAX_SIDE: u32 = 16384;
/// 2²⁸ pixels (16384 × 16384): 768 MiB of RGB.
pub const MAX_PIXELS: u64 = 1 << 28;

/// A pinhole camera and its image size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub position: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_half_v: f32,
    tan_half_h: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

/// The up direction of the data: Y (SPlisHSPlasH, default) or Z (Blender).
pub fn up_vector(z_up: bool) -> Vec3 {
    if z_up { Vec3::Z } else { Vec3::Y }
}

/// The default direction from the fluid's centre towards the auto-framed camera: from the
/// front (+Z for Y-up data, −Y for Z-up), a little to the right (+X) and above: azimuth
/// about 24°, elevation about 27°.
pub fn default_view(up: Vec3) -> Vec3 {
    if up.z.abs() > up.y.abs() {
        Vec3::new(0.45, -1.0, 0.55 * up.z.signum()).normalize()
    } else {
        Vec3::new(0.45, 0.55 * up.y.signum(), 1.0).normalize()
    }
}

/// Checks an image size: both sides from 1 to [`MAX_SIDE`], at most [`MAX_PIXELS`].
pub fn check_size(width: u32, height: u32) -> Result<()> {
    if width == 0 || height == 0 {
        bail_config!("image size {width}x{height}: both sides must be at least 1 pixel");
    }
    if width > MAX_SIDE || height > MAX_SIDE || width as u64 * height as u64 > MAX_PIXELS {
        bail_config!(
            "image size {width}x{height} is too large: at most {MAX_SIDE} pixels a side and \
             {MAX_PIXELS} pixels in all"
        );
    }
    Ok(())
}

/// Parses `WxH` (`1280x720`).
pub fn parse_size(text: &str) -> Result<(u32, u32)> {
    let bad = || {
        crate::Error::config(format!(
            "image size '{text}': expected WIDTHxHEIGHT in pixels, e.g. 1280x720"
        ))
    };
    let (w, h) = text.trim().split_once(['x', 'X', '×']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    check_size(w, h)?;
    Ok((w, h))
}

impl Camera {
    /// A camera at `position` looking at `target`, `up` giving the image's upward direction,
    /// `fov` the vertical field of view in degrees (0 < fov < 180).
    pub fn look_at(
        position: Vec3,
        target: Vec3,
        up: Vec3,
        fov: f32,
        width: u32,
        height: u32,
    ) -> Result<Camera> {
        check_size(width, height)?;
        for (name, v) in [("camera", position), ("look-at", target), ("up", up)] {
            if !v.is_finite() {
                bail_config!(
                    "the {name} vector ({}, {}, {}) is not finite",
                    v.x,
                    v.y,
                    v.z
                );
            }
        }
        if !(fov > 0.0 && fov < 180.0) {
            bail_config!("field of view {fov}°: it must lie strictly between 0 and 180 degrees");
        }
        let view = target - position;
        if view.length() <= 1e-6 * position.length().max(target.length()).max(1e-30) {
            bail_config!(
                "the camera ({}, {}, {}) and the point it looks at coincide",
                position.x,
                position.y,
                position.z
            );
        }
        let forward = view.normalize();
        let right = forward.cross(up);
        if up.length() == 0.0 || right.length() <= 1e-4 * up.length() {
            bail_config!(
                "the up vector ({}, {}, {}) is zero or parallel to the viewing direction",
                up.x,
                up.y,
                up.z
            );
        }
        let right = right.normalize();
        let tan_half_v = (fov.to_radians() / 2.0).tan();
        Ok(Camera {
            position,
            forward,
            right,
            up: right.cross(forward),
            tan_half_v,
            tan_half_h: tan_half_v * width as f32 / height as f32,
            width,
            height,
        })
    }

    /// A camera looking at the centre of `lo`–`hi` from direction `view` (towards the
    /// camera), far enough that the box's bounding sphere fills the narrower field of view.
    pub fn framing(
        lo: Vec3,
        hi: Vec3,
        up: Vec3,
        view: Vec3,
        fov: f32,
        width: u32,
        height: u32,
    ) -> Result<Camera> {
        if !(lo.is_finite() && hi.is_finite()) {
            bail_input!("cannot frame particles whose bounds are not finite");
        }
        if !view.is_finite() || view.length() == 0.0 {
            bail_config!("the view direction must be a non-zero vector");
        }
        check_size(width, height)?;
        if !(fov > 0.0 && fov < 180.0) {
            bail_config!("field of view {fov}°: it must lie strictly between 0 and 180 degrees");
        }
        let centre = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(1e-6 * centre.length().max(1.0));
        let tan_v = (fov.to_radians() / 2.0).tan();
        let tan_narrow = tan_v.min(tan_v * width as f32 / height as f32);
        let half = tan_narrow.atan();
        let distance = radius / half.sin();
        Camera::look_at(
            centre + view.normalize() * distance,
            centre,
            up,
            fov,
            width,
            height,
        )
    }

    /// A camera framing `points` (see [`Camera::framing`]) from their robust bounds: the 0.5th
    /// to 99.5th percentile on each axis, so that a few stray particles do not shrink the fluid
    /// to a dot, widened by `margin`.
    pub fn auto(
        points: &[Vec3],
        margin: f32,
        up: Vec3,
        view: Option<Vec3>,
        fov: f32,
        width: u32,
        height: u32,
    ) -> Result<Camera> {
        if points.is_empty() {
            bail_input!("cannot frame a camera around an empty frame: give --camera");
        }
        let (lo, hi) = robust_bounds(points);
        Camera::framing(
            lo - margin,
            hi + margin,
            up,
            view.unwrap_or_else(|| default_view(up)),
            fov,
            width,
            height,
        )
    }

    /// The unit direction of the ray through the centre of pixel (`x`, `y`), y downwards.
    pub fn direction(&self, x: u32, y: u32) -> Vec3 {
        self.direction_at(x as f32 + 0.5, y as f32 + 0.5)
    }

    /// The unit direction of the ray through image point (`x`, `y`) in pixels from the top
    /// left corner.
    pub fn direction_at(&self, x: f32, y: f32) -> Vec3 {
        let u = (x / self.width as f32 * 2.0 - 1.0) * self.tan_half_h;
        let v = (1.0 - y / self.height as f32 * 2.0) * self.tan_half_v;
        (self.forward + u * self.right + v * self.up).normalize()
    }

    /// The viewing direction.
    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// The image's right and up directions.
    pub fn basis(&self) -> (Vec3, Vec3) {
        (self.right, self.up)
    }
}

/// Per axis the 0.5th and 99.5th percentiles of `points` (all of them below 200 points).
pub fn robust_bounds(points: &[Vec3]) -> (Vec3, Vec3) {
    let mut lo = Vec3::ZERO;
    let mut hi = Vec3::ZERO;
    let n = points.len();
    let cut = if n < 200 { 0 } else { n / 200 };
    let mut values: Vec<f32> = Vec::with_capacity(n);
    for axis in 0..3 {
        values.clear();
        values.extend(points.iter().map(|p| p[axis]));
        let (_, &mut a, _) = values.select_nth_unstable_by(cut, f32::total_cmp);
        let (_, &mut b, _) = values.select_nth_unstable_by(n - 1 - cut, f32::total_cmp);
        lo[axis] = a;
        hi[axis] = b;
    }
    (lo, hi)
}
