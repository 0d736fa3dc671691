//! Shared helpers for every crate's tests: where the fixtures and the shared data live, how a
//! test says it skipped, and reading a tag's cells out of an image through its four corners.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use std::path::PathBuf;

/// The repository's top folder (this crate is its `crates/test-support`).
fn repository() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The repository's `fixtures/` folder.
pub fn fixtures_dir() -> PathBuf {
    repository().join("fixtures")
}

/// `../shared/data` beside the repository, if present (it is not part of the product).
pub fn shared_data() -> Option<PathBuf> {
    let p = repository().join("../shared/data");
    p.is_dir().then_some(p)
}

/// Says that a test skipped part of its work, on the terminal even when cargo captures test
/// output (it captures `print!`/`eprint!`, not writes to the stderr handle).
pub fn say_skipped(what: &str) {
    use std::io::Write as _;
    let _ = writeln!(std::io::stderr(), "SKIPPED: {what}");
}

/// Fixture sets: every folder of `fixtures/` holding a `ground_truth.json`, sorted.
pub fn fixture_sets() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(fixtures_dir())
        .map(|rd| {
            rd.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.join("ground_truth.json").is_file()).collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// Every fixture set and its number of frames, as `fixtures/README.md` lists them, in the order
/// of [`fixture_sets`]. Tests that loop over the fixtures compare what they went through with
/// this, so that a missing set or frame fails them instead of leaving them nothing to check;
/// `crates/synth/tests/fixtures.rs` checks it against the folders.
pub const FIXTURE_FRAMES: [(&str, usize); 8] = [
    ("chew-1080p", 3),
    ("clean-excursion-1080p", 4),
    ("clean-hinge-1080p", 5),
    ("clean-static-1080p", 18),
    ("clean-static-4k", 2),
    ("hinge-1080p", 5),
    ("static-1080p", 6),
    ("static-4k", 1),
];

/// A fixture set's name: its folder's.
pub fn set_name(set: &std::path::Path) -> String {
    set.file_name().and_then(|n| n.to_str()).unwrap_or("?").to_owned()
}

/// Asserts that `checked`, the (set name, frames checked) of a test's loop over
/// [`fixture_sets`], is every set of [`FIXTURE_FRAMES`] with all its frames.
#[track_caller]
pub fn assert_every_fixture_frame(what: &str, checked: &[(String, usize)]) {
    let want: Vec<(String, usize)> = FIXTURE_FRAMES.iter().map(|&(name, n)| (name.to_owned(), n)).collect();
    assert_eq!(checked, want, "{what}: the (set, frames) checked are not every fixture frame");
}

/// The homography mapping tag coordinates ((−1,+1) bottom-left … (−1,−1) top-left, y down)
/// to pixels through four corners in detection order.
pub fn tag_homography(corners: &[[f64; 2]; 4]) -> Option<Matrix3<f64>> {
    let tag = [(-1.0, 1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)];
    let mut a = SMatrix::<f64, 8, 8>::zeros();
    let mut b = SVector::<f64, 8>::zeros();
    for i in 0..4 {
        let (x, y) = tag[i];
        let [u, v] = corners[i];
        a.row_mut(2 * i).copy_from_slice(&[x, y, 1.0, 0.0, 0.0, 0.0, -u * x, -u * y]);
        a.row_mut(2 * i + 1).copy_from_slice(&[0.0, 0.0, 0.0, x, y, 1.0, -v * x, -v * y]);
        b[2 * i] = u;
        b[2 * i + 1] = v;
    }
    let h = a.lu().solve(&b)?;
    Some(Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], 1.0))
}

/// Bilinear sample of a gray image (pixel centres at integers); `None` outside.
pub fn bilinear(img: &image::GrayImage, x: f64, y: f64) -> Option<f64> {
    let (w, h) = img.dimensions();
    if x < 0.0 || y < 0.0 || x > f64::from(w - 1) || y > f64::from(h - 1) {
        return None;
    }
    let (x0, y0) = (x.floor() as u32, y.floor() as u32);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (x - f64::from(x0), y - f64::from(y0));
    let p = |x, y| f64::from(img.get_pixel(x, y)[0]);
    Some(
        p(x0, y0) * (1.0 - fx) * (1.0 - fy)
            + p(x1, y0) * fx * (1.0 - fy)
            + p(x0, y1) * (1.0 - fx) * fy
            + p(x1, y1) * fx * fy,
    )
}

/// A tag's 8×8 cells read from an image, and the levels found around them.
#[derive(Debug, Clone)]
pub struct TagReading {
    /// Mean value over the central part of each cell, `cells[y * 8 + x]`.
    pub cells: Vec<f64>,
    /// Mean of the 28 black-border cells.
    pub black: f64,
    /// Mean of 32 points of the white quiet zone just outside the black square.
    pub white: f64,
}

impl TagReading {
    /// Whether cell (x, y) reads white (above the midpoint of black and white).
    pub fn is_white(&self, x: usize, y: usize) -> bool {
        self.cells[y * 8 + x] > 0.5 * (self.black + self.white)
    }
}

/// Reads a tag's cells through its corners, or `None` if any sample falls outside the image.
pub fn read_tag(img: &image::GrayImage, corners: &[[f64; 2]; 4]) -> Option<TagReading> {
    let h = tag_homography(corners)?;
    let mean = |u: f64, v: f64| -> Option<f64> {
        let mut sum = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                let (du, dv) = ((f64::from(i) - 1.0) * 0.06, (f64::from(j) - 1.0) * 0.06);
                let p = h * Vector3::new(u + du, v + dv, 1.0);
                sum += bilinear(img, p.x / p.z, p.y / p.z)?;
            }
        }
        Some(sum / 9.0)
    };
    let cells = (0..64)
        .map(|i| mean(-1.0 + ((i % 8) as f64 + 0.5) / 4.0, -1.0 + ((i / 8) as f64 + 0.5) / 4.0))
        .collect::<Option<Vec<f64>>>()?;
    let quiet = (0..8)
        .flat_map(|i| {
            let t = -1.0 + (f64::from(i) + 0.5) / 4.0;
            [(t, -1.1), (t, 1.1), (-1.1, t), (1.1, t)]
        })
        .map(|(u, v)| mean(u, v))
        .collect::<Option<Vec<f64>>>()?;
    let border: Vec<f64> =
        (0..64).filter(|i| i % 8 == 0 || i % 8 == 7 || i / 8 == 0 || i / 8 == 7).map(|i| cells[i]).collect();
    Some(TagReading {
        black: border.iter().sum::<f64>() / border.len() as f64,
        white: quiet.iter().sum::<f64>() / quiet.len() as f64,
        cells,
    })
}

#[cfg(test)]
mod tests {
    /// The guard itself: a loop that checked no fixture frame fails.
    #[test]
    #[should_panic(expected = "not every fixture frame")]
    fn checking_no_fixture_frame_fails() {
        super::assert_every_fixture_frame("nothing", &[]);
    }
}
