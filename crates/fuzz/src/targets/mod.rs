//! The targets: one per parser and door a user's input reaches. To add one, write its seeds
//! and its `run` in a module here and list it in [`all`].

mod c_door;
mod files;
mod images;
mod mesh;
mod recording;
mod wire;

use crate::mutate::Shape;
use crate::run::Target;
use std::path::PathBuf;

/// The repository's `fixtures/`, where the seeds come from.
pub fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures")
}

/// Every target, in the order `--list` prints them.
pub fn all() -> Vec<Target> {
    const KB: usize = 1024;
    let t = |name, about, shape, max_len, seeds, run| Target { name, about, shape, max_len, seeds, run, note: None };
    vec![
        t(
            "marker",
            "marker files (versions 1–3) through Marker::from_json, written back and read again",
            Shape::Json,
            256 * KB,
            files::marker_seeds,
            files::marker,
        ),
        t(
            "recording",
            "recordings (header, frame and bite lines, sessions) through the one reader, then the metrics chain",
            Shape::JsonLines,
            256 * KB,
            recording::seeds,
            recording::run,
        ),
        t(
            "datagram",
            "pose datagrams, sealed and in plaintext, through wire::decode, encoded and decoded again",
            Shape::Binary,
            2 * KB,
            wire::pose_seeds,
            wire::datagram,
        ),
        t(
            "ack",
            "acknowledgement datagrams through Session::read_ack and wire::decode",
            Shape::Binary,
            2 * KB,
            wire::ack_seeds,
            wire::ack,
        ),
        t(
            "registration",
            "registration files through Registration::from_json, written back and read again",
            Shape::Json,
            64 * KB,
            files::registration_seeds,
            files::registration,
        ),
        t(
            "points",
            "points files through AnatomicalPoints::from_json, written back and read again",
            Shape::Json,
            64 * KB,
            files::points_seeds,
            files::points,
        ),
        t(
            "camera",
            "camera files through CameraFile::from_json, written back and read again",
            Shape::Json,
            64 * KB,
            files::camera_seeds,
            files::camera,
        ),
        t(
            "stl",
            "STL meshes (binary and ASCII) through Mesh::from_bytes, written as STL and read back",
            Shape::Text,
            64 * KB,
            mesh::stl_seeds,
            mesh::stl,
        ),
        t(
            "ply",
            "PLY meshes (ASCII and binary) through Mesh::from_bytes, written as STL and read back",
            Shape::Text,
            64 * KB,
            mesh::ply_seeds,
            mesh::ply,
        ),
        t(
            "obj",
            "OBJ meshes through Mesh::from_bytes, written as STL and read back",
            Shape::Text,
            64 * KB,
            mesh::obj_seeds,
            mesh::obj,
        ),
        t(
            "image",
            "PNG and JPEG files through frames::decode_image, then four detectors",
            Shape::Binary,
            256 * KB,
            images::image_seeds,
            images::image,
        ),
        t(
            "frame",
            "raw luma planes of any width, height and stride through ImageView::new and four detectors",
            Shape::Binary,
            256 * KB,
            images::frame_seeds,
            images::frame,
        ),
        Target {
            note: Some(c_door::calls_made),
            ..t(
                "c-door",
                "the C frame door (jt_tracker_new, jt_track_luma/bgra, jt_last_error, jt_tracker_free) with hostile sizes, strides, lengths, intrinsics and handles",
                Shape::Binary,
                256 * KB,
                c_door::seeds,
                c_door::run,
            )
        },
    ]
}
