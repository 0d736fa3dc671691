//! The index against brute force, screening one point and many, focused and not, against each
//! other, the descent's certificate against the neighbours it stands for, and the sign; on
//! bumpy sheets and on a sphere seen from both sides.

use super::*;
use crate::Mesh;

fn bumpy(n: usize) -> Mesh {
    // A height field z = sin·cos over 10 × 10 mm, normals up (+z).
    let mut vertices = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (10.0 * i as f64 / n as f64, 10.0 * j as f64 / n as f64);
            vertices.push(Point3::new(x, y, 0.8 * (x * 0.9).sin() * (y * 0.7).cos()));
        }
    }
    let mut triangles = Vec::new();
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    Mesh { vertices, triangles }
}

/// A seeded generator of uniform numbers in 0..1 (a linear congruential one: enough to
/// scatter test points).
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn a_triangle_certified_nearest_has_no_nearer_neighbour() {
    // A coarse and a fine bumpy sheet, and a sphere seen from outside and from inside:
    // convex, concave and saddle-shaped surroundings, on both sides.
    let meshes = [bumpy(12), bumpy(40), crate::scenes::sphere(Point3::new(1.0, 2.0, 3.0), 2.0, 24)];
    let mut rnd = uniform(777);
    let (mut certified, mut tried) = (0, 0);
    for mesh in &meshes {
        let surface = Surface::new(mesh);
        for _ in 0..20000 {
            let t = (rnd() * surface.len() as f64) as usize % surface.len();
            // A point a little in front of or behind a point of the triangle.
            let [a, b, c] = surface.geometry[t].corners;
            let (u, v) = (rnd(), rnd());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let on = a + (b - a) * u + (c - a) * v;
            let [x, y, z, _] = surface.geometry[t].plane;
            let p = on + Vector3::new(x, y, z) * ((rnd() - 0.5) * 0.6);
            let (d2, q, f) = surface.closest(t, &p);
            tried += 1;
            if !surface.certainly_nearest(t, &p, d2, &q, f) {
                continue;
            }
            certified += 1;
            for &n in surface.neighbours(t) {
                let (e2, ..) = surface.closest(n as usize, &p);
                assert!(e2.sqrt() >= d2.sqrt() - 1e-12, "triangle {n} is nearer to {p} than {t}");
            }
        }
    }
    // The certificate must also be worth having: most of these points are certified.
    assert!(certified * 2 > tried, "{certified} of {tried}");
}

#[test]
fn the_index_returns_exactly_what_brute_force_returns_within_its_reach() {
    let mesh = bumpy(30);
    let index = SurfaceIndex::new(&mesh, 0.6);
    let mut rnd = uniform(12345);
    let (mut within, mut beyond) = (0, 0);
    for _ in 0..20000 {
        let p = Point3::new(rnd() * 12.0 - 1.0, rnd() * 12.0 - 1.0, rnd() * 4.0 - 2.0);
        let reference = nearest_brute_force(index.surface(), &p).expect("non-empty");
        match index.nearest(&p) {
            Some(n) => {
                within += 1;
                assert!((n.distance - reference.distance).abs() < 1e-12, "{p}: {n:?} vs {reference:?}");
                assert!(n.distance.abs() <= 0.6);
            }
            None => {
                beyond += 1;
                assert!(reference.distance.abs() > 0.6, "{p}: missed {reference:?}");
            }
        }
    }
    assert!(within > 2000 && beyond > 2000, "{within} {beyond}");
}

#[test]
fn a_region_said_to_be_far_holds_no_point_the_lookup_would_answer() {
    let mesh = bumpy(30);
    // The whole band, and a focus on contacts within 0.1 mm.
    for (focus, min_far) in [(0.5, 500), (0.1, 900)] {
        let index = SurfaceIndex::with_focus(&mesh, 0.5, 0.5, 0.05, focus);
        let range = (-0.5, focus);
        let mut rnd = uniform(777);
        let (mut far, mut near) = (0, 0);
        for _ in 0..4000 {
            let centre = Point3::new(rnd() * 16.0 - 3.0, rnd() * 16.0 - 3.0, rnd() * 10.0 - 5.0);
            let radius = rnd() * 1.5;
            if !index.far_from(&centre, radius, range) {
                near += 1;
                continue;
            }
            far += 1;
            for _ in 0..20 {
                let offset = Vector3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
                let p = centre + offset.normalize() * radius * rnd().cbrt();
                assert_eq!(index.lookup(&p, range.0, range.1, range.1), Lookup::Far, "{p} within {radius} of {centre}");
                let reference = nearest_brute_force(index.surface(), &p).expect("non-empty");
                assert!(!(range.0..=range.1).contains(&reference.distance), "{p}: {reference:?}");
            }
        }
        assert!(far > min_far && near > 500, "focus {focus}: {far} {near}");
        if focus < 0.5 {
            // A range beyond the focus is never judged far in advance, even well off the grid.
            assert!(!index.far_from(&Point3::new(5.0, 5.0, 8.0), 0.1, (-0.5, 0.5)));
        }
    }
}

#[test]
fn a_focused_index_answers_as_an_unfocused_one() {
    let mesh = bumpy(30);
    let plain = SurfaceIndex::with_band(&mesh, 0.5, 0.5, 0.05);
    let focused = SurfaceIndex::with_focus(&mesh, 0.5, 0.5, 0.05, 0.1);
    let mut rnd = uniform(31);
    let mut answered = [0usize; 3];
    for _ in 0..20000 {
        let p = Point3::new(rnd() * 12.0 - 1.0, rnd() * 12.0 - 1.0, rnd() * 2.0 - 1.0);
        for (lo, hi) in [(-0.5, 0.1), (-0.5, 0.5), (-0.2, 0.05)] {
            let a = focused.lookup(&p, lo, hi, 0.05);
            assert_eq!(a, plain.lookup(&p, lo, hi, 0.05), "{p} in {lo}..{hi}");
            answered[match a {
                Lookup::Far => 0,
                Lookup::Approximate(_) => 1,
                Lookup::Exact(_) => 2,
            }] += 1;
        }
    }
    assert!(answered.iter().all(|&n| n > 1000), "{answered:?}");
}

#[test]
fn screening_many_points_answers_as_screening_each() {
    let mesh = bumpy(30);
    let index = SurfaceIndex::with_focus(&mesh, 0.5, 0.5, 0.05, 0.1);
    let mut rnd = uniform(4242);
    // Runs of nearby points, as a cluster's vertices are, some off the grid; runs longer
    // than a chunk, and a focused and an unfocused range.
    for (lo, hi) in [(-0.5, 0.1), (-0.5, 0.5)] {
        let mut kinds = [0usize; 3];
        for run in 0..300 {
            let centre = Point3::new(rnd() * 14.0 - 2.0, rnd() * 14.0 - 2.0, rnd() * 2.4 - 1.2);
            let points: Vec<Point3<f64>> =
                (0..run % 150).map(|_| centre + Vector3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 1.5).collect();
            let expected: Vec<(usize, Screen)> = points
                .iter()
                .enumerate()
                .map(|(j, p)| (j, index.screen(p, lo, hi, 0.05)))
                .filter(|(_, s)| *s != Screen::Answered(Lookup::Far))
                .collect();
            let mut got = Vec::new();
            index.screen_many(&points, lo, hi, 0.05, |j, s| got.push((j, s)));
            assert_eq!(got, expected, "run {run} about {centre}, range {lo}..{hi}");
            for (_, s) in &got {
                kinds[match s {
                    Screen::Answered(Lookup::Approximate(_)) => 0,
                    Screen::Search(_) => 1,
                    _ => 2,
                }] += 1;
            }
        }
        assert!(kinds[0] > 200 && kinds[1] > 1000 && kinds[2] == 0, "{lo}..{hi}: {kinds:?}");
    }
}

#[test]
fn the_sign_is_positive_in_front_and_negative_behind() {
    let mesh = bumpy(10);
    let index = SurfaceIndex::new(&mesh, 1.0);
    let top = mesh.vertices[60];
    let above = index.nearest(&(top + Vector3::new(0.0, 0.0, 0.3))).expect("near");
    let below = index.nearest(&(top - Vector3::new(0.0, 0.0, 0.3))).expect("near");
    assert!(above.distance > 0.0 && below.distance < 0.0, "{above:?} {below:?}");
}
