//! `board-plane`: how the corners of a real photo's tag grid sit on one rigid plane, and how
//! their error grows with each tag's blur, for the C library and for our detector through
//! each tone curve (issue 39).
//!
//! The photo is `apriltags-jl/taggridphoto.jpg` of `../shared/data/photos`: an iPhone 8
//! photo of a printed 8 × 5 grid of tag36h11 tags, ids 1–40 in columns of five. No truth
//! comes with it, so the board is its own: every configuration's 160 corners are fitted to
//! one plane (a homography, the tag's size against the grid's pitch, and two terms of radial
//! distortion about the image centre) by Gauss–Newton, and what is left says how well the
//! corners agree with a rigid board. A tag read through the wrong tone curve comes out too
//! large or too small by a share of its blur; the plane fit keeps the size that fits best,
//! so what it cannot absorb is the *dependence* of each tag's size on its blur, which this
//! measures as the slope of the tag's outward residual (px) against its blur σ (px).

use anyhow::{Context, Result, bail};
use clap::Parser;
use jawtrack_apriltag::{Detection, Detector, DetectorConfig, ImageView, ToneCurve, ToneSetting};
use jawtrack_pose::lm::{self, Damping};
use nalgebra::{DMatrix, DVector};
use std::collections::BTreeMap;
use std::path::PathBuf;

#[derive(Parser)]
#[command(about = "Real board photo: corners fitted to a rigid plane, residual against blur, per tone curve")]
struct Args {
    /// The photo folder with `reference_detections.jsonl` (default: `../shared/data/photos`).
    #[arg(long)]
    photos: Option<PathBuf>,
    /// Fixed curves to try besides sRGB and auto (e.g. gamma:1.8,gamma:2.6).
    #[arg(long, value_delimiter = ',', default_value = "gamma:1.8,gamma:2.0,gamma:2.4,gamma:2.6,gamma:2.8")]
    curves: Vec<String>,
    /// Also print every tag's blur and outward residual, per configuration.
    #[arg(long)]
    per_tag: bool,
}

const PHOTO: &str = "apriltags-jl/taggridphoto.jpg";
const COLUMNS_OF: u32 = 5;

/// One configuration's corners, by tag id.
type Corners = BTreeMap<u32, [[f64; 2]; 4]>;

/// The plane's parameters: homography (h33 = 1), the tag's side in grid pitches, and radial
/// distortion k1, k2 on coordinates scaled by the half-diagonal.
const PARAMS: usize = 11;

#[derive(Debug, Clone, Copy)]
struct Plane {
    p: [f64; PARAMS],
    centre: [f64; 2],
    scale: f64,
}

impl Plane {
    /// Where corner `k` (C's order) of tag `id` lands.
    fn project(&self, id: u32, k: usize) -> [f64; 2] {
        let p = &self.p;
        let (col, row) = (f64::from((id - 1) / COLUMNS_OF), f64::from((id - 1) % COLUMNS_OF));
        let (u, v) = [(-1.0, 1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)][k];
        let (x, y) = (col + u * p[8] / 2.0, row + v * p[8] / 2.0);
        let w = p[6] * x + p[7] * y + 1.0;
        let (px, py) = ((p[0] * x + p[1] * y + p[2]) / w, (p[3] * x + p[4] * y + p[5]) / w);
        let (dx, dy) = ((px - self.centre[0]) / self.scale, (py - self.centre[1]) / self.scale);
        let r2 = dx * dx + dy * dy;
        let f = 1.0 + p[9] * r2 + p[10] * r2 * r2;
        [self.centre[0] + dx * f * self.scale, self.centre[1] + dy * f * self.scale]
    }

    /// Each tag's corners' residuals (seen − model), with the tag's mean residual taken out
    /// when its place is left free.
    fn tag_residuals(&self, id: u32, seen: &[[f64; 2]; 4], free_place: bool) -> [[f64; 2]; 4] {
        let mut d = [[0.0; 2]; 4];
        for (k, s) in seen.iter().enumerate() {
            let m = self.project(id, k);
            d[k] = [s[0] - m[0], s[1] - m[1]];
        }
        if free_place {
            let mean = [d.iter().map(|v| v[0]).sum::<f64>() / 4.0, d.iter().map(|v| v[1]).sum::<f64>() / 4.0];
            for v in &mut d {
                *v = [v[0] - mean[0], v[1] - mean[1]];
            }
        }
        d
    }

    fn residuals(&self, corners: &Corners, free_places: bool) -> DVector<f64> {
        DVector::from_iterator(
            corners.len() * 8,
            corners.iter().flat_map(|(&id, c)| self.tag_residuals(id, c, free_places)).flatten(),
        )
    }
}

/// Levenberg–Marquardt (the loop PnP shares) on the parameters `moving`, the rest held, with
/// a forward-difference Jacobian.
fn refine(mut plane: Plane, corners: &Corners, free_places: bool, moving: &[usize]) -> Plane {
    let mut cost = plane.residuals(corners, free_places).norm_squared();
    let damping = Damping { initial: 1e-3, diagonal_floor: 0.0, relative_tolerance: 1e-12, max_iterations: 200 };
    let linearise = |plane: &Plane| {
        let r = plane.residuals(corners, free_places);
        let mut j = DMatrix::zeros(r.len(), moving.len());
        for (col, &i) in moving.iter().enumerate() {
            let h = 1e-7 * plane.p[i].abs().max(1e-3);
            let mut moved = Plane { p: plane.p, ..*plane };
            moved.p[i] += h;
            j.set_column(col, &((moved.residuals(corners, free_places) - &r) / -h));
        }
        Some((j.transpose() * &j, j.transpose() * &r))
    };
    let step = |plane: &Plane, (jtj, g): &(DMatrix<f64>, DVector<f64>), lambda: f64| {
        let delta = lm::damped(jtj, lambda, 0.0).lu().solve(g)?;
        let mut next = Plane { p: plane.p, ..*plane };
        for (col, &i) in moving.iter().enumerate() {
            next.p[i] += delta[col];
        }
        Some(next)
    };
    let evaluate = |plane: &Plane| plane.residuals(corners, free_places).norm_squared();
    // A failed linearisation cannot happen here; the plane is left at its best either way.
    let _ = lm::minimise(&mut plane, &mut cost, &damping, linearise, step, evaluate);
    plane
}

/// Fits the plane to the corners: first every tag where the grid puts it (the homography and
/// the distortion are read off the tags' places, which blur does not move: a tag blurred
/// through the wrong curve grows or shrinks about its centre), then, each tag's place left
/// free (a display draws each tag at whole screen pixels, up to a pixel off the grid), the
/// tag's size alone. Freeing the plane too would let its perspective and distortion soak up
/// whatever growth follows the blur, which follows the depth across the photo.
fn fit_plane(corners: &Corners, width: f64, height: f64) -> Result<Plane> {
    let centre_of = |id: u32| -> Result<[f64; 2]> {
        let c =
            corners.get(&id).with_context(|| format!("tag {id} was not found; the fit needs the grid's corners"))?;
        Ok([c.iter().map(|p| p[0]).sum::<f64>() / 4.0, c.iter().map(|p| p[1]).sum::<f64>() / 4.0])
    };
    // The affine start from tags 1 (0,0), 36 (7,0) and 5 (0,4).
    let (a, b, c) = (centre_of(1)?, centre_of(36)?, centre_of(5)?);
    let mut p = [0.0; PARAMS];
    p[0] = (b[0] - a[0]) / 7.0;
    p[3] = (b[1] - a[1]) / 7.0;
    p[1] = (c[0] - a[0]) / 4.0;
    p[4] = (c[1] - a[1]) / 4.0;
    p[2] = a[0];
    p[5] = a[1];
    p[8] = 0.5;
    let start = Plane { p, centre: [(width - 1.0) / 2.0, (height - 1.0) / 2.0], scale: width.hypot(height) / 2.0 };
    let placed = refine(start, corners, false, &(0..PARAMS).collect::<Vec<_>>());
    Ok(refine(placed, corners, true, &[8]))
}

/// A configuration's fit: RMS over all corner coordinates, each tag's place left free, and
/// each tag's outward residual (the mean over its corners of the residual along the direction
/// from the tag's centre).
struct Fitted {
    rms: f64,
    outward: BTreeMap<u32, f64>,
}

fn measure(corners: &Corners, width: f64, height: f64) -> Result<Fitted> {
    let plane = fit_plane(corners, width, height)?;
    let r = plane.residuals(corners, true);
    let rms = (r.norm_squared() / r.len() as f64).sqrt();
    let mut outward = BTreeMap::new();
    for (&id, c) in corners {
        let d = plane.tag_residuals(id, c, true);
        let model: Vec<[f64; 2]> = (0..4).map(|k| plane.project(id, k)).collect();
        let mid = [model.iter().map(|p| p[0]).sum::<f64>() / 4.0, model.iter().map(|p| p[1]).sum::<f64>() / 4.0];
        let mut sum = 0.0;
        for k in 0..4 {
            let (ox, oy) = (model[k][0] - mid[0], model[k][1] - mid[1]);
            sum += (d[k][0] * ox + d[k][1] * oy) / ox.hypot(oy);
        }
        outward.insert(id, sum / 4.0);
    }
    Ok(Fitted { rms, outward })
}

/// Least-squares slope and its standard error of y on x.
fn slope(points: &[(f64, f64)]) -> (f64, f64) {
    let n = points.len() as f64;
    let (mx, my) = (points.iter().map(|p| p.0).sum::<f64>() / n, points.iter().map(|p| p.1).sum::<f64>() / n);
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let b = sxy / sxx;
    let rss: f64 = points.iter().map(|p| (p.1 - my - b * (p.0 - mx)).powi(2)).sum();
    (b, (rss / (n - 2.0) / sxx).sqrt())
}

fn reference_corners(dir: &std::path::Path) -> Result<Corners> {
    let path = dir.join("reference_detections.jsonl");
    let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let v: serde_json::Value =
            serde_json::from_str(line).with_context(|| format!("a line of {}", path.display()))?;
        if v["path"].as_str() != Some(PHOTO) {
            continue;
        }
        let mut out = Corners::new();
        for d in v["detections"].as_array().context("the photo's line has no detections")? {
            let id = d["id"].as_u64().context("a detection has no id")? as u32;
            let c: [[f64; 2]; 4] = serde_json::from_value(d["corners"].clone()).context("a detection's corners")?;
            out.insert(id, c);
        }
        return Ok(out);
    }
    bail!("{} has no line for {PHOTO}", path.display())
}

fn ours(detector: &Detector, view: &ImageView<'_>) -> Result<Vec<Detection>> {
    // Auto settles over a few frames: the photo is shown as often as a take's settling needs.
    let mut last = Vec::new();
    for _ in 0..4 {
        last = detector.detect(view)?;
    }
    Ok(last)
}

fn main() -> Result<()> {
    let args = Args::parse();
    let dir = args.photos.unwrap_or_else(|| PathBuf::from("../shared/data/photos"));
    let path = dir.join(PHOTO);
    if !path.is_file() {
        bail!("{} is not there: pass --photos with the folder of ../shared/data/photos", path.display());
    }
    let img = image::open(&path).with_context(|| format!("reading {}", path.display()))?.to_luma8();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let view = ImageView::new(img.as_raw(), w, h, w)?;

    let mut settings: Vec<(String, DetectorConfig)> = vec![
        ("ours as C (reference settings)".into(), DetectorConfig::reference()),
        (
            "ours, linear edges through sRGB".into(),
            DetectorConfig { tone: ToneSetting::Fixed(ToneCurve::Srgb), ..DetectorConfig::default() },
        ),
        ("ours, auto (the default)".into(), DetectorConfig::default()),
    ];
    for c in &args.curves {
        let curve: ToneCurve = c.parse().map_err(|e| anyhow::anyhow!("--curves {c}: {e}"))?;
        settings.push((
            format!("ours through {curve}"),
            DetectorConfig { tone: ToneSetting::Fixed(curve), ..DetectorConfig::default() },
        ));
    }

    // The x axis is one for all: each tag's blur as the default detector measures it.
    let mut blur = BTreeMap::new();
    let mut runs: Vec<(String, Corners)> =
        vec![("C library (reference_detections.jsonl)".into(), reference_corners(&dir)?)];
    for (name, config) in settings {
        let detector = Detector::new(config)?;
        let dets = ours(&detector, &view)?;
        if name.contains("auto") {
            let tone = detector.tone();
            match tone.pooled {
                Some(p) => println!(
                    "auto read the photo through {} ({:?}): pooled power law {:.2} from {} sides, misfit {:.2} against \
                     sRGB's {:.2}\n",
                    tone.curve, tone.reason, p.gamma, p.sides, p.misfit, p.srgb_misfit
                ),
                None => println!("auto read the photo through {} ({:?})\n", tone.curve, tone.reason),
            }
            for d in &dets {
                if let Some(b) = d.blur_px {
                    blur.insert(d.id, b);
                }
            }
        }
        runs.push((name, dets.iter().map(|d| (d.id, d.corners)).collect()));
    }
    let mut per_tag = Vec::new();
    println!("| corners from | tags | plane RMS (px) | outward residual per px of blur σ (± s.e.) |");
    println!("|---|---|---|---|");
    for (name, corners) in &runs {
        let fit = measure(corners, w as f64, h as f64)?;
        let pts: Vec<(f64, f64)> = fit.outward.iter().filter_map(|(id, r)| blur.get(id).map(|b| (*b, *r))).collect();
        let (b, se) = slope(&pts);
        println!("| {name} | {} | {:.3} | {b:+.3} ± {se:.3} ({} tags) |", corners.len(), fit.rms, pts.len());
        if args.per_tag {
            for (id, r) in &fit.outward {
                per_tag.push(format!("{name}\t{id}\t{:.3}\t{r:+.3}", blur.get(id).copied().unwrap_or(f64::NAN)));
            }
        }
    }
    if args.per_tag {
        println!("\nconfiguration\ttag\tblur σ (px)\toutward residual (px)");
        for line in per_tag {
            println!("{line}");
        }
    }
    let bs: Vec<f64> = blur.values().copied().collect();
    println!(
        "\nblur σ over the tags: {:.2}–{:.2} px (median {:.2})",
        bs.iter().copied().fold(f64::INFINITY, f64::min),
        bs.iter().copied().fold(0.0, f64::max),
        jawtrack_pose::median(bs.iter().copied()).unwrap_or(f64::NAN)
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid seen through a known plane, every tag grown outward by `k` px per px of a
    /// made-up blur and, with `jitter`, moved off the grid by up to a pixel (as a display
    /// draws it).
    fn seen(k: f64, jitter: bool) -> (Corners, BTreeMap<u32, f64>) {
        let truth = Plane {
            p: [470.0, 8.0, 380.0, -6.0, 466.0, 495.0, 1e-5, -2e-5, 0.505, 0.012, -0.004],
            centre: [2015.5, 1511.5],
            scale: 2520.0,
        };
        let (mut corners, mut blur) = (Corners::new(), BTreeMap::new());
        for id in 1..=40u32 {
            let b = f64::from(id % 7) * 0.25;
            let shift = if jitter { [(f64::from(id) * 0.7).sin(), (f64::from(id) * 1.3).cos()] } else { [0.0; 2] };
            let model: Vec<[f64; 2]> = (0..4).map(|k| truth.project(id, k)).collect();
            let mid = [model.iter().map(|p| p[0]).sum::<f64>() / 4.0, model.iter().map(|p| p[1]).sum::<f64>() / 4.0];
            let mut c = [[0.0; 2]; 4];
            for (i, m) in model.iter().enumerate() {
                let (ox, oy) = (m[0] - mid[0], m[1] - mid[1]);
                let n = ox.hypot(oy);
                c[i] = [m[0] + shift[0] + k * b * ox / n, m[1] + shift[1] + k * b * oy / n];
            }
            corners.insert(id, c);
            blur.insert(id, b);
        }
        (corners, blur)
    }

    fn fitted_slope(fit: &Fitted, blur: &BTreeMap<u32, f64>) -> f64 {
        let pts: Vec<(f64, f64)> = fit.outward.iter().map(|(id, r)| (blur[id], *r)).collect();
        assert_eq!(pts.len(), 40);
        slope(&pts).0
    }

    #[test]
    fn a_rigid_grid_fits_to_nothing() {
        let (corners, _) = seen(0.0, false);
        let fit = measure(&corners, 4032.0, 3024.0).expect("every tag of the grid is there");
        assert!(fit.rms < 1e-4, "RMS {}", fit.rms);
        assert_eq!(fit.outward.len(), 40);
        assert!(fit.outward.values().all(|r| r.abs() < 1e-4), "{:?}", fit.outward);
    }

    #[test]
    fn tags_drawn_off_the_grid_leave_a_twentieth_of_their_shift() {
        // Places off by up to a pixel tilt the plane read off them a little: that is what is
        // left in the tags' shapes.
        let (corners, blur) = seen(0.0, true);
        let fit = measure(&corners, 4032.0, 3024.0).expect("every tag of the grid is there");
        assert!(fit.rms < 0.06, "RMS {}", fit.rms);
        assert!(fitted_slope(&fit, &blur).abs() < 0.02);
    }

    #[test]
    fn the_slope_of_a_tags_growth_with_its_blur_is_recovered() {
        for jitter in [false, true] {
            let (corners, blur) = seen(-0.4, jitter);
            let fit = measure(&corners, 4032.0, 3024.0).expect("every tag of the grid is there");
            let b = fitted_slope(&fit, &blur);
            assert!((b + 0.4).abs() < 0.02, "slope {b} (jitter {jitter})");
        }
    }
}
