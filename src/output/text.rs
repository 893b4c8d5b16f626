//! Text on images (chart labels, the preview's grid labels), drawn with `plotters` and
//! ab_glyph from an embedded DejaVu Sans Mono (assets/fonts/, Bitstream Vera licence), so
//! nothing depends on the machine's fonts.

use std::sync::Once;

use plotters::prelude::*;

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSansMono.ttf");

/// The family name text is drawn with, once [`register_font`] ran.
pub const FAMILY: &str = "sans-serif";

/// ab_glyph needs the font registered once per process under the family name we use.
pub fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // Only fails on a malformed font, which the embedded file is not (tested).
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT);
    });
}

/// A label at a pixel position (its top-left corner), in an RGB colour.
pub struct Label {
    pub x: i32,
    pub y: i32,
    pub text: String,
    pub color: [u8; 3],
}

/// Draw `labels` (`size` pixels high) onto an RGBA image in place.
pub fn draw_labels(rgba: &mut [u8], width: u32, height: u32, size: u32, labels: &[Label]) {
    register_font();
    let mut rgb: Vec<u8> = rgba
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        for l in labels {
            let [r, g, b] = l.color;
            let style = (FAMILY, size).into_font().color(&RGBColor(r, g, b));
            // Drawing only fails for text wholly outside the image, which is then skipped.
            let _ = root.draw(&Text::new(l.text.clone(), (l.x, l.y), style));
        }
        let _ = root.present();
    }
    for (p, q) in rgba.chunks_exact_mut(4).zip(rgb.chunks_exact(3)) {
        p[..3].copy_from_slice(q);
    }
}
