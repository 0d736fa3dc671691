//! Small SVG line charts for the reports of the `jawtrack` command and of the benchmarks
//! (trajectories against their truth, errors per view): axes with round-number ticks, one
//! polyline or set of dots per series, a legend; saved as SVG and, for reports read where SVG
//! is not shown, rasterised to PNG by resvg. Its own crate so that the command and the
//! benchmarks share it without either depending on the other.

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
pub use svg::Document;
use svg::node::element::{Circle, Line, Polyline, Rectangle, Text};

/// `v` with `decimals` decimals, as every report shows a number: a value that rounds to zero
/// prints without a minus sign ("-0.00 mm" reads as a direction).
pub fn fixed(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_owned(),
        _ => s,
    }
}

/// How a series is drawn.
#[derive(Clone, Copy)]
pub enum Style {
    /// A line through the points.
    Line,
    /// A dot at each point.
    Dots,
    /// A larger dot at each point with the series' name written beside it, for a few named
    /// points (landmarks).
    Marked,
}

/// One series of a chart.
pub struct Series<'a> {
    /// Its name in the legend.
    pub name: &'a str,
    /// Its SVG colour ("#d62728").
    pub color: &'a str,
    /// Line or dots.
    pub style: Style,
    /// (x, y) in the axes' units; points that are not finite are left out.
    pub points: Vec<(f64, f64)>,
}

const W: f64 = 640.0;
const H: f64 = 400.0;
const LEFT: f64 = 70.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 50.0;

/// The tick step, 1, 2 or 5 × 10ⁿ, for [lo, hi].
fn tick_step(lo: f64, hi: f64) -> f64 {
    let span = (hi - lo).max(1e-9);
    let raw = span / 6.0;
    let mag = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * mag).find(|s| span / s <= 8.0).unwrap_or(10.0 * mag)
}

/// Ticks at 1, 2 or 5 × 10ⁿ covering [lo, hi].
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let step = tick_step(lo, hi);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|i| i as f64 * step).collect()
}

/// The ticks of [lo, hi] with their labels, written with the step's decimals: a multiple of
/// the step is not exact in binary (3 × 0.2 is 0.6000000000000001).
fn labelled_ticks(lo: f64, hi: f64) -> Vec<(f64, String)> {
    let decimals = (-tick_step(lo, hi).log10().floor()).max(0.0) as usize;
    ticks(lo, hi).into_iter().map(|t| (t, format!("{t:.decimals$}"))).collect()
}

fn label(s: &str, x: f64, y: f64, anchor: &str) -> Text {
    Text::new(s)
        .set("x", x)
        .set("y", y)
        .set("font-family", "sans-serif")
        .set("font-size", 12)
        .set("text-anchor", anchor)
}

/// A chart of `series` with its title and axis labels; the y axis keeps the x axis's scale
/// when `equal_axes` (paths in a plane).
pub fn chart(title: &str, x_label: &str, y_label: &str, series: &[Series<'_>], equal_axes: bool) -> Document {
    let all = series.iter().flat_map(|s| s.points.iter().copied()).filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = all
        .fold((f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY), |(a, b, c, d), (x, y)| {
            (a.min(x), b.max(x), c.min(y), d.max(y))
        });
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    let pad = |lo: f64, hi: f64| {
        let p = ((hi - lo) * 0.05).max(1e-3);
        (lo - p, hi + p)
    };
    (x0, x1) = pad(x0, x1);
    (y0, y1) = pad(y0, y1);
    let (pw, ph) = (W - LEFT - RIGHT, H - TOP - BOTTOM);
    if equal_axes {
        // Widen the narrower range so one mm is as long on both axes.
        let scale = ((x1 - x0) / pw).max((y1 - y0) / ph);
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        (x0, x1) = (cx - scale * pw / 2.0, cx + scale * pw / 2.0);
        (y0, y1) = (cy - scale * ph / 2.0, cy + scale * ph / 2.0);
    }
    let sx = move |x: f64| LEFT + (x - x0) / (x1 - x0) * pw;
    let sy = move |y: f64| TOP + (y1 - y) / (y1 - y0) * ph;
    let mut doc = Document::new()
        .set("viewBox", (0, 0, W, H))
        .set("width", W)
        .set("height", H)
        .add(Rectangle::new().set("width", W).set("height", H).set("fill", "white"))
        .add(label(title, W / 2.0, 22.0, "middle").set("font-size", 15))
        .add(label(x_label, LEFT + pw / 2.0, H - 12.0, "middle"))
        .add(
            label(y_label, 16.0, TOP + ph / 2.0, "middle")
                .set("transform", format!("rotate(-90 16 {})", TOP + ph / 2.0)),
        );
    for (t, text) in labelled_ticks(x0, x1) {
        doc = doc
            .add(Line::new().set("x1", sx(t)).set("x2", sx(t)).set("y1", TOP).set("y2", TOP + ph).set("stroke", "#ddd"))
            .add(label(&text, sx(t), TOP + ph + 16.0, "middle"));
    }
    for (t, text) in labelled_ticks(y0, y1) {
        doc = doc
            .add(
                Line::new()
                    .set("x1", LEFT)
                    .set("x2", LEFT + pw)
                    .set("y1", sy(t))
                    .set("y2", sy(t))
                    .set("stroke", "#ddd"),
            )
            .add(label(&text, LEFT - 6.0, sy(t) + 4.0, "end"));
    }
    doc = doc.add(
        Rectangle::new()
            .set("x", LEFT)
            .set("y", TOP)
            .set("width", pw)
            .set("height", ph)
            .set("fill", "none")
            .set("stroke", "#444"),
    );
    let mut legend = 0;
    for s in series {
        let pts: Vec<(f64, f64)> =
            s.points.iter().filter(|p| p.0.is_finite() && p.1.is_finite()).map(|&(x, y)| (sx(x), sy(y))).collect();
        match s.style {
            Style::Line => {
                let list: Vec<String> = pts.iter().map(|(x, y)| format!("{x:.2},{y:.2}")).collect();
                doc = doc.add(
                    Polyline::new()
                        .set("points", list.join(" "))
                        .set("fill", "none")
                        .set("stroke", s.color)
                        .set("stroke-width", 2),
                );
            }
            Style::Dots => {
                for (x, y) in &pts {
                    doc = doc.add(Circle::new().set("cx", *x).set("cy", *y).set("r", 3).set("fill", s.color));
                }
            }
            Style::Marked => {
                for (x, y) in &pts {
                    // The name on the side of the plot's centre, so it stays inside the frame.
                    let right = *x < LEFT + pw / 2.0;
                    let (dx, anchor) = if right { (8.0, "start") } else { (-8.0, "end") };
                    doc = doc
                        .add(
                            Circle::new()
                                .set("cx", *x)
                                .set("cy", *y)
                                .set("r", 5)
                                .set("fill", s.color)
                                .set("stroke", "white"),
                        )
                        .add(label(s.name, x + dx, y - 6.0, anchor).set("font-size", 11));
                }
            }
        }
        // Marked points carry their names beside them, not in the legend.
        if matches!(s.style, Style::Marked) {
            continue;
        }
        let ly = TOP + 14.0 + 16.0 * legend as f64;
        legend += 1;
        doc = doc
            .add(
                Rectangle::new()
                    .set("x", LEFT + 10.0)
                    .set("y", ly - 9.0)
                    .set("width", 10)
                    .set("height", 10)
                    .set("fill", s.color),
            )
            .add(label(s.name, LEFT + 26.0, ly, "start"));
    }
    doc
}

/// Writes `doc` as `<stem>.svg` and `<stem>.png` (twice the SVG's size; text in the system's
/// sans-serif font, left out when the system has none); returns both paths.
pub fn save_svg_and_png(doc: &Document, stem: &Path) -> Result<[PathBuf; 2]> {
    use resvg::{tiny_skia, usvg};
    let svg_path = stem.with_extension("svg");
    let png_path = stem.with_extension("png");
    let text = doc.to_string();
    std::fs::write(&svg_path, &text).with_context(|| format!("writing {}", svg_path.display()))?;
    let mut options = usvg::Options::default();
    let fonts = options.fontdb_mut();
    fonts.load_system_fonts();
    // usvg reads "sans-serif" as Arial unless told otherwise: name a face the system has.
    let has = |name: &str| fonts.faces().any(|f| f.families.iter().any(|(n, _)| n == name));
    let family = ["DejaVu Sans", "Liberation Sans", "Noto Sans", "Arial", "Helvetica"]
        .into_iter()
        .find(|n| has(n))
        .map(str::to_owned)
        .or_else(|| fonts.faces().next().and_then(|f| f.families.first()).map(|(n, _)| n.clone()));
    if let Some(family) = family {
        fonts.set_sans_serif_family(family);
    }
    let tree = usvg::Tree::from_str(&text, &options).context("reading back our own SVG")?;
    const SCALE: f32 = 2.0;
    let size = tree.size().to_int_size().scale_by(SCALE).context("the chart's size")?;
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height()).context("a pixmap for the chart")?;
    resvg::render(&tree, tiny_skia::Transform::from_scale(SCALE, SCALE), &mut pixmap.as_mut());
    pixmap.save_png(&png_path).with_context(|| format!("writing {}", png_path.display()))?;
    Ok([svg_path, png_path])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_has_no_sign_and_everything_else_keeps_its_own() {
        assert_eq!(
            [fixed(-0.0, 2), fixed(-0.004, 2), fixed(-0.005, 3), fixed(1.5, 1)],
            ["0.00", "0.00", "-0.005", "1.5"]
        );
    }

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        assert_eq!(ticks(0.0, 10.0), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        let t = ticks(-0.37, 0.81);
        assert_eq!(t.first().copied(), Some(-0.2));
        assert!(t.iter().all(|v| (-0.37..=0.81).contains(v)));
    }

    #[test]
    fn tick_labels_show_the_step_s_decimals_only() {
        let s = [Series { name: "line", color: "#c00", style: Style::Line, points: vec![(0.0, 0.0), (1.0, 1.0)] }];
        let text = chart("t", "x", "y", &s, false).to_string();
        assert!(!text.contains("0.6000000000000001"), "{text}");
        for tick in ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"] {
            assert!(text.contains(&format!(">\n{tick}\n</text>")), "tick {tick} missing: {text}");
        }
    }

    #[test]
    fn a_chart_draws_each_series_and_its_legend() {
        let s = [
            Series { name: "truth", color: "#000", style: Style::Line, points: vec![(0.0, 0.0), (1.0, 2.0)] },
            Series {
                name: "tracked",
                color: "#c00",
                style: Style::Dots,
                points: vec![(0.0, 0.1), (1.0, 1.9), (2.0, f64::NAN)],
            },
        ];
        let text = chart("t", "x", "y", &s, false).to_string();
        assert_eq!(text.matches("<polyline").count(), 1);
        assert_eq!(text.matches("<circle").count(), 2, "the NaN point is left out");
        assert!(text.contains("truth") && text.contains("tracked"), "legend");
    }

    #[test]
    fn a_chart_saves_as_svg_and_a_png_that_is_not_blank() {
        let dir = tempfile::tempdir().expect("temp dir");
        let s = [Series { name: "line", color: "#c00", style: Style::Line, points: vec![(0.0, 0.0), (1.0, 2.0)] }];
        let [svg, png] = save_svg_and_png(&chart("t", "x", "y", &s, false), &dir.path().join("c")).expect("saved");
        assert!(std::fs::read_to_string(svg).expect("svg").contains("<polyline"));
        let img = image::open(png).expect("a PNG").to_rgb8();
        assert_eq!((img.width(), img.height()), (2 * W as u32, 2 * H as u32));
        let red = img.pixels().filter(|p| p[0] > 150 && p[1] < 80 && p[2] < 80).count();
        assert!(red > 100, "the red line is drawn ({red} red pixels)");
    }
}
