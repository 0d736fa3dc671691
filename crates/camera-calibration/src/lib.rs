//! Camera calibration from the markers themselves: the camera's focal lengths, principal
//! point, radial distortion (the model of [`CameraIntrinsics`]) and its rolling shutter's
//! readout time, from a short video of the marker pair waved in front of it, each with its
//! uncertainty. The tracker needs all of them: a focal length 1 % off scales every distance
//! by 1 %, and a readout left out shears a moving marker by pixels.
//!
//! Each frame's body pose is solved at the frame's time (its centre row's), and a corner seen
//! in row y is predicted where the body was at `t + RollingShutter::offset_s(y)`, the body
//! moving at the velocity its neighbouring frames' poses give (the derivative of the parabola
//! through three, [`Velocity::at`](jawtrack_pose::Velocity::at)). Within a frame the shear is velocity × readout, while the
//! velocity is seen between frames: so the readout is observable, where a free velocity per
//! frame would leave only their product. Intrinsics, readout and every pose are refined
//! together by Levenberg–Marquardt; the poses are coupled only to their neighbours, so the
//! normal equations are banded and the intrinsics are solved through a Schur complement.
//!
//! Each estimate's 1σ comes from the covariance of the least squares scaled by the residual.
//! A result is refused ([`CameraCalibrationError`]) when the residual says the model does not
//! fit, or an uncertainty says the frames did not constrain it (distortion without corners
//! near the image's edges, a readout without motion, …), with what to film instead.

mod file;
mod solve;
#[cfg(test)]
mod tests;

pub use file::{CalibratedAt, CameraFile, CameraFileError, LENS_POSITION_MOVED};

pub use jawtrack_calibration::SeenTag;
use jawtrack_calibration::{CalibrationFrame, check_focal};
use jawtrack_marker::{BodyKind, Marker};
use jawtrack_pose::{CameraIntrinsics, Observation, PnpOptions, RollingShutter, solve_pnp};
use nalgebra::{Point2, Point3};
use serde::{Deserialize, Serialize};
use solve::{Problem, Sighting, Track, ViewData};

/// The tags seen in one frame, and when.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraFrame {
    /// The frame's time (s): that of its centre row.
    pub t: f64,
    /// The marker's tags detected in it (corner pixels as the detector gives them).
    pub tags: Vec<SeenTag>,
}

/// Settings of the calibration: where to start and what a usable result is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraCalibrationOptions {
    /// A first guess of the intrinsics; `None` starts from the image size (focal length 0.8 ×
    /// the width, principal point at the centre, no distortion). Either way a scan of the
    /// focal length over a factor of 3 each way finds the basin first.
    pub initial: Option<CameraIntrinsics>,
    /// A first guess of the readout (s).
    pub initial_readout_s: f64,
    /// Frames (with a body seen in its neighbours too) needed at least.
    pub min_frames: usize,
    /// Two frames of a body are neighbours when at most this many median frame intervals
    /// apart (a body missed in a frame or two still has its velocity).
    pub max_gap_intervals: f64,
    /// Refuse when the RMS corner residual (px) exceeds this.
    pub max_rms_px: f64,
    /// Refuse when the focal lengths' 1σ exceeds this fraction of them.
    pub max_focal_sigma: f64,
    /// Refuse when the principal point's 1σ exceeds this (px).
    pub max_principal_sigma_px: f64,
    /// Refuse when the distortion at the image's corners is uncertain by more than this (px, 1σ).
    pub max_distortion_sigma_px: f64,
    /// Refuse when the readout's 1σ exceeds this (s).
    pub max_readout_sigma_s: f64,
    /// A tag sighting whose RMS error exceeds this many times the median sighting's (and
    /// `outlier_px`) is left out and the fit run again: a misdetected corner must not pull.
    pub outlier_ratio: f64,
    /// … and this (px).
    pub outlier_px: f64,
    /// Levenberg–Marquardt linearisations at most, per fit.
    pub max_iterations: usize,
}

impl Default for CameraCalibrationOptions {
    fn default() -> Self {
        CameraCalibrationOptions {
            initial: None,
            initial_readout_s: 0.0,
            min_frames: 20,
            max_gap_intervals: 3.5,
            max_rms_px: 1.0,
            max_focal_sigma: 0.003,
            max_principal_sigma_px: 5.0,
            max_distortion_sigma_px: 1.0,
            max_readout_sigma_s: 0.001,
            outlier_ratio: 5.0,
            outlier_px: 0.5,
            max_iterations: 60,
        }
    }
}

/// 1σ of each estimate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Uncertainty {
    /// Of fx (px).
    pub fx: f64,
    /// Of fy (px).
    pub fy: f64,
    /// Of cx (px).
    pub cx: f64,
    /// Of cy (px).
    pub cy: f64,
    /// Of k1.
    pub k1: f64,
    /// Of k2.
    pub k2: f64,
    /// Of the readout (s).
    pub readout_s: f64,
    /// Of the distortion's displacement at the image corner farthest from the principal
    /// point (px): what k1 and k2's uncertainties, together, mean where it matters most.
    pub corner_distortion_px: f64,
}

/// A camera calibrated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CameraCalibration {
    /// Image size [width, height] (px).
    pub image_size: [u32; 2],
    /// The intrinsics.
    pub intrinsics: CameraIntrinsics,
    /// Rolling-shutter readout, first row to last (s).
    pub readout_s: f64,
    /// 1σ of each, from the covariance of the least squares scaled by the residual.
    pub sigma: Uncertainty,
    /// RMS corner residual (px, distance per corner).
    pub rms_px: f64,
    /// Frames used.
    pub frames_used: usize,
    /// Body views used (a frame shows up to two bodies).
    pub views_used: usize,
    /// Corners used.
    pub corners_used: usize,
    /// Tag sightings left out as misfits.
    pub sightings_dropped: usize,
    /// Fraction of the image (a 8 × 6 grid of cells) in which a corner was seen.
    pub coverage: f64,
}

impl std::fmt::Display for CameraCalibration {
    /// What was used, then each value with its 1σ, one per line, as `jawtrack
    /// calibrate-camera` prints them.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (k, s) = (&self.intrinsics, &self.sigma);
        writeln!(
            f,
            "{} frames ({} marker views, {} corners; {} tag sightings left out as misfits); corners seen in {:.0} % of \
             the image",
            self.frames_used,
            self.views_used,
            self.corners_used,
            self.sightings_dropped,
            100.0 * self.coverage
        )?;
        writeln!(f, "  fx       {:10.2} ± {:.2} px ({:.3} %)", k.fx, s.fx, 100.0 * s.fx / k.fx)?;
        writeln!(f, "  fy       {:10.2} ± {:.2} px ({:.3} %)", k.fy, s.fy, 100.0 * s.fy / k.fy)?;
        writeln!(f, "  cx       {:10.2} ± {:.2} px", k.cx, s.cx)?;
        writeln!(f, "  cy       {:10.2} ± {:.2} px", k.cy, s.cy)?;
        writeln!(f, "  k1       {:10.5} ± {:.5}", k.k1, s.k1)?;
        writeln!(f, "  k2       {:10.5} ± {:.5}", k.k2, s.k2)?;
        writeln!(f, "  (distortion at the image corners known to ± {:.2} px)", s.corner_distortion_px)?;
        writeln!(f, "  readout  {:10.3} ± {:.3} ms (first row to last)", self.readout_s * 1e3, s.readout_s * 1e3)?;
        write!(f, "  RMS corner residual {:.3} px", self.rms_px)
    }
}

/// Why no calibration was returned.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CameraCalibrationError {
    /// Input that cannot be calibrated from (an image without rows, times that do not increase).
    #[error("bad input: {0}")]
    BadInput(String),
    /// Too few frames show a body with two tags next to another frame that shows it.
    #[error(
        "only {usable} frames show a marker body (two tags or more) in a run of neighbouring frames; at least \
         {needed} are needed: film longer, with the marker close enough that its tags are detected"
    )]
    TooFewFrames {
        /// Frames usable.
        usable: usize,
        /// Frames needed.
        needed: usize,
    },
    /// The least squares could not be solved (no step lowered the error from the start).
    #[error("the fit failed: {0}")]
    NoFit(String),
    /// The model does not fit the corners.
    #[error(
        "the corners fit with an RMS error of {rms_px:.2} px, more than {limit_px:.2} px: the frames do not follow \
         one fixed camera (zoom, stabilisation or lens switching on? frames from two cameras?), or the marker file \
         is not that of the marker filmed"
    )]
    PoorFit {
        /// RMS corner residual (px).
        rms_px: f64,
        /// The limit (px).
        limit_px: f64,
    },
    /// The distortion is not pinned down where the image needs it.
    #[error(
        "k1 and k2 are not constrained: the distortion at the image corners is uncertain by ±{sigma_px:.2} px \
         (limit ±{limit_px:.2} px); corners were seen in {coverage_percent:.0} % of the image: wave the marker \
         across the whole image, into its corners and along its edges"
    )]
    DistortionUnconstrained {
        /// 1σ of the distortion at the farthest image corner (px).
        sigma_px: f64,
        /// The limit (px).
        limit_px: f64,
        /// Percentage of the image cells a corner was seen in.
        coverage_percent: f64,
    },
    /// The focal lengths are not pinned down.
    #[error(
        "the focal length is not constrained: ±{sigma_percent:.2} % (limit ±{limit_percent:.2} %): use more frames, \
         with the marker nearer (90-200 mm) and tilted so several faces show at different depths"
    )]
    FocalUnconstrained {
        /// 1σ of the focal lengths (% of them).
        sigma_percent: f64,
        /// The limit (%).
        limit_percent: f64,
    },
    /// The principal point is not pinned down.
    #[error(
        "the principal point is not constrained: ±{sigma_px:.1} px (limit ±{limit_px:.1} px): wave the marker \
         across the whole image, at different depths and tilts"
    )]
    PrincipalPointUnconstrained {
        /// 1σ of cx or cy, the larger (px).
        sigma_px: f64,
        /// The limit (px).
        limit_px: f64,
    },
    /// The readout is not pinned down.
    #[error(
        "the rolling-shutter readout is not constrained: ±{sigma_ms:.2} ms (limit ±{limit_ms:.2} ms): move the \
         marker faster (50-150 mm/s, across the image and up and down), in a steady video rather than still frames"
    )]
    ReadoutUnconstrained {
        /// 1σ of the readout (ms).
        sigma_ms: f64,
        /// The limit (ms).
        limit_ms: f64,
    },
}

/// A tag seen: its id, its corners in the body (mm) and in the image (px).
type SeenCorners = (u32, [Point3<f64>; 4], [[f64; 2]; 4]);

/// Tags of one body a view needs for its starting pose (one tag's pose is ambiguous).
const MIN_TAGS: usize = 2;
/// A view whose starting pose misses by more than this many times the median view's RMS …
const START_RATIO: f64 = 5.0;
/// … and this (px) is left out.
const START_PX: f64 = 10.0;
/// Coverage grid (cells across, down).
const GRID: (usize, usize) = (8, 6);

/// Calibrates the camera from `frames` (in time order) of an image `width` × `height` px
/// showing `marker`'s tags.
pub fn calibrate_camera(
    frames: &[CameraFrame],
    width: u32,
    height: u32,
    marker: &Marker,
    options: &CameraCalibrationOptions,
) -> Result<CameraCalibration, CameraCalibrationError> {
    check_input(frames, width, height)?;
    let initial = options.initial.unwrap_or_else(|| {
        let f = 0.8 * f64::from(width);
        CameraIntrinsics::pinhole(f, f, (f64::from(width) - 1.0) / 2.0, (f64::from(height) - 1.0) / 2.0)
    });
    initial.validate().map_err(|e| CameraCalibrationError::BadInput(format!("the initial guess: {e}")))?;
    if !options.initial_readout_s.is_finite() {
        return Err(CameraCalibrationError::BadInput("the initial readout is not a number".into()));
    }
    // Into the basin: the focal length that best fits every view's perspective.
    let as_views: Vec<CalibrationFrame> =
        frames.iter().map(|f| CalibrationFrame { camera: initial, tags: f.tags.clone() }).collect();
    let scale = check_focal(marker, &as_views).map_or(1.0, |c| c.best_scale);
    let start = CameraIntrinsics { fx: initial.fx * scale, fy: initial.fy * scale, ..initial };

    let mut problem = build_problem(frames, height, marker, &start, options)?;
    let usable = problem.frames_used();
    if usable < options.min_frames {
        return Err(CameraCalibrationError::TooFewFrames { usable, needed: options.min_frames });
    }
    let mut state = problem.start_state(&start, options.initial_readout_s);
    problem.fit(&mut state, options.max_iterations)?;
    let dropped = problem.drop_outliers(&mut state, options.outlier_ratio, options.outlier_px);
    if dropped > 0 {
        problem.fit(&mut state, options.max_iterations)?;
    }
    let fit = problem.summary(&state)?;
    let usable = problem.frames_used();
    if usable < options.min_frames {
        return Err(CameraCalibrationError::TooFewFrames { usable, needed: options.min_frames });
    }
    let intrinsics = state.intrinsics();
    let corner_distortion_px = corner_distortion_sigma(&intrinsics, &fit.covariance, width, height);
    let sd = |i: usize| fit.covariance[(i, i)].max(0.0).sqrt();
    let sigma = Uncertainty {
        fx: sd(0),
        fy: sd(1),
        cx: sd(2),
        cy: sd(3),
        k1: sd(4),
        k2: sd(5),
        readout_s: sd(6),
        corner_distortion_px,
    };
    let result = CameraCalibration {
        image_size: [width, height],
        intrinsics,
        readout_s: state.readout_s(),
        sigma,
        rms_px: fit.rms_px,
        frames_used: usable,
        views_used: problem.views.len(),
        corners_used: fit.corners,
        sightings_dropped: dropped,
        coverage: coverage(&problem, width, height),
    };
    judge(&result, options)?;
    Ok(result)
}

fn check_input(frames: &[CameraFrame], width: u32, height: u32) -> Result<(), CameraCalibrationError> {
    if width < 2 || height < 2 {
        return Err(CameraCalibrationError::BadInput(format!("an image of {width} × {height} px")));
    }
    for (i, f) in frames.iter().enumerate() {
        if !f.t.is_finite() {
            return Err(CameraCalibrationError::BadInput(format!("frame {i}'s time is not a number")));
        }
        if i > 0 && f.t <= frames[i - 1].t {
            return Err(CameraCalibrationError::BadInput(format!(
                "frame times must increase: frame {i} at {} s follows one at {} s",
                f.t,
                frames[i - 1].t
            )));
        }
        if f.tags.iter().flat_map(|t| t.corners.iter().flatten()).any(|v| !v.is_finite()) {
            return Err(CameraCalibrationError::BadInput(format!("frame {i} has a corner that is not a number")));
        }
    }
    Ok(())
}

/// Every body view with a starting pose, grouped into runs of neighbouring frames.
fn build_problem(
    frames: &[CameraFrame],
    height: u32,
    marker: &Marker,
    start: &CameraIntrinsics,
    options: &CameraCalibrationOptions,
) -> Result<Problem, CameraCalibrationError> {
    // The fraction of the readout after the centre row at which each row is exposed: the
    // offset is linear in the readout, so the rule is taken from the shutter at a unit readout.
    const UNIT_S: f64 = 0.5;
    let unit =
        RollingShutter::new(UNIT_S, height as usize).map_err(|e| CameraCalibrationError::BadInput(e.to_string()))?;
    let row_fraction = |y: f64| unit.offset_s(y) / UNIT_S;
    let mut intervals: Vec<f64> = frames.windows(2).map(|w| w[1].t - w[0].t).collect();
    intervals.sort_by(f64::total_cmp);
    let max_gap = intervals.get(intervals.len() / 2).copied().unwrap_or(f64::INFINITY) * options.max_gap_intervals;
    let pnp = PnpOptions { outlier_px: f64::INFINITY, ..PnpOptions::default() };
    let mut tracks = Vec::new();
    for kind in BodyKind::ALL {
        let mut run: Vec<ViewData> = Vec::new();
        for (frame, f) in frames.iter().enumerate() {
            let seen: Vec<SeenCorners> = f
                .tags
                .iter()
                .filter_map(|s| match marker.find_tag(s.id) {
                    Some((k, tag)) if k == kind => Some((s.id, tag.corners.map(Point3::from), s.corners)),
                    _ => None,
                })
                .collect();
            if seen.len() < MIN_TAGS {
                continue;
            }
            let observations: Vec<Observation> = seen
                .iter()
                .flat_map(|(id, body, px)| {
                    (0..4).map(move |i| Observation { tag: *id, body: body[i], pixel: Point2::new(px[i][0], px[i][1]) })
                })
                .collect();
            let Ok(pose) = solve_pnp(&observations, start, None, &pnp) else { continue };
            let sightings = seen
                .iter()
                .map(|(_, body, px)| Sighting {
                    corners: std::array::from_fn(|i| {
                        (body[i], Point2::new(px[i][0], px[i][1]), row_fraction(px[i][1]))
                    }),
                })
                .collect();
            let view = ViewData {
                frame,
                t: f.t,
                pose: *pose.camera_from_body.isometry(),
                sightings,
                start_rms_px: pose.rms_px,
            };
            if run.last().is_some_and(|last| view.t - last.t > max_gap) {
                tracks.push(Track { views: std::mem::take(&mut run) });
            }
            run.push(view);
        }
        tracks.push(Track { views: run });
    }
    // A view no pose fits at the start (a tag misdetected, a misidentified id) would pull the
    // fit into another basin; the distortion not yet known leaves a few px at the edges.
    let mut start_errors: Vec<f64> = tracks.iter().flat_map(|t| t.views.iter().map(|v| v.start_rms_px)).collect();
    start_errors.sort_by(f64::total_cmp);
    if let Some(&median) = start_errors.get(start_errors.len() / 2) {
        let limit = (START_RATIO * median).max(START_PX);
        for t in &mut tracks {
            t.views.retain(|v| v.start_rms_px <= limit);
        }
    }
    // A run of fewer than three views gives no velocity that is more than a secant.
    tracks.retain(|t| t.views.len() >= 3);
    Ok(Problem::new(tracks))
}

/// 1σ (px) of the distortion's displacement at the image corner farthest from the principal
/// point, from the covariance of (k1, k2).
fn corner_distortion_sigma(k: &CameraIntrinsics, covariance: &nalgebra::SMatrix<f64, 7, 7>, w: u32, h: u32) -> f64 {
    let corners =
        [(0.0, 0.0), (f64::from(w) - 1.0, 0.0), (0.0, f64::from(h) - 1.0), (f64::from(w) - 1.0, f64::from(h) - 1.0)];
    corners
        .iter()
        .map(|&(x, y)| {
            let nd = k.pixel_to_distorted(&Point2::new(x, y));
            let n = k.undistort(nd).unwrap_or(nd);
            let r2 = n.norm_squared();
            // d(pixel)/d(k1, k2) along the radius: f r (r², r⁴).
            let f = k.fx.max(k.fy) * r2.sqrt();
            let g = nalgebra::Vector2::new(f * r2, f * r2 * r2);
            let c = covariance.fixed_view::<2, 2>(4, 4);
            (g.transpose() * c * g)[(0, 0)].max(0.0).sqrt()
        })
        .fold(0.0, f64::max)
}

/// Fraction of the image's cells (an 8 × 6 grid) in which a corner used was seen.
fn coverage(problem: &Problem, w: u32, h: u32) -> f64 {
    let mut hit = [[false; GRID.0]; GRID.1];
    for s in problem.views.iter().flat_map(|v| &v.data.sightings) {
        for (_, px, _) in &s.corners {
            let cx = ((px.x + 0.5) / f64::from(w) * GRID.0 as f64).floor();
            let cy = ((px.y + 0.5) / f64::from(h) * GRID.1 as f64).floor();
            if (0.0..GRID.0 as f64).contains(&cx) && (0.0..GRID.1 as f64).contains(&cy) {
                hit[cy as usize][cx as usize] = true;
            }
        }
    }
    hit.iter().flatten().filter(|h| **h).count() as f64 / (GRID.0 * GRID.1) as f64
}

/// Whether `value` is over `limit` or not a number (an unconstrained σ).
fn exceeds(value: f64, limit: f64) -> bool {
    value.is_nan() || value > limit
}

/// Refuses a result the residual or an uncertainty says is poor, the first problem found in
/// the order a user would fix them.
fn judge(r: &CameraCalibration, o: &CameraCalibrationOptions) -> Result<(), CameraCalibrationError> {
    if exceeds(r.rms_px, o.max_rms_px) {
        return Err(CameraCalibrationError::PoorFit { rms_px: r.rms_px, limit_px: o.max_rms_px });
    }
    if exceeds(r.sigma.corner_distortion_px, o.max_distortion_sigma_px) {
        return Err(CameraCalibrationError::DistortionUnconstrained {
            sigma_px: r.sigma.corner_distortion_px,
            limit_px: o.max_distortion_sigma_px,
            coverage_percent: 100.0 * r.coverage,
        });
    }
    let focal = (r.sigma.fx / r.intrinsics.fx).max(r.sigma.fy / r.intrinsics.fy);
    if exceeds(focal, o.max_focal_sigma) {
        return Err(CameraCalibrationError::FocalUnconstrained {
            sigma_percent: 100.0 * focal,
            limit_percent: 100.0 * o.max_focal_sigma,
        });
    }
    let principal = r.sigma.cx.max(r.sigma.cy);
    if exceeds(principal, o.max_principal_sigma_px) {
        return Err(CameraCalibrationError::PrincipalPointUnconstrained {
            sigma_px: principal,
            limit_px: o.max_principal_sigma_px,
        });
    }
    if exceeds(r.sigma.readout_s, o.max_readout_sigma_s) {
        return Err(CameraCalibrationError::ReadoutUnconstrained {
            sigma_ms: 1e3 * r.sigma.readout_s,
            limit_ms: 1e3 * o.max_readout_sigma_s,
        });
    }
    Ok(())
}
