//! The fit: pixels gathered once at the starting pose, then the pose and the tags' levels moved
//! together until the image and the model agree.

use crate::gather::{Sample, TagPixels, gather};
use crate::parts::Parts;
use crate::plane::{Looked, Plane, Seen, look, plane, to_tag};
use crate::robust::{huber_weights, rho, scale};
use crate::{Body, Motion, Options, RefineError, Refined, Tag};
use jawtrack_pose::lm::{Damping, damped, minimise_until};
use jawtrack_pose::pnp::perturb;
use jawtrack_pose::{CameraIntrinsics, Pose};
use nalgebra::{DMatrix, DVector, Matrix2, Matrix6, SMatrix, SVector, Vector2, Vector6};
use rayon::prelude::*;
use std::cell::RefCell;
use std::ops::AddAssign;

/// The fit stops once a step lowers its cost by less than this fraction. Near the minimum the
/// cost is the pixels' noise, so at 20,000 pixels the fit may stop up to √(10⁻⁵ × 20,000) ≈ 0.45
/// of the pose's standard deviation short of it. Measured (`jawtrack-bench dense`, still cases):
/// the same errors at 10⁻⁴ and 10⁻⁶; stopping at 10⁻² of one pixel's noise variance (about 10⁻⁷
/// here) left the jitter at 200 mm as it was (2.32 µm against 2.36, measured with a two-pass fit
/// since dropped) and took 60 % longer.
const RELATIVE_TOLERANCE: f64 = 1e-5;
/// Pixels within this many blur σ of an edge of the pattern (plus [`EDGE_BAND_PX`] for the
/// pose's error at the start) are compared. Within 2σ is 99.5 % of what an edge tells of its
/// place (its slope squared is a Gaussian of σ/√2); the pixels beyond cost time and, with
/// `Options::max_pixels_per_tag`, crowded out the ones that tell (`docs/dense.md`: 3σ + 1.5 px,
/// taken as 2.3 times that, was twice as slow and no better). The band adds nothing for the
/// smear: σ is the detector's, measured across each edge, so it carries the smear across the
/// edge already (bodies smeared 6–20 px start at σ 0.9–3.5 px and end the fit at 0.3–0.7). Half
/// the smear added on top took 1.1–1.5× the time, and chewing's p95 from 0.0222 to 0.0257 mm
/// (2 ms) and 0.0338 to 0.0375 (8 ms): it took the pixels where the sweep's model is least
/// exact.
const EDGE_BAND_SIGMAS: f64 = 2.0;
const EDGE_BAND_PX: f64 = 0.5;
/// The residuals' robust scale is never taken below this (linear light, 0–255): a noiseless
/// render would otherwise make every pixel an outlier.
const MIN_SCALE: f64 = 0.05;
/// The pixel's own area as a blur: a box of 1 px, σ² = 1/12 px².
const PIXEL_VARIANCE: f64 = 1.0 / 12.0;
/// A moving body whose rows' own times move its tags by less than this (px), and whose exposure
/// does not smear them, is not also fitted as still. Measured (`jawtrack-bench dense`, chewing
/// with a 10 ms readout): 72 such bodies under 0.02 px fitted both ways ended within 0.02 % of
/// each other's cost (one at 0.76 px fitted moving at half the still fit's cost). Keeping the
/// still fit alone there took chew-2ms's median from 0.0091 to 0.0099 mm; the moving one alone
/// kept it (0.0089).
const STILL_SKEW_PX: f64 = 0.05;
/// The still alternative to a moving fit is given up when its first pass costs this many times
/// the moving fit's end. Measured (`jawtrack-bench dense`, 257 bodies with a smear): a still fit
/// that won began at most 1.35 times the moving fit's end; the chewing mandible's began at
/// 2.2–40 times it and lost.
const STILL_CATCH_UP: f64 = 3.0;
/// The blur's σ (px) is kept at least this: below it every edge is a step to the model.
const MIN_SIGMA_PX: f64 = 0.1;
/// A fit out of linearisations whose next step would move no corner farther than this (px) has
/// settled. This only judges a fit that has used every linearisation (on a noiseless render,
/// where each step lowers the cost by a large fraction while moving the pose by next to
/// nothing); the fit's own end is [`SETTLED_SIGMAS`]: at 100 mm a hundredth of a pixel is 0.67
/// µm, more than the jitter of a still jaw there (0.45 µm, `docs/dense.md`).
const SETTLED_PX: f64 = 0.01;
/// A step shorter than this many of the estimate's standard deviations is not taken: the fit
/// has settled within its own noise (left whole, such a step would add 9 % to the estimate's
/// variance; 0.1 and 1 were measured too, `docs/dense.md`).
const SETTLED_SIGMAS: f64 = 0.3;
/// The tone's power is kept within these: beyond, the curve given was not a tone curve.
const MIN_GAMMA: f64 = 0.25;
const MAX_GAMMA: f64 = 4.0;

/// The fit's state: the pose, the blur (σ, px: the lens's and the pixel's own), the tone's
/// error and each tag's (ink, contrast) in linear light.
#[derive(Clone, PartialEq)]
struct State {
    pose: Pose,
    sigma_px: f64,
    /// The image, read through the tone curve the caller gave, is the scene's linear light to
    /// this power (1: the curve is right). A wrong curve bends every edge's ramp one way, which
    /// a symmetric blur cannot take up: it would move the edges (a tag's ink seems to grow or
    /// shrink) and so the pose.
    gamma: f64,
    /// Each tag's ink and contrast (linear light, 0–255). One blur serves the body's tags: a
    /// blur per tag (their depths differ by millimetres where a phone's depth of field is a few
    /// millimetres deep) traded with their sizes and made the far case worse (`docs/dense.md`).
    levels: Vec<[f64; PER_TAG]>,
}

impl State {
    /// What a pixel seeing `paper` of tag `k` reads (linear light, 0–255), with its derivatives
    /// by the light the scene sends (ink + contrast × paper) and by the tone's power.
    fn predict(&self, k: usize, paper: f64) -> (f64, f64, f64) {
        let [ink, contrast] = self.levels[k];
        let u = ((ink + contrast * paper) / 255.0).max(1e-9);
        // u^γ as exp(γ ln u): the logarithm is needed for the derivative by γ anyway, and
        // `powf` was a tenth of the refinement's time.
        let ln_u = u.ln();
        let value = 255.0 * (self.gamma * ln_u).exp();
        (value, self.gamma * value / (255.0 * u), value * ln_u)
    }
}

/// Pixels of a tag taken as one piece of work: small enough that two threads share a body of a
/// few tags of different sizes evenly, large enough that each piece's planes (one per row it
/// covers and part of the exposure) are few beside its pixels.
const PIECE: usize = 1024;

/// Parameters shared by the tags: the pose's six, the blur and the tone's power.
const SHARED: usize = 8;
/// Parameters of each tag: its ink and its contrast.
const PER_TAG: usize = 2;
/// One tag's parameters: the shared ones, then its own.
const BLOCK: usize = SHARED + PER_TAG;
type Block = SMatrix<f64, BLOCK, BLOCK>;
type BlockVector = SVector<f64, BLOCK>;

/// Refines `start`, the body's pose at the frame's time, from the pixels of its tags.
pub fn refine(body: &Body<'_>, start: &Pose, options: &Options) -> Result<Refined, RefineError> {
    validate(options, body.blur_px, body.motion.as_ref())?;
    let best = fit(body, &Begin { pose: *start, sigma_px: sigma_px(body.blur_px), gamma: 1.0 }, options)?;
    let (state, normal) = (&best.state, &best.normal);
    let variance = normal.variance(best.pixels);
    let inverse = normal.h.clone().try_inverse().ok_or(RefineError::Singular)?;
    let covariance = Matrix6::from_fn(|i, j| inverse[(i, j)] * variance);
    let shift_px = shift(body.camera, start, &state.pose, body.tags);
    if shift_px.is_nan() || shift_px > options.max_shift_px {
        return Err(RefineError::Strayed { shift_px, limit_px: options.max_shift_px });
    }
    let contrast = state.levels.iter().map(|l| l[1]).sum::<f64>() / state.levels.len() as f64;
    Ok(Refined {
        camera_from_body: state.pose,
        covariance,
        rms_contrast: (normal.sq / best.pixels as f64).sqrt() / contrast.abs().max(f64::MIN_POSITIVE),
        pixels: best.pixels,
        iterations: best.iterations,
        shift_px,
        blur_px: (state.sigma_px * state.sigma_px - PIXEL_VARIANCE).max(0.0).sqrt(),
        tone_power: state.gamma,
        motion: best.motion,
    })
}

/// Where a fit starts: the pose, the blur's σ (px, the pixel's own spread included) and the
/// tone's power.
struct Begin {
    pose: Pose,
    sigma_px: f64,
    gamma: f64,
}

/// The σ (px) of a detector's blur with the pixel's own spread.
fn sigma_px(blur_px: f64) -> f64 {
    (blur_px * blur_px + PIXEL_VARIANCE).sqrt()
}

/// The fit of the body from `begin` over the pixels taken there. With motion given, the same
/// pixels are also fitted as a still body and the better fit is kept: the velocity comes from
/// the poses before, and the image says whether it holds (a view that jumped with the
/// regularity of motion would otherwise have its sharp tags modelled smeared). Not where the
/// motion moves the tags by under [`STILL_SKEW_PX`] without a smear, and not on from a still
/// start [`STILL_CATCH_UP`] times as costly as the moving fit's end.
fn fit(body: &Body<'_>, begin: &Begin, options: &Options) -> Result<Outcome, RefineError> {
    let (camera, motion) = (body.camera, body.motion.as_ref());
    let (pixels, parts) = setup(body, &begin.pose, begin.sigma_px, options)?;
    // Motion changes the model only through a smear or rows read at their own times.
    let smeared = parts.smeared();
    let modelled = smeared || motion.is_some_and(|m| !m.shutter.is_global());
    // A wrong velocity could make the moving model worse than a still one only by the smear
    // and skew it gives: where those are next to nothing, the still alternative is not fitted.
    let alternative = smeared || motion.is_some_and(|m| skew_px(camera, &begin.pose, body.tags, m) >= STILL_SKEW_PX);
    let threads = options.threads;
    let still = Fit { camera, pixels: &pixels, parts: Parts::instant(), motion: None, pose_fixed: false, threads };
    let moving = modelled.then(|| Fit { camera, pixels: &pixels, parts, motion, pose_fixed: false, threads });
    let mut best = match &moving {
        None => still.run(begin, options)?,
        Some(moving) if !alternative => moving.run(begin, options)?,
        Some(moving) => {
            let best = moving.run(begin, options)?;
            match still.start(begin, options) {
                // So far behind that it will not catch up: the fit would be wasted.
                Ok(s) if s.normal.cost > STILL_CATCH_UP * best.cost => best,
                Ok(s) => match still.run_from(s, options) {
                    Ok(s) if s.cost < best.cost => s,
                    _ => best,
                },
                Err(_) => best,
            }
        }
    };
    // The covariance is read from the reweighted normal equations (every pixel at its Huber
    // weight), as the corner solver's: the fit's own give outliers no curvature. Its last
    // evaluation summed those beside its own.
    best.normal.h = std::mem::take(&mut best.normal.h_reweighted);
    Ok(best)
}

/// The Cramér–Rao bound on the pose of the body at `pose` from the pixels [`refine`] would
/// compare there: the inverse of their Fisher information, each pixel's noise variance given
/// by `noise` at its modelled linear value (0–255 scale, squared), the blur, the tone's power
/// and each tag's levels estimated beside the pose (so their uncertainty counts). Those are
/// the ones that fit the image best with the pose held at `pose` (the body's `blur_px` is
/// where that fit starts). A left perturbation in the camera frame, as [`Refined::covariance`].
pub fn bound(
    body: &Body<'_>,
    pose: &Pose,
    options: &Options,
    noise: &(dyn Fn(f64) -> f64 + Sync),
) -> Result<Matrix6<f64>, RefineError> {
    validate(options, body.blur_px, body.motion.as_ref())?;
    let begin = Begin { pose: *pose, sigma_px: sigma_px(body.blur_px), gamma: 1.0 };
    let (pixels, parts) = setup(body, pose, begin.sigma_px, options)?;
    let mut fit = Fit {
        camera: body.camera,
        pixels: &pixels,
        parts,
        motion: body.motion.as_ref(),
        pose_fixed: true,
        threads: options.threads,
    };
    let fitted = fit.run(&begin, options)?;
    // The pixels the refinement would take with the blur that fits.
    let (pixels, parts) = setup(body, pose, fitted.state.sigma_px, options)?;
    fit.pixels = &pixels;
    fit.parts = parts;
    let seen = fit.seen(pose, fitted.state.sigma_px, true);
    let levels = fit.levels(&seen).ok_or(RefineError::Singular)?;
    let state = State { levels, ..fitted.state };
    let information = fit.normal(
        &state,
        &|_, model| {
            let w = 1.0 / noise(model).max(f64::MIN_POSITIVE);
            (w, w)
        },
        f64::INFINITY,
        Some(&seen),
    );
    let inverse = information.h.try_inverse().ok_or(RefineError::Singular)?;
    Ok(Matrix6::from_fn(|i, j| inverse[(i, j)]))
}

/// What [`refine`] and [`bound`] share: the pixels gathered at `pose` for a blur of `sigma_px`,
/// and the parts of the exposure each row is modelled over.
fn setup(
    body: &Body<'_>,
    pose: &Pose,
    sigma_px: f64,
    options: &Options,
) -> Result<(Vec<TagPixels>, Parts), RefineError> {
    let (camera, motion) = (body.camera, body.motion.as_ref());
    let smear = motion.map_or(0.0, |m| smear_px(camera, pose, body.tags, m));
    let band_px = EDGE_BAND_SIGMAS * sigma_px + EDGE_BAND_PX;
    let pixels: Vec<TagPixels> =
        body.tags.iter().filter_map(|t| gather(&body.image, camera, pose, t, band_px, options)).collect();
    if pixels.is_empty() {
        return Err(RefineError::NoPixels);
    }
    Ok((pixels, Parts::of(smear, sigma_px, motion, options)))
}

fn validate(o: &Options, blur_px: f64, motion: Option<&Motion>) -> Result<(), RefineError> {
    let bad = |s: String| Err(RefineError::BadOptions(s));
    if !(blur_px.is_finite() && blur_px >= 0.0) {
        return bad(format!("the blur must be a finite σ of at least 0 px, got {blur_px}"));
    }
    if o.max_iterations == 0 || o.max_subframes == 0 || o.threads == 0 {
        return bad("iterations, sub-frames and threads must be at least 1".into());
    }
    if !(o.quiet_zone_cells.is_finite() && (0.0..=1.0).contains(&o.quiet_zone_cells)) {
        return bad(format!("the quiet zone taken must be 0–1 cells, got {}", o.quiet_zone_cells));
    }
    if !(o.huber.is_finite() && o.huber > 0.0 && o.max_shift_px.is_finite() && o.max_shift_px > 0.0) {
        return bad("Huber's constant and the largest shift must be positive".into());
    }
    if let Some(m) = motion
        && !(m.velocity.is_finite() && m.exposure_s.is_finite() && m.exposure_s >= 0.0)
    {
        return bad("the motion's velocity and exposure must be finite, the exposure at least 0".into());
    }
    Ok(())
}

/// How far (px) the body's motion carries its tags' corners over the exposure.
fn smear_px(camera: &CameraIntrinsics, start: &Pose, tags: &[Tag<'_>], m: &Motion) -> f64 {
    let half = m.exposure_s / 2.0;
    let (before, after) = (m.velocity.advance(start, -half), m.velocity.advance(start, half));
    let mut smear: f64 = 0.0;
    for c in tags.iter().flat_map(|t| t.corners) {
        let p = c.into();
        if let (Some(a), Some(b)) =
            (camera.project(&before.transform_point(&p)), camera.project(&after.transform_point(&p)))
        {
            smear = smear.max((a - b).norm());
        }
    }
    smear
}

/// How far (px) the rows' own times move the tags' corners: the body's motion between the
/// times of the highest and the lowest corner's rows ([`shift`]: infinite where a corner
/// leaves the view, so that the still alternative is then fitted).
fn skew_px(camera: &CameraIntrinsics, start: &Pose, tags: &[Tag<'_>], m: &Motion) -> f64 {
    let rows = tags.iter().flat_map(|t| t.corners).filter_map(|c| camera.project(&start.transform_point(&c.into())));
    let (top, bottom) = rows.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.y), b.max(p.y)));
    if top > bottom {
        return 0.0; // no corner in view
    }
    let at = |y: f64| m.velocity.advance(start, m.shutter.offset_s(y));
    shift(camera, &at(top), &at(bottom), tags)
}

/// The farthest any tag corner moved (px) between `a` and `b`.
fn shift(camera: &CameraIntrinsics, a: &Pose, b: &Pose, tags: &[Tag<'_>]) -> f64 {
    let mut most: f64 = 0.0;
    for c in tags.iter().flat_map(|t| t.corners) {
        let p = c.into();
        match (camera.project(&a.transform_point(&p)), camera.project(&b.transform_point(&p))) {
            (Some(x), Some(y)) => most = most.max((x - y).norm()),
            _ => return f64::INFINITY,
        }
    }
    most
}

/// The normal equations at a state, with the residuals' sums.
#[derive(Clone)]
struct Normal {
    h: DMatrix<f64>,
    /// The curvature with each pixel at its weight in the gradient (for the covariance).
    h_reweighted: DMatrix<f64>,
    g: DVector<f64>,
    /// Σ r² over the pixels.
    sq: f64,
    /// Σ w r².
    weighted_sq: f64,
    /// Huber's cost of the residuals.
    cost: f64,
}

impl Normal {
    /// The residuals' variance over `pixels`, each at its Huber weight, per degree of freedom
    /// left: what scales the inverse curvature into the estimate's covariance.
    fn variance(&self, pixels: usize) -> f64 {
        self.weighted_sq / (pixels as f64 - self.h.nrows() as f64).max(1.0)
    }
}

/// Where one fit ended.
struct Outcome {
    state: State,
    /// Huber's cost there.
    cost: f64,
    iterations: usize,
    normal: Normal,
    /// Whether it modelled the body's motion.
    motion: bool,
    /// The pixels it compared.
    pixels: usize,
}

/// A fit after its first pass.
struct Started {
    state: State,
    /// Huber's constant (linear light, 0–255), from the residuals' robust scale there.
    huber: f64,
    /// The normal equations there.
    normal: Normal,
}

/// What the fit needs: the pixels, the optics and the motion.
struct Fit<'a> {
    camera: &'a CameraIntrinsics,
    pixels: &'a [TagPixels],
    /// The parts of a row's exposure.
    parts: Parts,
    motion: Option<&'a Motion>,
    /// The pose is held where the fit begins; only the blur, the tone and the levels move.
    pose_fixed: bool,
    /// Above 1, a pass over the pixels is shared out in pieces ([`Options::threads`]).
    threads: usize,
}

impl Fit<'_> {
    /// The fit from `begin`: Levenberg–Marquardt with Huber weights on the residuals' robust
    /// scale there (the levels are fitted there first, by least squares).
    fn run(&self, begin: &Begin, options: &Options) -> Result<Outcome, RefineError> {
        self.run_from(self.start(begin, options)?, options)
    }

    /// The fit's first pass: the model at `begin` gives the levels, the residuals' scale and
    /// the first normal equations.
    fn start(&self, begin: &Begin, options: &Options) -> Result<Started, RefineError> {
        let seen = self.seen(&begin.pose, begin.sigma_px, true);
        let levels = self.levels(&seen).ok_or(RefineError::Singular)?;
        let state = State { pose: begin.pose, sigma_px: begin.sigma_px, gamma: begin.gamma, levels };
        let huber = options.huber * scale(self.residuals(&state, &seen)).max(MIN_SCALE);
        let normal = self.normal(&state, &|r, _| huber_weights(r, huber), huber, Some(&seen));
        Ok(Started { state, huber, normal })
    }

    /// The fit on from its first pass.
    fn run_from(&self, started: Started, options: &Options) -> Result<Outcome, RefineError> {
        let Started { mut state, huber, normal } = started;
        let huber_weight = |r: f64, _: f64| huber_weights(r, huber);
        // A state is evaluated with its normal equations at once: a step that is taken (most
        // are, near the minimum) is linearised next, from this.
        let evaluated = RefCell::new((state.clone(), normal));
        let mut cost = evaluated.borrow().1.cost;
        let damping = Damping {
            initial: 1e-3,
            diagonal_floor: 1e-9,
            relative_tolerance: RELATIVE_TOLERANCE,
            max_iterations: options.max_iterations,
        };
        let mut iterations = 0;
        let linearise = |s: &State| {
            let (at, normal) = &*evaluated.borrow();
            if at != s {
                return None; // the loop only linearises the state it evaluated last
            }
            Some(normal.clone())
        };
        // The state last linearised: where the loop ends after steps found no better (or
        // settled), its equations are not the ones evaluated last.
        let linearised = RefCell::new(None::<(State, Normal)>);
        // The step the last candidate was made by, for whether it has settled.
        let last_step = RefCell::new(None::<DVector<f64>>);
        minimise_until(
            &mut state,
            &mut cost,
            &damping,
            |s| {
                iterations += 1;
                let normal = linearise(s).unwrap_or_else(|| self.normal(s, &huber_weight, huber, None));
                *linearised.borrow_mut() = Some((s.clone(), normal.clone()));
                Some(normal)
            },
            |s, n, lambda| {
                let step = self.step(n, lambda, damping.diagonal_floor)?;
                *last_step.borrow_mut() = Some(step.clone());
                let d = Vector6::from_iterator(step.iter().take(6).copied());
                let pose = Pose::from_isometry(perturb(s.pose.isometry(), &d));
                let sigma_px = (s.sigma_px + step[6]).max(MIN_SIGMA_PX);
                let gamma = (s.gamma + step[7]).clamp(MIN_GAMMA, MAX_GAMMA);
                let levels = s.levels.iter().enumerate().map(|(k, l)| {
                    let o = SHARED + PER_TAG * k;
                    [l[0] + step[o], l[1] + step[o + 1]]
                });
                Some(State { pose, sigma_px, gamma, levels: levels.collect() })
            },
            |_, n, _| last_step.borrow().as_ref().is_some_and(|step| self.settled(step, n)),
            |s| {
                let normal = self.normal(s, &huber_weight, huber, None);
                let cost = normal.cost;
                *evaluated.borrow_mut() = (s.clone(), normal);
                cost
            },
        )
        .ok_or(RefineError::Singular)?;
        let normal = linearise(&state)
            .or_else(|| linearised.take().and_then(|(at, normal)| (at == state).then_some(normal)))
            .unwrap_or_else(|| self.normal(&state, &huber_weight, huber, None));
        // Every linearisation used: the steps were still lowering the cost when they ran out.
        // Where there is next to no noise (a clean render) each step lowers it by a larger
        // fraction while moving the pose by next to nothing: settled, if the next step would
        // move no corner by SETTLED_PX.
        if iterations >= options.max_iterations {
            let settled = self.next_step_px(&state, &normal) < SETTLED_PX; // false for NaN
            if !settled {
                return Err(RefineError::NotConverged { iterations });
            }
        }
        let pixels = self.pixels.iter().map(|t| t.samples.len()).sum();
        Ok(Outcome { state, cost, iterations, normal, motion: self.motion.is_some(), pixels })
    }

    /// The damped Gauss–Newton step of the normal equations `n`: every parameter's, or, with the
    /// pose held, zero for the pose's six and the rest solved without them.
    fn step(&self, n: &Normal, lambda: f64, floor: f64) -> Option<DVector<f64>> {
        if !self.pose_fixed {
            return Some(damped(&n.h, lambda, floor).cholesky()?.solve(&(-&n.g)));
        }
        let m = n.h.nrows() - 6;
        let h = n.h.view((6, 6), (m, m)).clone_owned();
        let rest = damped(&h, lambda, floor).cholesky()?.solve(&(-n.g.rows(6, m)));
        Some(DVector::from_iterator(6 + m, std::iter::repeat_n(0.0, 6).chain(rest.iter().copied())))
    }

    /// How far (px, the farthest tag corner) the next Gauss–Newton step from `s` would move the
    /// pose; infinite when it cannot be taken.
    fn next_step_px(&self, s: &State, n: &Normal) -> f64 {
        let Some(step) = self.step(n, 1e-9, 1e-9) else { return f64::INFINITY };
        let next =
            Pose::from_isometry(perturb(s.pose.isometry(), &Vector6::from_iterator(step.iter().take(6).copied())));
        let mut most: f64 = 0.0;
        for t in self.pixels {
            for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let p = (t.centre + t.x * sx + t.y * sy).into();
                match (self.camera.project(&s.pose.transform_point(&p)), self.camera.project(&next.transform_point(&p)))
                {
                    (Some(a), Some(b)) => most = most.max((a - b).norm()),
                    _ => return f64::INFINITY,
                }
            }
        }
        most
    }

    /// Whether `step`, from the state whose normal equations are `n`, is within a fraction
    /// ([`SETTLED_SIGMAS`]) of the estimate's own standard deviation: (δᵀ H δ / the residuals'
    /// variance)^½, the step's length in the covariance the fit reports: taking it would move
    /// the fit by less than a third of its own noise. Never with the pose held.
    fn settled(&self, step: &DVector<f64>, n: &Normal) -> bool {
        if self.pose_fixed {
            return false;
        }
        let pixels = self.pixels.iter().map(|t| t.samples.len()).sum();
        (step.dot(&(&n.h * step)) / n.variance(pixels)).sqrt() < SETTLED_SIGMAS
    }

    /// The tag's plane for each of `rows` rows from `first_row` at the middle of each part of its
    /// exposure (`rows × parts`, row-major), and, where the sweep is modelled, at the parts'
    /// ends (`rows × (parts + 1)`).
    fn planes(&self, pose: &Pose, t: &TagPixels, first_row: usize, rows: usize) -> Option<(Vec<Plane>, Vec<Plane>)> {
        let k = self.parts.middles.len();
        let mut middles = Vec::with_capacity(rows * k);
        let mut ends = Vec::with_capacity(if self.parts.smeared() { rows * (k + 1) } else { 0 });
        for r in 0..rows {
            let row_offset = self.motion.map_or(0.0, |m| m.shutter.offset_s((first_row + r) as f64));
            let at = |dt: f64| {
                let at = match self.motion {
                    Some(m) if row_offset + dt != 0.0 => m.velocity.advance(pose, row_offset + dt),
                    _ => *pose,
                };
                plane(&at, &t.centre, &t.x, &t.y)
            };
            for &dt in &self.parts.middles {
                middles.push(at(dt)?);
            }
            if self.parts.smeared() {
                let first = self.parts.middles[0] - self.parts.length_s / 2.0;
                for i in 0..=k {
                    ends.push(at(first + i as f64 * self.parts.length_s)?);
                }
            }
        }
        Some((middles, ends))
    }

    /// Every pixel's model at `pose`, tag by tag (`None` where a plane is edge-on).
    fn seen(&self, pose: &Pose, sigma_px: f64, jacobian: bool) -> Vec<Option<Vec<Seen>>> {
        let pieces = self.each_piece(|_, t, _, samples| {
            let mut out = Vec::with_capacity(samples.len());
            self.each_seen(t, samples, pose, sigma_px, jacobian, |_, m| out.push(m))?;
            Some(out)
        });
        pieces.into_iter().map(|tag| tag.into_iter().collect::<Option<Vec<_>>>().map(|p| p.concat())).collect()
    }

    /// `f(k, tag k, at, a piece of its pixels from the at-th)` over each tag's pixels in pieces
    /// of at most [`PIECE`], the results tag by tag and piece by piece in order: one piece after
    /// another, or with [`Fit::threads`] above 1 each a piece of work for the rayon pool the
    /// call runs in (a pool's thread that is done takes the next). The pieces do not depend on
    /// the threads, so neither do the sums made of them.
    fn each_piece<T: Send>(&self, f: impl Fn(usize, &TagPixels, usize, &[Sample]) -> T + Sync + Send) -> Vec<Vec<T>> {
        let pieces: Vec<(usize, usize, &[Sample])> = self
            .pixels
            .iter()
            .enumerate()
            .flat_map(|(k, t)| t.samples.chunks(PIECE).enumerate().map(move |(i, c)| (k, i * PIECE, c)))
            .collect();
        let run = |&(k, at, samples): &(usize, usize, &[Sample])| (k, f(k, &self.pixels[k], at, samples));
        let done: Vec<(usize, T)> = if self.threads <= 1 || pieces.len() <= 1 {
            pieces.iter().map(run).collect()
        } else {
            pieces.par_iter().with_max_len(1).map(run).collect()
        };
        let mut out: Vec<Vec<T>> = self.pixels.iter().map(|_| Vec::new()).collect();
        for (k, r) in done {
            out[k].push(r);
        }
        out
    }

    /// Calls `f` with each of `samples` (pixels of `t`, in row order) and its model at `pose`,
    /// in order, without keeping them (the normal equations need each once). `None` where a
    /// plane is edge-on, once `f` has seen the pixels before it.
    fn each_seen(
        &self,
        t: &TagPixels,
        samples: &[Sample],
        pose: &Pose,
        sigma_px: f64,
        jacobian: bool,
        mut f: impl FnMut(&Sample, Seen),
    ) -> Option<()> {
        let sigma = sigma_px / (self.camera.fx * self.camera.fy).sqrt();
        let k = self.parts.middles.len();
        // The rows the samples span (they are in row order).
        let first_row = samples.first().map_or(0, |s| s.row);
        let rows = samples.last().map_or(0, |s| s.row + 1 - first_row);
        let (middles, ends) = self.planes(pose, t, first_row, rows)?;
        let half = t.pattern.cells() as f64 / 2.0;
        let sees = |p: &Plane, n: &Vector2<f64>| to_tag(&p.to_tag, n).map(|(x, y)| Vector2::new(x, y));
        for s in samples {
            let r = s.row - first_row;
            let mut seen = Seen { paper: 0.0, d: Looked::zeros() };
            // Where the pixel looks on the tag at the start of each part, for its sweep.
            let ends = if ends.is_empty() { &[][..] } else { &ends[r * (k + 1)..][..k + 1] };
            let mut from = match ends.first() {
                Some(p) => sees(p, &s.normalised)?,
                None => Vector2::zeros(),
            };
            for (i, p) in middles[r * k..][..k].iter().enumerate() {
                let sweep = match ends.get(i + 1) {
                    Some(end) => {
                        let to = sees(end, &s.normalised)?;
                        let sweep = to - from;
                        from = to;
                        sweep
                    }
                    None => Vector2::zeros(),
                };
                let one = look(p, &t.pattern, &s.normalised, sigma, half, &sweep, jacobian)?;
                seen.paper += one.paper;
                seen.d += one.d;
            }
            // σ in normalised units to σ in pixels.
            seen.d[6] /= k as f64 * sigma_px / sigma;
            if k > 1 {
                seen.paper /= k as f64;
                seen.d.fixed_rows_mut::<6>(0).unscale_mut(k as f64);
            }
            f(s, seen);
        }
        Some(())
    }

    /// Each tag's (ink, contrast) fitted by least squares to the model `seen`.
    fn levels(&self, seen: &[Option<Vec<Seen>>]) -> Option<Vec<[f64; PER_TAG]>> {
        self.pixels
            .iter()
            .zip(seen)
            .map(|(t, s)| {
                let s = s.as_ref()?;
                let (mut a, mut b) = (Matrix2::zeros(), Vector2::zeros());
                for (px, m) in t.samples.iter().zip(s) {
                    let j = Vector2::new(1.0, m.paper);
                    a += j * j.transpose();
                    b += j * px.linear;
                }
                let x = a.try_inverse()? * b;
                Some([x.x, x.y])
            })
            .collect()
    }

    /// The residuals of the model `seen` read at the state's levels and tone.
    fn residuals(&self, s: &State, seen: &[Option<Vec<Seen>>]) -> Vec<f64> {
        let mut out = Vec::new();
        for (k, (t, m)) in self.pixels.iter().zip(seen).enumerate() {
            let Some(m) = m else { continue };
            out.extend(t.samples.iter().zip(m).map(|(px, m)| px.linear - s.predict(k, m.paper).0));
        }
        out
    }

    /// The normal equations at `s`, with each pixel's weights `weights(residual, model)`: its
    /// weight in the gradient (Σ w r J) and in the curvature (Σ c J Jᵀ); beside them the
    /// curvature at the gradient's weights (Σ w J Jᵀ). With Huber's cost (constant `huber`) of
    /// the residuals there: infinite where a tag is seen edge-on, whose pixels are then left
    /// out of the equations. The pixels' models are `seen` if given (made at `s` with their
    /// derivatives), else made here.
    fn normal(
        &self,
        s: &State,
        weights: &(dyn Fn(f64, f64) -> (f64, f64) + Sync),
        huber: f64,
        seen: Option<&[Option<Vec<Seen>>]>,
    ) -> Normal {
        let n = SHARED + PER_TAG * self.pixels.len();
        let (mut h, mut h_reweighted, mut g) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n), DVector::zeros(n));
        let (mut sq, mut weighted_sq, mut cost) = (0.0, 0.0, 0.0);
        // Each piece's sums are its own, so pieces may be summed at once; they are added up here
        // tag by tag and piece by piece, the same for any number of threads.
        let pieces = self.each_piece(|k, t, at, samples| {
            let l = s.levels[k];
            // The tag's block: the shared parameters, then its own levels. Only the lower
            // triangles are summed; `extra` holds what the pixels whose two weights differ
            // (Huber's outliers) add to the reweighted curvature.
            let mut sums = TagSums::default();
            let mut add = |px: &Sample, m: Seen| {
                let (model, by_light, by_gamma) = s.predict(k, m.paper);
                let r = px.linear - model;
                let (w, c) = weights(r, model);
                let mut j = BlockVector::zeros();
                j.fixed_rows_mut::<7>(0).copy_from(&(m.d * (-by_light * l[1])));
                j[7] = -by_gamma;
                j[SHARED] = -by_light;
                j[SHARED + 1] = -by_light * m.paper;
                sums.h.syger(c, &j, &j, 1.0);
                if w != c {
                    sums.extra.syger(w - c, &j, &j, 1.0);
                }
                sums.g.axpy(w * r, &j, 1.0);
                sums.sq += r * r;
                sums.weighted_sq += w * r * r;
                sums.cost += rho(r, huber);
            };
            // A tag seen edge-on has no sums.
            let whole = match seen {
                Some(seen) => seen[k].as_ref().map(|m| samples.iter().zip(&m[at..]).for_each(|(px, m)| add(px, *m))),
                None => self.each_seen(t, samples, &s.pose, s.sigma_px, true, &mut add),
            };
            whole.map(|_| sums)
        });
        for (k, tag) in pieces.into_iter().enumerate() {
            let tag = tag.into_iter().try_fold(TagSums::default(), |mut all, piece| {
                all.add(&piece?);
                Some(all)
            });
            let Some(mut t) = tag else {
                cost = f64::INFINITY;
                continue;
            };
            sq += t.sq;
            weighted_sq += t.weighted_sq;
            cost += t.cost;
            t.extra += t.h;
            add_block(&mut h, &t.h, k);
            add_block(&mut h_reweighted, &t.extra, k);
            let o = SHARED + PER_TAG * k;
            g.rows_mut(0, SHARED).add_assign(&t.g.fixed_rows::<SHARED>(0));
            g.rows_mut(o, PER_TAG).add_assign(&t.g.fixed_rows::<PER_TAG>(SHARED));
        }
        Normal { h, h_reweighted, g, sq, weighted_sq, cost }
    }
}

/// One tag's share of the normal equations: the lower triangles of its block of the curvature
/// and of what the reweighted curvature adds to it, its block of the gradient, and its
/// residuals' sums.
#[derive(Default)]
struct TagSums {
    h: Block,
    extra: Block,
    g: BlockVector,
    sq: f64,
    weighted_sq: f64,
    cost: f64,
}

impl TagSums {
    /// Adds another piece of the tag's pixels.
    fn add(&mut self, o: &TagSums) {
        self.h += o.h;
        self.extra += o.extra;
        self.g += o.g;
        self.sq += o.sq;
        self.weighted_sq += o.weighted_sq;
        self.cost += o.cost;
    }
}

/// Adds tag `k`'s block, of which the lower triangle is summed, to the normal equations' `h`.
fn add_block(h: &mut DMatrix<f64>, block: &Block, k: usize) {
    let mut b = *block;
    b.fill_upper_triangle_with_lower_triangle();
    let o = SHARED + PER_TAG * k;
    h.view_mut((0, 0), (SHARED, SHARED)).add_assign(&b.fixed_view::<SHARED, SHARED>(0, 0));
    h.view_mut((0, o), (SHARED, PER_TAG)).add_assign(&b.fixed_view::<SHARED, PER_TAG>(0, SHARED));
    h.view_mut((o, 0), (PER_TAG, SHARED)).add_assign(&b.fixed_view::<PER_TAG, SHARED>(SHARED, 0));
    h.view_mut((o, o), (PER_TAG, PER_TAG)).add_assign(&b.fixed_view::<PER_TAG, PER_TAG>(SHARED, SHARED));
}
