//! The bundle adjustment itself: Levenberg–Marquardt over every view's pose and the free
//! tags' in-plane placements, with a Huber loss (reweighted each iteration) and a weak prior
//! pulling the placements toward where they started (see the crate docs).
//!
//! The normal equations are solved by the Schur complement, as bundle adjusters do: each
//! corner depends on one view's pose and one tag, so the poses' block is block-diagonal
//! (6×6 per view) and is eliminated view by view, leaving a system in the free tags alone
//! (3 per tag, 36 at most). A session of thousands of frames costs a few milliseconds per
//! iteration where the dense system would cost minutes.

use crate::{TagModel, View};
use jawtrack_pose::lm::{self, Damping};
use jawtrack_pose::pnp::{perturb, pose_jacobian, projection_jacobian};
use nalgebra::{DMatrix, DVector, Matrix2x3, Matrix3, Matrix6, SMatrix, Vector3, Vector6};

/// Settings of one adjustment.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Adjustment {
    /// Prior weights (px per mm, px per mm, px per rad): corner noise over the prior spreads.
    pub(crate) prior: Vector3<f64>,
    /// Huber threshold (px).
    pub(crate) huber_px: f64,
    /// Iterations at most.
    pub(crate) max_iterations: usize,
}

/// The Huber loss of one corner, scaled as a square (e² inside `k`, 2k·e − k² beyond), and
/// its weight in the normal equations.
pub(crate) fn huber(e2: f64, k: f64) -> (f64, f64) {
    let e = e2.sqrt();
    if e <= k { (e2, 1.0) } else { (2.0 * k * e - k * k, k / e) }
}

/// The Huber cost of one view's sightings under its pose.
fn view_cost(view: &View, models: &[TagModel], k: f64) -> f64 {
    let mut sum = 0.0;
    for s in &view.seen {
        for i in 0..4 {
            let c = view.pose * models[s.tag].corner(i);
            if c.z <= 1e-9 {
                return 1e12;
            }
            sum += huber(((c.coords.xy() / c.z - s.rays[i]).component_mul(&view.focal)).norm_squared(), k).0;
        }
    }
    sum
}

/// The normal equations in blocks.
struct Normal {
    /// Per view: its pose's 6×6 block and gradient.
    pose: Vec<(Matrix6<f64>, Vector6<f64>)>,
    /// Per view: the pose–tag blocks of the free tags it sees, by slot.
    cross: Vec<Vec<(usize, SMatrix<f64, 6, 3>)>>,
    /// Per free tag: its 3×3 block and gradient (tags never share a corner: block-diagonal).
    tag: Vec<(Matrix3<f64>, Vector3<f64>)>,
}

type State = (Vec<View>, Vec<TagModel>);

/// Adjusts `views`' poses and the `free` tags' placements in place.
pub(crate) fn adjust(views: &mut [View], models: &mut [TagModel], free: &[usize], a: &Adjustment) {
    let mut slot_of = vec![None; models.len()];
    for (k, &t) in free.iter().enumerate() {
        slot_of[t] = Some(k);
    }
    let cost = |views: &[View], models: &[TagModel]| -> f64 {
        let data: f64 = views.iter().map(|v| view_cost(v, models, a.huber_px)).sum();
        let reg: f64 = free.iter().map(|&t| models[t].e.component_mul(&a.prior).norm_squared()).sum();
        data + reg
    };
    let damping =
        Damping { initial: 1e-4, diagonal_floor: 1e-9, relative_tolerance: 1e-10, max_iterations: a.max_iterations };
    let linearise = |(views, models): &State| -> Option<Normal> {
        let mut normal = Normal {
            pose: Vec::with_capacity(views.len()),
            cross: Vec::with_capacity(views.len()),
            tag: vec![(Matrix3::zeros(), Vector3::zeros()); free.len()],
        };
        for v in views {
            let rot = v.pose.rotation.to_rotation_matrix();
            let (mut hp, mut gp) = (Matrix6::zeros(), Vector6::zeros());
            let mut cross: Vec<(usize, SMatrix<f64, 6, 3>)> = Vec::new();
            for s in &v.seen {
                let model = &models[s.tag];
                let slot = slot_of[s.tag];
                let mut hpt = SMatrix::<f64, 6, 3>::zeros();
                for i in 0..4 {
                    let c = v.pose * model.corner(i);
                    let Some(dproj) = projection_jacobian(&c, &v.focal) else { continue };
                    let r = (c.coords.xy() / c.z - s.rays[i]).component_mul(&v.focal);
                    let w = huber(r.norm_squared(), a.huber_px).1.sqrt();
                    let jp = pose_jacobian(&c, &dproj) * w;
                    let r = r * w;
                    hp += jp.transpose() * jp;
                    gp += jp.transpose() * r;
                    if let Some(k) = slot {
                        let jt: Matrix2x3<f64> = dproj * rot.matrix() * model.corner_jacobian(i) * w;
                        normal.tag[k].0 += jt.transpose() * jt;
                        normal.tag[k].1 += jt.transpose() * r;
                        hpt += jp.transpose() * jt;
                    }
                }
                if let Some(k) = slot {
                    cross.push((k, hpt));
                }
            }
            normal.pose.push((hp, gp));
            normal.cross.push(cross);
        }
        for (k, &t) in free.iter().enumerate() {
            let p2 = a.prior.component_mul(&a.prior);
            normal.tag[k].0 += Matrix3::from_diagonal(&p2);
            normal.tag[k].1 += p2.component_mul(&models[t].e);
        }
        Some(normal)
    };
    let step = |state: &State, n: &Normal, lambda: f64| -> Option<State> {
        let damp6 = |h: &Matrix6<f64>| lm::damped(h, lambda, damping.diagonal_floor);
        // Eliminate each view's pose: S = H_tt − Σ H_tp H_pp⁻¹ H_pt, b = −g_t + Σ H_tp H_pp⁻¹ g_p.
        let k = free.len();
        let mut s = DMatrix::<f64>::zeros(3 * k, 3 * k);
        let mut b = DVector::<f64>::zeros(3 * k);
        for (j, (h, g)) in n.tag.iter().enumerate() {
            s.view_mut((3 * j, 3 * j), (3, 3)).copy_from(&lm::damped(h, lambda, damping.diagonal_floor));
            b.rows_mut(3 * j, 3).copy_from(&(-g));
        }
        let mut inverses = Vec::with_capacity(n.pose.len());
        for ((h, g), cross) in n.pose.iter().zip(&n.cross) {
            let inv = damp6(h).cholesky()?.inverse();
            for &(ja, ref ca) in cross {
                let left = ca.transpose() * inv;
                let mut rows = b.rows_mut(3 * ja, 3);
                rows += left * g;
                for &(jb, ref cb) in cross {
                    let mut block = s.view_mut((3 * ja, 3 * jb), (3, 3));
                    block -= left * cb;
                }
            }
            inverses.push(inv);
        }
        let dt = if k == 0 { DVector::zeros(0) } else { s.cholesky()?.solve(&b) };
        let (mut views, mut models) = state.clone();
        for (vi, v) in views.iter_mut().enumerate() {
            let mut rhs = -n.pose[vi].1;
            for &(j, ref c) in &n.cross[vi] {
                rhs -= c * dt.fixed_rows::<3>(3 * j);
            }
            v.pose = perturb(&v.pose, &(inverses[vi] * rhs));
        }
        for (j, &t) in free.iter().enumerate() {
            models[t].e += dt.fixed_rows::<3>(3 * j);
        }
        Some((views, models))
    };
    let mut state: State = (views.to_vec(), models.to_vec());
    let mut current = cost(views, models);
    // The normal equations always exist here: no abort, nothing to report.
    let _ = lm::minimise(&mut state, &mut current, &damping, linearise, step, |(v, m)| cost(v, m));
    views.clone_from_slice(&state.0);
    models.clone_from_slice(&state.1);
}
