//! Cross-sections of every procedural asset (`splat::assets`), as one PNG: a row per asset,
//! the planes y = 0 (x–z), x = 0 (y–z) and z = 0 (x–y), each region in its colour. It shows
//! what only a cut (or a fracture) reveals: seeds, cores, cavities, pores.
//!
//! `cargo run --release --example asset_sections -- out/sections.png [pixels per panel]`

use splatter::splat::assets::{Asset, Kind};

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().unwrap_or_else(|| "asset_sections.png".into());
    let px: u32 = args.next().and_then(|a| a.parse().ok()).unwrap_or(160);
    let background = [0.15, 0.15, 0.2];
    let mut img = image::RgbImage::new(px * 3, px * Kind::ALL.len() as u32);
    for (row, kind) in Kind::ALL.iter().enumerate() {
        let asset = Asset::new(*kind, kind.default_size());
        // The same scale for the three planes: the box's longest half extent.
        let m = asset.half.max_element();
        for plane in 0..3u32 {
            for j in 0..px {
                for i in 0..px {
                    let u = ((i as f64 + 0.5) / px as f64 * 2.0 - 1.0) * m;
                    let v = (1.0 - (j as f64 + 0.5) / px as f64 * 2.0) * m;
                    let p = match plane {
                        0 => [u, 0.0, v],
                        1 => [0.0, u, v],
                        _ => [u, v, 0.0],
                    };
                    let c = asset.sample(p).map_or(background, |(_, c)| c);
                    let rgb = image::Rgb(c.map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8));
                    img.put_pixel(plane * px + i, row as u32 * px + j, rgb);
                }
            }
        }
    }
    img.save(&path)
        .unwrap_or_else(|e| panic!("cannot write {path}: {e}"));
    println!("wrote {path}");
}
