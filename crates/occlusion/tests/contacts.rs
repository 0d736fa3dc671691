//! Kinematic contacts against scenes with closed-form answers, against the brute-force
//! reference (every vertex against every triangle), and against parry's point projection.

use jawtrack_occlusion::contacts::{Arch, ContactMap, ContactSettings, Side, contacts, contacts_brute_force};
use jawtrack_occlusion::{Mesh, scenes};
use jawtrack_pose::Pose;
use nalgebra::{Point3, Vector3};
use std::f64::consts::PI;

fn arch(mesh: Mesh, settings: &ContactSettings) -> Arch {
    Arch::new(vec![("arch".to_owned(), mesh)], settings)
}

/// A 3 mm sphere pressed `h` mm up through a downward-facing patch at z = 0.
fn sphere_through_patch(h: f64, settings: &ContactSettings) -> (Arch, Arch) {
    let r = 3.0;
    let upper = arch(scenes::patch(10.0, 250, 0.0, true), settings);
    let lower = arch(scenes::sphere(Point3::new(0.0, 0.0, h - r), r, 120), settings);
    (upper, lower)
}

#[test]
fn a_sphere_through_a_plane_gives_the_closed_form_depth_and_areas() {
    let (r, h) = (3.0, 0.2);
    for threshold in [0.01, 0.1, 0.5] {
        let settings = ContactSettings { threshold_mm: threshold, ..Default::default() };
        let (upper, lower) = sphere_through_patch(h, &settings);
        let c = contacts(&upper, &lower, &Pose::identity(), &settings);
        let on = |side: Side| {
            let found: Vec<_> = c.regions.iter().filter(|g| g.arch == side).collect();
            assert_eq!(found.len(), 1, "{threshold}: {side:?}: {found:?}");
            found[0].clone()
        };
        let (plane, ball) = (on(Side::Maxilla), on(Side::Mandible));
        // The patch's vertex under the pole is h inside the (slightly faceted) sphere.
        assert!((plane.depth_mm - h).abs() < 1e-3, "{plane:?}");
        // The sphere's pole is h above the plane (distances are kept as f32).
        assert!((ball.depth_mm - h).abs() < 1e-6, "{ball:?}");
        let disc = PI * ((r + threshold).powi(2) - (r - h).powi(2));
        let cap = 2.0 * PI * r * (h + threshold);
        assert!((plane.area_mm2 / disc - 1.0).abs() < 0.01, "{threshold}: disc {} vs {disc}", plane.area_mm2);
        assert!((ball.area_mm2 / cap - 1.0).abs() < 0.01, "{threshold}: cap {} vs {cap}", ball.area_mm2);
        for g in [&plane, &ball] {
            assert!(g.centroid[0].abs() < 1e-3 && g.centroid[1].abs() < 1e-3, "{g:?}");
        }
    }
}

#[test]
fn a_gap_is_a_negative_depth_and_disappears_past_the_threshold() {
    let settings = ContactSettings { threshold_mm: 0.1, ..Default::default() };
    // The sphere's top 0.05 mm below the plane: within the threshold, not touching.
    let (upper, lower) = sphere_through_patch(-0.05, &settings);
    let c = contacts(&upper, &lower, &Pose::identity(), &settings);
    let ball = c.regions.iter().find(|g| g.arch == Side::Mandible).expect("near region");
    assert!((ball.depth_mm + 0.05).abs() < 1e-6, "{ball:?}");
    // Moving the sphere 0.1 mm further down (a pose on the lower scan) leaves nothing.
    let away = Pose::from_parts(Default::default(), Vector3::new(0.0, 0.0, -0.1));
    assert!(contacts(&upper, &lower, &away, &settings).regions.is_empty());
}

#[test]
fn two_flat_patches_overlapping_give_the_overlap_area() {
    let settings = ContactSettings::default();
    // Upper 10 × 10 facing down at z = 0; lower 6 × 6 facing up, 0.05 mm inside it, moved
    // 1.5 mm sideways: all of it lies under the upper one.
    let upper = arch(scenes::patch(10.0, 50, 0.0, true), &settings);
    let lower = arch(scenes::patch(6.0, 30, 0.05, false), &settings);
    let pose = Pose::from_parts(Default::default(), Vector3::new(1.5, -1.0, 0.0));
    let c = contacts(&upper, &lower, &pose, &settings);
    let lower_region = c.regions.iter().find(|g| g.arch == Side::Mandible).expect("overlap");
    assert!((lower_region.depth_mm - 0.05).abs() < 1e-6, "{lower_region:?}");
    assert!((lower_region.area_mm2 - 36.0).abs() < 1e-6, "{lower_region:?}");
    assert!((lower_region.centroid[0] - 1.5).abs() < 1e-6 && (lower_region.centroid[1] + 1.0).abs() < 1e-6);
    // The upper patch is in contact over the same 6 × 6 square, plus the rim strip where the
    // lower patch's edge is within the threshold (0.087 mm wide, less than the upper's 0.2 mm
    // cells over which the distance is interpolated).
    let upper_region = c.regions.iter().find(|g| g.arch == Side::Maxilla).expect("overlap");
    assert!(upper_region.area_mm2 >= 36.0 - 1e-6 && upper_region.area_mm2 < 36.0 + 24.0 * 0.2, "{upper_region:?}");
}

#[test]
fn the_indexed_query_equals_brute_force_on_test_scenes() {
    let settings = ContactSettings { threshold_mm: 0.2, ..Default::default() };
    let (u, l) = scenes::arch_pair(4000);
    // On crowns, whole clusters of wall vertices are skipped as far from the other arch.
    let (cu, cl) = scenes::arch_pair_with_walls(4000, 8.0);
    let slid = Pose::from_axis_angle(Vector3::new(0.0, 0.01, 0.0), Vector3::new(0.1, 0.0, -0.05));
    let scenes = [
        (arch(u, &settings), arch(l, &settings), Pose::identity()),
        (arch(cu, &settings), arch(cl, &settings), slid),
        {
            let upper = arch(scenes::patch(10.0, 60, 0.0, true), &settings);
            let lower = arch(scenes::sphere(Point3::new(0.0, 0.0, 0.3 - 3.0), 3.0, 40), &settings);
            let tilted = Pose::from_axis_angle(Vector3::new(0.05, -0.03, 0.4), Vector3::new(0.3, -0.2, 0.05));
            (upper, lower, tilted)
        },
    ];
    for (upper, lower, pose) in &scenes {
        let fast = contacts(upper, lower, pose, &settings);
        let slow = contacts_brute_force(upper, lower, pose, &settings);
        let mut compared = 0;
        for arch in 0..2 {
            // Each vertex is listed once, and only with a distance.
            let listed: std::collections::HashSet<u32> = fast.distances[arch].0.iter().map(|x| x.0).collect();
            assert_eq!(listed.len(), fast.distances[arch].0.len());
            assert!(fast.distances[arch].0.iter().all(|x| x.1.is_finite()));
            let n = [&upper, &lower][arch].mesh.vertices.len();
            for (a, b) in fast.distances[arch].dense(n).iter().zip(&slow.distances[arch].dense(n)) {
                // Every vertex the reference puts within the threshold has the same depth.
                if *b as f64 <= settings.threshold_mm {
                    assert!((a - b).abs() <= 1e-6, "{a} vs {b}");
                    compared += 1;
                }
            }
        }
        assert!(compared > 100, "{compared}");
        assert!(!fast.regions.is_empty());
        assert_eq!(fast.regions.len(), slow.regions.len());
        // Regions are listed by area, which the two compute slightly differently: pair them
        // by their deepest point instead.
        let sorted = |c: &jawtrack_occlusion::contacts::Contacts| {
            let mut r = c.regions.clone();
            r.sort_by(|a, b| {
                (a.arch as u8, a.vertices).cmp(&(b.arch as u8, b.vertices)).then(a.depth_mm.total_cmp(&b.depth_mm))
            });
            r
        };
        for (a, b) in sorted(&fast).iter().zip(&sorted(&slow)) {
            assert_eq!((a.arch, a.vertices), (b.arch, b.vertices));
            assert!((a.depth_mm - b.depth_mm).abs() <= 1e-6, "{a:?} vs {b:?}");
            assert!((a.area_mm2 - b.area_mm2).abs() < 1e-9, "{a:?} vs {b:?}");
        }
    }
}

#[test]
fn distances_agree_with_parry_point_projection() {
    use parry3d_f64::math::Vector as V;
    use parry3d_f64::query::PointQuery;
    let settings = ContactSettings { threshold_mm: 0.2, ..Default::default() };
    let (u, l) = scenes::arch_pair(6000);
    let upper = arch(u.clone(), &settings);
    let lower = arch(l.clone(), &settings);
    let c = contacts(&upper, &lower, &Pose::identity(), &settings);
    let trimesh = parry3d_f64::shape::TriMesh::new(
        u.vertices.iter().map(|p| V::new(p.x, p.y, p.z)).collect(),
        u.triangles.clone(),
    )
    .expect("valid mesh");
    let mut compared = 0;
    for (v, d) in l.vertices.iter().zip(&c.distances[1].dense(l.vertices.len())) {
        if d.is_nan() || *d as f64 > settings.threshold_mm {
            continue;
        }
        let projection = trimesh.project_local_point(V::new(v.x, v.y, v.z), false);
        let parry = (projection.point - V::new(v.x, v.y, v.z)).length();
        assert!((parry - d.abs() as f64).abs() < 1e-6, "{v}: parry {parry} vs ours {d}");
        compared += 1;
    }
    assert!(compared > 100, "{compared}");
}

#[test]
fn the_contact_map_counts_frames_in_contact() {
    let settings = ContactSettings::default();
    let (upper, lower) = sphere_through_patch(0.2, &settings);
    let mut map = ContactMap::new(&upper, &lower);
    for z in [0.0, -0.1, -0.5] {
        let c = contacts(&upper, &lower, &Pose::from_parts(Default::default(), Vector3::new(0.0, 0.0, z)), &settings);
        map.add(&c, &settings);
    }
    // The sphere's pole (vertex 0) is in contact in the first two frames only.
    assert_eq!(map.frames, 3);
    assert_eq!(map.hits[1][0], 2);
    assert!((map.max_depth[1][0] - 0.2).abs() < 1e-6);
    let colours = map.frequency_colours(1);
    assert_ne!(colours[0], jawtrack_occlusion::contacts::GREY);
    assert_eq!(colours[lower.mesh.vertices.len() - 1], jawtrack_occlusion::contacts::GREY);
}
