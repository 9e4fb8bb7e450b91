//! Images as PNG (8-bit RGB), written atomically like the meshes.

use std::io::{self, BufWriter, Write};
use std::path::Path;

/// An RGB image, rows top to bottom, 3 bytes a pixel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height × 3` bytes.
    pub rgb: Vec<u8>,
}

impl Image {
    /// The pixel at (`x`, `y`).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }
}

/// Encodes `image` as PNG into `w`.
pub fn encode_png(image: &Image, w: impl Write) -> io::Result<()> {
    let mut encoder = png::Encoder::new(BufWriter::new(w), image.width, image.height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header().map_err(io::Error::other)?;
    writer
        .write_image_data(&image.rgb)
        .map_err(io::Error::other)?;
    writer.finish().map_err(io::Error::other)
}

/// Writes `image` to `path` as PNG through a temporary file renamed into place, so that an
/// existing file is always a complete image. Creates missing parent directories.
pub fn write_png(path: &Path, image: &Image) -> crate::Result<()> {
    crate::io::atomic::write_file(path, |file| encode_png(image, file))
}
