//! The benchtop's tables, pure functions of a [`Run`]: the error of an estimate along the
//! head's axes, per static view the mean and SD, per opening and glide a regression of the
//! tracked incisor path on the true one, and flips.

use super::{FLIP_DEG, FrameRecord, Run};
use jawtrack_kinematics::Mounting;
use jawtrack_pose::Pose;
use jawtrack_synth::SceneKind;
use jawtrack_synth::scenes::JawMotion;
use nalgebra::Vector3;

/// An estimate's error along the head's axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorParts {
    /// Position error of the mandible marker along head X, Y, Z (mm).
    pub position_mm: Vector3<f64>,
    /// The error rotation's components about head X, Y, Z (°).
    pub rotation_deg: Vector3<f64>,
}

impl ErrorParts {
    /// The position error's length (mm).
    pub fn mm(&self) -> f64 {
        self.position_mm.norm()
    }

    /// The error rotation's angle (°).
    pub fn deg(&self) -> f64 {
        self.rotation_deg.norm()
    }
}

/// The error of an estimate of `maxilla_from_mandible` against the truth, along the head's
/// axes (`head_from_maxilla` turns maxilla-frame vectors into head-frame ones).
pub fn error_parts(estimate: &Pose, truth: &Pose, head_from_maxilla: &Pose) -> ErrorParts {
    let turn = head_from_maxilla.rotation();
    let position_mm = turn * (estimate.translation() - truth.translation());
    let delta = estimate.rotation() * truth.rotation().inverse();
    ErrorParts { position_mm, rotation_deg: (turn * delta.scaled_axis()).map(f64::to_degrees) }
}

/// Mean and sample standard deviation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeanSd {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (0 for one value).
    pub sd: f64,
}

impl MeanSd {
    /// Of some values; `None` when there are none.
    pub fn of(values: impl IntoIterator<Item = f64>) -> Option<MeanSd> {
        let v: Vec<f64> = values.into_iter().collect();
        if v.is_empty() {
            return None;
        }
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let sd = if v.len() > 1 { (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() } else { 0.0 };
        Some(MeanSd { mean, sd })
    }
}

/// Ordinary least squares of tracked values on true ones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Regression {
    /// Points.
    pub n: usize,
    /// Slope (`None` when the truth does not move along this axis).
    pub slope: Option<f64>,
    /// Coefficient of determination (`None` likewise).
    pub r2: Option<f64>,
    /// Standard error of the estimate (mm): the residuals' RMS over n − 2 degrees of freedom;
    /// when the truth does not move, the tracked values' SD about their mean (n − 1).
    pub se_mm: f64,
}

/// Truth spread (mm) below which an axis counts as not moving.
const STILL_MM: f64 = 1e-3;

/// Regresses `tracked` on `truth`; `None` with fewer than 3 points.
pub fn regress(truth: &[f64], tracked: &[f64]) -> Option<Regression> {
    let n = truth.len().min(tracked.len());
    if n < 3 {
        return None;
    }
    let (x, y) = (&truth[..n], &tracked[..n]);
    let nf = n as f64;
    let (mx, my) = (x.iter().sum::<f64>() / nf, y.iter().sum::<f64>() / nf);
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let syy: f64 = y.iter().map(|b| (b - my).powi(2)).sum();
    if (sxx / nf).sqrt() < STILL_MM {
        return Some(Regression { n, slope: None, r2: None, se_mm: (syy / (nf - 1.0)).sqrt() });
    }
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let slope = sxy / sxx;
    let ss_res: f64 = x.iter().zip(y).map(|(a, b)| (b - my - slope * (a - mx)).powi(2)).sum();
    let r2 = if syy > 0.0 { 1.0 - ss_res / syy } else { 1.0 };
    Some(Regression { n, slope: Some(slope), r2: Some(r2), se_mm: (ss_res / (nf - 2.0)).sqrt() })
}

/// One static view's errors for one column.
#[derive(Debug, Clone)]
pub struct StaticRow {
    /// Hand-held (else on a tripod).
    pub hand_held: bool,
    /// Camera azimuth (°).
    pub azimuth_deg: f64,
    /// Camera distance (mm).
    pub distance_mm: f64,
    /// Frames of the view.
    pub frames: usize,
    /// Errors of the frames with a jaw pose.
    pub errors: Vec<ErrorParts>,
}

impl StaticRow {
    /// Mean and SD of the position error along head axis `axis` (0 X, 1 Y, 2 Z).
    pub fn position(&self, axis: usize) -> Option<MeanSd> {
        MeanSd::of(self.errors.iter().map(|e| e.position_mm[axis]))
    }

    /// Mean and SD of the rotation error about head axis `axis`.
    pub fn rotation(&self, axis: usize) -> Option<MeanSd> {
        MeanSd::of(self.errors.iter().map(|e| e.rotation_deg[axis]))
    }

    /// Mean and SD of the position error's length.
    pub fn mm(&self) -> Option<MeanSd> {
        MeanSd::of(self.errors.iter().map(ErrorParts::mm))
    }

    /// Mean and SD of the orientation error's angle.
    pub fn deg(&self) -> Option<MeanSd> {
        MeanSd::of(self.errors.iter().map(ErrorParts::deg))
    }
}

/// The run's frames of `scene` with column `column`'s estimate, as (frame, error), plus the
/// frames without one.
fn judged(run: &Run, scene: SceneKind, column: usize) -> impl Iterator<Item = (&FrameRecord, Option<ErrorParts>)> {
    let head_from_maxilla = Mounting::default().head_from_maxilla;
    run.frames
        .iter()
        .filter(move |f| f.scene == scene)
        .map(move |f| (f, f.estimates[column].map(|e| error_parts(&e, &f.truth, &head_from_maxilla))))
}

/// The static table for one column: tripod then hand-held, by distance, then by angle.
pub fn static_rows(run: &Run, column: usize) -> Vec<StaticRow> {
    let mut rows: Vec<StaticRow> = Vec::new();
    for (f, error) in judged(run, SceneKind::Static, column) {
        let hand_held = f.view.hand_seed.is_some();
        let row = match rows.iter_mut().find(|r| {
            r.hand_held == hand_held && r.azimuth_deg == f.view.azimuth_deg && r.distance_mm == f.view.distance_mm
        }) {
            Some(r) => r,
            None => {
                rows.push(StaticRow {
                    hand_held,
                    azimuth_deg: f.view.azimuth_deg,
                    distance_mm: f.view.distance_mm,
                    frames: 0,
                    errors: Vec::new(),
                });
                rows.last_mut().expect("just pushed")
            }
        };
        row.frames += 1;
        row.errors.extend(error);
    }
    rows
}

/// One opening (hinge) or glide (excursion) for one column: the incisor's displacement from
/// its closed position along the head's axes, truth and tracked, for the frames with a pose.
#[derive(Debug, Clone)]
pub struct DynamicRow {
    /// "10 mm", "left", …
    pub label: String,
    /// Frames of the movement.
    pub frames: usize,
    /// True incisor displacement (mm), frames with a pose.
    pub truth: Vec<Vector3<f64>>,
    /// Tracked incisor displacement (mm), same frames.
    pub tracked: Vec<Vector3<f64>>,
    /// Pose errors, same frames.
    pub errors: Vec<ErrorParts>,
}

impl DynamicRow {
    /// The regression of the tracked incisor on the truth along head axis `axis`.
    pub fn regression(&self, axis: usize) -> Option<Regression> {
        let truth: Vec<f64> = self.truth.iter().map(|v| v[axis]).collect();
        let tracked: Vec<f64> = self.tracked.iter().map(|v| v[axis]).collect();
        regress(&truth, &tracked)
    }

    /// The largest standard error over the three axes (mm).
    pub fn worst_se_mm(&self) -> Option<f64> {
        (0..3).map(|a| self.regression(a).map(|r| r.se_mm)).collect::<Option<Vec<_>>>()?.into_iter().reduce(f64::max)
    }

    /// Mean and SD of the incisor's 3D error (mm).
    pub fn incisor_mm(&self) -> Option<MeanSd> {
        MeanSd::of(self.truth.iter().zip(&self.tracked).map(|(a, b)| (a - b).norm()))
    }
}

/// The hinge (by opening) or excursion (by glide) table for one column.
pub fn dynamic_rows(run: &Run, scene: SceneKind, column: usize) -> Vec<DynamicRow> {
    let mounting = Mounting::default();
    let closed = mounting.lower_incisal_point;
    let mut rows: Vec<DynamicRow> = Vec::new();
    for (f, error) in judged(run, scene, column) {
        let label = match f.motion {
            JawMotion::Hinge { opening_mm, .. } => format!("{opening_mm:.0} mm"),
            JawMotion::Glide { direction, .. } => format!("{direction:?}").to_lowercase(),
            JawMotion::Rest => "rest".into(),
            JawMotion::Chew { .. } => "chew".into(),
            JawMotion::Border { movement, .. } => format!("border {movement:?}").to_lowercase(),
        };
        let row = match rows.iter_mut().find(|r| r.label == label) {
            Some(r) => r,
            None => {
                rows.push(DynamicRow { label, frames: 0, truth: Vec::new(), tracked: Vec::new(), errors: Vec::new() });
                rows.last_mut().expect("just pushed")
            }
        };
        row.frames += 1;
        if let (Some(estimate), Some(error)) = (f.estimates[column], error) {
            row.truth.push(mounting.lower_incisor(&f.truth).coords - closed);
            row.tracked.push(mounting.lower_incisor(&estimate).coords - closed);
            row.errors.push(error);
        }
    }
    if scene == SceneKind::Hinge {
        rows.sort_by(|a, b| a.label.len().cmp(&b.label.len()).then(a.label.cmp(&b.label)));
    }
    rows
}

/// Frames of a scene, how many had a pose, how many were flips, and the worst orientation
/// error (°), for one column.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Flips {
    /// Frames.
    pub frames: usize,
    /// Frames with a jaw pose.
    pub posed: usize,
    /// Frames more than `FLIP_DEG` off.
    pub flips: usize,
    /// Worst orientation error (°).
    pub worst_deg: f64,
}

/// Flips of one column in one scene.
pub fn flips(run: &Run, scene: SceneKind, column: usize) -> Flips {
    let mut out = Flips { frames: 0, posed: 0, flips: 0, worst_deg: 0.0 };
    for (_, error) in judged(run, scene, column) {
        out.frames += 1;
        if let Some(e) = error {
            out.posed += 1;
            out.flips += usize::from(e.deg() > FLIP_DEG);
            out.worst_deg = out.worst_deg.max(e.deg());
        }
    }
    out
}
