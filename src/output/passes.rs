//! The passes written beside the colour frames (`--passes alpha,depth`; docs/method.md
//! §7.7): `OUT/alpha/frame_00042.png`, RGBA8 with straight (not premultiplied) colour, and
//! `OUT/depth/frame_00042.exr`, an OpenEXR image of one 32-bit float channel `Z`, the
//! alpha-weighted mean camera-space depth (+∞ where nothing was drawn).

use std::path::{Path, PathBuf};

/// A pass beside the colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Pass {
    Alpha,
    Depth,
}

impl Pass {
    /// Its name on the command line and its folder in the output directory.
    pub fn name(self) -> &'static str {
        match self {
            Pass::Alpha => "alpha",
            Pass::Depth => "depth",
        }
    }

    /// Its folder under the output directory `out`.
    pub fn dir(self, out: &Path) -> PathBuf {
        out.join(self.name())
    }

    /// Frame `frame`'s file of this pass under the output directory `out`.
    pub fn frame_file(self, out: &Path, frame: u32) -> PathBuf {
        let ext = match self {
            Pass::Alpha => "png",
            Pass::Depth => "exr",
        };
        self.dir(out).join(format!("frame_{frame:05}.{ext}"))
    }
}

/// An RGBA8 image as an RGBA PNG.
pub fn encode_rgba_png(width: u32, height: u32, rgba: &[u8]) -> Result<Vec<u8>, image::ImageError> {
    use image::ImageEncoder;
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes).write_image(
        rgba,
        width,
        height,
        image::ExtendedColorType::Rgba8,
    )?;
    Ok(bytes)
}

/// Row-major depths as an OpenEXR image: one layer, one 32-bit float channel `Z` (the
/// name compositors read depth from), ZIP-compressed per 16 lines (lossless).
pub fn encode_depth_exr(
    width: u32,
    height: u32,
    depth: &[f32],
) -> Result<Vec<u8>, exr::error::Error> {
    use exr::prelude::*;
    let channel = AnyChannel::new("Z", FlatSamples::F32(depth.to_vec()));
    let layer = Layer::new(
        (width as usize, height as usize),
        LayerAttributes::named("depth"),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(std::iter::once(channel).collect()),
    );
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer).write().to_buffered(&mut bytes)?;
    Ok(bytes.into_inner())
}
