//! The ground-truth file written beside rendered frames (`ground_truth.json`).
//!
//! Every pose is a 4×4 row-major matrix in mm, camera frame x right, y down, z forward; pixel
//! coordinates put the centre of the top-left pixel at (0, 0).

use crate::post::Glare;
use crate::realism::Realism;
use crate::scenes::FrameSpec;
use jawtrack_pose::{CameraIntrinsics, Pose};
use serde::{Deserialize, Serialize};

/// The whole file.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct GroundTruth {
    /// File format version (1).
    pub version: u32,
    /// Scene name.
    pub scene: String,
    /// Seed everything random was drawn from.
    pub seed: u64,
    /// Image size [width, height] (px).
    pub image_size: [u32; 2],
    /// Camera intrinsics.
    pub intrinsics: CameraIntrinsics,
    /// Realism settings used (exposure and rolling-shutter readout among them).
    pub realism: Realism,
    /// Each tag's print error: how the printed tag really sits relative to the nominal file.
    pub print_errors: Vec<PrintErrorTruth>,
    /// The marker as printed (print errors included), in the marker-file schema: the oracle
    /// geometry a perfect calibration would find.
    pub true_marker: serde_json::Value,
    /// The frames.
    pub frames: Vec<FrameTruth>,
}

/// One tag's print error.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct PrintErrorTruth {
    /// Tag id.
    pub id: u32,
    /// Shift along the tag's x axis (mm).
    pub shift_x: f64,
    /// Shift along the tag's y axis (mm).
    pub shift_y: f64,
    /// In-plane rotation, counter-clockwise seen from outside (degrees).
    pub rotation_deg: f64,
}

/// One frame.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FrameTruth {
    /// Frame number.
    pub index: usize,
    /// Image file name.
    pub file: String,
    /// Time at mid-exposure (s); with a rolling shutter, of the centre row (row y is exposed
    /// centred at [`Realism::row_time`]). Every pose below is at this time.
    pub t: f64,
    /// Maxilla marker in the camera frame at `t`.
    pub camera_from_maxilla: Pose,
    /// Mandible marker in the camera frame at `t`.
    pub camera_from_mandible: Pose,
    /// Mandible marker in the maxilla marker's frame: what the tracker must report.
    pub maxilla_from_mandible: Pose,
    /// The head in the camera frame (see `scenes` for the head frame).
    pub camera_from_head: Pose,
    /// Sub-frames averaged for motion blur; with a rolling shutter, the most instants a row
    /// averaged.
    pub subframes: u32,
    /// Speed of the lower incisal point relative to the maxilla at `t` (mm/s; absent in older
    /// files: 0).
    #[serde(default)]
    pub incisor_speed_mm_s: f64,
    /// Focus distance used for defocus (mm), if any.
    pub focus_mm: Option<f64>,
    /// Glare patches added.
    pub glare: Vec<Glare>,
    /// Whether an occluder was placed in front of a marker.
    pub occluder: bool,
    /// Every tag facing the camera.
    pub tags: Vec<TagTruth>,
    /// How the frame was made.
    pub spec: FrameSpec,
}

/// A tag facing the camera in one frame.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TagTruth {
    /// Tag id.
    pub id: u32,
    /// Body name.
    pub body: String,
    /// Corners (px) in detection order: bottom-left, bottom-right, top-right, top-left. Each is
    /// where it is seen: with a rolling shutter, projected at its own row's mid-exposure time.
    pub corners: [[f64; 2]; 4],
    /// Centre (px), seen as the corners are.
    pub center: [f64; 2],
    /// Angle between the line of sight and the face normal (degrees).
    pub view_angle_deg: f64,
    /// Shortest side in the image (px).
    pub min_side_px: f64,
    /// All four corners lie inside the image.
    pub in_image: bool,
    /// Fraction of the tag hidden by the other marker, an occluder, or the image border.
    pub occluded_fraction: f64,
}

impl TagTruth {
    /// Whether a detector should find this tag: whole, unoccluded, in the image, seen at less
    /// than 75° from its normal and at least 12 px across.
    pub fn should_be_detected(&self) -> bool {
        self.in_image && self.occluded_fraction == 0.0 && self.view_angle_deg < 75.0 && self.min_side_px >= 12.0
    }
}
