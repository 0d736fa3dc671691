//! AprilTag support for JawTrack. For now this crate holds the tag36h11 family — its codebook
//! and bit layout, and the printed pattern of each tag — which the renderer, the harness
//! printouts and the detector all read from here, so the family is defined exactly once.

mod codes;

pub mod family;

pub use family::{Tag36h11, TagBitmap};
