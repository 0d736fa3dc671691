//! Pose from every pixel: a marker body's pose refined by comparing the image with what its
//! tags print, as the camera saw them.
//!
//! The corner pipeline rests a body's pose on four corners per tag, each from a model of one
//! edge. Once the tags are decoded their whole pattern is known, so every pixel of every
//! visible tag can speak: at a pose, each pixel looks through the camera model onto a tag's
//! plane, where the printed pattern blurred by the lens's spread ([`model`]) says how much
//! paper it sees; the image, read in linear light through the tone curve, should be the tag's
//! ink level plus that fraction of its contrast, raised to a power that takes up a tone curve
//! that is not quite the camera's. The body's pose (six parameters), the blur, that power and
//! each tag's two levels are fitted to all pixels together by Levenberg–Marquardt with Huber
//! weights, so an occluder, a glare spot or a neighbour's edge costs only its own pixels.
//!
//! Motion is modelled as the camera records it: each row is exposed at its own time under a
//! rolling shutter, and over the exposure the body moves on at its tracked velocity, so a
//! pixel sees the pattern averaged over its row's exposure window: the window is cut into up
//! to [`Options::max_subframes`] parts, each seen at its middle with its sweep as a blur. The pose is the body's at the frame's time (its centre
//! row's), as the corner pipeline's is. The motion is kept only where it fits the image better
//! than a still body does, a velocity taken from earlier frames can be wrong; where it smears
//! nothing and moves the tags by a twentieth of a pixel at most, a wrong one cannot matter and
//! the still fit is not made.
//!
//! The refinement starts from the corner pose and is checked against it: a refinement that does
//! not settle within [`Options::max_iterations`], cannot be solved, or lands farther than
//! [`Options::max_shift_px`] from it, is refused with the reason ([`RefineError`]), and the
//! caller keeps the corner pose.
//!
//! # Examples
//!
//! ```
//! use jawtrack_apriltag::ImageView;
//! use jawtrack_photometric::{Body, Image, Options, Tag, refine};
//! use jawtrack_pose::{CameraIntrinsics, Pose};
//! use jawtrack_tag_family::TagFamily;
//! use nalgebra::{UnitQuaternion, Vector3};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let (width, height) = (640, 480);
//! let luma = vec![128u8; width * height]; // the camera's frame
//! let frame = ImageView::new(&luma, width, height, width)?;
//! let camera = CameraIntrinsics::pinhole(600.0, 600.0, 319.5, 239.5);
//! // How the camera's 8-bit values map to linear light: here a camera that delivers it.
//! let linear: [f64; 256] = std::array::from_fn(|v| v as f64);
//! // Tag 0, a 10 mm square facing the camera 100 mm away, as the corner pipeline posed it.
//! let bitmap = TagFamily::TAG36H11.bitmap(0).ok_or("tag 0")?;
//! let corners = [[-5.0, 5.0, 0.0], [5.0, 5.0, 0.0], [5.0, -5.0, 0.0], [-5.0, -5.0, 0.0]];
//! let tags = [Tag { corners, bitmap: &bitmap }];
//! let corner_pose = Pose::from_parts(UnitQuaternion::identity(), Vector3::new(0.0, 0.0, 100.0));
//! let body = Body { image: Image { frame, linear: &linear }, camera: &camera, tags: &tags, blur_px: 0.6, motion: None };
//! match refine(&body, &corner_pose, &Options::default()) {
//!     Ok(r) => println!("{:?} from {} pixels", r.camera_from_body, r.pixels),
//!     // A grey frame shows no tag: the corner pose stands, and the reason is given.
//!     Err(e) => println!("kept the corner pose: {e}"),
//! }
//! # Ok(())
//! # }
//! ```

mod gather;
pub mod model;
mod parts;
mod plane;
mod robust;
mod solve;

pub use model::Pattern;
pub use solve::{bound, refine};

use jawtrack_apriltag::ImageView;
use jawtrack_pose::{CameraIntrinsics, Pose, RollingShutter, Velocity};
use jawtrack_tag_family::TagBitmap;
use nalgebra::Matrix6;

/// A frame and how to read its values as linear light.
#[derive(Debug, Clone, Copy)]
pub struct Image<'a> {
    /// The frame's luma.
    pub frame: ImageView<'a>,
    /// Each 8-bit value as linear light on the same 0–255 scale (the tone curve's
    /// `decode_table`).
    pub linear: &'a [f64; 256],
}

/// One tag of the body: its corners in the body frame (mm), in the detector's order (the tag's
/// bottom-left, bottom-right, top-right, top-left as its upright image is drawn), and what it
/// prints.
#[derive(Debug, Clone, Copy)]
pub struct Tag<'a> {
    /// Corners of its black-border square, body frame (mm).
    pub corners: [[f64; 3]; 4],
    /// Its cells.
    pub bitmap: &'a TagBitmap,
}

/// One marker body as a frame shows it: what [`refine`] and [`bound`] compare.
#[derive(Debug, Clone, Copy)]
pub struct Body<'a> {
    /// The frame, and how to read it as linear light.
    pub image: Image<'a>,
    /// The camera that took it.
    pub camera: &'a CameraIntrinsics,
    /// The body's tags to compare (those its pose was solved from).
    pub tags: &'a [Tag<'a>],
    /// The lens's blur (σ, px) on its edges without the pixel's own spread: the start of the
    /// blur fitted (the detector's `blur_px`).
    pub blur_px: f64,
    /// How it moved over the frame's readout and exposure (`None`: still, or unknown).
    pub motion: Option<Motion>,
}

/// How the body moved while the frame was read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    /// The body's velocity at the frame's time.
    pub velocity: Velocity,
    /// How the rows were read.
    pub shutter: RollingShutter,
    /// Each row's exposure (s).
    pub exposure_s: f64,
}

/// Settings of the refinement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Linearisations at most: a fit still lowering its cost after these is refused
    /// ([`RefineError::NotConverged`]). It takes 4–6.
    pub max_iterations: usize,
    /// How far into the quiet zone pixels are taken (cells): the zone is one cell wide on
    /// JawTrack's faces, and beyond it the face's edge may come.
    pub quiet_zone_cells: f64,
    /// The most parts a row's exposure is cut into: each is modelled at its middle instant
    /// with its sweep as a blur, and sweeps the tags by at most twice the blur where this
    /// allows.
    pub max_subframes: usize,
    /// Huber's constant, in robust standard deviations of the residuals (1.4826 × their median
    /// absolute value at the start). Pixels farther off count linearly: an occluder, a glare
    /// spot, another tag's edge. Three keeps the model's own misfit at the edges (a few per cent
    /// of the contrast) quadratic, so the fit converges in 4–6 steps where 1.345 takes 6–9.
    pub huber: f64,
    /// Pixels near edges compared per tag at most (about): more are thinned, scattered by a hash
    /// of their place. The pose's variance grows as their number falls.
    pub max_pixels_per_tag: usize,
    /// A refined pose that moves any tag corner farther than this (px) from the start is
    /// refused: the corner pose is better than that, so the fit went astray.
    pub max_shift_px: f64,
    /// Above 1, each pass over the pixels is shared out in pieces of a tag's pixels over the
    /// rayon pool the call runs in (the tracker's, which refines the two bodies at once on the
    /// same pool; rayon's global pool outside any). The pieces are cut and their sums added in
    /// the same order for any number, so the result is the same for any number.
    pub threads: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            max_iterations: 20,
            quiet_zone_cells: 0.5,
            max_subframes: 8,
            huber: 3.0,
            max_pixels_per_tag: 20000,
            max_shift_px: 1.5,
            threads: 1,
        }
    }
}

/// A refined pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Refined {
    /// The body's pose at the frame's time.
    pub camera_from_body: Pose,
    /// Its covariance: a left perturbation in the camera frame (rotation vector in rad,
    /// translation in mm), as the corner solver's.
    pub covariance: Matrix6<f64>,
    /// RMS residual over the pixels, as a fraction of the tags' mean contrast.
    pub rms_contrast: f64,
    /// Pixels compared.
    pub pixels: usize,
    /// Linearisations made.
    pub iterations: usize,
    /// The farthest a tag corner moved from the start (px).
    pub shift_px: f64,
    /// The lens's blur (σ, px, without the pixel's own spread) fitted with the pose.
    pub blur_px: f64,
    /// The power the image, read through the tone curve given, bears to the scene's light
    /// (fitted with the pose): 1 when the curve is right.
    pub tone_power: f64,
    /// Whether the body's motion was modelled: given, and fitting the image better than a still
    /// body does.
    pub motion: bool,
}

/// Why a refinement was refused; the caller keeps its corner pose.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RefineError {
    /// Nothing to compare.
    #[error("no tag pixels to compare: every tag is off the frame, behind the camera or too small")]
    NoPixels,
    /// A setting out of range.
    #[error("invalid refinement setting: {0}")]
    BadOptions(String),
    /// The fit could not be solved.
    #[error("the photometric fit is singular: the tags' pixels do not fix the pose")]
    Singular,
    /// The fit was still moving when its linearisations ran out.
    #[error("the photometric fit did not settle in {iterations} steps")]
    NotConverged {
        /// Linearisations made.
        iterations: usize,
    },
    /// The fit went astray.
    #[error("the photometric fit moved a corner {shift_px:.2} px from the corner pose (at most {limit_px} px allowed)")]
    Strayed {
        /// How far it moved (px).
        shift_px: f64,
        /// The limit (px).
        limit_px: f64,
    },
}
