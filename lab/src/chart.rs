//! PNG charts of the studies with `plotters` (bitmap backend into a buffer, encoded by the
//! `image` crate the renderer already uses). Text: [`splatter::output::text`].

use std::path::Path;

use anyhow::{anyhow, Result};
use plotters::prelude::*;

use splatter::output::text::register_font;

/// A colour per series index (colour-blind friendly Tableau-like palette).
pub fn palette(i: usize) -> RGBColor {
    const C: [(u8, u8, u8); 8] = [
        (31, 119, 180),
        (255, 127, 14),
        (44, 160, 44),
        (214, 39, 40),
        (148, 103, 189),
        (140, 86, 75),
        (227, 119, 194),
        (127, 127, 127),
    ];
    let (r, g, b) = C[i % C.len()];
    RGBColor(r, g, b)
}

/// One series of a log-log chart.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Joined by a line (else markers only).
    pub line: bool,
    /// Markers drawn too.
    pub markers: bool,
    pub color: usize,
}

/// Bounds of all positive points, widened by a factor on each side (log axes).
fn log_bounds(series: &[Series]) -> ((f64, f64), (f64, f64)) {
    let pts = series.iter().flat_map(|s| s.points.iter());
    let pos = pts.filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in pos {
        x0 = x0.min(*x);
        x1 = x1.max(*x);
        y0 = y0.min(*y);
        y1 = y1.max(*y);
    }
    if x0 > x1 {
        return ((0.1, 1.0), (0.1, 1.0));
    }
    // Headroom above the data for a legend in an upper corner.
    ((x0 / 1.5, x1 * 1.5), (y0 / 2.0, y1 * 20.0))
}

fn plot_err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("chart: {e:?}")
}

/// The frame both line charts share: caption, margin and label areas.
fn framed<'a, 'b>(
    root: &'a DrawingArea<BitMapBackend<'b>, plotters::coord::Shift>,
    title: &str,
) -> ChartBuilder<'a, 'b, BitMapBackend<'b>> {
    let mut builder = ChartBuilder::on(root);
    builder
        .caption(title, ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(46)
        .y_label_area_size(80);
    builder
}

/// A log-log chart of `series` written to `path` as PNG.
pub fn loglog(
    path: &Path,
    (title, x_desc, y_desc): (&str, &str, &str),
    series: &[Series],
    legend: SeriesLabelPosition,
) -> Result<()> {
    draw_png(path, (900, 600), |root| {
        let ((x0, x1), (y0, y1)) = log_bounds(series);
        let mut chart = framed(root, title)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .x_labels(6)
            .x_label_formatter(&|v| format!("{v:.1e}"))
            .y_label_formatter(&|v| format!("{v:.1e}"))
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(plot_err)?;
        draw_series(&mut chart, series, legend, |(x, y)| *x > 0.0 && *y > 0.0)?;
        Ok(())
    })
}

/// The series and their legend on a chart of any axes; `keep` drops points the axes
/// cannot show (non-positive ones on a log axis).
fn draw_series<'a, DB, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    series: &[Series],
    legend: SeriesLabelPosition,
    keep: impl Fn(&(f64, f64)) -> bool,
) -> Result<()>
where
    DB: DrawingBackend + 'a,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    for s in series {
        let color = palette(s.color);
        let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(&keep).collect();
        if s.line {
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                .map_err(plot_err)?
                .label(&s.label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
        }
        if s.markers {
            let series = chart
                .draw_series(pts.iter().map(|p| Circle::new(*p, 4, color.filled())))
                .map_err(plot_err)?;
            if !s.line {
                series
                    .label(&s.label)
                    .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
            }
        }
    }
    chart
        .configure_series_labels()
        .position(legend)
        .label_font(("sans-serif", 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(plot_err)?;
    Ok(())
}

/// A chart of `series` on linear axes from zero, written to `path` as PNG: for data
/// spanning less than a decade, where a log axis would show no tick.
pub fn lines(
    path: &Path,
    (title, x_desc, y_desc): (&str, &str, &str),
    series: &[Series],
    legend: SeriesLabelPosition,
) -> Result<()> {
    draw_png(path, (900, 600), |root| {
        let pts = || {
            series
                .iter()
                .flat_map(|s| s.points.iter())
                .filter(|(x, y)| x.is_finite() && y.is_finite())
        };
        let x1 = pts()
            .map(|p| p.0)
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE)
            * 1.15;
        // Headroom above the data for the legend.
        let y1 = pts().map(|p| p.1).fold(1.0, f64::max) * 1.6;
        let mut chart = framed(root, title)
            .build_cartesian_2d(0.0..x1, 0.0..y1)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .x_labels(8)
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(plot_err)?;
        draw_series(&mut chart, series, legend, |_| true)?;
        Ok(())
    })
}

/// One cell of a classification map: a colour class and a short text.
pub struct Cell {
    pub class: usize,
    pub text: String,
}

/// A table of coloured cells (rows × columns) with a legend of the classes: the stability
/// atlas. `classes` gives each class's name and colour.
pub fn cell_map(
    path: &Path,
    title: &str,
    row_labels: &[String],
    col_labels: &[String],
    cells: &[Vec<Cell>],
    classes: &[(&str, RGBColor)],
) -> Result<()> {
    let (label_w, head_h, cell_w, cell_h) = (230i32, 70i32, 140i32, 30i32);
    let w = (label_w + cell_w * col_labels.len() as i32 + 20) as u32;
    let h = (head_h + cell_h * row_labels.len() as i32 + 60) as u32;
    draw_png(path, (w, h), |root| {
        let font = |size: i32| ("sans-serif", size).into_font().color(&BLACK);
        root.draw(&Text::new(title, (10, 8), font(15)))
            .map_err(plot_err)?;
        for (j, c) in col_labels.iter().enumerate() {
            let x = label_w + cell_w * j as i32 + 4;
            root.draw(&Text::new(c.as_str(), (x, head_h - 24), font(13)))
                .map_err(plot_err)?;
        }
        for (i, r) in row_labels.iter().enumerate() {
            let y = head_h + cell_h * i as i32;
            root.draw(&Text::new(r.as_str(), (8, y + 8), font(13)))
                .map_err(plot_err)?;
            for (j, cell) in cells[i].iter().enumerate() {
                let x = label_w + cell_w * j as i32;
                let color = classes[cell.class].1;
                root.draw(&Rectangle::new(
                    [(x, y), (x + cell_w - 2, y + cell_h - 2)],
                    color.filled(),
                ))
                .map_err(plot_err)?;
                root.draw(&Text::new(cell.text.as_str(), (x + 4, y + 8), font(12)))
                    .map_err(plot_err)?;
            }
        }
        let y = head_h + cell_h * row_labels.len() as i32 + 16;
        for (k, (name, color)) in classes.iter().enumerate() {
            let x = 10 + 180 * k as i32;
            root.draw(&Rectangle::new([(x, y), (x + 20, y + 16)], color.filled()))
                .map_err(plot_err)?;
            root.draw(&Text::new(*name, (x + 26, y + 2), font(13)))
                .map_err(plot_err)?;
        }
        Ok(())
    })
}

/// A white `w`×`h` bitmap handed to `draw`, then written to `path` as PNG.
fn draw_png(
    path: &Path,
    (w, h): (u32, u32),
    draw: impl FnOnce(&DrawingArea<BitMapBackend, plotters::coord::Shift>) -> Result<()>,
) -> Result<()> {
    register_font();
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        draw(&root)?;
        root.present().map_err(plot_err)?;
    }
    save_rgb(path, w, h, &buf)
}

fn save_rgb(path: &Path, w: u32, h: u32, buf: &[u8]) -> Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    image::save_buffer(path, buf, w, h, image::ExtendedColorType::Rgb8)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Text renders with the embedded font: a caption-only chart has dark pixels in the
    /// caption band, and a chart with no text has none there.
    #[test]
    fn text_renders() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("t.png");
        let classes = [("stable", RGBColor(200, 230, 200))];
        cell_map(&file, "Title text", &[], &[], &[], &classes).unwrap();
        let img = image::open(&file).unwrap().to_rgb8();
        let dark = (0..30)
            .flat_map(|y| (0..200).map(move |x| (x, y)))
            .filter(|&(x, y)| img.get_pixel(x, y)[0] < 128)
            .count();
        assert!(dark > 50, "title drew {dark} dark pixels");
    }
}
