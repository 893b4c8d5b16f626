//! PlayCanvas SOG (docs/formats.md): `meta.json` and lossless WebP images, one texel per
//! Gaussian (row-major), either as a folder or bundled in a zip (`.sog`). Positions are
//! 16 bits per axis split over two images (low and high bytes) of a symmetric log
//! transform; rotations are "smallest three" bytes; scales, DC colour and the rest SH use
//! 256-entry codebooks (version 2) or per-channel ranges (version 1, no `version` key).

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use serde_json::Value;

use super::codec::{decode_parallel, Builder, Decoded, Format, SplatError};

fn damaged(file: &str, what: impl Into<String>) -> SplatError {
    SplatError::Damaged {
        file: file.to_string(),
        format: Format::Sog,
        what: what.into(),
    }
}

/// Where the files come from: a folder, or the entries of a zip.
pub enum Source<'a> {
    Folder(&'a Path),
    Zip(&'a [u8]),
}

/// Read a SOG folder (the path of the folder or of its `meta.json`) or a `.sog` zip.
pub fn read(source: Source<'_>, file: &str) -> Result<Builder, SplatError> {
    let mut files = Files::open(source, file)?;
    let meta = files.get("meta.json")?;
    let meta: Value = serde_json::from_slice(&meta)
        .map_err(|e| damaged(file, format!("meta.json is not valid JSON: {e}")))?;
    let version = meta.get("version").and_then(Value::as_u64).unwrap_or(1);
    if version > 2 {
        return Err(SplatError::Unsupported {
            file: file.to_string(),
            format: Format::Sog,
            what: format!("meta.json version {version}"),
            expected: "SOG versions 1 and 2 (splat-transform writes version 2 by default)",
        });
    }
    Decoder::new(&meta, version, &mut files, file)?.decode()
}

struct Files<'a> {
    source: Source<'a>,
    zip: HashMap<String, Vec<u8>>,
    file: String,
}

impl<'a> Files<'a> {
    fn open(source: Source<'a>, file: &str) -> Result<Files<'a>, SplatError> {
        let mut zip = HashMap::new();
        if let Source::Zip(bytes) = &source {
            let mut archive = zip::ZipArchive::new(std::io::Cursor::new(*bytes))
                .map_err(|e| damaged(file, format!("zip archive: {e}")))?;
            for i in 0..archive.len() {
                let mut entry = archive
                    .by_index(i)
                    .map_err(|e| damaged(file, format!("zip entry {i}: {e}")))?;
                if entry.is_dir() {
                    continue;
                }
                let name = entry
                    .name()
                    .map_err(|e| damaged(file, format!("zip entry {i}: {e}")))?
                    .rsplit('/')
                    .next()
                    .unwrap_or_default()
                    .to_string();
                let mut data = Vec::with_capacity(entry.size().min(1 << 30) as usize);
                entry
                    .by_ref()
                    .take(1 << 31)
                    .read_to_end(&mut data)
                    .map_err(|e| damaged(file, format!("zip entry `{name}`: {e}")))?;
                zip.insert(name, data);
            }
        }
        Ok(Files {
            source,
            zip,
            file: file.to_string(),
        })
    }

    fn get(&mut self, name: &str) -> Result<Vec<u8>, SplatError> {
        if name.contains('/') || name.contains('\\') || name.starts_with('.') {
            return Err(damaged(
                &self.file,
                format!("meta.json names the file `{name}` outside the folder"),
            ));
        }
        match &self.source {
            Source::Folder(dir) => std::fs::read(dir.join(name)).map_err(|e| {
                damaged(
                    &self.file,
                    format!(
                        "cannot read `{name}` (named by meta.json) in {}: {e}",
                        dir.display()
                    ),
                )
            }),
            Source::Zip(_) => self.zip.remove(name).ok_or_else(|| {
                damaged(
                    &self.file,
                    format!("the archive has no `{name}` (named by meta.json)"),
                )
            }),
        }
    }

    fn image(&mut self, name: &str) -> Result<Image, SplatError> {
        let bytes = self.get(name)?;
        let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::WebP)
            .map_err(|e| damaged(&self.file, format!("image `{name}`: {e}")))?
            .to_rgba8();
        Ok(Image {
            width: img.width() as usize,
            height: img.height() as usize,
            rgba: img.into_raw(),
            name: name.to_string(),
        })
    }
}

struct Image {
    width: usize,
    height: usize,
    rgba: Vec<u8>,
    name: String,
}

impl Image {
    fn texel(&self, i: usize) -> [u8; 4] {
        let t = &self.rgba[4 * i..4 * i + 4];
        [t[0], t[1], t[2], t[3]]
    }
    fn at(&self, x: usize, y: usize) -> [u8; 4] {
        self.texel(y * self.width + x)
    }
}

/// A table from bytes to values: a 256-entry codebook (v2) or a linear range (v1).
enum Table {
    Codebook(Vec<f32>),
    Range(Vec<f32>, Vec<f32>),
}

impl Table {
    fn value(&self, channel: usize, b: u8) -> f32 {
        match self {
            Table::Codebook(c) => c[usize::from(b)],
            Table::Range(lo, hi) => {
                let (l, h) = (lo[channel.min(lo.len() - 1)], hi[channel.min(hi.len() - 1)]);
                l + (h - l) * f32::from(b) / 255.0
            }
        }
    }
}

struct Decoder {
    count: usize,
    mins: [f32; 3],
    maxs: [f32; 3],
    means_l: Image,
    means_u: Image,
    quats: Image,
    scales: Image,
    scale_table: Table,
    sh0: Image,
    sh0_table: Table,
    /// Opacity from sh0's alpha: v2 a byte of sigmoid, v1 a range of logits.
    opacity_range: Option<(f32, f32)>,
    sh_n: Option<ShN>,
}

struct ShN {
    centroids: Image,
    labels: Image,
    table: Table,
    /// Coefficients per channel beyond DC: 3, 8 or 15.
    coeffs: usize,
    palette: usize,
}

fn floats(v: Option<&Value>, what: &str, file: &str) -> Result<Vec<f32>, SplatError> {
    let list = v
        .and_then(Value::as_array)
        .ok_or_else(|| damaged(file, format!("meta.json lacks `{what}`")))?;
    list.iter()
        .map(|x| {
            x.as_f64()
                .map(|x| x as f32)
                .ok_or_else(|| damaged(file, format!("meta.json `{what}` holds a non-number")))
        })
        .collect()
}

fn files_of<'v>(
    meta: &'v Value,
    key: &str,
    want: usize,
    file: &str,
) -> Result<Vec<&'v str>, SplatError> {
    let names: Vec<&str> = meta
        .get(key)
        .and_then(|m| m.get("files"))
        .and_then(Value::as_array)
        .map(|a| a.iter().filter_map(Value::as_str).collect())
        .unwrap_or_default();
    if names.len() < want {
        return Err(damaged(
            file,
            format!(
                "meta.json `{key}.files` names {} images, expected {want}",
                names.len()
            ),
        ));
    }
    Ok(names)
}

fn table(meta: &Value, key: &str, version: u64, file: &str) -> Result<Table, SplatError> {
    let m = meta.get(key);
    if version >= 2 {
        let c = floats(
            m.and_then(|m| m.get("codebook")),
            &format!("{key}.codebook"),
            file,
        )?;
        if c.len() != 256 {
            return Err(damaged(
                file,
                format!("`{key}.codebook` has {} entries, expected 256", c.len()),
            ));
        }
        Ok(Table::Codebook(c))
    } else {
        let one = |k: &str| -> Result<Vec<f32>, SplatError> {
            match m.and_then(|m| m.get(k)) {
                Some(Value::Number(n)) => Ok(vec![n.as_f64().unwrap_or_default() as f32]),
                v => floats(v, &format!("{key}.{k}"), file),
            }
        };
        Ok(Table::Range(one("mins")?, one("maxs")?))
    }
}

impl Decoder {
    // Over 80 lines on purpose: the bundle's images in the order its meta.json lists them,
    // each decoded where it is checked.
    fn new(
        meta: &Value,
        version: u64,
        files: &mut Files<'_>,
        file: &str,
    ) -> Result<Decoder, SplatError> {
        let means = files_of(meta, "means", 2, file)?;
        let means_l = files.image(means[0])?;
        let means_u = files.image(means[1])?;
        let count = match meta.get("count").and_then(Value::as_u64) {
            Some(c) => c as usize,
            None if version == 1 => meta
                .get("means")
                .and_then(|m| m.get("shape"))
                .and_then(|s| s.get(0))
                .and_then(Value::as_u64)
                .map_or(means_l.width * means_l.height, |c| c as usize),
            None => return Err(damaged(file, "meta.json lacks `count`")),
        };
        let m = meta.get("means");
        let lo = floats(m.and_then(|m| m.get("mins")), "means.mins", file)?;
        let hi = floats(m.and_then(|m| m.get("maxs")), "means.maxs", file)?;
        if lo.len() < 3 || hi.len() < 3 {
            return Err(damaged(
                file,
                "`means.mins`/`means.maxs` need 3 numbers each",
            ));
        }
        let quats = files.image(files_of(meta, "quats", 1, file)?[0])?;
        let scales = files.image(files_of(meta, "scales", 1, file)?[0])?;
        let sh0 = files.image(files_of(meta, "sh0", 1, file)?[0])?;
        let opacity_range = if version >= 2 {
            None
        } else {
            let s = meta.get("sh0");
            let lo = floats(s.and_then(|m| m.get("mins")), "sh0.mins", file)?;
            let hi = floats(s.and_then(|m| m.get("maxs")), "sh0.maxs", file)?;
            if lo.len() < 4 || hi.len() < 4 {
                return Err(damaged(file, "`sh0.mins`/`sh0.maxs` need 4 numbers each"));
            }
            Some((lo[3], hi[3]))
        };
        let sh_n = match meta.get("shN") {
            None | Some(Value::Null) => None,
            Some(s) => {
                let names = files_of(meta, "shN", 2, file)?;
                let centroids = files.image(names[0])?;
                let labels = files.image(names[1])?;
                let bands = match s.get("bands").and_then(Value::as_u64) {
                    Some(b) => b as usize,
                    None => match centroids.width {
                        192 => 1,
                        512 => 2,
                        960 => 3,
                        w => {
                            return Err(damaged(
                                file,
                                format!("cannot tell the SH bands from a centroid image {w} wide"),
                            ))
                        }
                    },
                };
                let coeffs = match bands {
                    1 => 3,
                    2 => 8,
                    3 => 15,
                    b => {
                        return Err(damaged(
                            file,
                            format!("`shN.bands` is {b}, expected 1, 2 or 3"),
                        ))
                    }
                };
                let palette = (centroids.width / coeffs) * centroids.height;
                Some(ShN {
                    table: table(meta, "shN", version, file)?,
                    centroids,
                    labels,
                    coeffs,
                    palette,
                })
            }
        };
        let d = Decoder {
            count,
            mins: [lo[0], lo[1], lo[2]],
            maxs: [hi[0], hi[1], hi[2]],
            means_l,
            means_u,
            quats,
            scales,
            scale_table: table(meta, "scales", version, file)?,
            sh0,
            sh0_table: table(meta, "sh0", version, file)?,
            opacity_range,
            sh_n,
        };
        for img in [&d.means_l, &d.means_u, &d.quats, &d.scales, &d.sh0] {
            if img.width * img.height < count {
                return Err(damaged(
                    file,
                    format!(
                        "image `{}` has {}×{} texels for {count} Gaussians",
                        img.name, img.width, img.height
                    ),
                ));
            }
        }
        if let Some(s) = &d.sh_n {
            if s.labels.width * s.labels.height < count {
                return Err(damaged(
                    file,
                    format!(
                        "image `{}` is too small for {count} Gaussians",
                        s.labels.name
                    ),
                ));
            }
        }
        Ok(d)
    }

    fn decode(self) -> Result<Builder, SplatError> {
        let degree = match self.sh_n.as_ref().map(|s| s.coeffs) {
            Some(3) => 1,
            Some(8) => 2,
            Some(15) => 3,
            _ => 0,
        };
        let d = &self;
        Ok(decode_parallel(d.count, degree, |b, i| {
            let (l, u) = (d.means_l.texel(i), d.means_u.texel(i));
            let position = [0, 1, 2].map(|a| {
                let q = f32::from(u16::from(l[a]) | u16::from(u[a]) << 8) / 65535.0;
                let range = d.maxs[a] - d.mins[a];
                let n = d.mins[a] + if range == 0.0 { 1.0 } else { range } * q;
                n.signum() * (n.abs().exp() - 1.0)
            });
            let qt = d.quats.texel(i);
            let rotation = if (252..=255).contains(&qt[3]) {
                let largest = usize::from(qt[3] - 252);
                let mut q = [0.0f32; 4];
                let mut k = 0;
                let mut sum = 0.0;
                for (j, c) in q.iter_mut().enumerate() {
                    if j == largest {
                        continue;
                    }
                    *c = (f32::from(qt[k]) / 255.0 * 2.0 - 1.0) * std::f32::consts::FRAC_1_SQRT_2;
                    sum += *c * *c;
                    k += 1;
                }
                q[largest] = (1.0 - sum).max(0.0).sqrt();
                q
            } else {
                [1.0, 0.0, 0.0, 0.0]
            };
            let st = d.scales.texel(i);
            let log_scale = [0, 1, 2].map(|a| d.scale_table.value(a, st[a]));
            let c = d.sh0.texel(i);
            let mut coeffs = [0.0f32; 48];
            for ch in 0..3 {
                coeffs[ch] = d.sh0_table.value(ch, c[ch]);
            }
            let opacity = match d.opacity_range {
                None => f32::from(c[3]) / 255.0,
                Some((lo, hi)) => super::codec::sigmoid(lo + (hi - lo) * f32::from(c[3]) / 255.0),
            };
            let mut rest = 0;
            if let Some(s) = &d.sh_n {
                rest = s.coeffs;
                let lt = s.labels.texel(i);
                let label = usize::from(lt[0]) | usize::from(lt[1]) << 8;
                if label < s.palette {
                    let per_row = s.centroids.width / s.coeffs;
                    let (x0, y) = ((label % per_row) * s.coeffs, label / per_row);
                    for j in 0..s.coeffs {
                        let t = s.centroids.at(x0 + j, y);
                        for ch in 0..3 {
                            coeffs[3 * (j + 1) + ch] = s.table.value(ch, t[ch]);
                        }
                    }
                }
            }
            b.push(Decoded {
                position,
                log_scale,
                rotation,
                opacity,
                sh: &coeffs[..3 * (rest + 1)],
            })
        }))
    }
}
