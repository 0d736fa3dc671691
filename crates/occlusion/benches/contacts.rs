//! The kinematic contact query on pairs of synthetic arches of about 150k triangles each,
//! side by side with parry's capped point projection (`project_local_point_with_max_dist`
//! for every vertex of both arches), in the same run, on one core: whole passes over a
//! motion of small movements, alternating between the two, medians of the per-frame times.
//! Two scenes:
//!
//! - `crowns`: occlusal surfaces on crowns with 8 mm buccal and lingual walls, the triangles
//!   spread over the whole surface as on an intra-oral scan;
//! - `occlusal only`: the same occlusal surfaces alone, a worst case where most of both
//!   surfaces is within reach of the other.
//!
//! `cargo bench -p jawtrack-occlusion --bench contacts [-- --triangles N --frames N]`

use jawtrack_occlusion::Mesh;
use jawtrack_occlusion::contacts::{Arch, ContactSettings, contacts};
use jawtrack_occlusion::scenes;
use jawtrack_pose::{Pose, median};
use nalgebra::Vector3;
use parry3d_f64::math::Vector as V;
use parry3d_f64::query::PointQuery;
use std::time::Instant;

/// Passes over the motion for each of the two.
const PASSES: usize = 3;

fn arg(name: &str, default: usize) -> usize {
    let args: Vec<String> = std::env::args().collect();
    args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).and_then(|v| v.parse().ok()).unwrap_or(default)
}

fn to_parry(m: &Mesh) -> parry3d_f64::shape::TriMesh {
    parry3d_f64::shape::TriMesh::new(m.vertices.iter().map(|p| V::new(p.x, p.y, p.z)).collect(), m.triangles.clone())
        .expect("valid mesh")
}

fn run(name: &str, (u, l): (Mesh, Mesh), frames: usize) {
    let settings = ContactSettings::default();
    let start = Instant::now();
    let upper = Arch::new(vec![("upper".into(), u.clone())], &settings);
    let lower = Arch::new(vec![("lower".into(), l.clone())], &settings);
    let build_s = start.elapsed().as_secs_f64();
    // Small jaw movements about intercuspation, where the arches are closest.
    let poses: Vec<Pose> = (0..frames)
        .map(|k| {
            let s = k as f64 / frames as f64;
            Pose::from_axis_angle(Vector3::new(0.0, 0.002 * s, 0.0), Vector3::new(0.05 * s, 0.0, -0.1 * s))
        })
        .collect();
    let (pu, pl) = (to_parry(&u), to_parry(&l));
    let reach = settings.max_depth_mm;
    let (mut ours, mut parry, mut found) = (Vec::new(), Vec::new(), 0usize);
    // Whole passes over the motion, as a recording is processed, alternating between the two
    // so that both see the machine's load alike; each frame is timed on its own.
    for _ in 0..PASSES {
        for pose in &poses {
            let t = Instant::now();
            let c = contacts(&upper, &lower, pose, &settings);
            ours.push(t.elapsed().as_secs_f64() * 1e3);
            std::hint::black_box(c);
        }
        for pose in &poses {
            let inverse = pose.inverse();
            let t = Instant::now();
            found = 0;
            for v in &l.vertices {
                let p = pose.transform_point(v);
                found +=
                    usize::from(pu.project_local_point_with_max_dist(V::new(p.x, p.y, p.z), false, reach).is_some());
            }
            for v in &u.vertices {
                let p = inverse.transform_point(v);
                found +=
                    usize::from(pl.project_local_point_with_max_dist(V::new(p.x, p.y, p.z), false, reach).is_some());
            }
            parry.push(t.elapsed().as_secs_f64() * 1e3);
        }
    }
    let (ours, parry) = (median(ours).unwrap_or(f64::NAN), median(parry).unwrap_or(f64::NAN));
    let c = contacts(&upper, &lower, &poses[0], &settings);
    println!(
        "{name}: {} + {} triangles ({} + {} vertices), {frames} frames, {PASSES} passes each, one core",
        u.triangles.len(),
        l.triangles.len(),
        u.vertices.len(),
        l.vertices.len()
    );
    for ((arch, d), n) in ["upper", "lower"].iter().zip(&c.distances).zip([u.vertices.len(), l.vertices.len()]) {
        let count = |lo: f64, hi: f64| d.0.iter().filter(|&&(_, x)| (x as f64) > lo && (x as f64) <= hi).count();
        println!(
            "  {arch} vertices: penetrating {}, gap 0-{} mm {}, found beyond it {}, not listed {}",
            count(-9.0, 0.0),
            settings.threshold_mm,
            count(0.0, settings.threshold_mm),
            count(settings.threshold_mm, 9.0),
            n - d.0.len()
        );
    }
    println!("  index build (both arches): {:.0} ms", build_s * 1e3);
    println!("  jawtrack contacts (distances, regions, areas): median {ours:.2} ms/frame");
    println!(
        "  parry project_point_with_max_dist ({found} vertices within {reach} mm), distances only: median {parry:.2} ms/frame"
    );
    println!("  ratio: {:.2}x", parry / ours);
}

fn main() {
    let triangles = arg("--triangles", 150_000);
    let frames = arg("--frames", 40);
    run("crowns", scenes::arch_pair_with_walls(triangles, 8.0), frames);
    run("occlusal only (worst case)", scenes::arch_pair(triangles), frames);
}
