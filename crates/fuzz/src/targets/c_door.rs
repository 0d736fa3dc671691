//! The C frame door the iPhone app calls (`jt_tracker_new`, `jt_track_luma`,
//! `jt_track_bgra`, `jt_last_error`, `jt_tracker_free`), driven with hostile sizes, strides,
//! buffer lengths, intrinsics, times, handles and settings — but always with buffers as long
//! as the length passed says, which is the caller's one promise. Every call must return a
//! status that is not `Panic`; a refusal must leave a message; a summary must be finite.
//! Run under valgrind (docs/fuzzing.md), a read outside the buffer given shows up too.

// The door is C: calling it takes raw pointers, each justified where it is passed.
#![allow(unsafe_code)]

use crate::run::Verdict;
use jawtrack_ffi::c_api::{
    JtBody, JtFrameSummary, JtIntrinsics, JtSettings, JtStatus, jt_last_error, jt_settings_default, jt_track_bgra,
    jt_track_luma, jt_tracker_free, jt_tracker_new,
};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// The tracker the calls share (a call may free it and make another).
static HANDLE: Mutex<Option<u64>> = Mutex::new(None);

/// Calls made into the door so far.
static CALLS_MADE: AtomicU64 = AtomicU64::new(0);

/// How many calls the door has taken, for the run's report.
pub fn calls_made() -> String {
    format!("{} calls into the C door", CALLS_MADE.load(Ordering::Relaxed))
}

/// Bytes read off the input, zero past its end.
struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn u8(&mut self) -> u8 {
        let (b, rest) = self.0.split_first().map_or((0, &[][..]), |(b, r)| (*b, r));
        self.0 = rest;
        b
    }
    fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.u8(), self.u8()])
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }
    fn pick<T: Copy>(&mut self, from: &[T]) -> T {
        from[usize::from(self.u8()) % from.len()]
    }
}

const ODD: [f64; 9] = [0.0, -1.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e300, -1e-300, 0.008, 1.0];

/// The input's layout: calls of [`CALL`] bytes each, then the pixels every frame is cut from.
/// A call's zero bytes choose the sane value of each argument, so mutants stray one at a time.
const CALL: usize = 16;
const CALLS: usize = 6;

pub fn seeds() -> Vec<Vec<u8>> {
    // A tracker made up front: the first call then costs what the rest do.
    fresh_tracker();
    // The smaller window of tags (each frame tracked costs what its tags do), and the same
    // size of flat grey, where the detector finds nothing.
    let frames = crate::targets::images::frame_seeds();
    let Some(tags) = frames.last() else { return vec![] };
    let (w, h) = (u16::from_le_bytes([tags[0], tags[1]]), u16::from_le_bytes([tags[2], tags[3]]));
    let grey = vec![128; tags.len() - 6];
    [&tags[6..], &grey[..]]
        .into_iter()
        .map(|pixels| {
            let mut calls = Vec::new();
            for op in [0u8, 112, 0, 224] {
                // Exact stride and buffer, sane intrinsics, increasing time, a summary, the live tracker.
                let mut call = vec![op];
                call.extend(w.to_le_bytes());
                call.extend(h.to_le_bytes());
                call.resize(CALL, 0);
                calls.extend(call);
            }
            calls.resize(CALL * CALLS, 0);
            calls.extend(pixels);
            calls
        })
        .collect()
}

/// The shared tracker: default settings but for the edge model, whose cost would dominate
/// and which `frame` and `image` fuzz through the detector; here the door is under test.
fn fresh_tracker() -> Option<u64> {
    let mut handle = 0;
    let settings = JtSettings { linear_edges: false, ..jt_settings_default() };
    // SAFETY: valid settings; a null marker means the nominal one; `handle` is writable.
    let status = unsafe { jt_tracker_new(&settings, std::ptr::null(), &mut handle) };
    let made = (status == JtStatus::Ok).then_some(handle);
    if let Ok(mut h) = HANDLE.lock() {
        if let Some(old) = h.take() {
            jt_tracker_free(old);
        }
        *h = made;
    }
    made
}

pub fn run(input: &[u8]) -> Result<Verdict, String> {
    let split = input.len().min(CALL * CALLS);
    let (calls, pixels) = input.split_at(split);
    let mut accepted = false;
    for (k, call) in calls.chunks(CALL).enumerate() {
        accepted |= one_call(k, &mut Reader(call), pixels)?;
    }
    Ok(if accepted { Verdict::Accepted } else { Verdict::Refused })
}

/// One call; true when it returned `Ok`.
fn one_call(k: usize, r: &mut Reader<'_>, pixels: &[u8]) -> Result<bool, String> {
    // Frames mostly (a zero byte: luma); trackers are made and freed rarely, each costing
    // more than a frame.
    let op = match r.u8() {
        0..=111 => 0,
        112..=223 => 1,
        224..=239 => 2,
        240..=247 => 3,
        _ => 4,
    };
    CALLS_MADE.fetch_add(1, Ordering::Relaxed);
    let current = HANDLE.lock().ok().and_then(|h| *h);
    let live = current.or_else(fresh_tracker).unwrap_or(0);
    let status = match op {
        0 | 1 => frame_call(op == 1, k, r, pixels, live)?,
        2 => {
            // The message buffer at every length, null included.
            let len = usize::from(r.u8() % 64);
            let mut buf = vec![0 as std::ffi::c_char; len];
            let ptr = if len == 0 { std::ptr::null_mut() } else { buf.as_mut_ptr() };
            // SAFETY: `ptr` is null or points to `len` writable bytes.
            let full = unsafe { jt_last_error(ptr, len) };
            if len > 0 && buf.iter().all(|&c| c != 0) {
                return Err(format!(
                    "jt_last_error left a {len}-byte buffer without its NUL (message of {full} bytes)"
                ));
            }
            // Not a call that can be refused: it counts as neither.
            return Ok(false);
        }
        3 => {
            let handle = r.pick(&[live, 0, u64::MAX, live.wrapping_add(1)]);
            let status = jt_tracker_free(handle);
            if handle == live {
                fresh_tracker();
            }
            status
        }
        _ => new_tracker_call(r),
    };
    judge(status)
}

/// A tracker made with hostile settings and marker text, and freed.
fn new_tracker_call(r: &mut Reader<'_>) -> JtStatus {
    let mut s = jt_settings_default();
    s.decimate = r.pick(&[2.0, 0.0, -1.0, f32::NAN, 1e9, 1.5]);
    s.quad_sigma = r.pick(&[0.0, f32::NAN, -1e9, 0.8]);
    // 0 is the only valid Hamming limit tried here: the shared tracker has the default, 2.
    s.max_hamming = r.pick(&[0, 3, 99, u32::MAX]);
    s.threads = r.pick(&[1, 0, 2, 9, u32::MAX]);
    s.readout_s = r.pick(&ODD);
    // Null (the nominal marker) unless the byte says otherwise: the settings must reach the tracker.
    let text: Option<&[u8]> = r.pick(&[None, Some(&b"{"[..]), Some(b""), Some(b"{\"version\": 3}"), Some(b"\xff\xfe")]);
    let marker = text.and_then(|t| std::ffi::CString::new(t).ok());
    let settings: &JtSettings = &s;
    let mut handle = 0;
    // SAFETY: valid settings, a NUL-terminated marker or null, a writable handle.
    let status =
        unsafe { jt_tracker_new(settings, marker.as_ref().map_or(std::ptr::null(), |m| m.as_ptr()), &mut handle) };
    if status == JtStatus::Ok {
        jt_tracker_free(handle);
    }
    status
}

/// A frame handed in as the app hands one: `bgra` or luma, with the call's sizes.
fn frame_call(bgra: bool, k: usize, r: &mut Reader<'_>, pixels: &[u8], live: u64) -> Result<JtStatus, String> {
    let pixel = if bgra { 4 } else { 1 };
    let (width, height) = (u32::from(r.u16()), u32::from(r.u16()));
    let row = width as usize * pixel;
    let bytes_per_row = match r.u8() % 5 {
        0 => row as u32,
        1 => (row + 64) as u32,
        2 => (row as u32).saturating_sub(1),
        3 => r.u32(),
        _ => 0,
    };
    let needed = (bytes_per_row as usize).saturating_mul((height as usize).saturating_sub(1)).saturating_add(row);
    let len = match r.u8() % 4 {
        0 => needed,
        1 => needed.saturating_sub(1),
        2 => needed.saturating_add(usize::from(r.u8())),
        _ => usize::from(r.u16()),
    }
    // Kept to what a test can allocate: a longer claim must be refused before any read.
    .min(1 << 24);
    // Exactly `len` bytes on the heap, so a read past them is outside the allocation.
    let buffer: Box<[u8]> = if pixels.is_empty() {
        vec![0; len].into_boxed_slice()
    } else {
        pixels.iter().copied().cycle().take(len).collect()
    };
    let f = r.pick(&[1500.0, width as f64, 0.0, -1.0, f64::NAN, f64::INFINITY, 1e300]);
    let intrinsics = JtIntrinsics {
        fx: f,
        fy: if r.u8() % 4 == 3 { r.pick(&ODD) } else { f },
        cx: if r.u8() % 4 == 3 { r.pick(&ODD) } else { width as f64 / 2.0 },
        cy: height as f64 / 2.0,
        k1: if r.u8() % 4 == 3 { r.pick(&ODD) } else { 0.0 },
        k2: 0.0,
    };
    let null_intrinsics = r.u8() % 8 == 7;
    let t = if r.u8() % 4 == 3 { r.pick(&ODD) } else { k as f64 / 60.0 };
    let exposure = r.pick(&[0.0, 0.008, f64::NAN, -1.0, 1e9]);
    let handle = r.pick(&[live, live, live, 0, u64::MAX]);
    let null_buffer = r.u8() % 16 == 15;
    let nobody = JtBody { found: false, camera_from_body: [0.0; 16], tag_count: 0, rms_px: 0.0 };
    let mut summary = JtFrameSummary {
        frame: 0,
        maxilla: nobody,
        mandible: nobody,
        has_maxilla_from_mandible: false,
        maxilla_from_mandible: [0.0; 16],
        flag_count: 0,
        detection_ms: 0.0,
        pose_ms: 0.0,
    };
    let summary_out: *mut JtFrameSummary = if r.u8() % 4 == 3 { std::ptr::null_mut() } else { &mut summary };
    let data = if null_buffer { std::ptr::null() } else { buffer.as_ptr() };
    let k_ptr: *const JtIntrinsics = if null_intrinsics { std::ptr::null() } else { &intrinsics };
    // SAFETY: `data` is null or has `len` readable bytes; the intrinsics and the summary are
    // null or valid; the handle may be anything, which the door checks.
    let status = unsafe {
        if bgra {
            jt_track_bgra(handle, data, len, width, height, bytes_per_row, k_ptr, t, exposure, summary_out)
        } else {
            jt_track_luma(handle, data, len, width, height, bytes_per_row, k_ptr, t, exposure, summary_out)
        }
    };
    if status == JtStatus::Ok && !summary_out.is_null() {
        finite_summary(&summary)?;
    }
    Ok(status)
}

fn finite_summary(s: &JtFrameSummary) -> Result<(), String> {
    let bodies = [&s.maxilla, &s.mandible];
    let finite = bodies.iter().all(|b| b.camera_from_body.iter().all(|v| v.is_finite()) && b.rms_px.is_finite())
        && s.maxilla_from_mandible.iter().all(|v| v.is_finite())
        && s.detection_ms.is_finite()
        && s.pose_ms.is_finite();
    if finite { Ok(()) } else { Err(format!("a summary holds a value that is not finite: {s:?}")) }
}

/// `Panic` is a bug; a refusal must say why.
fn judge(status: JtStatus) -> Result<bool, String> {
    let message = || {
        let mut buf = vec![0 as std::ffi::c_char; 512];
        // SAFETY: `buf` has 512 writable bytes.
        unsafe { jt_last_error(buf.as_mut_ptr(), buf.len()) };
        // SAFETY: jt_last_error NUL-terminates within the buffer.
        unsafe { std::ffi::CStr::from_ptr(buf.as_ptr()) }.to_string_lossy().into_owned()
    };
    match status {
        JtStatus::Ok => Ok(true),
        JtStatus::Panic => Err(format!("the door panicked: {}", message())),
        _ if message().trim().is_empty() => Err(format!("{status:?} with no message")),
        _ => Ok(false),
    }
}
