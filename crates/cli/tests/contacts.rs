//! `jawtrack contacts` on scenes with closed-form answers: a 3 mm sphere (the "lower arch")
//! poking up through a flat patch facing down (the "upper arch"). Its depth is known exactly,
//! the contact area on the sphere is a cap (2πR(h+t)) and on the patch a disc
//! (π((R+t)² − (R−h)²)). The meshes go through STL, OBJ and PLY files, the poses through a
//! one-line identity file and through a recording with frames that lost a marker.

use jawtrack_occlusion::{Mesh, scenes};
use nalgebra::Point3;
use serde_json::{Value, json};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
mod common;
use common::{identity_bite, jawtrack, ok, refused, s};

/// The height of the legend strip under each occlusal view (the binary's `LEGEND_PX`).
const LEGEND_PX: u32 = 36;
const R: f64 = 3.0;

/// Writes `mesh` as OBJ (the library writes STL and PLY only).
fn write_obj(mesh: &Mesh, path: &Path) {
    let mut text = String::new();
    for v in &mesh.vertices {
        text += &format!("v {:.9} {:.9} {:.9}\n", v.x, v.y, v.z);
    }
    for t in &mesh.triangles {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(path, text).expect("write obj");
}

/// A 10 mm patch facing down at z = 0, written as STL.
fn upper_stl(dir: &Path, cells: usize) -> PathBuf {
    let p = dir.join("upper.stl");
    scenes::patch(10.0, cells, 0.0, true).write_stl_file(&p).expect("write stl");
    p
}

/// A sphere of radius R whose top is `h` above z = 0 (scan frame), written as OBJ.
fn lower_obj(dir: &Path, h: f64, n: usize) -> PathBuf {
    let p = dir.join("lower.obj");
    write_obj(&scenes::sphere(Point3::new(0.0, 0.0, h - R), R, n), &p);
    p
}

/// A frame line whose `maxilla_from_mandible` moves the lower scan by `dz` mm along z.
fn frame(frame: u64, t: f64, dz: Option<f64>) -> String {
    let pose = dz.map(|dz| [1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., dz, 0., 0., 0., 1.]);
    json!({"frame": frame, "t": t, "maxilla_from_mandible": pose}).to_string()
}

fn lines(path: &Path) -> Vec<Value> {
    std::fs::read_to_string(path)
        .expect("contacts.jsonl")
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect()
}

fn json_file(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("readable")).expect("JSON")
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("a number: {v}"))
}

fn regions_on<'a>(line: &'a Value, arch: &str) -> Vec<&'a Value> {
    line["regions"].as_array().expect("regions").iter().filter(|r| r["arch"] == arch).collect()
}

#[test]
fn a_sphere_through_a_plane_in_occlusion_gives_the_closed_form_depth_and_areas() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (h, t) = (0.2, 0.1);
    let upper = upper_stl(dir.path(), 250);
    let lower = lower_obj(dir.path(), h, 120);
    // Scans exported in occlusion: the identity in a one-line poses file.
    let poses = dir.path().join("identity.jsonl");
    std::fs::write(&poses, "{\"frame\":0,\"t\":0,\"maxilla_from_mandible\":[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}\n")
        .expect("write poses");
    let out = dir.path().join("out");
    let stdout = ok(&jawtrack(&[
        "contacts",
        "--maxilla",
        s(&upper),
        "--mandible",
        s(&lower),
        "--poses",
        s(&poses),
        "--out",
        s(&out),
    ]));
    assert!(stdout.contains("deepest penetration 0.200 mm at frame 0"), "{stdout}");
    assert!(stdout.contains("63001 vertices, 125000 triangles"), "one line per mesh: {stdout}");

    let l = lines(&out.join("contacts.jsonl"));
    assert_eq!(l.len(), 2, "a header and one frame");
    let header = &l[0]["contacts"];
    assert_eq!((header["version"].as_u64(), header["units"].as_str()), (Some(1), Some("mm")));
    assert_eq!((header["mode"].as_str(), f(&header["threshold_mm"])), (Some("kinematic"), t));
    assert!(header["registration"].is_null());
    assert_eq!(header["maxilla"][0].as_str(), Some(s(&upper)));

    let line = &l[1];
    assert_eq!((line["frame"].as_u64(), f(&line["t"])), (Some(0), 0.0));
    assert!((f(&line["max_depth_mm"]) - h).abs() < 1e-3, "{line}");
    let (plane, ball) = (regions_on(line, "maxilla"), regions_on(line, "mandible"));
    assert_eq!((plane.len(), ball.len()), (1, 1), "{line}");
    let (plane, ball) = (plane[0], ball[0]);
    assert!(plane.get("tooth").is_none(), "one file per arch: no tooth");
    for r in [plane, ball] {
        assert!((f(&r["depth_mm"]) - h).abs() < 1e-3, "{r}");
        assert!(f(&r["centroid"][0]).abs() < 1e-3 && f(&r["centroid"][1]).abs() < 1e-3, "{r}");
        assert!(r["vertices"].as_u64().is_some_and(|n| n > 10), "{r}");
    }
    let disc = PI * ((R + t).powi(2) - (R - h).powi(2));
    let cap = 2.0 * PI * R * (h + t);
    let (a_plane, a_ball) = (f(&plane["area_mm2"]), f(&ball["area_mm2"]));
    assert!((a_plane / disc - 1.0).abs() < 0.01, "disc {a_plane} vs {disc}");
    assert!((a_ball / cap - 1.0).abs() < 0.01, "cap {a_ball} vs {cap}");
    assert_eq!(f(&line["area_mm2"]["maxilla"]), a_plane);
    assert_eq!(f(&line["area_mm2"]["mandible"]), a_ball);

    // The coloured PLYs are the arches' meshes.
    for (name, vertices) in [("maxilla", 251 * 251), ("mandible", 119 * 240 + 2)] {
        for what in ["frequency", "depth"] {
            let m = Mesh::load(&out.join(format!("{name}_{what}.ply"))).expect("a readable PLY");
            assert_eq!(m.vertices.len(), vertices, "{name}_{what}");
        }
    }
    // The patch's occlusal view, seen from the sphere's side: the contact disc in red
    // (in contact in every frame), on the grey patch.
    let png = image::open(out.join("maxilla_occlusal.png")).expect("a PNG").to_rgb8();
    assert_eq!(png.width().max(png.height() - LEGEND_PX), 800);
    let count = |pred: &dyn Fn(&image::Rgb<u8>) -> bool| {
        png.enumerate_pixels().filter(|(_, y, p)| *y < png.height() - LEGEND_PX && pred(p)).count()
    };
    let red = count(&|p| p[0] > 200 && p[1] < 60 && p[2] < 60);
    let grey = count(&|p| p[0] > 150 && p[0].abs_diff(p[1]) < 20 && p[1].abs_diff(p[2]) < 20 && p[0] < 250);
    // The disc of the patch's contact area; the 10 mm patch spans 800 px less 4 % margins.
    let px_per_mm2 = (736.0f64 / 10.0).powi(2);
    let expected = disc * px_per_mm2;
    assert!((red as f64 / expected - 1.0).abs() < 0.05, "{red} red px, expected about {expected:.0}");
    assert!(grey as f64 > 50.0 * px_per_mm2, "{grey} grey px");
    // The ball, having no flattest direction, is seen from the patch: its cap in red.
    let png = image::open(out.join("mandible_occlusal.png")).expect("a PNG").to_rgb8();
    let red = png
        .enumerate_pixels()
        .filter(|(_, y, p)| *y < png.height() - LEGEND_PX && p[0] > 200 && p[1] < 60 && p[2] < 60)
        .count();
    let cap_seen = PI * (R * R - (R - h - t).powi(2)) * (736.0f64 / (2.0 * R)).powi(2);
    assert!((red as f64 / cap_seen - 1.0).abs() < 0.05, "{red} red px, expected about {cap_seen:.0}");

    let summary = json_file(&out.join("summary.json"));
    let frames = &summary["frames"];
    assert_eq!(
        [&frames["read"], &frames["checked"], &frames["skipped_no_pose"], &frames["with_contact"]].map(Value::as_u64),
        [Some(1), Some(1), Some(0), Some(1)]
    );
    assert_eq!(summary["meshes"]["maxilla"][0]["report"]["boundary_loops"].as_u64(), Some(1));
    assert_eq!(summary["meshes"]["mandible"][0]["report"]["components"].as_u64(), Some(1));
    assert!((f(&summary["deepest"]["depth_mm"]) - h).abs() < 1e-3);
    assert!(f(&summary["timing"]["ms_per_frame_median"]) > 0.0);
    eprintln!(
        "one frame, {} + {} triangles: {:.1} ms",
        125000,
        120 * 240,
        f(&summary["timing"]["ms_per_frame_median"])
    );
}

#[test]
fn moving_the_sphere_away_gives_decreasing_contact_then_none_and_frames_without_a_pose_are_counted() {
    let dir = tempfile::tempdir().expect("temp dir");
    let upper = upper_stl(dir.path(), 100);
    let lower = lower_obj(dir.path(), 0.2, 60);
    let poses = dir.path().join("session.jsonl");
    let steps = [(0.0, Some(0.0)), (0.1, None), (0.2, Some(-0.1)), (0.3, Some(-0.2)), (0.4, None), (0.5, Some(-0.25))];
    // Scan poses written by hand: no recording header (a tracked recording's are the markers').
    let mut text = vec![];
    text.extend(steps.iter().enumerate().map(|(k, (t, dz))| frame(k as u64, *t, *dz)));
    text.push(frame(6, 0.6, Some(-0.5)));
    std::fs::write(&poses, text.join("\n") + "\n").expect("write poses");
    let out = dir.path().join("out");
    let stdout = ok(&jawtrack(&[
        "contacts",
        "--maxilla",
        s(&upper),
        "--mandible",
        s(&lower),
        "--poses",
        s(&poses),
        "--out",
        s(&out),
        "--quiet",
    ]));
    assert!(stdout.contains("5 frames checked of 7, 2 without a pose skipped"), "{stdout}");
    let l = lines(&out.join("contacts.jsonl"));
    let frames: Vec<u64> = l[1..].iter().map(|x| x["frame"].as_u64().expect("frame")).collect();
    assert_eq!(frames, [0, 2, 3, 5, 6]);
    // The sphere's top: 0.2 and 0.1 mm through the plane, touching it, 0.05 mm below it, gone.
    let depth: Vec<Option<f64>> = l[1..].iter().map(|x| x["max_depth_mm"].as_f64()).collect();
    for (got, want) in depth.iter().zip([Some(0.2), Some(0.1), Some(0.0), Some(-0.05), None]) {
        match (got, want) {
            (Some(g), Some(w)) => assert!((g - w).abs() < 1e-3, "{depth:?}"),
            (g, w) => assert_eq!(*g, w, "{depth:?}"),
        }
    }
    let area: Vec<f64> = l[1..].iter().map(|x| f(&x["area_mm2"]["mandible"])).collect();
    assert!(area.windows(2).all(|w| w[1] < w[0]) && area[4] == 0.0, "{area:?}");
    assert!(l[5]["regions"].as_array().is_some_and(Vec::is_empty));

    let summary = json_file(&out.join("summary.json"));
    let frames = &summary["frames"];
    assert_eq!(
        [&frames["read"], &frames["checked"], &frames["skipped_no_pose"], &frames["with_contact"]].map(Value::as_u64),
        [Some(7), Some(5), Some(2), Some(4)]
    );
    assert_eq!(summary["contact_area"]["mandible"]["max_frame"].as_u64(), Some(0));
    assert_eq!(summary["deepest"]["frame"].as_u64(), Some(0));

    // Every other frame with a pose.
    let out2 = dir.path().join("out2");
    ok(&jawtrack(&[
        "contacts",
        "--maxilla",
        s(&upper),
        "--mandible",
        s(&lower),
        "--poses",
        s(&poses),
        "--out",
        s(&out2),
        "--every",
        "2",
    ]));
    let frames: Vec<u64> =
        lines(&out2.join("contacts.jsonl"))[1..].iter().map(|x| x["frame"].as_u64().expect("frame")).collect();
    assert_eq!(frames, [0, 3, 6]);
}

#[test]
fn per_tooth_meshes_tag_their_regions() {
    let dir = tempfile::tempdir().expect("temp dir");
    // The upper arch as PLY this time.
    let upper = dir.path().join("upper.ply");
    let patch = scenes::patch(10.0, 100, 0.0, true);
    patch.write_coloured_ply(&upper, &[]).expect("write ply");
    let tooth = |name: &str, x: f64| {
        let p = dir.path().join(name);
        write_obj(&scenes::sphere(Point3::new(x, 0.0, 0.2 - 2.0), 2.0, 40), &p);
        p
    };
    // The lower left and the lower right first molar (side by side, as far as contacts care).
    let (t36, t37) = (tooth("lower_FDI=36.obj", -2.5), tooth("lower_FDI=46.obj", 2.5));
    let out = dir.path().join("out");
    ok(&jawtrack(&[
        "contacts",
        "--maxilla",
        s(&upper),
        "--mandible",
        s(&t36),
        s(&t37),
        "--poses",
        s(&identity_bite(dir.path())),
        "--out",
        s(&out),
    ]));
    let l = lines(&out.join("contacts.jsonl"));
    assert_eq!(l[0]["contacts"]["mandible"].as_array().map(Vec::len), Some(2));
    let ball = regions_on(&l[1], "mandible");
    assert_eq!(ball.len(), 2, "{}", l[1]);
    for r in ball {
        let want = if f(&r["centroid"][0]) < 0.0 { "36" } else { "46" };
        assert_eq!(r["tooth"].as_str(), Some(want), "{r}");
        assert!((f(&r["depth_mm"]) - 0.2).abs() < 1e-3, "{r}");
    }
    let plane = regions_on(&l[1], "maxilla");
    assert_eq!(plane.len(), 2);
    assert!(plane.iter().all(|r| r.get("tooth").is_none()));
    let summary = json_file(&out.join("summary.json"));
    assert_eq!(summary["meshes"]["mandible"][0]["tooth"].as_str(), Some("36"));
    assert_eq!(summary["meshes"]["mandible"][1]["tooth"].as_str(), Some("46"));
    // Per-tooth totals, with both numbers.
    let teeth = summary["teeth"].as_array().expect("teeth");
    assert_eq!(teeth.len(), 2, "{summary}");
    for (t, fdi, universal) in [(&teeth[0], 36, 19), (&teeth[1], 46, 30)] {
        assert_eq!((t["fdi"].as_u64(), t["universal"].as_u64()), (Some(fdi), Some(universal)), "{t}");
        assert_eq!(t["frames_in_contact"].as_u64(), Some(1));
        assert!((f(&t["max_depth_mm"]) - 0.2).abs() < 1e-3 && f(&t["max_area_mm2"]) > 0.0, "{t}");
    }
    // The lower depth map names both teeth and puts "patient's left" on 36's side of the image.
    let map = std::fs::read_to_string(out.join("mandible_depth_map.svg")).expect("the map");
    let x_of = |needle: &str| {
        let at = map.find(needle).unwrap_or_else(|| panic!("{needle} on the map"));
        let tag = &map[map[..at].rfind("<text").expect("a text element")..at];
        let x = tag.split("x=\"").nth(1).and_then(|v| v.split('"').next()).expect("an x");
        x.parse::<f64>().expect("a number")
    };
    let (x36, x46, x_left) = (x_of(">36 (Univ. 19)<"), x_of(">46 (Univ. 30)<"), x_of(">patient's left<"));
    assert!((x_left - x36).abs() < (x_left - x46).abs(), "left at {x_left}, 36 at {x36}, 46 at {x46}");
    assert!(map.contains("mm deep") && map.contains("10 mm"), "the scales");
    // The upper arch is one mesh: its side is unknown, and the map says so.
    let upper_map = std::fs::read_to_string(out.join("maxilla_depth_map.svg")).expect("the map");
    assert!(upper_map.contains("side is unknown"));
}

#[test]
fn bad_input_is_refused_with_a_message_saying_what_is_wrong() {
    let dir = tempfile::tempdir().expect("temp dir");
    let upper = upper_stl(dir.path(), 20);
    let lower = lower_obj(dir.path(), 0.2, 16);
    let poses = identity_bite(dir.path());
    let out = dir.path().join("out");
    let run = |upper: &Path, lower: &Path, poses: &Path, extra: &[&str]| {
        let mut args = vec!["contacts", "--maxilla", s(upper), "--mandible", s(lower), "--poses", s(poses)];
        args.extend_from_slice(&["--out", s(&out)]);
        args.extend_from_slice(extra);
        jawtrack(&args)
    };
    refused(
        &run(&upper, &lower, &poses, &["--threshold", "0.6"]),
        "--threshold: the contact threshold must be 0.01-0.5 mm, got 0.6",
    );
    refused(&run(&upper, &lower, &poses, &["--threshold", "-1"]), "the contact threshold must be");
    refused(&run(&upper, &lower, &poses, &["--max-depth", "0"]), "--max-depth: the measured penetration depth");
    refused(&run(&upper, &lower, &poses, &["--mode", "dynamic", "--dt", "0.5"]), "step");
    refused(&run(&upper, &lower, &poses, &["--every", "0"]), "--every");
    assert!(!out.exists(), "nothing written for refused input");

    // A scan in metres.
    let metres = dir.path().join("lower_m.obj");
    write_obj(&scenes::sphere(Point3::new(0.0, 0.0, 0.2 - R), R, 16).transformed(|p| p * 0.001), &metres);
    let o = run(&upper, &metres, &poses, &[]);
    refused(&o, "looks like metres");
    refused(&o, "lower_m.obj");
    // Empty and corrupt files.
    let empty = dir.path().join("empty.stl");
    std::fs::write(&empty, "").expect("write");
    refused(&run(&empty, &lower, &poses, &[]), "empty.stl");
    let corrupt = dir.path().join("corrupt.ply");
    std::fs::write(&corrupt, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1 2\n")
        .expect("write");
    refused(&run(&upper, &corrupt, &poses, &[]), "corrupt.ply");
    refused(&run(&upper, &dir.path().join("missing.stl"), &poses, &[]), "missing.stl");
    // Poses: none at all, none with a jaw pose, a malformed registration.
    let no_pose = dir.path().join("lost.jsonl");
    std::fs::write(&no_pose, frame(0, 0.0, None) + "\n" + &frame(1, 0.1, None) + "\n").expect("write");
    refused(&run(&upper, &lower, &no_pose, &[]), "none of its 2 frames has a pose");
    let garbage = dir.path().join("garbage.jsonl");
    std::fs::write(&garbage, "{\"t\":0}\nnot json\n").expect("write");
    refused(&run(&upper, &lower, &garbage, &[]), "no frames");
    let reg = dir.path().join("reg.json");
    std::fs::write(&reg, "{\"version\":1}").expect("write");
    refused(&run(&upper, &lower, &poses, &["--registration", s(&reg)]), "reg.json");
}

#[test]
fn a_tracked_recording_without_a_registration_is_refused_and_arches_that_never_meet_are_warned_of() {
    let dir = tempfile::tempdir().expect("temp dir");
    let upper = upper_stl(dir.path(), 20);
    let lower = lower_obj(dir.path(), 0.2, 16);
    // A tracked recording: its poses are the markers', 44 mm apart as on a patient.
    let poses = dir.path().join("tracked.jsonl");
    let header = jawtrack_recording::RecordingHeader::new("jawtrack track").to_line();
    std::fs::write(&poses, header + "\n" + &frame(0, 0.0, Some(-44.0)) + "\n").expect("write");
    let run = |poses: &Path, out: &str| {
        jawtrack(&[
            "contacts",
            "--maxilla",
            s(&upper),
            "--mandible",
            s(&lower),
            "--poses",
            s(poses),
            "--out",
            s(&dir.path().join(out)),
        ])
    };
    let o = run(&poses, "refused");
    refused(&o, "tracked.jsonl: its poses place the mandible's marker");
    refused(&o, "--registration");
    assert!(!dir.path().join("refused").exists(), "nothing written");
    // Hand-written scan poses that keep the arches apart give no contact, and a warning.
    let apart = dir.path().join("apart.jsonl");
    std::fs::write(&apart, frame(0, 0.0, Some(-44.0)) + "\n").expect("write");
    let o = run(&apart, "apart");
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert!(common::stderr(&o).contains("never came within 0.1 mm"), "{}", common::stderr(&o));
}

#[test]
fn a_registration_maps_marker_poses_to_scan_poses() {
    let dir = tempfile::tempdir().expect("temp dir");
    let upper = upper_stl(dir.path(), 100);
    let lower = lower_obj(dir.path(), 0.2, 60);
    // The mandible marker sits 5 mm below the lower scan's origin (and the maxilla marker at
    // the upper scan's); tracked 5 mm below the maxilla marker, the scans are in occlusion.
    let mut reg = jawtrack_registration::Registration::identity();
    reg.mandible_scan_from_mandible_marker =
        jawtrack_pose::Pose::from_axis_angle(nalgebra::Vector3::zeros(), nalgebra::Vector3::new(0.0, 0.0, -5.0));
    let reg_path = dir.path().join("reg.json");
    std::fs::write(&reg_path, reg.to_json()).expect("write");
    let poses = dir.path().join("poses.jsonl");
    std::fs::write(&poses, frame(0, 0.0, Some(-5.0)) + "\n").expect("write");
    let out = dir.path().join("out");
    ok(&jawtrack(&[
        "contacts",
        "--maxilla",
        s(&upper),
        "--mandible",
        s(&lower),
        "--poses",
        s(&poses),
        "--registration",
        s(&reg_path),
        "--out",
        s(&out),
    ]));
    let l = lines(&out.join("contacts.jsonl"));
    assert!((f(&l[1]["max_depth_mm"]) - 0.2).abs() < 1e-3, "{}", l[1]);
    assert_eq!(l[0]["contacts"]["registration"].as_str(), Some(s(&reg_path)));
    // A second run into the same folder keeps the first's results unless told otherwise.
    let again = |extra: &[&str]| {
        let mut args = vec!["contacts", "--maxilla", s(&upper), "--mandible", s(&lower), "--poses", s(&poses)];
        args.extend(["--registration", s(&reg_path), "--out", s(&out)]);
        args.extend_from_slice(extra);
        jawtrack(&args)
    };
    refused(&again(&[]), "already holds contacts.jsonl");
    ok(&again(&["--force"]));
}

#[test]
fn dynamic_mode_slides_the_sphere_out_of_the_plane_and_reports_the_force() {
    let dir = tempfile::tempdir().expect("temp dir");
    let upper = upper_stl(dir.path(), 60);
    // The sphere's top 0.2 mm through the plane for the whole (0.2 s) path: the resolved
    // sphere rests on the plane, held there by a contact force equal to the spring's pull.
    let lower = lower_obj(dir.path(), 0.2, 24);
    let poses = dir.path().join("poses.jsonl");
    let text: String = (0..7).map(|k| frame(k, k as f64 / 30.0, Some(0.0)) + "\n").collect();
    std::fs::write(&poses, text).expect("write poses");
    let out = dir.path().join("dyn");
    ok(&jawtrack(&[
        "contacts",
        "--maxilla",
        s(&upper),
        "--mandible",
        s(&lower),
        "--poses",
        s(&poses),
        "--mode",
        "dynamic",
        "--out",
        s(&out),
        "--quiet",
    ]));
    let frames = lines(&out.join("contacts.jsonl"));
    assert_eq!(frames[0]["contacts"]["mode"], "dynamic");
    assert_eq!(frames.len(), 8);
    // Spring force at the held 0.2 mm offset: m (2π f)² · 0.2 mm, in N.
    let (m, hz) = (0.1, 15.0);
    let spring = m * (std::f64::consts::TAU * hz).powi(2) * 0.2e-3;
    for line in &frames[1..] {
        let d = &line["dynamics"];
        assert!(f(&d["max_penetration_mm"]) <= 0.01, "{line}");
        // Resting on the plane: at most touching, never deeper than the 0.01 mm target.
        if let Some(depth) = line["max_depth_mm"].as_f64() {
            assert!(depth <= 0.01, "{line}");
        }
    }
    let last = &frames[7]["dynamics"];
    assert!((f(&last["force_n"]) / spring - 1.0).abs() < 0.05, "{last} vs spring {spring} N");
    assert!((f(&last["target_offset_mm"]) - 0.2).abs() < 0.01, "{last}");
    let summary = json_file(&out.join("summary.json"));
    let correction = &summary["dynamics"]["intercuspation_correction"];
    let shift: f64 =
        correction["shift_mm"].as_array().expect("3-vector").iter().map(|x| f(x).powi(2)).sum::<f64>().sqrt();
    assert!((shift - 0.2).abs() < 0.01, "{correction}");
}

#[test]
fn options_are_refused_before_any_input_is_read() {
    // The inputs do not exist: a refusal naming the option shows it came before reading them
    // (and before the seconds of indexing that follow).
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("results.txt");
    std::fs::write(&file, "not a folder").expect("write");
    let base = ["contacts", "--maxilla", "/nonexistent/upper.stl", "--mandible", "/nonexistent/lower.stl"];
    let with = |extra: &[&str]| jawtrack(&[&base[..], &["--poses", "/nonexistent/poses.jsonl"], extra].concat());
    refused(&with(&["--out", file.to_str().expect("utf-8")]), "--out");
    let out = dir.path().join("out");
    let out = out.to_str().expect("utf-8");
    refused(&with(&["--out", out, "--mode", "dynamic", "--mass", "0"]), "--mass: ");
    refused(&with(&["--out", out, "--mode", "dynamic", "--dt", "10"]), "--dt: ");
    refused(&with(&["--out", out, "--mode", "dynamic", "--spring-hz", "-1"]), "--spring-hz: ");
    assert!(!Path::new(out).exists(), "nothing written");
}
