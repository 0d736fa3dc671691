//! The Levenberg–Marquardt loop that PnP and marker calibration share: how the damping starts
//! and moves, when a step is taken and when the loop stops. Each caller keeps what is its own:
//! the state, its cost, its normal equations and how a step is solved and applied.

use nalgebra::{DefaultAllocator, Dim, OMatrix, allocator::Allocator};

/// How the damping starts and when the loop stops.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Damping {
    /// λ at the start; ×10 after a step that does not lower the cost, ÷10 (down to 1e-12)
    /// after one that does.
    pub initial: f64,
    /// Each diagonal entry of H gets λ × max(entry, this), so a direction without curvature is
    /// still damped.
    pub diagonal_floor: f64,
    /// Stop once a step lowers the cost by no more than this fraction of it.
    pub relative_tolerance: f64,
    /// Linearisations at most.
    pub max_iterations: usize,
}

/// Damping tries per linearisation before the loop gives up: λ grows 10¹⁰ over them.
const TRIES: usize = 10;

/// H with λ·max(Hᵢᵢ, floor) added to its diagonal.
pub fn damped<D: Dim>(h: &OMatrix<f64, D, D>, lambda: f64, floor: f64) -> OMatrix<f64, D, D>
where
    DefaultAllocator: Allocator<D, D>,
{
    let mut d = h.clone();
    for i in 0..h.nrows() {
        d[(i, i)] += lambda * h[(i, i)].max(floor);
    }
    d
}

/// Minimises from `state`, whose cost is `cost`, and leaves the best state and its cost
/// there. `linearise` gives the normal equations at a state (`None` aborts: the result is
/// `None` and the state is the last accepted one); `step` gives the candidate a damped step
/// with λ leads to (`None` when that system cannot be solved: λ grows); `evaluate` gives a
/// candidate's cost.
pub fn minimise<S, N>(
    state: &mut S,
    cost: &mut f64,
    damping: &Damping,
    linearise: impl FnMut(&S) -> Option<N>,
    step: impl FnMut(&S, &N, f64) -> Option<S>,
    evaluate: impl FnMut(&S) -> f64,
) -> Option<()> {
    minimise_until(state, cost, damping, linearise, step, |_, _, _| false, evaluate)
}

/// [`minimise`], also stopping, before evaluating it, at the first candidate that
/// `settled(state, normal equations there, candidate)` says moves the state by less than
/// matters (the state is kept).
/// Where evaluating is costly and the cost is only approximately smooth at the scale of the
/// last steps, this saves the evaluations that would only find the damped steps no better.
///
/// # Examples
///
/// ```
/// use jawtrack_pose::lm::{Damping, minimise_until};
///
/// // (x − 3)², stopped once a step would move x by under 0.01.
/// let (mut x, mut cost, mut evaluations) = (0.0_f64, 9.0, 0);
/// let damping = Damping { initial: 1e-3, diagonal_floor: 1e-12, relative_tolerance: 1e-15, max_iterations: 50 };
/// minimise_until(
///     &mut x,
///     &mut cost,
///     &damping,
///     |x| Some((2.0, 2.0 * (x - 3.0))),
///     |x, (h, g), lambda| Some(x - g / (h * (1.0 + lambda))),
///     |x, _, next| (next - x).abs() < 0.01,
///     |x| {
///         evaluations += 1;
///         (x - 3.0) * (x - 3.0)
///     },
/// );
/// assert!((x - 3.0).abs() < 0.01);
/// assert!(evaluations < 10);
/// ```
pub fn minimise_until<S, N>(
    state: &mut S,
    cost: &mut f64,
    damping: &Damping,
    mut linearise: impl FnMut(&S) -> Option<N>,
    mut step: impl FnMut(&S, &N, f64) -> Option<S>,
    mut settled: impl FnMut(&S, &N, &S) -> bool,
    mut evaluate: impl FnMut(&S) -> f64,
) -> Option<()> {
    let mut lambda = damping.initial;
    for _ in 0..damping.max_iterations {
        let normal = linearise(state)?;
        let mut improved = false;
        for _ in 0..TRIES {
            let Some(candidate) = step(state, &normal, lambda) else {
                lambda *= 10.0;
                continue;
            };
            if settled(state, &normal, &candidate) {
                return Some(());
            }
            let c = evaluate(&candidate);
            if c < *cost {
                let converged = *cost - c <= damping.relative_tolerance * *cost;
                *state = candidate;
                *cost = c;
                lambda = (lambda / 10.0).max(1e-12);
                improved = !converged;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector2};

    /// The Rosenbrock valley as least squares: r = (10 (y − x²), 1 − x), minimum at (1, 1).
    #[test]
    fn it_walks_down_a_curved_valley() {
        let residual = |p: &Vector2<f64>| Vector2::new(10.0 * (p.y - p.x * p.x), 1.0 - p.x);
        let jacobian = |p: &Vector2<f64>| Matrix2::new(-20.0 * p.x, 10.0, -1.0, 0.0);
        let cost = |p: &Vector2<f64>| residual(p).norm_squared();
        let mut p = Vector2::new(-1.2, 1.0);
        let mut c = cost(&p);
        let damping = Damping { initial: 1e-3, diagonal_floor: 1e-12, relative_tolerance: 1e-15, max_iterations: 200 };
        minimise(
            &mut p,
            &mut c,
            &damping,
            |p| Some((jacobian(p).transpose() * jacobian(p), jacobian(p).transpose() * residual(p))),
            |p, (h, g), lambda| damped(h, lambda, damping.diagonal_floor).cholesky().map(|ch| p + ch.solve(&(-g))),
            cost,
        )
        .expect("never aborted");
        assert!((p - Vector2::new(1.0, 1.0)).norm() < 1e-6, "{p}");
        assert!(c < 1e-12);
    }

    #[test]
    fn a_settled_candidate_ends_the_loop_unevaluated_and_the_state_is_kept() {
        let damping = Damping { initial: 1e-3, diagonal_floor: 1e-12, relative_tolerance: 1e-15, max_iterations: 50 };
        let (mut x, mut c, mut evaluations) = (0.0_f64, 9.0, 0);
        let out = minimise_until(
            &mut x,
            &mut c,
            &damping,
            |x| Some((2.0, 2.0 * (x - 3.0))),
            |x, (h, g), lambda| Some(x - g / (h * (1.0 + lambda))),
            |_, _, next| (next - 3.0).abs() < 1.0,
            |x| {
                evaluations += 1;
                (x - 3.0) * (x - 3.0)
            },
        );
        assert_eq!((out, x, c, evaluations), (Some(()), 0.0, 9.0, 0), "the first step lands within 1 of 3");
        // Never settled: the same loop as `minimise`, which goes on until the cost stops falling.
        let (mut y, mut d, mut evaluations) = (0.0_f64, 9.0, 0);
        minimise_until(
            &mut y,
            &mut d,
            &damping,
            |y| Some((2.0, 2.0 * (y - 3.0))),
            |y, (h, g), lambda| Some(y - g / (h * (1.0 + lambda))),
            |_, _, _| false,
            |y| {
                evaluations += 1;
                (y - 3.0) * (y - 3.0)
            },
        );
        assert!((y - 3.0).abs() < 1e-6 && evaluations > 2, "{y} after {evaluations}");
    }

    #[test]
    fn a_failed_linearisation_aborts_and_keeps_the_start() {
        let mut x = 3.0;
        let mut c = 9.0;
        let damping = Damping { initial: 1e-3, diagonal_floor: 1e-12, relative_tolerance: 1e-6, max_iterations: 5 };
        let out = minimise(&mut x, &mut c, &damping, |_| None::<f64>, |x, _, _| Some(*x), |x| x * x);
        assert_eq!((out, x, c), (None, 3.0, 9.0));
    }
}
