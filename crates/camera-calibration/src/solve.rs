//! The joint least squares: intrinsics, readout and one pose per body view, by
//! Levenberg–Marquardt on the corners' reprojection errors.
//!
//! A view's residuals depend on the intrinsics and on three poses of its body's run (its own
//! and its neighbours', which give its velocity), so ordered run by run and in time the pose
//! block of the normal equations is banded (two pose blocks either side of the diagonal). It
//! is factored as a band and the seven camera parameters solved through the Schur complement,
//! whose inverse is also their covariance. Derivatives are central differences: each view has
//! only 25 parameters, and the velocity's dependence on three poses is then exact to second order
//! without a hand-derived Jacobian of [`Velocity::at`].

use crate::CameraCalibrationError;
use jawtrack_pose::lm::{self, Damping};
use jawtrack_pose::pnp::perturb;
use jawtrack_pose::{CameraIntrinsics, Pose, Velocity};
use nalgebra::{DMatrix, DVector, Isometry3, Point2, Point3, SMatrix, SVector, Vector6};

/// Camera parameters: fx, fy, cx, cy, k1, k2, readout (s).
pub(crate) const NC: usize = 7;
/// Parameters of a view's residuals: the camera's and three poses'.
const NL: usize = NC + 18;
/// Half-bandwidth of the pose block (scalars): two poses beyond a pose's own six.
const BW: usize = 6 * 3 - 1;
/// Central-difference steps: fx, fy, cx, cy (px), k1, k2, readout (s); rotation (rad) and
/// translation (mm) of a pose.
const STEPS: [f64; NC] = [1e-3, 1e-3, 1e-3, 1e-3, 1e-6, 1e-6, 1e-6];
/// The parabola's velocity is read here and this much later to get its slope (s).
const ACCELERATION_PROBE_S: f64 = 1e-3;
const ROTATION_STEP: f64 = 1e-6;
const TRANSLATION_STEP: f64 = 1e-5;

/// One tag seen in one view: per corner its body point (mm), where it was seen (px) and the
/// fraction of the readout after the centre row at which its row was exposed.
#[derive(Debug, Clone)]
pub(crate) struct Sighting {
    pub corners: [(Point3<f64>, Point2<f64>, f64); 4],
}

/// A body seen in a frame, with its starting pose.
#[derive(Debug, Clone)]
pub(crate) struct ViewData {
    pub frame: usize,
    pub t: f64,
    pub pose: Isometry3<f64>,
    pub sightings: Vec<Sighting>,
    /// RMS error (px) of the starting pose.
    pub start_rms_px: f64,
}

/// One body's views in a run of neighbouring frames, in time order.
pub(crate) struct Track {
    pub views: Vec<ViewData>,
}

/// A view in the problem: its pose is `poses[index]`, its velocity that of the parabola
/// through the poses `nodes` (three consecutive views of its run) at its time.
pub(crate) struct View {
    pub data: ViewData,
    nodes: [usize; 3],
    run: usize,
}

/// The current estimate.
#[derive(Debug, Clone)]
pub(crate) struct State {
    theta: [f64; NC],
    poses: Vec<Isometry3<f64>>,
}

impl State {
    pub(crate) fn intrinsics(&self) -> CameraIntrinsics {
        let [fx, fy, cx, cy, k1, k2, _] = self.theta;
        CameraIntrinsics { fx, fy, cx, cy, k1, k2 }
    }

    pub(crate) fn readout_s(&self) -> f64 {
        self.theta[6]
    }
}

/// The views, run by run.
pub(crate) struct Problem {
    pub views: Vec<View>,
}

/// The fit at the solution.
pub(crate) struct Fit {
    /// Covariance of the camera parameters, scaled by the residual.
    pub covariance: SMatrix<f64, NC, NC>,
    pub rms_px: f64,
    pub corners: usize,
}

/// A symmetric band matrix: the lower triangle within `BW` of the diagonal.
#[derive(Clone)]
struct Band {
    n: usize,
    data: Vec<f64>,
}

impl Band {
    fn zeros(n: usize) -> Self {
        Band { n, data: vec![0.0; n * (BW + 1)] }
    }
    /// Entry (i, j) with j ≤ i ≤ j + BW.
    fn at(&self, i: usize, j: usize) -> f64 {
        self.data[j * (BW + 1) + (i - j)]
    }
    fn at_mut(&mut self, i: usize, j: usize) -> &mut f64 {
        &mut self.data[j * (BW + 1) + (i - j)]
    }

    /// The Cholesky factor L (lower, in the same band), `None` if not positive definite.
    fn cholesky(&self) -> Option<Band> {
        let mut l = self.clone();
        for j in 0..self.n {
            let mut d = l.at(j, j);
            for k in j.saturating_sub(BW)..j {
                d -= l.at(j, k) * l.at(j, k);
            }
            if !d.is_finite() || d <= 0.0 {
                return None;
            }
            let d = d.sqrt();
            *l.at_mut(j, j) = d;
            for i in j + 1..self.n.min(j + BW + 1) {
                let mut s = l.at(i, j);
                for k in i.saturating_sub(BW)..j {
                    s -= l.at(i, k) * l.at(j, k);
                }
                *l.at_mut(i, j) = s / d;
            }
        }
        Some(l)
    }

    /// Solves L Lᵀ x = b with `self` the factor L.
    fn solve(&self, b: &DVector<f64>) -> DVector<f64> {
        let n = self.n;
        let mut y = b.clone();
        for i in 0..n {
            let mut s = y[i];
            for k in i.saturating_sub(BW)..i {
                s -= self.at(i, k) * y[k];
            }
            y[i] = s / self.at(i, i);
        }
        for i in (0..n).rev() {
            let mut s = y[i];
            for k in i + 1..n.min(i + BW + 1) {
                s -= self.at(k, i) * y[k];
            }
            y[i] = s / self.at(i, i);
        }
        y
    }
}

/// The normal equations JᵀJ δ = −Jᵀr, split into the poses' band and the camera's block.
struct Normal {
    poses: Band,
    cross: DMatrix<f64>,
    camera: SMatrix<f64, NC, NC>,
    g_poses: DVector<f64>,
    g_camera: SVector<f64, NC>,
}

/// The camera parameters' system after eliminating the poses: S δc = rhs, then
/// δp = −xg − xc δc.
struct Reduced {
    s: SMatrix<f64, NC, NC>,
    rhs: SVector<f64, NC>,
    xg: DVector<f64>,
    xc: DMatrix<f64>,
}

impl Problem {
    pub(crate) fn new(tracks: Vec<Track>) -> Self {
        let mut views = Vec::new();
        for (run, track) in tracks.into_iter().enumerate() {
            let start = views.len();
            let n = track.views.len();
            for (k, data) in track.views.into_iter().enumerate() {
                // The three views centred on this one, or the first or last three of the run.
                let first = k.saturating_sub(1).min(n.saturating_sub(3));
                views.push(View { data, nodes: [start + first, start + first + 1, start + first + 2], run });
            }
        }
        Problem { views }
    }

    pub(crate) fn frames_used(&self) -> usize {
        let mut frames: Vec<usize> = self.views.iter().map(|v| v.data.frame).collect();
        frames.dedup();
        frames.sort_unstable();
        frames.dedup();
        frames.len()
    }

    pub(crate) fn start_state(&self, k: &CameraIntrinsics, readout_s: f64) -> State {
        State {
            theta: [k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, readout_s],
            poses: self.views.iter().map(|v| v.data.pose).collect(),
        }
    }

    /// Minimises the squared reprojection error from `state`.
    pub(crate) fn fit(&self, state: &mut State, max_iterations: usize) -> Result<(), CameraCalibrationError> {
        let mut cost = self.cost(state);
        if !cost.is_finite() {
            return Err(CameraCalibrationError::NoFit("a starting pose puts the marker behind the camera".into()));
        }
        let damping = Damping { initial: 1e-3, diagonal_floor: 1e-12, relative_tolerance: 1e-10, max_iterations };
        lm::minimise(
            state,
            &mut cost,
            &damping,
            |s| self.normal(s),
            |s, n, lambda| self.step(s, n, lambda, damping.diagonal_floor),
            |s| self.cost(s),
        )
        .ok_or_else(|| CameraCalibrationError::NoFit("the model cannot be linearised at the start".into()))
    }

    /// Drops the sightings that fit far worse than the median one (and views left without
    /// any, and runs left too short), returning how many sightings went.
    pub(crate) fn drop_outliers(&mut self, state: &mut State, ratio: f64, floor_px: f64) -> usize {
        let mut errors: Vec<Vec<f64>> = Vec::with_capacity(self.views.len());
        let mut all = Vec::new();
        for v in &self.views {
            let e = self.sighting_rms(state, v);
            all.extend(e.iter().copied());
            errors.push(e);
        }
        all.sort_by(f64::total_cmp);
        let Some(&median) = all.get(all.len() / 2) else { return 0 };
        let limit = (ratio * median).max(floor_px);
        let mut dropped = 0;
        // Rebuild the runs from what is left, each view keeping its place in its run.
        let mut tracks: Vec<Track> = Vec::new();
        let mut poses = Vec::new();
        let old = std::mem::take(&mut self.views);
        for (i, (mut view, e)) in old.into_iter().zip(errors).enumerate() {
            if tracks.len() <= view.run {
                tracks.resize_with(view.run + 1, || Track { views: Vec::new() });
            }
            let before = view.data.sightings.len();
            let mut k = 0;
            view.data.sightings.retain(|_| {
                let keep = e.get(k).is_none_or(|&x| x <= limit);
                k += 1;
                keep
            });
            dropped += before - view.data.sightings.len();
            if !view.data.sightings.is_empty() {
                view.data.pose = state.poses[i];
                tracks[view.run].views.push(view.data);
            }
        }
        tracks.retain(|t| t.views.len() >= 3);
        for t in &tracks {
            poses.extend(t.views.iter().map(|v| v.pose));
        }
        *self = Problem::new(tracks);
        state.poses = poses;
        dropped
    }

    /// RMS error, corners used and the camera parameters' covariance at `state`.
    pub(crate) fn summary(&self, state: &State) -> Result<Fit, CameraCalibrationError> {
        let cost = self.cost(state);
        let corners: usize = self.views.iter().map(|v| 4 * v.data.sightings.len()).sum();
        let unknowns = NC + 6 * self.views.len();
        let residuals = 2 * corners;
        if !cost.is_finite() || residuals <= unknowns {
            return Err(CameraCalibrationError::NoFit("fewer corners than unknowns".into()));
        }
        let variance = cost / (residuals - unknowns) as f64;
        let unconstrained = SMatrix::<f64, NC, NC>::from_diagonal_element(f64::INFINITY);
        let covariance = self
            .normal(state)
            .and_then(|n| self.schur(&n, 0.0, 0.0))
            .and_then(|r| r.s.try_inverse())
            .map_or(unconstrained, |inverse| inverse * variance);
        Ok(Fit { covariance, rms_px: (cost / corners.max(1) as f64).sqrt(), corners })
    }

    fn cost(&self, state: &State) -> f64 {
        let mut r = Vec::new();
        let mut total = 0.0;
        for v in &self.views {
            r.clear();
            if self.residuals(&state.theta, &self.node_poses(state, v), v, &mut r).is_none() {
                return f64::INFINITY;
            }
            total += r.iter().map(|x| x * x).sum::<f64>();
        }
        total
    }

    /// Each sighting's RMS corner error (px).
    fn sighting_rms(&self, state: &State, v: &View) -> Vec<f64> {
        let mut r = Vec::new();
        if self.residuals(&state.theta, &self.node_poses(state, v), v, &mut r).is_none() {
            return vec![f64::INFINITY; v.data.sightings.len()];
        }
        r.chunks(8).map(|c| (c.iter().map(|x| x * x).sum::<f64>() / 4.0).sqrt()).collect()
    }

    fn node_poses(&self, state: &State, v: &View) -> [Isometry3<f64>; 3] {
        v.nodes.map(|n| state.poses[n])
    }

    /// A view's residuals (px, x then y per corner) under the camera `theta` and its three
    /// node poses; `None` where a point does not project or no velocity follows.
    fn residuals(&self, theta: &[f64; NC], nodes: &[Isometry3<f64>; 3], v: &View, out: &mut Vec<f64>) -> Option<()> {
        let [fx, fy, cx, cy, k1, k2, readout] = *theta;
        let camera = CameraIntrinsics { fx, fy, cx, cy, k1, k2 };
        let history: Vec<(f64, Pose)> =
            v.nodes.iter().zip(nodes).map(|(n, p)| (self.views[*n].data.t, Pose::from_isometry(*p))).collect();
        // The parabola's velocity is linear in time, and its displacement over dt is the velocity
        // at dt/2 times dt: exact for constant acceleration, where a constant velocity leaves
        // a·dt²/2 (0.1 px at 20 ms of readout in a brisk wave).
        let velocity = Velocity::at(&history, v.data.t)?;
        let later = Velocity::at(&history, v.data.t + ACCELERATION_PROBE_S)?;
        let centre = v.nodes.iter().position(|n| self.views[*n].data.t == v.data.t)?;
        let pose = Pose::from_isometry(nodes[centre]);
        for s in &v.data.sightings {
            for (body, pixel, fraction) in &s.corners {
                let dt = readout * fraction;
                let w = dt / 2.0 / ACCELERATION_PROBE_S;
                let mid = Velocity {
                    angular: velocity.angular + (later.angular - velocity.angular) * w,
                    linear: velocity.linear + (later.linear - velocity.linear) * w,
                };
                let at_row = mid.advance(&pose, dt);
                let p = camera.project(&at_row.transform_point(body))?;
                out.push(p.x - pixel.x);
                out.push(p.y - pixel.y);
            }
        }
        Some(())
    }

    /// The normal equations at `state`, from central differences.
    fn normal(&self, state: &State) -> Option<Normal> {
        let np = 6 * self.views.len();
        let mut n = Normal {
            poses: Band::zeros(np),
            cross: DMatrix::zeros(np, NC),
            camera: SMatrix::zeros(),
            g_poses: DVector::zeros(np),
            g_camera: SVector::zeros(),
        };
        let (mut r0, mut plus, mut minus) = (Vec::new(), Vec::new(), Vec::new());
        for v in &self.views {
            let nodes = self.node_poses(state, v);
            r0.clear();
            self.residuals(&state.theta, &nodes, v, &mut r0)?;
            let m = r0.len();
            let mut j = DMatrix::<f64>::zeros(m, NL);
            for c in 0..NL {
                let (mut tp, mut tm, mut np_, mut nm) = (state.theta, state.theta, nodes, nodes);
                let h = if c < NC {
                    tp[c] += STEPS[c];
                    tm[c] -= STEPS[c];
                    STEPS[c]
                } else {
                    let (node, k) = ((c - NC) / 6, (c - NC) % 6);
                    let h = if k < 3 { ROTATION_STEP } else { TRANSLATION_STEP };
                    let mut d = Vector6::zeros();
                    d[k] = h;
                    np_[node] = perturb(&nodes[node], &d);
                    nm[node] = perturb(&nodes[node], &(-d));
                    h
                };
                plus.clear();
                minus.clear();
                self.residuals(&tp, &np_, v, &mut plus)?;
                self.residuals(&tm, &nm, v, &mut minus)?;
                for row in 0..m {
                    j[(row, c)] = (plus[row] - minus[row]) / (2.0 * h);
                }
            }
            let r = DVector::from_column_slice(&r0);
            let jtj = j.transpose() * &j;
            let jtr = j.transpose() * &r;
            // Local column → global: camera 0..7, then node poses.
            let global = |c: usize| v.nodes[(c - NC) / 6] * 6 + (c - NC) % 6;
            for a in 0..NC {
                n.g_camera[a] += jtr[a];
                for b in 0..NC {
                    n.camera[(a, b)] += jtj[(a, b)];
                }
            }
            for a in NC..NL {
                let ga = global(a);
                n.g_poses[ga] += jtr[a];
                for b in 0..NC {
                    n.cross[(ga, b)] += jtj[(a, b)];
                }
                for b in NC..NL {
                    let gb = global(b);
                    if ga >= gb {
                        // Nodes are three consecutive views: always inside the band.
                        *n.poses.at_mut(ga, gb) += jtj[(a, b)];
                    }
                }
            }
        }
        Some(n)
    }

    /// The Schur complement of the damped pose band, with what the step needs:
    /// (S, right-hand side −(g_c − Hcpᵀ H⁻¹ g_p), H⁻¹ g_p, H⁻¹ Hpc).
    fn schur(&self, n: &Normal, lambda: f64, floor: f64) -> Option<Reduced> {
        let mut band = n.poses.clone();
        for i in 0..band.n {
            let d = band.at(i, i);
            *band.at_mut(i, i) = d + lambda * d.max(floor);
        }
        let mut camera = n.camera;
        for i in 0..NC {
            camera[(i, i)] += lambda * camera[(i, i)].max(floor);
        }
        let l = band.cholesky()?;
        let xg = l.solve(&n.g_poses);
        let mut xc = DMatrix::zeros(band.n, NC);
        for c in 0..NC {
            xc.set_column(c, &l.solve(&n.cross.column(c).into_owned()));
        }
        let reduced = camera - n.cross.transpose() * &xc;
        let s = SMatrix::<f64, NC, NC>::from_iterator(reduced.iter().copied());
        let rhs_d = -(n.g_camera.clone_owned()
            - SVector::<f64, NC>::from_iterator((n.cross.transpose() * &xg).iter().copied()));
        Some(Reduced { s, rhs: rhs_d, xg, xc })
    }

    /// The state a damped step with λ leads to.
    fn step(&self, state: &State, n: &Normal, lambda: f64, floor: f64) -> Option<State> {
        let Reduced { s, rhs, xg, xc } = self.schur(n, lambda, floor)?;
        let dc = s.cholesky()?.solve(&rhs);
        let dp = -(xg + xc * DVector::from_column_slice(dc.as_slice()));
        let mut next = state.clone();
        for (t, d) in next.theta.iter_mut().zip(dc.iter()) {
            *t += d;
        }
        for (i, pose) in next.poses.iter_mut().enumerate() {
            let d = Vector6::from_iterator(dp.rows(6 * i, 6).iter().copied());
            *pose = perturb(pose, &d);
        }
        let k = next.intrinsics();
        (k.validate().is_ok() && dp.iter().all(|v| v.is_finite())).then_some(next)
    }
}
