//! The detector: the stages of the C library's `apriltag_detector_detect` in order — decimate,
//! threshold, regions, clusters, quads; then per quad at full resolution edge refinement,
//! homography, decoding against a gray model of the border with sharpening; then removal of
//! overlapping duplicates. Each stage is a port that reproduces C's results (see the stage
//! modules); this one adds only the bookkeeping and JawTrack's pixel convention.

use crate::DetectError;
use crate::clusters::gradient_clusters_par;
use crate::components::{UnionFind, connected_components_with};
use crate::config::{DetectorConfig, Roi};
use crate::decode::CodeTable;
use crate::gray::Gray;
use crate::image::ImageView;
use crate::preprocess::{blur_or_sharpen, decimate_with};
use crate::quads::{Quad, fit_quads};
use crate::threshold::threshold_with;
use crate::tone::{ToneSession, ToneSummary};
use crate::workers::Workers;
use jawtrack_tag_family::TagFamily;
use std::sync::{Arc, Mutex, TryLockError};
use tone_refit::PendingFit;

mod border;
mod confirm;
mod edges;
mod nested;
mod per_quad;
mod stages;
mod tone_fit;
mod tone_refit;

pub use border::PIXEL_SIGMA_PX;
pub use confirm::Expected;
use per_quad::finish;
use stages::Clock;
pub use stages::StageTimes;

/// How to search one frame ([`Detector::search`]): what a tracker knows of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Search {
    /// Only inside this region, in full-frame coordinates (the whole frame for `None`).
    pub roi: Option<Roi>,
    /// Fit edges as motion ramps ([`DetectorConfig::smeared_edges`]).
    pub smeared: bool,
    /// The decimation quads are found at, in place of the settings' (1, 1.5, 2, 3 or 4).
    pub quad_decimate: f32,
    /// Quads whose longest side is shorter than this (px) are neither refitted nor decoded: a
    /// tracker that knows its tags' size passes over the quads a tag's data cells make. 0
    /// tries every quad.
    pub min_quad_px: f64,
}

/// One detected tag, in JawTrack's pixel convention (the centre of the top-left pixel is
/// (0, 0); the C library reports 0.5 more).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Detection {
    /// Id in the detector's family.
    pub id: u32,
    /// Bits corrected.
    pub hamming: u32,
    /// How far the sampled bits sit from the threshold on average (the weaker of the light
    /// and dark bits); low values mean a doubtful decode.
    pub decision_margin: f32,
    /// Centre (px).
    pub center: [f64; 2],
    /// Corners (px): bottom-left, bottom-right, top-right, top-left of the upright tag.
    pub corners: [[f64; 2]; 4],
    /// Homography from tag coordinates ([−1, 1]², y down) to pixels, row-major 3×3.
    pub homography: [f64; 9],
    /// How blurred the tag's edges are (σ of a Gaussian, px), what the lens and motion add to
    /// the pixel's own spread, read from its second-sharpest side (a side along the motion is
    /// not smeared, so this is the lens's defocus); `None` when it was not measured
    /// ([`DetectorConfig::blur_aware_edges`] off, or a side could not be fitted).
    pub blur_px: Option<f64>,
}

impl Detection {
    /// The same tag in pixels moved by (`dx`, `dy`): a window's detection in its frame, or
    /// a frame's in a patch of it.
    pub(crate) fn shifted(&self, dx: f64, dy: f64) -> Detection {
        Detection {
            center: [self.center[0] + dx, self.center[1] + dy],
            corners: self.corners.map(|p| [p[0] + dx, p[1] + dy]),
            homography: shifted_homography(&self.homography, dx, dy),
            ..*self
        }
    }
}

/// Homography `h` followed by moving its pixels by (`dx`, `dy`).
pub(crate) fn shifted_homography(h: &[f64; 9], dx: f64, dy: f64) -> [f64; 9] {
    [
        h[0] + dx * h[6],
        h[1] + dx * h[7],
        h[2] + dx * h[8],
        h[3] + dy * h[6],
        h[4] + dy * h[7],
        h[5] + dy * h[8],
        h[6],
        h[7],
        h[8],
    ]
}

/// An AprilTag detector for one family ([`DetectorConfig::family`]).
#[derive(Debug)]
pub struct Detector {
    config: DetectorConfig,
    table: CodeTable,
    /// The tone curve frames are read through now, and how it was found.
    tone: Mutex<ToneState>,
    /// Shared by clones: a pool of `nthreads` threads.
    workers: Arc<Workers>,
    /// Frame-sized buffers kept between frames: allocating them afresh costs a page fault
    /// per 4 kB, as much time as the stage that fills them. Not shared by clones.
    scratch: Mutex<Scratch>,
    /// Where the last detection's time went.
    stages: Mutex<StageTimes>,
}

impl Clone for Detector {
    fn clone(&self) -> Self {
        Detector {
            config: self.config,
            table: self.table.clone(),
            tone: Mutex::new(self.tone_state().clone()),
            workers: Arc::clone(&self.workers),
            scratch: Mutex::new(Scratch::default()),
            stages: Mutex::new(StageTimes::default()),
        }
    }
}

/// The buffers of one detection.
#[derive(Debug, Default)]
struct Scratch {
    decimated: Gray,
    threshold: Gray,
    regions: Option<UnionFind>,
    pixel_region: Vec<u32>,
}

impl Detector {
    /// Checks the settings and builds the decoding table.
    pub fn new(config: DetectorConfig) -> Result<Self, DetectError> {
        config.validate()?;
        let table = CodeTable::new(&config.family, config.max_hamming)?;
        Ok(Detector {
            config,
            table,
            tone: Mutex::new(ToneState::new(&config)),
            workers: Arc::new(Workers::new(config.nthreads)),
            scratch: Mutex::new(Scratch::default()),
            stages: Mutex::new(StageTimes::default()),
        })
    }

    /// Where the time of the last detection (of this detector, on any thread) went: a
    /// detection through a region and a second one of the whole frame count as two.
    pub fn last_stages(&self) -> StageTimes {
        *self.stages.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The settings.
    pub fn config(&self) -> &DetectorConfig {
        &self.config
    }

    /// The detector's threads, for work its callers share out beside detection (the tracker's
    /// dense refinement of its two bodies).
    pub fn workers(&self) -> &Workers {
        &self.workers
    }

    /// The tone curve frames are read through now ([`DetectorConfig::tone`]) and how it was
    /// found: with `Auto`, from the tags of the frames detected so far.
    pub fn tone(&self) -> ToneSummary {
        self.tone_state().session.summary()
    }

    /// Whether the next detection fits the tone curve: `Auto`, edges fitted in linear light,
    /// and the curve still settling or due a refit ([`crate::tone`]). A tracker searches such
    /// a frame rather than confirming predicted tags ([`Detector::confirm`]), so that the curve
    /// is fitted to the tags a search finds, however the other frames are found.
    pub fn tone_fit_due(&self) -> bool {
        self.fits_tone(&self.tone_state())
    }

    /// Whether a detection now fits the tone curve, `state` being the detector's.
    fn fits_tone(&self, state: &ToneState) -> bool {
        self.config.linear_edges && state.session.due() && state.pending.is_none()
    }

    fn tone_state(&self) -> std::sync::MutexGuard<'_, ToneState> {
        self.tone.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Detects tags, sorted by id. With a region of interest in the settings, only tags inside
    /// it are found, in full-frame coordinates.
    pub fn detect(&self, frame: &ImageView<'_>) -> Result<Vec<Detection>, DetectError> {
        self.detect_in(frame, self.config.roi)
    }

    /// Detects tags inside `roi` (the whole frame for `None`), whatever the settings say: a
    /// tracker moves its region with the markers from frame to frame.
    pub fn detect_in(&self, frame: &ImageView<'_>, roi: Option<Roi>) -> Result<Vec<Detection>, DetectError> {
        self.detect_in_with(frame, roi, self.config.smeared_edges)
    }

    /// As [`Detector::detect_in`], with the smeared-edge fit on or off for this frame
    /// ([`DetectorConfig::smeared_edges`]): a tracker knows which frames move.
    ///
    /// With [`DetectorConfig::tone`] `Auto`, the frame's tags also feed the estimate of the
    /// camera's tone curve when a fit is due ([`crate::tone`]); when that changes the curve,
    /// the frame is detected again through the new one, so no frame is read through a curve
    /// its own tags refuted.
    pub fn detect_in_with(
        &self,
        frame: &ImageView<'_>,
        roi: Option<Roi>,
        smeared: bool,
    ) -> Result<Vec<Detection>, DetectError> {
        self.search(frame, &Search { roi, smeared, quad_decimate: self.config.quad_decimate, min_quad_px: 0.0 })
    }

    /// Detects tags as `search` says: where, whether edges are smeared, and on how coarse an
    /// image quads are found (a tracker that expects large tags searches a coarser one). The
    /// tone curve is estimated as in [`Detector::detect_in_with`].
    ///
    /// # Examples
    ///
    /// ```
    /// use jawtrack_apriltag::{Detector, DetectorConfig, ImageView, Search};
    ///
    /// let detector = Detector::new(DetectorConfig::default()).expect("valid settings");
    /// let frame = vec![128u8; 640 * 480];
    /// let view = ImageView::new(&frame, 640, 480, 640).expect("a frame");
    /// let search = Search { roi: None, smeared: false, quad_decimate: 4.0, min_quad_px: 0.0 };
    /// assert!(detector.search(&view, &search).expect("searched").is_empty());
    /// ```
    pub fn search(&self, frame: &ImageView<'_>, search: &Search) -> Result<Vec<Detection>, DetectError> {
        if search.quad_decimate != self.config.quad_decimate {
            DetectorConfig { quad_decimate: search.quad_decimate, ..self.config }.validate()?;
        }
        self.with_tone(frame, |lut| self.detect_through(frame, search, lut))
    }

    /// Runs `detect` on the frame through the current tone curve; with [`DetectorConfig::tone`]
    /// `Auto` and a fit due, fits the curve to the tags found. While the curve settles the fit
    /// is made here, and when it changes the curve `detect` runs again through the new one;
    /// once settled it is made on a thread of its own and taken a fixed number of detections
    /// later ([`tone_refit`]).
    fn with_tone(
        &self,
        frame: &ImageView<'_>,
        detect: impl Fn(&[f64; 256]) -> Result<Vec<Detection>, DetectError>,
    ) -> Result<Vec<Detection>, DetectError> {
        let lut = self.tone_state().lut.clone();
        let dets = detect(&lut)?;
        {
            let mut state = self.tone_state();
            state.take_due_refit();
            if !self.fits_tone(&state) {
                state.session.skip();
                return Ok(dets);
            }
            if state.session.settled()
                && let Some(pending) = PendingFit::start(self.config.family, frame, &dets, Arc::clone(&lut))
            {
                state.pending = Some(pending);
                state.session.skip();
                return Ok(dets);
            }
        }
        let fit = tone_fit::fit_tone_through(&self.config.family, frame, &dets, &lut);
        let changed = {
            let mut state = self.tone_state();
            state.session.record(fit).map(|curve| {
                state.lut = Arc::new(curve.decode_table());
                Arc::clone(&state.lut)
            })
        };
        match changed {
            Some(lut) => detect(&lut),
            None => Ok(dets),
        }
    }

    fn detect_through(
        &self,
        frame: &ImageView<'_>,
        search: &Search,
        lut: &[f64; 256],
    ) -> Result<Vec<Detection>, DetectError> {
        let (dets, st) = self.detect_region(frame, search, lut, &self.workers)?;
        *self.stages.lock().unwrap_or_else(|p| p.into_inner()) = st;
        Ok(dets)
    }

    /// The tags `search` finds through `lut`, the work spread over `workers`, and where its
    /// time went.
    fn detect_region(
        &self,
        frame: &ImageView<'_>,
        search: &Search,
        lut: &[f64; 256],
        workers: &Workers,
    ) -> Result<(Vec<Detection>, StageTimes), DetectError> {
        let (view, ox, oy) = match search.roi {
            None => (*frame, 0.0, 0.0),
            Some(r) => {
                if r.x + r.width > frame.width() || r.y + r.height > frame.height() {
                    return Err(DetectError::BadConfig(format!(
                        "roi {}×{} at ({}, {}) leaves the {}×{} frame",
                        r.width,
                        r.height,
                        r.x,
                        r.y,
                        frame.width(),
                        frame.height()
                    )));
                }
                (frame.sub_view(r.x, r.y, r.width, r.height)?, r.x as f64, r.y as f64)
            }
        };
        let (dets, st) = self.detect_view(&view, search, lut, workers);
        Ok((dets.iter().map(|d| d.shifted(ox, oy)).collect(), st))
    }

    fn detect_view(
        &self,
        im: &ImageView<'_>,
        search: &Search,
        lut: &[f64; 256],
        workers: &Workers,
    ) -> (Vec<Detection>, StageTimes) {
        let (smeared, decimate) = (search.smeared, search.quad_decimate);
        let c = &self.config;
        // Another thread detecting with this detector has the buffers: use fresh ones.
        let (mut guard, mut own);
        let s: &mut Scratch = match self.scratch.try_lock() {
            Ok(g) => {
                guard = g;
                &mut guard
            }
            Err(TryLockError::Poisoned(p)) => {
                guard = p.into_inner();
                &mut guard
            }
            Err(TryLockError::WouldBlock) => {
                own = Scratch::default();
                &mut own
            }
        };
        let mut clock = Clock::start();
        let mut st = StageTimes::default();
        let blur = c.quad_sigma != 0.0;
        if decimate > 1.0 {
            decimate_with(im, decimate, &mut s.decimated, workers);
        } else if blur {
            s.decimated.reset(im.width(), im.height(), 0);
            for (y, row) in s.decimated.data.chunks_exact_mut(im.width()).enumerate() {
                row.copy_from_slice(im.row(y));
            }
        }
        if blur {
            blur_or_sharpen(&mut s.decimated, c.quad_sigma);
        }
        let quad_im = if decimate > 1.0 || blur {
            match s.decimated.view() {
                Ok(v) => v,
                Err(_) => return (Vec::new(), st), // too small to hold a tag
            }
        } else {
            *im
        };
        // Undecimated, C blurs the frame itself, so edges are refined and bits read on the
        // blurred frame too.
        let im = if decimate > 1.0 { im } else { &quad_im };
        st.decimate_s = clock.lap();
        threshold_with(&quad_im, c.quad.min_white_black_diff, c.quad.deglitch, &mut s.threshold, workers);
        st.threshold_s = clock.lap();
        let uf = s.regions.get_or_insert_with(|| UnionFind::new(0));
        connected_components_with(&s.threshold, uf, workers);
        st.components_s = clock.lap();
        let clusters = gradient_clusters_par(&s.threshold, uf, &mut s.pixel_region, workers);
        st.clusters_s = clock.lap();
        let mut quads = fit_quads(&clusters, &quad_im, &c.quad, decimate, workers);
        st.quads_s = clock.lap();
        st.clusters = clusters.len();
        if decimate > 1.0 {
            for q in &mut quads {
                for p in &mut q.p {
                    p[0] *= decimate;
                    p[1] *= decimate;
                }
            }
        }
        if search.min_quad_px > 0.0 {
            quads.retain(|q| longest_side(q) >= search.min_quad_px);
        }
        let tag = |q: &Quad| self.tag_from_quad(im, q, decimate, lut, smeared);
        let dets = if c.linear_edges {
            // The quads nested in a larger one wait, and those a decoded tag holds (its data
            // cells') are passed over; the tags come out in the quads' order as before.
            let (first, nested) = nested::split(&quads);
            let mut found = workers.filter_map(&first, |&i| tag(&quads[i]).map(|d| (i, d)));
            let nested: Vec<usize> =
                nested.into_iter().filter(|&i| !nested::held_by_a_tag(&quads[i], &found)).collect();
            st.quads = first.len() + nested.len();
            found.extend(workers.filter_map(&nested, |&i| tag(&quads[i]).map(|d| (i, d))));
            found.sort_by_key(|&(i, _)| i);
            found.into_iter().map(|(_, d)| d).collect()
        } else {
            st.quads = quads.len();
            workers.filter_map(&quads, tag)
        };
        st.tags_s = clock.lap();
        let dets = finish(dets);
        st.finish_s = clock.lap();
        st.tags = dets.len();
        st.quad_decimate = decimate;
        (dets, st)
    }
}

/// A side is taken from the model fit of the border ([`border`]) where its blur (σ, the pixel's
/// own spread included) exceeds this fraction of its cell: below it the gradient fit's line
/// is as good or better (drawn tags: 0.005 against 0.01 px at 0.15 of a cell), above it the
/// neighbouring cells' ramps pull the gradient fit off (0.07 px at 0.23, 0.46–0.72 px at 0.37;
/// the model fit stays within 0.07 px; `border::tests`).
const MODEL_SIDE_BLUR_PER_CELL: f64 = 0.17;
/// … and where the model explains the image: its RMS residual within this fraction of the
/// paper–ink contrast. Drawn tags under a Gaussian blur are fitted within 0.015 and sensor
/// noise adds about as much; a tag smeared by motion (a ramp, not a Gaussian) or seen so
/// steeply that its cells are a few pixels wide and deep misses by 0.1–4 there, and its model
/// sides land 0.3–5 px off (`fixtures/hinge-1080p`).
const MODEL_SIDE_MAX_MISFIT: f64 = 0.05;

/// `d` with its blur measured, and (with `sides`) its sides from the model fit of its border
/// where they are blurred enough for the neighbouring cells to pull the gradient fit off
/// ([`MODEL_SIDE_BLUR_PER_CELL`]), when the fit succeeds and lands near the gradient fit
/// (within a third of a cell: farther is not the same tag's border); else `d` as it was. A
/// smeared frame keeps the ramp fit's sides: motion smears an edge into a ramp, not the
/// Gaussian the model assumes (a tag smeared 8 px over 12 px cells: 0.065 px off with the
/// model's sides, within 0.02 px with the ramp's).
fn with_border_fit(im: &ImageView<'_>, lut: &[f64; 256], family: &TagFamily, d: Detection, sides: bool) -> Detection {
    let Some(bitmap) = family.bitmap(d.id) else { return d };
    let Some(fit) = border::fit_border(im, lut, &bitmap, &d.homography, sides) else { return d };
    let measured = Detection { blur_px: Some(fit.blur_px), ..d };
    let Some(fitted) = fit.sides.filter(|_| sides) else { return measured };
    let c = d.corners;
    // The gradient fit's sides, as the border fit orders them: top, right, bottom, left.
    let gradient = [[c[3], c[2]], [c[2], c[1]], [c[1], c[0]], [c[0], c[3]]];
    let mut lines = gradient;
    for (line, side) in lines.iter_mut().zip(&fitted) {
        if side.sigma_px > MODEL_SIDE_BLUR_PER_CELL * side.cell_px && side.misfit < MODEL_SIDE_MAX_MISFIT {
            *line = side.line;
        }
    }
    if lines == gradient {
        return measured;
    }
    let [top, right, bottom, left] = lines;
    let corners = [
        border::intersect(&bottom, &left),
        border::intersect(&bottom, &right),
        border::intersect(&top, &right),
        border::intersect(&top, &left),
    ];
    let Some(corners) = corners.into_iter().collect::<Option<Vec<_>>>() else { return measured };
    let corners: [[f64; 2]; 4] = [corners[0], corners[1], corners[2], corners[3]];
    let distance = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let smallest_cell = (0..4).map(|i| distance(c[i], c[(i + 1) % 4])).fold(f64::INFINITY, f64::min) / 8.0;
    let moved = c.iter().zip(&corners).map(|(a, b)| distance(*a, *b)).fold(0.0, f64::max);
    if moved.is_nan() || moved > smallest_cell / 3.0 {
        return measured;
    }
    let [bl, br, tr, tl] = corners;
    let Some(homography) = homography_of([tl, tr, br, bl]) else { return measured };
    let (cx, cy) = project(&homography, 0.0, 0.0);
    Detection { corners, center: [cx, cy], homography, ..measured }
}

/// The longest side (px) of the quad with corners `c`.
fn longest_side_of(c: &[[f64; 2]; 4]) -> f64 {
    (0..4).map(|i| (c[(i + 1) % 4][0] - c[i][0]).hypot(c[(i + 1) % 4][1] - c[i][1])).fold(0.0, f64::max)
}

/// The longest side of `q` (px), computed in the quad's own `f32`.
fn longest_side(q: &Quad) -> f64 {
    (0..4)
        .map(|i| f64::from((q.p[(i + 1) % 4][0] - q.p[i][0]).hypot(q.p[(i + 1) % 4][1] - q.p[i][1])))
        .fold(0.0, f64::max)
}

/// Pixel values as they are (what C uses).
static IDENTITY: [f64; 256] = {
    let mut t = [0.0; 256];
    let mut i = 0;
    while i < 256 {
        t[i] = i as f64;
        i += 1;
    }
    t
};

/// The tone curve of a detector's frames, and the table it is read through.
#[derive(Debug, Clone)]
struct ToneState {
    session: ToneSession,
    /// Encoded values to linear light: the curve undone (identity for C's edge fit).
    lut: Arc<[f64; 256]>,
    /// A refit under way on its own thread.
    pending: Option<PendingFit>,
}

impl ToneState {
    fn new(c: &DetectorConfig) -> Self {
        let session = ToneSession::new(c.tone);
        let lut = if c.linear_edges { session.curve().decode_table() } else { IDENTITY };
        ToneState { session, lut: Arc::new(lut), pending: None }
    }

    /// Counts a detection for the refit under way, and takes it into the session when its
    /// time has come: later detections read through the curve it leads to.
    fn take_due_refit(&mut self) {
        let Some(fit) = self.pending.as_mut().and_then(PendingFit::tick) else { return };
        self.pending = None;
        if let Some(curve) = self.session.record(fit) {
            self.lut = Arc::new(curve.decode_table());
        }
    }
}

/// C's `homography_compute2`: the homography taking tag coordinates (−1,−1), (1,−1), (1,1),
/// (−1,1) to the quad's corners, by Gaussian elimination with partial pivoting. `None` when
/// singular (as C's also gives up when the inverse does not exist).
fn homography(q: &Quad) -> Option<[f64; 9]> {
    homography_of(q.p.map(|p| p.map(f64::from)))
}

/// The homography taking tag coordinates (−1,−1), (1,−1), (1,1), (−1,1) to `p`'s four points.
fn homography_of(p: [[f64; 2]; 4]) -> Option<[f64; 9]> {
    let tag = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let mut a = [0.0f64; 72];
    for i in 0..4 {
        let (x, y) = tag[i];
        let (u, v) = (p[i][0], p[i][1]);
        a[(2 * i) * 9..(2 * i) * 9 + 9].copy_from_slice(&[x, y, 1.0, 0.0, 0.0, 0.0, -x * u, -y * u, u]);
        a[(2 * i + 1) * 9..(2 * i + 1) * 9 + 9].copy_from_slice(&[0.0, 0.0, 0.0, x, y, 1.0, -x * v, -y * v, v]);
    }
    for col in 0..8 {
        let (mut max_val, mut max_row) = (0.0f64, None);
        for row in col..8 {
            let v = a[row * 9 + col].abs();
            if v > max_val {
                max_val = v;
                max_row = Some(row);
            }
        }
        let max_row = max_row?;
        if max_val < 1e-10 {
            return None;
        }
        if max_row != col {
            for i in col..9 {
                a.swap(col * 9 + i, max_row * 9 + i);
            }
        }
        for i in col + 1..8 {
            let f = a[i * 9 + col] / a[col * 9 + col];
            a[i * 9 + col] = 0.0;
            for j in col + 1..9 {
                a[i * 9 + j] -= f * a[col * 9 + j];
            }
        }
    }
    for col in (0..8).rev() {
        let mut sum = 0.0;
        for i in col + 1..8 {
            sum += a[col * 9 + i] * a[i * 9 + 8];
        }
        a[col * 9 + 8] = (a[col * 9 + 8] - sum) / a[col * 9 + col];
    }
    let h = [a[8], a[17], a[26], a[35], a[44], a[53], a[62], a[71], 1.0];
    let det = h[0] * h[4] * h[8] - h[0] * h[5] * h[7] + h[1] * h[5] * h[6] - h[1] * h[3] * h[8] + h[2] * h[3] * h[7]
        - h[2] * h[4] * h[6];
    (det != 0.0).then_some(h)
}

fn project(h: &[f64; 9], x: f64, y: f64) -> (f64, f64) {
    let z = h[6] * x + h[7] * y + h[8];
    ((h[0] * x + h[1] * y + h[2]) / z, (h[3] * x + h[4] * y + h[5]) / z)
}

/// A least-squares plane of gray values over the tag: C's `graymodel`.
#[derive(Default)]
struct GrayModel {
    a: [[f64; 3]; 3],
    b: [f64; 3],
    c: [f64; 3],
}

impl GrayModel {
    fn add(&mut self, x: f64, y: f64, gray: f64) {
        self.a[0][0] += x * x;
        self.a[0][1] += x * y;
        self.a[0][2] += x;
        self.a[1][1] += y * y;
        self.a[1][2] += y;
        self.a[2][2] += 1.0;
        self.b[0] += x * gray;
        self.b[1] += y * gray;
        self.b[2] += gray;
    }

    /// C's `mat33_sym_solve`: Cholesky of the upper triangle, inverse, two products.
    fn solve(&mut self) {
        let a = [self.a[0][0], self.a[0][1], self.a[0][2], 0.0, self.a[1][1], self.a[1][2], 0.0, 0.0, self.a[2][2]];
        let mut l = [0.0f64; 9];
        l[0] = a[0].sqrt();
        l[3] = a[1] / l[0];
        l[6] = a[2] / l[0];
        l[4] = (a[4] - l[3] * l[3]).sqrt();
        l[7] = (a[5] - l[3] * l[6]) / l[4];
        l[8] = (a[8] - l[6] * l[6] - l[7] * l[7]).sqrt();
        let mut m = [0.0f64; 9];
        m[0] = 1.0 / l[0];
        m[3] = -l[3] * m[0] / l[4];
        m[4] = 1.0 / l[4];
        m[6] = (-l[6] * m[0] - l[7] * m[3]) / l[8];
        m[7] = -l[7] * m[4] / l[8];
        m[8] = 1.0 / l[8];
        let b = self.b;
        let t = [m[0] * b[0], m[3] * b[0] + m[4] * b[1], m[6] * b[0] + m[7] * b[1] + m[8] * b[2]];
        self.c = [m[0] * t[0] + m[3] * t[1] + m[6] * t[2], m[4] * t[1] + m[7] * t[2], m[8] * t[2]];
    }

    fn at(&self, x: f64, y: f64) -> f64 {
        self.c[0] * x + self.c[1] * y + self.c[2]
    }
}

/// C's `value_for_pixel`: bilinear interpolation in C's pixel-corner convention; `None`
/// outside the image.
fn value_for_pixel(im: &ImageView<'_>, px: f64, py: f64) -> Option<f64> {
    let x1 = (px - 0.5).floor() as i64;
    let x2 = (px - 0.5).ceil() as i64;
    let x = px - 0.5 - x1 as f64;
    let y1 = (py - 0.5).floor() as i64;
    let y2 = (py - 0.5).ceil() as i64;
    let y = py - 0.5 - y1 as f64;
    if x1 < 0 || x2 >= im.width() as i64 || y1 < 0 || y2 >= im.height() as i64 {
        return None;
    }
    let p = |x: i64, y: i64| f64::from(im.get(x as usize, y as usize).unwrap_or(0));
    Some(p(x1, y1) * (1.0 - x) * (1.0 - y) + p(x2, y1) * x * (1.0 - y) + p(x1, y2) * (1.0 - x) * y + p(x2, y2) * x * y)
}

fn decode_quad(
    im: &ImageView<'_>,
    h: &[f64; 9],
    family: &TagFamily,
    table: &CodeTable,
    sharpening: f64,
) -> Option<Detection> {
    let wab = family.width_at_border as f64;
    let total = family.total_width;
    // Sample lines just outside (white) and just inside (black) each side of the border.
    let patterns: [[f32; 5]; 8] = [
        [-0.5, 0.5, 0.0, 1.0, 1.0],
        [0.5, 0.5, 0.0, 1.0, 0.0],
        [wab as f32 + 0.5, 0.5, 0.0, 1.0, 1.0],
        [wab as f32 - 0.5, 0.5, 0.0, 1.0, 0.0],
        [0.5, -0.5, 1.0, 0.0, 1.0],
        [0.5, 0.5, 1.0, 0.0, 0.0],
        [0.5, wab as f32 + 0.5, 1.0, 0.0, 1.0],
        [0.5, wab as f32 - 0.5, 1.0, 0.0, 0.0],
    ];
    let (mut white, mut black) = (GrayModel::default(), GrayModel::default());
    for p in &patterns {
        for i in 0..family.width_at_border {
            let tx01 = (f64::from(p[0]) + i as f64 * f64::from(p[2])) / wab;
            let ty01 = (f64::from(p[1]) + i as f64 * f64::from(p[3])) / wab;
            let (tx, ty) = (2.0 * (tx01 - 0.5), 2.0 * (ty01 - 0.5));
            let (px, py) = project(h, tx, ty);
            let (ix, iy) = (px as i64, py as i64);
            if ix < 0 || iy < 0 || ix >= im.width() as i64 || iy >= im.height() as i64 {
                continue;
            }
            let v = f64::from(im.get(ix as usize, iy as usize).unwrap_or(0));
            if p[4] != 0.0 { white.add(tx, ty, v) } else { black.add(tx, ty, v) }
        }
    }
    white.solve();
    black.solve();
    // The border is dark inside light: anything else is not this family.
    if white.at(0.0, 0.0) - black.at(0.0, 0.0) < 0.0 {
        return None;
    }
    let min_coord = (family.width_at_border as i64 - total as i64) / 2;
    let mut values = vec![0.0f64; total * total];
    let cell = |bx: u8, by: u8| ((i64::from(by) - min_coord) as usize) * total + (i64::from(bx) - min_coord) as usize;
    for &(bx, by) in family.bit_cells {
        let tx = 2.0 * ((f64::from(bx) + 0.5) / wab - 0.5);
        let ty = 2.0 * ((f64::from(by) + 0.5) / wab - 0.5);
        let (px, py) = project(h, tx, ty);
        let Some(v) = value_for_pixel(im, px, py) else { continue };
        let thresh = (black.at(tx, ty) + white.at(tx, ty)) / 2.0;
        values[cell(bx, by)] = v - thresh;
    }
    sharpen(&mut values, total, sharpening);
    let (mut white_score, mut black_score) = (0.0f32, 0.0f32);
    let (mut white_count, mut black_count) = (1.0f32, 1.0f32);
    let mut rcode = 0u64;
    for &(bx, by) in family.bit_cells {
        rcode <<= 1;
        let v = values[cell(bx, by)];
        if v > 0.0 {
            white_score += v as f32;
            white_count += 1.0;
            rcode |= 1;
        } else {
            black_score -= v as f32;
            black_count += 1.0;
        }
    }
    let decoded = table.decode(rcode)?;
    let margin = (white_score / white_count).min(black_score / black_count);
    if margin < 0.0 {
        return None;
    }
    // C counts its own (counter-clockwise) quarter turns; ours are clockwise.
    let c_turns = (4 - decoded.rotation) % 4;
    let theta = f64::from(c_turns) * std::f64::consts::PI / 2.0;
    let (c, s) = (theta.cos(), theta.sin());
    let r = [c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0];
    let mut hr = [0.0f64; 9];
    for i in 0..3 {
        for j in 0..3 {
            hr[i * 3 + j] = (0..3).map(|k| h[i * 3 + k] * r[k * 3 + j]).sum();
        }
    }
    let center = project(&hr, 0.0, 0.0);
    let corners: [[f64; 2]; 4] = std::array::from_fn(|i| {
        let tx = if i == 1 || i == 2 { 1.0 } else { -1.0 };
        let ty = if i < 2 { 1.0 } else { -1.0 };
        let (x, y) = project(&hr, tx, ty);
        [x, y]
    });
    Some(Detection {
        id: decoded.id,
        hamming: decoded.hamming,
        decision_margin: margin,
        center: [center.0, center.1],
        corners,
        homography: hr,
        blur_px: None,
    })
}

/// C's `sharpen`: add `k` times a 3×3 Laplacian (4-neighbour) of the sampled values.
fn sharpen(values: &mut [f64], size: usize, k: f64) {
    let kernel = [0.0, -1.0, 0.0, -1.0, 4.0, -1.0, 0.0, -1.0, 0.0];
    let mut sharpened = vec![0.0f64; size * size];
    for y in 0..size as i64 {
        for x in 0..size as i64 {
            let mut acc = 0.0;
            for i in 0..3i64 {
                for j in 0..3i64 {
                    let (yy, xx) = (y + i - 1, x + j - 1);
                    if yy < 0 || yy > size as i64 - 1 || xx < 0 || xx > size as i64 - 1 {
                        continue;
                    }
                    acc += values[(yy as usize) * size + xx as usize] * kernel[(i * 3 + j) as usize];
                }
            }
            sharpened[(y as usize) * size + x as usize] = acc;
        }
    }
    for (v, s) in values.iter_mut().zip(&sharpened) {
        *v += k * s;
    }
}

#[cfg(test)]
mod tests;
