//! `jawtrack-bench dense`: the dense (photometric) refinement beside the corner pipeline on the
//! same rendered frames (issue 41). Each case is tracked twice from the same frames, once per
//! [`PoseRefinement`], with the marker as rendered (exact), the true intrinsics, and the readout
//! and exposure told; the error of the mandible in the maxilla against the truth, the jitter
//! of a still jaw (frames of one tripod view that differ only in sensor noise) against its
//! Cramér–Rao bound ([`jawtrack_photometric::bound`], from the renderer's noise model), and the
//! refinement's time per body.

use crate::chew::PoseError;
use crate::frames::{self, Development, Phone, Request};
use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_apriltag::tone::{SETTLING_FRAMES, ToneSummary};
use jawtrack_apriltag::{DetectorConfig, ImageView};
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_photometric::{Body, Image, Options, Tag};
use jawtrack_pose::Pose;
use jawtrack_synth::{GroundTruth, Realism, Resolution, SceneKind};
use jawtrack_tone::{ToneCurve, ToneSetting};
use jawtrack_tracker::{Flag, FrameResult, PoseRefinement, Tracker, TrackerConfig};
use nalgebra::{Matrix3, Matrix3x6, Matrix6};
use std::path::PathBuf;

/// Arguments of `jawtrack-bench dense`.
#[derive(Args)]
pub struct DenseArgs {
    /// Cases to run (comma-separated): still-200 (a Pro iPhone's wide camera 200 mm away,
    /// focused there, 1×: the far case), still-100 (the default lens at 100 mm: the easy
    /// case), gamma-1.8 (that, developed with a gamma-1.8 curve), hinge (the default hinge),
    /// chew-2ms and chew-8ms (the capture plan: 220 mm, 2× crop, 10 ms readout, at that
    /// exposure), defocus (the phone 200 mm away with the 2× crop, its focus locked 12 mm behind
    /// the tags: a few millimetres of depth of field miss them), defocus-gamma-1.8 (that,
    /// developed with a gamma-1.8 curve: both strains at once).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "still-200,still-100,gamma-1.8,hinge,chew-2ms,chew-8ms,defocus,defocus-gamma-1.8"
    )]
    cases: Vec<String>,
    /// Frames per view of the still cases (3 tripod and 3 hand-held views): the jitter is
    /// the spread over a tripod view's frames without glare or an occluder, read through the
    /// settled tone curve (23 of the 30 tripod frames at seed 7).
    #[arg(long, default_value_t = 10)]
    still_frames: usize,
    /// Frames of the hinge and chew cases (60 frames/s for chewing).
    #[arg(long, default_value_t = 40)]
    motion_frames: usize,
    /// Where rendered frames are cached.
    #[arg(long, default_value = "target/dense-bench-frames")]
    cache: PathBuf,
    /// Seed of everything random.
    #[arg(long, default_value_t = 7)]
    seed: u64,
    /// Also write the table (Markdown) here.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// How far (mm) behind the tags the `defocus` case's lens is focused: at 200 mm a 6.8 mm f/1.78
/// lens spreads a point 12 mm off its focus over a disc of about 3.5 px at the 2× crop's 1080p
/// (7.6 µm on the sensor).
const DEFOCUS_MM: f64 = 12.0;

/// One case: what is rendered and how it is tracked.
struct Case {
    name: &'static str,
    request: Request,
}

fn case(name: &str, a: &DenseArgs) -> Result<Case> {
    let phone = |distance_mm, zoom| Phone { resolution: Resolution::P1080, zoom, distance_mm, focus_mm: distance_mm };
    let still = |req: Request| Request { distance_mm: Some(100.0), ..req };
    let base = |scene, per_view, fps| Request::new(scene, a.seed, per_view, 1, fps);
    let gamma_1_8 = Some(Development { curve: ToneCurve::Gamma { gamma: 1.8 }, sharpen: None, local_tone_map: 0.0 });
    let defocus = || Request {
        phone: Some(Phone { focus_mm: 200.0 + DEFOCUS_MM, ..phone(200.0, 2.0) }),
        ..base(SceneKind::Static, a.still_frames, 30.0)
    };
    let chew = |exposure_ms: f64| Request {
        max_frames: Some(a.motion_frames),
        exposure_s: Some(exposure_ms / 1000.0),
        readout_s: 0.010,
        phone: Some(phone(220.0, 2.0)),
        ..base(SceneKind::Chew, 1, 60.0)
    };
    let (name, request) = match name {
        "still-200" => {
            ("still-200", Request { phone: Some(phone(200.0, 1.0)), ..base(SceneKind::Static, a.still_frames, 30.0) })
        }
        "still-100" => ("still-100", still(base(SceneKind::Static, a.still_frames, 30.0))),
        "gamma-1.8" => {
            ("gamma-1.8", Request { development: gamma_1_8, ..still(base(SceneKind::Static, a.still_frames, 30.0)) })
        }
        "hinge" => ("hinge", Request { max_frames: Some(a.motion_frames), ..base(SceneKind::Hinge, 1, 30.0) }),
        "chew-2ms" => ("chew-2ms", chew(2.0)),
        "chew-8ms" => ("chew-8ms", chew(8.0)),
        "defocus" => ("defocus", defocus()),
        "defocus-gamma-1.8" => ("defocus-gamma-1.8", Request { development: gamma_1_8, ..defocus() }),
        other => bail!(
            "unknown case '{other}' (choose still-200, still-100, gamma-1.8, hinge, chew-2ms, chew-8ms, defocus or \
             defocus-gamma-1.8)"
        ),
    };
    Ok(Case { name, request })
}

/// One refinement's run over a case's frames.
#[derive(Default)]
struct Run {
    errors_mm: Vec<f64>,
    /// Jaw translations per tripod view (still cases).
    views: Vec<Vec<[f64; 3]>>,
    failed: usize,
    bodies: usize,
    refine_s: f64,
}

/// Runs `jawtrack-bench dense`.
pub fn run(a: &DenseArgs) -> Result<()> {
    let cases: Vec<Case> = a.cases.iter().map(|c| case(c, a)).collect::<Result<_>>()?;
    let mut rows = Vec::new();
    for c in &cases {
        let scene = frames::scene(&a.cache, &c.request, &mut |done, total| {
            eprint!("\r{}: rendering {done}/{total}   ", c.name);
        })?;
        eprintln!();
        let truth = &scene.truth;
        let marker = Marker::from_json(&truth.true_marker.to_string()).context("the marker in ground_truth.json")?;
        let mut runs = Vec::new();
        let mut bounds = Vec::new();
        for refine in PoseRefinement::ALL {
            let config = TrackerConfig {
                detector: DetectorConfig { linear_edges: truth.realism.gamma, ..DetectorConfig::default() },
                readout_s: c.request.readout_s,
                exposure_s: truth.realism.exposure_s,
                refine,
                ..TrackerConfig::default()
            };
            let mut tracker = Tracker::new(marker.clone(), config)?;
            let mut run = Run::default();
            let mut view_of = None;
            for (i, f) in truth.frames.iter().enumerate() {
                eprint!("\r{}: tracking with {refine} {i}/{}   ", c.name, truth.frames.len());
                let path = scene.dir.join(&f.file);
                let img = image::open(&path).with_context(|| format!("reading {}", path.display()))?.to_luma8();
                let view =
                    ImageView::new(img.as_raw(), img.width() as usize, img.height() as usize, img.width() as usize)?;
                let r = tracker.track(&view, &truth.intrinsics, f.t)?;
                run.refine_s += r.timings.refine_s;
                run.bodies += [&r.maxilla, &r.mandible].iter().filter(|b| b.is_some()).count();
                run.failed += r.flags.iter().filter(|f| matches!(f, Flag::DenseFailed(_))).count();
                if let Some(p) = r.maxilla_from_mandible {
                    run.errors_mm.push(PoseError::of(&p, &f.maxilla_from_mandible).mm);
                }
                // Frames of a still tripod view differ only in noise, once those with a glare
                // spot or an occluder (placed at random per frame) are set aside, and those
                // read before the tone curve settled.
                let still = c.request.scene == SceneKind::Static
                    && f.spec.view.hand_seed.is_none()
                    && f.glare.is_empty()
                    && !f.occluder
                    && tone_settled(&tracker.tone());
                if still {
                    let key = (f.spec.view.distance_mm.to_bits(), f.spec.view.azimuth_deg.to_bits());
                    if view_of != Some(key) {
                        run.views.push(Vec::new());
                        view_of = Some(key);
                    }
                    if let Some(p) = r.maxilla_from_mandible {
                        let t = p.translation();
                        run.views.last_mut().expect("pushed").push([t.x, t.y, t.z]);
                    }
                    if refine == PoseRefinement::Dense {
                        bounds.extend(jaw_bound(&view, truth, f, &r, &marker));
                    }
                }
            }
            eprintln!();
            runs.push(run);
        }
        rows.push(row(c.name, truth, &runs[0], &runs[1], &bounds));
    }
    let table = markdown(&rows);
    crate::say(format_args!("{table}"));
    if let Some(out) = &a.out {
        std::fs::write(out, &table).with_context(|| format!("writing {}", out.display()))?;
    }
    Ok(())
}

/// Whether the frame just tracked was read through the curve the frames after it keep: a
/// curve given, or an estimate past its settling fits. At `auto` a session's first frames are
/// read through sRGB and then through the first fits' curves: through a gamma-1.8 render they
/// lay the jaw 1–3 µm from where the settled frames do (docs/dense.md), which is not noise.
fn tone_settled(t: &ToneSummary) -> bool {
    t.setting != ToneSetting::Auto || t.frames_fitted >= SETTLING_FRAMES
}

/// The Cramér–Rao bound (RMS over the three axes, mm) on the jaw's translation in one still
/// frame: each body's bound at its true pose from the tags it was solved from, combined.
fn jaw_bound(
    view: &ImageView<'_>,
    truth: &GroundTruth,
    f: &jawtrack_synth::FrameTruth,
    r: &FrameResult,
    marker: &Marker,
) -> Option<f64> {
    let curve = truth.realism.encoding().unwrap_or(ToneCurve::Srgb);
    let linear = curve.decode_table();
    let image = Image { frame: *view, linear: &linear };
    let noise = |l: f64| pixel_variance(&truth.realism, curve, l);
    let mut covariance = Vec::new();
    for (kind, body, pose) in [
        (BodyKind::Maxilla, &r.maxilla, f.camera_from_maxilla),
        (BodyKind::Mandible, &r.mandible, f.camera_from_mandible),
    ] {
        let body = body.as_ref()?;
        let bitmaps: Vec<_> = body.tags.iter().filter_map(|&id| marker.family.bitmap(id)).collect();
        let tags: Vec<Tag<'_>> = body
            .tags
            .iter()
            .zip(&bitmaps)
            .filter_map(|(&id, bitmap)| {
                let (k, tag) = marker.find_tag(id)?;
                (k == kind).then(|| Tag { corners: tag.corners.map(|c| [c.x, c.y, c.z]), bitmap })
            })
            .collect();
        let blur =
            jawtrack_pose::median(r.detections.iter().filter(|d| body.tags.contains(&d.id)).filter_map(|d| d.blur_px));
        let seen = Body { image, camera: &truth.intrinsics, tags: &tags, blur_px: blur.unwrap_or(0.0), motion: None };
        let b = jawtrack_photometric::bound(&seen, &pose, &Options::default(), &noise).ok()?;
        covariance.push(b);
    }
    let jaw =
        jaw_translation_covariance(&f.camera_from_maxilla, &f.camera_from_mandible, &covariance[0], &covariance[1]);
    Some(jaw.trace().sqrt())
}

/// The covariance of `maxilla_from_mandible`'s translation from independent left perturbations
/// (camera frame) of the two bodies' poses with covariances `a` and `b`: the translation is
/// R_aᵀ (t_b − t_a), which moves by R_aᵀ ([t_b]× ω_a − τ_a − [t_b]× ω_b + τ_b).
fn jaw_translation_covariance(
    camera_from_maxilla: &Pose,
    camera_from_mandible: &Pose,
    a: &Matrix6<f64>,
    b: &Matrix6<f64>,
) -> Matrix3<f64> {
    let r = camera_from_maxilla.rotation_matrix().transpose();
    let tb = camera_from_mandible.translation().cross_matrix();
    let mut ja = Matrix3x6::zeros();
    ja.fixed_view_mut::<3, 3>(0, 0).copy_from(&(r * tb));
    ja.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-r));
    let jb = Matrix3x6::from_fn(|i, j| -ja[(i, j)]);
    ja * a * ja.transpose() + jb * b * jb.transpose()
}

/// A pixel's noise variance in linear light (0–255 scale, squared) at the linear value `l`, as
/// the renderer makes it: shot and read noise in electrons ([`jawtrack_synth::post`]), then the
/// 8-bit encoding's rounding carried back through the curve.
fn pixel_variance(realism: &Realism, curve: ToneCurve, l: f64) -> f64 {
    let v = (l / 255.0).clamp(0.0, 1.0);
    let fw = realism.pixel_full_well_e();
    let sensor =
        if fw > 0.0 { 255.0 * 255.0 * (v * fw + realism.read_noise_e * realism.read_noise_e) / (fw * fw) } else { 0.0 };
    let e = curve.encode(v) * 255.0;
    let slope = 255.0 * (curve.decode(((e + 0.5) / 255.0).min(1.0)) - curve.decode(((e - 0.5) / 255.0).max(0.0)));
    sensor + slope * slope / 12.0
}

/// A case's line of the table.
struct Row {
    name: &'static str,
    frames: usize,
    corners: Summary,
    dense: Summary,
    failed: usize,
    bodies: usize,
    bound_um: Option<f64>,
    ms_per_body: f64,
    fx: f64,
}

/// Errors (mm) and jitter (µm) of one run.
struct Summary {
    median: f64,
    p95: f64,
    max: f64,
    jitter_um: Option<f64>,
    posed: usize,
}

fn summary(r: &Run) -> Summary {
    let mut e = r.errors_mm.clone();
    e.sort_by(f64::total_cmp);
    let q = |p: f64| if e.is_empty() { f64::NAN } else { e[((e.len() - 1) as f64 * p).round() as usize] };
    Summary {
        median: q(0.5),
        p95: q(0.95),
        max: q(1.0),
        jitter_um: spread(&r.views).map(|s| s * 1000.0),
        posed: e.len(),
    }
}

/// The 3-D spread of points about their view's mean, pooled over the views: √(Σ squared
/// distances / Σ (n − 1)). Pooled, because a view keeps only its frames without glare or an
/// occluder, read through the settled tone curve (23 of the 30 tripod frames at seed 7), and
/// one view's spread alone rests on about 20 degrees of freedom, uncertain by about 15 %.
/// `None` without two frames in any view.
fn spread(views: &[Vec<[f64; 3]>]) -> Option<f64> {
    let (mut ss, mut dof) = (0.0, 0usize);
    for v in views.iter().filter(|v| v.len() >= 2) {
        let n = v.len() as f64;
        let mean: Vec<f64> = (0..3).map(|k| v.iter().map(|p| p[k]).sum::<f64>() / n).collect();
        ss += v.iter().map(|p| (0..3).map(|k| (p[k] - mean[k]).powi(2)).sum::<f64>()).sum::<f64>();
        dof += v.len() - 1;
    }
    (dof > 0).then(|| (ss / dof as f64).sqrt())
}

fn row(name: &'static str, truth: &GroundTruth, corners: &Run, dense: &Run, bounds: &[f64]) -> Row {
    Row {
        name,
        frames: truth.frames.len(),
        corners: summary(corners),
        dense: summary(dense),
        failed: dense.failed,
        bodies: dense.bodies,
        // The RMS of the frames' bounds, as the spread is an RMS over their frames.
        bound_um: (!bounds.is_empty())
            .then(|| (bounds.iter().map(|b| b * b).sum::<f64>() / bounds.len() as f64).sqrt() * 1000.0),
        ms_per_body: dense.refine_s * 1000.0 / dense.bodies.max(1) as f64,
        fx: truth.intrinsics.fx,
    }
}

fn markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "| case | frames | fx (px) | corners: median / p95 / max (mm) | dense: median / p95 / max (mm) | dense ÷ corners (median, p95) | dense failed (bodies) | still jitter: corners / dense / bound (µm) | dense jitter ÷ bound | dense ms per body |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let um = |v: Option<f64>| v.map_or("—".to_string(), |v| format!("{v:.2}"));
    for r in rows {
        let (c, d) = (&r.corners, &r.dense);
        s += &format!(
            "| {} | {} ({} / {} posed) | {:.0} | {:.4} / {:.4} / {:.4} | {:.4} / {:.4} / {:.4} | {:.3}, {:.3} | {} of {} | {} / {} / {} | {} | {:.1} |\n",
            r.name,
            r.frames,
            c.posed,
            d.posed,
            r.fx,
            c.median,
            c.p95,
            c.max,
            d.median,
            d.p95,
            d.max,
            d.median / c.median,
            d.p95 / c.p95,
            r.failed,
            r.bodies,
            um(c.jitter_um),
            um(d.jitter_um),
            um(r.bound_um),
            d.jitter_um.zip(r.bound_um).map_or("—".to_string(), |(j, b)| format!("{:.2}", j / b)),
            r.ms_per_body,
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{UnitQuaternion, Vector3};

    #[test]
    fn the_jaw_covariance_follows_the_relative_pose_under_perturbations() {
        let a = Pose::from_parts(
            UnitQuaternion::from_scaled_axis(Vector3::new(0.2, 3.0, -0.1)),
            Vector3::new(3.0, -20.0, 110.0),
        );
        let b = Pose::from_parts(
            UnitQuaternion::from_scaled_axis(Vector3::new(0.1, 2.9, 0.2)),
            Vector3::new(1.0, 24.0, 104.0),
        );
        let rel = |a: &Pose, b: &Pose| (a.inverse() * *b).translation();
        let h = 1e-6;
        let mut checked = 0;
        // One parameter at a time: the covariance of a unit variance there is the outer product
        // of the numeric derivative.
        for body in 0..2 {
            for i in 0..6 {
                let mut d = nalgebra::Vector6::zeros();
                d[i] = h;
                let moved = Pose::from_isometry(jawtrack_pose::pnp::perturb(
                    if body == 0 { a.isometry() } else { b.isometry() },
                    &d,
                ));
                let numeric = (if body == 0 { rel(&moved, &b) } else { rel(&a, &moved) } - rel(&a, &b)) / h;
                let mut unit = Matrix6::zeros();
                unit[(i, i)] = 1.0;
                let zero = Matrix6::zeros();
                let c = if body == 0 {
                    jaw_translation_covariance(&a, &b, &unit, &zero)
                } else {
                    jaw_translation_covariance(&a, &b, &zero, &unit)
                };
                let expected = numeric * numeric.transpose();
                assert!((c - expected).norm() < 1e-4 * (1.0 + expected.norm()), "body {body}, {i}: {c} vs {expected}");
                checked += 1;
            }
        }
        assert_eq!(checked, 12);
    }

    #[test]
    fn the_spread_is_pooled_about_each_views_own_mean() {
        // Two views far apart, each spread ±1 along x: the views' offset counts for nothing.
        let views = vec![
            vec![[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
            vec![[99.0, 5.0, 0.0], [101.0, 5.0, 0.0], [100.0, 5.0, 0.0]],
            vec![[7.0, 7.0, 7.0]],
        ];
        // (2 + 2) squared distances over (1 + 2) degrees of freedom.
        let s = spread(&views).expect("two views of two or more");
        assert!((s - (4.0f64 / 3.0).sqrt()).abs() < 1e-12, "{s}");
        assert_eq!(spread(&[vec![[1.0, 2.0, 3.0]]]), None, "one frame has no spread");
    }

    #[test]
    fn every_case_is_named_and_an_unknown_one_is_refused() {
        let a = DenseArgs {
            cases: vec![],
            still_frames: 2,
            motion_frames: 3,
            cache: PathBuf::from("x"),
            seed: 1,
            out: None,
        };
        let mut checked = 0;
        for name in
            ["still-200", "still-100", "gamma-1.8", "hinge", "chew-2ms", "chew-8ms", "defocus", "defocus-gamma-1.8"]
        {
            assert_eq!(case(name, &a).expect("known").name, name);
            checked += 1;
        }
        assert_eq!(checked, 8);
        let e = case("still-300", &a).err().expect("refused").to_string();
        assert!(e.contains("still-300") && e.contains("chew-8ms"), "{e}");
    }

    #[test]
    fn a_pixel_is_noisier_where_brighter_and_the_rounding_counts() {
        let r = Realism::default();
        let (dark, bright) = (pixel_variance(&r, ToneCurve::Srgb, 10.0), pixel_variance(&r, ToneCurve::Srgb, 200.0));
        assert!(bright > dark && dark > 0.0, "{dark} {bright}");
        let clean = Realism { full_well_e: 0.0, ..r };
        assert!(pixel_variance(&clean, ToneCurve::Srgb, 100.0) > 0.0, "8-bit rounding remains");
        // A 2× crop's pixel gathers a quarter of the light: its shot noise, relative to its
        // signal, is twice as large (read noise and rounding aside, at this level about 4×).
        let crop = Realism { zoom: 2.0, ..r };
        let (whole, cropped) =
            (pixel_variance(&r, ToneCurve::Srgb, 200.0), pixel_variance(&crop, ToneCurve::Srgb, 200.0));
        assert!(cropped > 3.5 * whole && cropped < 4.5 * whole, "{whole} {cropped}");
    }

    #[test]
    fn frames_count_as_still_once_the_tone_curve_has_settled() {
        use jawtrack_tone::ToneReason;
        let at = |setting, frames_fitted| ToneSummary {
            setting,
            curve: ToneCurve::Srgb,
            reason: ToneReason::NotYetTold,
            frames_fitted,
            pooled: None,
        };
        let settled: Vec<bool> = (0..=SETTLING_FRAMES + 1).map(|n| tone_settled(&at(ToneSetting::Auto, n))).collect();
        let mut want = vec![false; SETTLING_FRAMES];
        want.extend([true, true]);
        assert_eq!(settled, want, "auto: frames read before the settling fits are done do not count");
        assert!(tone_settled(&at(ToneSetting::Fixed(ToneCurve::Srgb), 0)), "a curve given never changes");
    }
}
