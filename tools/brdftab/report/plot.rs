//! Rate–distortion plots (error vs bytes stored) as PNG, drawn with plotters.
//!
//! Text needs a font and CI machines have none, so DejaVu Sans (embedded by the `dejavu` crate)
//! is registered once as plotters' `sans-serif`.
//!
//! One figure per source, two panels: the cosine-weighted relative RMSE and the relative RMSE of
//! the preview render, each against the compressed size, log scale on both axes. One line per
//! parameterization × codec through the grid presets (small → large, i.e. growing bytes); with a
//! single preset each line is a single marker (markers shrink with the codec index, so equal
//! points nest). Zero errors (e.g. a Lambert table) are drawn at
//! the panel's floor [`FLOOR`]; unmeasured values (−1) are left out.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;

use super::suite::Row;
use brdftab::error::{Error, Result};

/// Smallest error drawn (log axes cannot show 0).
pub const FLOOR: f64 = 1e-7;

static FONT: Once = Once::new();

fn register_font() {
    FONT.call_once(|| {
        // The embedded font is a valid TTF; a failure here would only lose the text.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

fn perr<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> Error + '_ {
    move |e| Error::Unsupported(format!("plot {}: {e}", path.display()))
}

/// One series: label and (bytes, error) points sorted by bytes.
type Series = (String, Vec<(f64, f64)>);

fn series(rows: &[&Row], metric: impl Fn(&Row) -> f64) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    for r in rows {
        let e = metric(r);
        if r.bytes == 0 || e < 0.0 || !e.is_finite() {
            continue;
        }
        let label = format!("{} {}", r.param, r.codec);
        let p = (r.bytes as f64, e.max(FLOOR));
        match out.iter_mut().find(|s| s.0 == label) {
            Some(s) => s.1.push(p),
            None => out.push((label, vec![p])),
        }
    }
    for s in &mut out {
        s.1.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    out
}

fn log_range(vals: impl Iterator<Item = f64>, min_floor: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for v in vals {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() || hi <= 0.0 {
        return (min_floor, min_floor * 10.0);
    }
    let lo = 10f64.powf(lo.max(min_floor).log10().floor());
    let hi = 10f64.powf(hi.log10().ceil()).max(lo * 10.0);
    (lo, hi)
}

fn panel(
    area: &DrawingArea<BitMapBackend, plotters::coord::Shift>,
    path: &Path,
    title: &str,
    y_desc: &str,
    data: &[Series],
    xr: (f64, f64),
) -> Result<()> {
    let yr = log_range(data.iter().flat_map(|s| s.1.iter().map(|p| p.1)), FLOOR);
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        // The ranges are padded by 0.1 % so that plotters' log key points (which round
        // log10(start) up) include the lower decade and its intermediate labels.
        .build_cartesian_2d(
            (xr.0 * 0.999..xr.1 * 1.001).log_scale(),
            (yr.0 * 0.999..yr.1 * 1.001).log_scale(),
        )
        .map_err(perr(path))?;
    chart
        .configure_mesh()
        .x_desc("bytes stored (compressed)")
        .y_desc(y_desc)
        .x_labels(10)
        .y_labels(10)
        .x_label_formatter(&|x| format!("{x:.0e}"))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .label_style(("sans-serif", 13))
        .light_line_style(RGBColor(238, 238, 238))
        .axis_desc_style(("sans-serif", 15))
        .draw()
        .map_err(perr(path))?;
    if data.is_empty() {
        chart
            .draw_series(std::iter::once(Text::new(
                "not measured",
                ((xr.0 * xr.1).sqrt(), (yr.0 * yr.1).sqrt()),
                ("sans-serif", 16),
            )))
            .map_err(perr(path))?;
        return Ok(());
    }
    let codecs: Vec<&str> = {
        let mut v: Vec<&str> = Vec::new();
        for (l, _) in data {
            let c = l.split_once(' ').map_or(l.as_str(), |x| x.1);
            if !v.contains(&c) {
                v.push(c);
            }
        }
        v
    };
    for (i, (label, pts)) in data.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        // Markers shrink with the codec's index, so codecs with equal errors and sizes nest
        // instead of hiding each other.
        let k = codecs.iter().position(|c| label.ends_with(c)).unwrap_or(0) as i32;
        let size = (9 - 2 * k).max(3);
        // halfdiff: filled circles and solid lines; inout: hollow triangles.
        let inout = label.starts_with("inout");
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))
            .map_err(perr(path))?
            .label(label.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        if inout {
            chart
                .draw_series(
                    pts.iter()
                        .map(|&p| TriangleMarker::new(p, size + 2, color.stroke_width(2))),
                )
                .map_err(perr(path))?;
        } else {
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, size, color.filled())))
                .map_err(perr(path))?;
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(perr(path))?;
    Ok(())
}

/// Draws the rate–distortion figure of one source's rows into the PNG `path` (1400 × 560).
pub fn rate_distortion(source: &str, rows: &[&Row], path: &Path) -> Result<()> {
    register_font();
    let rmse = series(rows, |r| r.rel_rmse);
    let rend = series(rows, |r| {
        if r.render == "ok" {
            r.render_rel_rmse
        } else {
            -1.0
        }
    });
    let xr = log_range(
        rows.iter().filter(|r| r.bytes > 0).map(|r| r.bytes as f64),
        1.0,
    );
    let root = BitMapBackend::new(path, (1400, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(perr(path))?;
    let root = root
        .titled(&format!("{source}: error vs size"), ("sans-serif", 22))
        .map_err(perr(path))?;
    let (left, right) = root.split_horizontally(700);
    panel(
        &left,
        path,
        "BRDF error (random pairs)",
        "relative RMSE, cosine-weighted",
        &rmse,
        xr,
    )?;
    panel(
        &right,
        path,
        "preview render error",
        "relative RMSE of the render",
        &rend,
        xr,
    )?;
    root.present().map_err(perr(path))?;
    Ok(())
}
