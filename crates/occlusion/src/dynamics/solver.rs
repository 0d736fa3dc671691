//! The projection's solve: the least motion in the mass/inertia metric that meets every
//! linearised contact constraint, by projected Gauss–Seidel on the dual.

use super::projection::Constraint;
use nalgebra::{Matrix3, Vector3};

/// Projected Gauss–Seidel sweeps per solve, at most.
const MAX_SWEEPS: usize = 500;

/// min ½ δᵀMδ subject to nᵢ·Δx + (rᵢ×nᵢ)·Δθ ≥ −gapᵢ, by projected Gauss–Seidel on the dual:
/// returns Δx, Δθ and the multipliers λᵢ ≥ 0 (with Mδ = Σ λᵢ Jᵢᵀ). Stops when a sweep changes
/// no constraint's value by more than `stop` mm.
pub(super) fn solve(
    constraints: &[Constraint],
    inverse_mass: f64,
    inverse_inertia: &Matrix3<f64>,
    stop: f64,
) -> (Vector3<f64>, Vector3<f64>, Vec<f64>) {
    // Deepest first: the sweep then starts from the constraints that decide the answer.
    let mut order: Vec<usize> = (0..constraints.len()).collect();
    order.sort_by(|&a, &b| constraints[a].gap.total_cmp(&constraints[b].gap));
    let rows: Vec<(Vector3<f64>, Vector3<f64>, f64)> = constraints
        .iter()
        .map(|c| {
            let (b_lin, b_rot) = (c.normal * inverse_mass, inverse_inertia * c.lever_normal);
            (b_lin, b_rot, c.normal.dot(&b_lin) + c.lever_normal.dot(&b_rot))
        })
        .collect();
    let (mut dx, mut dtheta) = (Vector3::zeros(), Vector3::zeros());
    let mut lambda = vec![0.0; constraints.len()];
    for _ in 0..MAX_SWEEPS {
        let mut largest: f64 = 0.0;
        for &i in &order {
            let (c, (b_lin, b_rot, diagonal)) = (&constraints[i], &rows[i]);
            let violation = -c.gap - (c.normal.dot(&dx) + c.lever_normal.dot(&dtheta));
            let updated = (lambda[i] + violation / diagonal).max(0.0);
            let change = updated - lambda[i];
            if change != 0.0 {
                dx += b_lin * change;
                dtheta += b_rot * change;
                lambda[i] = updated;
                largest = largest.max((change * diagonal).abs());
            }
        }
        if largest <= stop {
            break;
        }
    }
    (dx, dtheta, lambda)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_constraint_is_met_by_the_least_motion() {
        // A contact on the axis through the centre: pure translation along its normal.
        let n = Vector3::new(0.0, 0.0, -1.0);
        let c = Constraint { key: (1, 0), gap: -0.2, normal: n, lever_normal: Vector3::zeros() };
        let (dx, dtheta, lambda) = solve(&[c], 10.0, &Matrix3::identity(), 1e-12);
        assert!((dx - n * 0.2).norm() < 1e-12 && dtheta.norm() < 1e-15, "{dx} {dtheta}");
        assert!((lambda[0] - 0.02).abs() < 1e-12, "{lambda:?}");
        // Two opposite levers: translation only, split between them.
        let lever = Vector3::new(1.0, 0.0, 0.0);
        let a = Constraint { lever_normal: lever, ..c };
        let b = Constraint { lever_normal: -lever, key: (1, 1), ..c };
        let (dx, dtheta, _) = solve(&[a, b], 10.0, &Matrix3::identity(), 1e-12);
        assert!((dx - n * 0.2).norm() < 1e-9 && dtheta.norm() < 1e-9, "{dx} {dtheta}");
    }
}
