//! Written files read back by the two Python C3D readers biomechanics people use, ezc3d and
//! py-c3d (`c3d` on PyPI): rate, point count, labels, descriptions, units, frame count, every
//! coordinate within 1e-4 mm, and each missing point reported missing. Without python3 or a
//! package a test prints `SKIPPED: ...` to stderr and passes; with them it asserts.

use jawtrack_c3d::{MAX_FRAMES, PointTrack, write};
use std::path::{Path, PathBuf};
use std::process::Command;

const RATE_HZ: f64 = 60.0;
const FRAMES: usize = 50;
/// condyle_left is not seen in this frame (0-based).
const MISSING_FRAME: usize = 17;

/// Three jaw points with distinct, non-round values; condyle_right starts exactly at the
/// origin, which must still read as present (ezc3d's setters treat (0, 0, 0) as missing).
fn tracks() -> Vec<PointTrack> {
    let track = |label: &str, description: &str, at: &dyn Fn(f64) -> [f64; 3]| PointTrack {
        label: label.into(),
        description: description.into(),
        positions: (0..FRAMES).map(|f| Some(at(f as f64))).collect(),
    };
    let incisor = track("lower_incisor", "Lower incisor tip", &|f| {
        [10.0 + 0.25 * f, -35.5 + 2.0 * (0.2 * f).sin(), 80.125 - 0.1 * f]
    });
    let mut left = track("condyle_left", "Left condyle centre", &|f| [-48.3 + 0.01 * f, 12.7, -3.0 * (0.1 * f).cos()]);
    left.positions[MISSING_FRAME] = None;
    let right = track("condyle_right", "Right condyle centre", &|f| [0.5 * f, -0.02 * f * f, 1e-3 * f]);
    vec![incisor, left, right]
}

/// The longest file: past 32767 frames POINT:FRAMES is read back as unsigned, and no padding
/// frame is added (see `MAX_FRAMES`).
fn longest() -> Vec<PointTrack> {
    let positions = (0..MAX_FRAMES).map(|f| (f != 40_000).then(|| [f as f64 * 1e-3, -7.25, 100.0])).collect();
    vec![PointTrack { label: "lower_incisor".into(), description: String::new(), positions }]
}

/// What the script checks against, one tab-separated fact a line: `rate`, then `point` label
/// description, then `at` point frame x y z or `missing` point frame.
fn expectations(tracks: &[PointTrack], rate_hz: f64) -> String {
    let mut out = format!("rate\t{rate_hz}\n");
    for t in tracks {
        out += &format!("point\t{}\t{}\n", t.label, t.description);
    }
    for (i, t) in tracks.iter().enumerate() {
        for (f, p) in t.positions.iter().enumerate() {
            out += &match p {
                Some([x, y, z]) => format!("at\t{i}\t{f}\t{x}\t{y}\t{z}\n"),
                None => format!("missing\t{i}\t{f}\n"),
            };
        }
    }
    out
}

/// Reads the file with the reader named in argv[1] and compares it with the expectations;
/// exits 1 listing every mismatch.
const SCRIPT: &str = r#"
import math, sys, warnings

reader, path, expected_path = sys.argv[1:4]
rate, points, want = None, [], {}
for line in open(expected_path):
    f = line.rstrip("\n").split("\t")
    if f[0] == "rate":
        rate = float(f[1])
    elif f[0] == "point":
        points.append((f[1], f[2]))
    elif f[0] == "at":
        want[(int(f[1]), int(f[2]))] = tuple(float(v) for v in f[3:6])
    elif f[0] == "missing":
        want[(int(f[1]), int(f[2]))] = None
frames = 1 + max(f for _, f in want)
failures = []

def check(ok, what):
    if not ok:
        failures.append(what)

def read_ezc3d():
    import ezc3d
    c = ezc3d.c3d(path)
    p, h = c["parameters"]["POINT"], c["header"]["points"]
    check(h["frame_rate"] == p["RATE"]["value"][0], "header and POINT:RATE differ")
    check((h["first_frame"], h["last_frame"]) == (0, frames - 1), "ezc3d frame range %r" % ((h["first_frame"], h["last_frame"]),))
    xyz, residuals = c["data"]["points"], c["data"]["meta_points"]["residuals"]
    def at(i, f):
        if residuals[0, i, f] < 0:
            check(all(math.isnan(v) for v in xyz[:3, i, f]), "missing point %d frame %d has numbers" % (i, f))
            return None, "residual %g, xyz %s" % (residuals[0, i, f], list(xyz[:3, i, f]))
        return tuple(float(v) for v in xyz[:3, i, f]), residuals[0, i, f]
    return dict(rate=p["RATE"]["value"][0], count=h["size"], frames=xyz.shape[2],
                labels=list(p["LABELS"]["value"]), descriptions=list(p["DESCRIPTIONS"]["value"]),
                units=list(p["UNITS"]["value"]), at=at)

def read_py_c3d():
    import c3d
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with open(path, "rb") as handle:
            r = c3d.Reader(handle)
            read = [(n, p.copy()) for n, p, _ in r.read_frames()]
    # The one expected warning: this writer stores no analog channels.
    odd = [str(w.message) for w in caught if "No analog data found" not in str(w.message)]
    check(not odd, "py-c3d warned: %s" % odd)
    check([n for n, _ in read] == list(range(1, frames + 1)), "py-c3d frame numbers %s" % [n for n, _ in read][:3])
    def at(i, f):
        x, y, z, residual, cameras = read[f][1][i]
        if residual < 0:
            check((x, y, z, residual) == (0, 0, 0, -1), "missing point %d frame %d reads %s" % (i, f, read[f][1][i]))
            return None, "residual %g, xyz %s, cameras %g" % (residual, [x, y, z], cameras)
        return (float(x), float(y), float(z)), residual
    return dict(rate=r.point_rate, count=r.point_used, frames=len(read),
                labels=[s.strip() for s in r.point_labels],
                descriptions=[s.strip() for s in r.get("POINT:DESCRIPTIONS").string_array],
                units=[r.get("POINT:UNITS").string_value.strip()], at=at)

got = {"ezc3d": read_ezc3d, "c3d": read_py_c3d}[reader]()
check(abs(got["rate"] - rate) < 1e-4, "rate %r, want %r" % (got["rate"], rate))
check(got["count"] == len(points), "point count %r, want %d" % (got["count"], len(points)))
check(got["frames"] == frames, "frame count %r, want %d" % (got["frames"], frames))
check(got["labels"] == [l for l, _ in points], "labels %r" % got["labels"])
check(got["descriptions"] == [d for _, d in points], "descriptions %r" % got["descriptions"])
check(got["units"] == ["mm"], "units %r" % got["units"])
if got["count"] == len(points) and got["frames"] == frames:
    for (i, f), expected in sorted(want.items()):
        value, residual = got["at"](i, f)
        if expected is None:
            check(value is None, "point %d frame %d should be missing, reads %s" % (i, f, value))
            if value is None:
                print("missing point %d frame %d reads as: %s" % (i, f, residual))
            continue
        check(value is not None, "point %d frame %d reads missing (%s)" % (i, f, residual))
        check(value is None or residual == 0, "point %d frame %d residual %r, want 0" % (i, f, residual))
        if value is not None and max(abs(a - b) for a, b in zip(value, expected)) >= 1e-4:
            check(False, "point %d frame %d reads %s, want %s" % (i, f, value, expected))
if failures:
    print("MISMATCH between the C3D writer and %s:" % reader)
    for f in failures[:40]:
        print("  " + f)
    sys.exit(1)
print("ok: %s reads %d points x %d frames at %g Hz, labels %s" % (reader, got["count"], got["frames"], got["rate"], got["labels"]))
"#;

/// Why the reader cannot run here, as the SKIPPED line's tail, or None when it can.
fn unavailable(module: &str, package: &str) -> Option<String> {
    let install = format!("python3 -m pip install {package}");
    match Command::new("python3").args(["-c", &format!("import {module}")]).output() {
        Err(e) => Some(format!("no python3 ({e}): install Python 3, then `{install}`")),
        Ok(out) if !out.status.success() => Some(format!("python3 cannot import {module}: `{install}`")),
        Ok(_) => None,
    }
}

/// A fresh directory of this test's own under the system temp dir.
fn scratch(module: &str) -> PathBuf {
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    let dir = std::env::temp_dir().join(format!("jawtrack-c3d-{module}-{}-{nanos}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("create a scratch directory");
    dir
}

fn read_back_with(module: &str, package: &str, tracks: &[PointTrack], rate_hz: f64) {
    if let Some(why) = unavailable(module, package) {
        // Past the test harness's capture (which swallows eprintln! in a passing test), so
        // that CI counts the skip.
        let line = format!("SKIPPED: the {package} check of the C3D writer: {why}\n");
        let _ = std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes());
        return;
    }
    let bytes = write(tracks, rate_hz).expect("the test tracks are valid");
    let dir = scratch(module);
    let (c3d, expected) = (dir.join("jaw.c3d"), dir.join("expected.tsv"));
    std::fs::write(&c3d, bytes).expect("write the C3D file");
    std::fs::write(&expected, expectations(tracks, rate_hz)).expect("write the expectations");
    let out = run(module, &c3d, &expected);
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(
        out.status.success(),
        "{package} disagrees with the writer ({}), files kept in {}:\n{text}",
        out.status,
        dir.display()
    );
    println!("{text}");
    std::fs::remove_dir_all(&dir).expect("remove the scratch directory");
}

fn run(module: &str, c3d: &Path, expected: &Path) -> std::process::Output {
    Command::new("python3").args(["-c", SCRIPT, module]).arg(c3d).arg(expected).output().expect("run python3")
}

#[test]
fn ezc3d_reads_what_we_write() {
    read_back_with("ezc3d", "ezc3d", &tracks(), RATE_HZ);
}

#[test]
fn py_c3d_reads_what_we_write() {
    read_back_with("c3d", "c3d", &tracks(), RATE_HZ);
}

#[test]
fn ezc3d_reads_the_longest_file() {
    read_back_with("ezc3d", "ezc3d", &longest(), 1000.0);
}

#[test]
fn py_c3d_reads_the_longest_file() {
    read_back_with("c3d", "c3d", &longest(), 1000.0);
}
