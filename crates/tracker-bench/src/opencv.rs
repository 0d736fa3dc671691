//! OpenCV's `solvePnP` (SQPnP, with ITERATIVE timed beside it) in one Python child process
//! for the whole run, fed JSON lines of correspondences (`python/solve_pnp.py`).

use anyhow::{Context, Result, bail};
use jawtrack_pose::{CameraIntrinsics, Pose};
use nalgebra::Vector3;
use serde::Deserialize;
use std::io::{BufRead as _, BufReader, Write as _};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

/// The script, embedded so that the binary runs from anywhere.
const SCRIPT: &str = include_str!("../python/solve_pnp.py");

/// How to get OpenCV when no Python has it.
pub const INSTALL_HINT: &str = "pip install opencv-python-headless";

/// One body's correspondences: body-frame points (mm) and where they were seen (px).
#[derive(Debug, Clone, Default)]
pub struct BodyCase {
    /// Points in the body frame (mm).
    pub object: Vec<[f64; 3]>,
    /// Their pixels, in the same order.
    pub image: Vec<[f64; 2]>,
}

/// OpenCV's answer for one body.
#[derive(Debug, Clone, Copy)]
pub struct Solved {
    /// SQPnP's `camera_from_body`.
    pub camera_from_body: Pose,
    /// Median time of one SQPnP call (µs), as Python sees it.
    pub sqpnp_us: f64,
    /// Median time of one ITERATIVE call on the same points (µs).
    pub iterative_us: f64,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Answer {
    Solved { rvec: [f64; 3], tvec: [f64; 3], sqpnp_us: f64, iterative_us: f64 },
    Failed { error: String },
}

#[derive(Deserialize)]
struct Reply {
    poses: Vec<Answer>,
}

#[derive(Deserialize)]
struct Hello {
    opencv: String,
}

/// The Python process.
pub struct OpenCv {
    child: Child,
    stdin: Option<ChildStdin>,
    stdout: BufReader<ChildStdout>,
    /// The Python command used.
    pub python: String,
    /// OpenCV's version.
    pub version: String,
}

impl OpenCv {
    /// Starts the script under the first of `candidates` that imports cv2. `Ok(None)` with
    /// the reason when none does (the caller reports ours alone); an error when a Python with
    /// cv2 was found but the script would not start.
    pub fn start(candidates: &[String]) -> Result<std::result::Result<OpenCv, String>> {
        let mut tried = Vec::new();
        let Some(python) = candidates.iter().find(|py| {
            let ok = Command::new(py.as_str())
                .args(["-c", "import cv2"])
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status()
                .is_ok_and(|s| s.success());
            tried.push(py.as_str());
            ok
        }) else {
            return Ok(Err(format!(
                "no Python with OpenCV (tried {}: `import cv2` failed); install it with `{INSTALL_HINT}`",
                tried.join(", ")
            )));
        };
        let mut child = Command::new(python)
            .args(["-c", SCRIPT])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .with_context(|| format!("starting {python} with solve_pnp.py"))?;
        let stdin = child.stdin.take().context("the script's stdin")?;
        let mut stdout = BufReader::new(child.stdout.take().context("the script's stdout")?);
        let mut line = String::new();
        stdout.read_line(&mut line).context("reading solve_pnp.py's greeting")?;
        let hello: Hello = serde_json::from_str(&line)
            .with_context(|| format!("solve_pnp.py did not start (it said {:?})", line.trim()))?;
        Ok(Ok(OpenCv { child, stdin: Some(stdin), stdout, python: python.clone(), version: hello.opencv }))
    }

    /// Solves each body with SQPnP; per body, the pose or why OpenCV found none.
    pub fn solve(
        &mut self,
        camera: &CameraIntrinsics,
        bodies: &[BodyCase],
    ) -> Result<Vec<std::result::Result<Solved, String>>> {
        let request = serde_json::json!({
            "camera": [camera.fx, camera.fy, camera.cx, camera.cy, camera.k1, camera.k2],
            "bodies": bodies.iter().map(|b| serde_json::json!({"object": b.object, "image": b.image})).collect::<Vec<_>>(),
        });
        let stdin = self.stdin.as_mut().context("solve_pnp.py's input is closed")?;
        writeln!(stdin, "{request}").and_then(|()| stdin.flush()).context("writing to solve_pnp.py (did it crash?)")?;
        let mut line = String::new();
        if self.stdout.read_line(&mut line).context("reading from solve_pnp.py")? == 0 {
            bail!("solve_pnp.py exited early (its error, if any, is above)");
        }
        let reply: Reply = serde_json::from_str(&line).with_context(|| format!("solve_pnp.py answered {line:?}"))?;
        if reply.poses.len() != bodies.len() {
            bail!("solve_pnp.py answered {} poses for {} bodies", reply.poses.len(), bodies.len());
        }
        Ok(reply
            .poses
            .into_iter()
            .map(|a| match a {
                Answer::Solved { rvec, tvec, sqpnp_us, iterative_us } => {
                    let camera_from_body = Pose::from_axis_angle(Vector3::from(rvec), Vector3::from(tvec));
                    if camera_from_body.is_finite() {
                        Ok(Solved { camera_from_body, sqpnp_us, iterative_us })
                    } else {
                        Err("SQPnP returned a pose that is not finite".into())
                    }
                }
                Answer::Failed { error } => Err(error),
            })
            .collect())
    }
}

impl Drop for OpenCv {
    fn drop(&mut self) {
        // Closing its input ends the script's loop.
        drop(self.stdin.take());
        let _ = self.child.wait();
    }
}
