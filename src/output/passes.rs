//! The passes written beside the colour frames (`--passes alpha,depth,normal,id`;
//! docs/method.md §7.7): `OUT/alpha/frame_00042.png`, RGBA8 with straight (not
//! premultiplied) colour; `OUT/depth/frame_00042.exr`, an OpenEXR image of one 32-bit float
//! channel `Z`, the alpha-weighted mean camera-space depth (+∞ where nothing was drawn);
//! `OUT/normal/frame_00042.exr`, channels `R`, `G`, `B` the camera-space normal's x, y, z
//! (0 where nothing was drawn); `OUT/id/frame_00042.png`, a 16-bit grey PNG of the id of
//! the Gaussian that contributes most (0 where nothing was drawn), ids as the manifest's
//! `ids` table names them ([`IdTable`]).

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::render::{PassSet, Splats};
use crate::splat::NO_LABEL;

/// A pass beside the colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Pass {
    Alpha,
    Depth,
    Normal,
    Id,
}

impl Pass {
    /// Its name on the command line and its folder in the output directory.
    pub fn name(self) -> &'static str {
        match self {
            Pass::Alpha => "alpha",
            Pass::Depth => "depth",
            Pass::Normal => "normal",
            Pass::Id => "id",
        }
    }

    /// What the renderer must make for `passes`.
    pub fn set(passes: &[Pass]) -> PassSet {
        PassSet {
            alpha_depth: passes
                .iter()
                .any(|p| matches!(p, Pass::Alpha | Pass::Depth)),
            normal: passes.contains(&Pass::Normal),
            id: passes.contains(&Pass::Id),
        }
    }

    /// Its folder under the output directory `out`.
    pub fn dir(self, out: &Path) -> PathBuf {
        out.join(self.name())
    }

    /// Frame `frame`'s file of this pass under the output directory `out`.
    pub fn frame_file(self, out: &Path, frame: u32) -> PathBuf {
        let ext = match self {
            Pass::Alpha | Pass::Id => "png",
            Pass::Depth | Pass::Normal => "exr",
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

/// Row-major ids as a 16-bit grey PNG.
pub fn encode_id_png(width: u32, height: u32, ids: &[u16]) -> Result<Vec<u8>, image::ImageError> {
    let image = image::ImageBuffer::<image::Luma<u16>, &[u16]>::from_raw(width, height, ids)
        .expect("one id a pixel");
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, image::ImageFormat::Png)?;
    Ok(bytes.into_inner())
}

/// Row-major camera-space normals as an OpenEXR image of three 32-bit float channels `R`,
/// `G`, `B` (x, y, z), ZIP-compressed per 16 lines (lossless).
pub fn encode_normal_exr(
    width: u32,
    height: u32,
    normals: &[[f32; 3]],
) -> Result<Vec<u8>, exr::error::Error> {
    use exr::prelude::*;
    let channel = |name: &str, k: usize| {
        AnyChannel::new(
            name,
            FlatSamples::F32(normals.iter().map(|n| n[k]).collect()),
        )
    };
    let layer = Layer::new(
        (width as usize, height as usize),
        LayerAttributes::named("normal"),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(
            [channel("R", 0), channel("G", 1), channel("B", 2)]
                .into_iter()
                .collect(),
        ),
    );
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer).write().to_buffered(&mut bytes)?;
    Ok(bytes.into_inner())
}

/// One entry of the id pass's table: pixels of value `id` show this object's region.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct IdEntry {
    pub id: u16,
    pub object: String,
    /// The region label (a procedural asset's `rind`, a capture's segment), if any.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub region: Option<String>,
}

/// The id pass's ids: one per (object, region) pair that has Gaussians, numbered from 1 in
/// the order the Gaussians come (0 is nothing drawn).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IdTable {
    pub entries: Vec<IdEntry>,
    /// Each Gaussian's id.
    pub ids: Vec<u16>,
}

impl IdTable {
    /// From the objects' runs of `splats` (name, Gaussians) and the splats' region labels.
    /// More than 65,535 pairs do not fit the 16-bit PNG: the rest share the last id.
    pub fn new(objects: &[(String, Range<usize>)], splats: &Splats) -> IdTable {
        let mut entries: Vec<IdEntry> = Vec::new();
        let mut ids = vec![0; splats.len()];
        // (object, label id) → id: one lookup per Gaussian, one name copy per pair. An
        // object may come in several runs (its static and its simulated Gaussians).
        let mut known: HashMap<(&str, u16), u16> = HashMap::new();
        for (name, run) in objects {
            for g in run.clone() {
                let label = splats.labels.get(g).copied().unwrap_or(NO_LABEL);
                ids[g] = *known.entry((name.as_str(), label)).or_insert_with(|| {
                    if entries.len() >= usize::from(u16::MAX) {
                        return u16::MAX;
                    }
                    let id = entries.len() as u16 + 1;
                    entries.push(IdEntry {
                        id,
                        object: name.clone(),
                        region: splats.label_name(g).map(str::to_string),
                    });
                    id
                });
            }
        }
        IdTable { entries, ids }
    }
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
