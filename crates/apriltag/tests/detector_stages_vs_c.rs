//! Our detector's stages against the AprilTag C library's, bit for bit. In debug mode the C
//! library writes each stage's image into the current directory; this binary (its own process,
//! one test, so changing directory is safe) runs it in a temporary folder and compares.

use jawtrack_apriltag::workers::Workers;
use jawtrack_apriltag::{ImageView, QuadThreshold, clusters, components, preprocess, quads, threshold};
use jawtrack_apriltag_reference::{ReferenceDetector, ReferenceParams};
use jawtrack_test_support::{FIXTURE_FRAMES, fixture_sets, set_name};
use std::collections::HashMap;

fn read_pnm(path: &std::path::Path) -> image::GrayImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_luma8()
}

#[test]
fn decimation_threshold_regions_clusters_and_quads_match_c() {
    let dir = tempfile_dir();
    std::env::set_current_dir(&dir).expect("enter the temporary folder");
    // The C debug output of a 4K frame is slow to write; 1080p covers the logic.
    let hd = |name: &str| !name.ends_with("-4k");
    let frames: Vec<_> =
        fixture_sets().into_iter().filter(|s| hd(&set_name(s))).map(|s| s.join("frame_0000.png")).collect();
    let want: Vec<_> = FIXTURE_FRAMES.iter().filter(|(name, _)| hd(name)).map(|(name, _)| name.to_string()).collect();
    let got: Vec<_> = frames.iter().filter_map(|f| f.parent()).map(set_name).collect();
    assert_eq!(got, want, "the first frame of every 1080p fixture set");
    let settings =
        [(1.0, false, 5), (1.5, false, 5), (2.0, false, 5), (2.0, true, 5), (3.0, false, 40), (4.0, false, 5)];
    let mut compared = 0;
    let mut total_quads = 0;
    for path in &frames {
        let img = image::open(path).expect("png").to_luma8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        // An odd stride and an odd crop exercise the edges of the tiling.
        let crop_w = w - 3;
        let view = ImageView::new(img.as_raw(), crop_w, h - 1, w).expect("valid view");
        for &(decimate, deglitch, diff) in &settings {
            let params = ReferenceParams {
                quad_decimate: decimate,
                deglitch,
                min_white_black_diff: diff,
                debug: true,
                ..ReferenceParams::default()
            };
            let mut c = ReferenceDetector::new(&params).expect("reference");
            c.detect(img.as_raw(), crop_w, h - 1, w).expect("detects");
            let c_pre = read_pnm(&dir.join("debug_preprocess.pnm"));
            let c_thr = read_pnm(&dir.join("debug_threshold.pnm"));

            let ours_pre = if decimate == 1.0 {
                jawtrack_apriltag::Gray {
                    width: crop_w,
                    height: h - 1,
                    data: (0..h - 1).flat_map(|y| view.row(y).to_vec()).collect(),
                }
            } else {
                preprocess::decimate(&view, decimate)
            };
            let label = format!("{} decimate {decimate} deglitch {deglitch} diff {diff}", path.display());
            assert_eq!((ours_pre.width as u32, ours_pre.height as u32), c_pre.dimensions(), "{label}: preprocess size");
            assert!(ours_pre.data == *c_pre.as_raw(), "{label}: preprocess differs");
            let ours_thr = threshold::threshold(&ours_pre.view().expect("non-empty"), diff as u8, deglitch);
            let differing = ours_thr.data.iter().zip(c_thr.as_raw()).filter(|(a, b)| a != b).count();
            assert_eq!(differing, 0, "{label}: {differing} threshold pixels differ");
            bands_match_one_thread(&view, &ours_pre, &ours_thr, (decimate, deglitch, diff as u8), &label);
            compare_segmentation(&ours_thr, &dir.join("debug_segmentation.pnm"), &label);
            compare_clusters(&ours_thr, &dir.join("debug_clusters.pnm"), &label);
            total_quads += compare_quads(&ours_pre, &ours_thr, &dir.join("debug_lines.ps"), decimate, diff, &label);
            compared += 1;
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    use std::io::Write as _;
    let _ = writeln!(
        std::io::stderr(),
        "decimation, threshold, regions, cluster points and {total_quads} quads equal C's on {compared} frame/setting pairs"
    );
    assert_eq!(compared, settings.len() * want.len(), "every setting on every frame");
    assert!(total_quads > 100, "too few quads compared: {total_quads}");
}

/// The stages split into bands of rows over three threads give what one thread gives: the
/// same decimated and threshold images, the same regions (their representatives may differ),
/// the same clusters point for point.
fn bands_match_one_thread(
    view: &ImageView<'_>,
    pre: &jawtrack_apriltag::Gray,
    thr: &jawtrack_apriltag::Gray,
    (decimate, deglitch, diff): (f32, bool, u8),
    label: &str,
) {
    let many = Workers::new(3);
    assert!(many.band_ranges(thr.height).len() > 4, "{label}: too few bands to test the seams");
    if decimate != 1.0 {
        let mut banded = jawtrack_apriltag::Gray::default();
        preprocess::decimate_with(view, decimate, &mut banded, &many);
        assert!(banded == *pre, "{label}: decimation in bands differs");
    }
    let mut banded = jawtrack_apriltag::Gray::default();
    threshold::threshold_with(&pre.view().expect("non-empty"), diff, deglitch, &mut banded, &many);
    assert!(banded == *thr, "{label}: threshold in bands differs");
    let mut one = components::connected_components(thr);
    let mut split = components::UnionFind::new(0);
    components::connected_components_with(thr, &mut split, &many);
    let (mut to_split, mut to_one) = (HashMap::new(), HashMap::new());
    for i in 0..(thr.width * thr.height) as u32 {
        let (a, b) = (one.find(i), split.find(i));
        assert_eq!(*to_split.entry(a).or_insert(b), b, "{label}: pixel {i}: one region becomes two");
        assert_eq!(*to_one.entry(b).or_insert(a), a, "{label}: pixel {i}: two regions become one");
        assert_eq!(one.set_size(a), split.set_size(b), "{label}: pixel {i}: region sizes differ");
    }
    let want = clusters::gradient_clusters(thr, &mut one);
    let got = clusters::gradient_clusters_par(thr, &mut split, &mut Vec::new(), &many);
    assert!(got == want, "{label}: clusters in bands differ ({} vs {} clusters)", got.len(), want.len());
}

/// C colours every region of at least 5 pixels (`min_cluster_pixels`) with a random colour
/// and leaves smaller ones black. Ours must mark the same pixels, each of our regions must
/// carry one colour (we never merge two of C's), and we may have more regions than C has
/// colours only by the chance of two random colours coinciding (we never split one of C's).
fn compare_segmentation(thr: &jawtrack_apriltag::Gray, c_path: &std::path::Path, label: &str) {
    let c = image::open(c_path).expect("segmentation pnm").to_rgb8();
    let mut uf = components::connected_components(thr);
    let mut colour_of: HashMap<u32, [u8; 3]> = HashMap::new();
    for (i, p) in c.pixels().enumerate() {
        let root = uf.find(i as u32);
        let big = uf.set_size(root) >= 5;
        let coloured = p.0 != [0, 0, 0];
        assert_eq!(big, coloured, "{label}: pixel {i} region size disagrees with C");
        if big {
            let prev = *colour_of.entry(root).or_insert(p.0);
            assert_eq!(prev, p.0, "{label}: our region at pixel {i} spans two of C's");
        }
    }
    let colours: std::collections::HashSet<[u8; 3]> = colour_of.values().copied().collect();
    let n = colour_of.len() as f64;
    let expected_coincidences = n * n / (2.0 * 150f64.powi(3));
    let extra = colour_of.len() - colours.len();
    assert!(
        (extra as f64) <= 3.0 * expected_coincidences + 3.0,
        "{label}: {} regions but {} colours (chance coincidences expected: {expected_coincidences:.1})",
        colour_of.len(),
        colours.len()
    );
}

/// C paints every cluster point (x/2, y/2) in its cluster's colour; which colour wins where
/// clusters overlap depends on C's hash order, so compare where points are, exactly.
fn compare_clusters(thr: &jawtrack_apriltag::Gray, c_path: &std::path::Path, label: &str) {
    let c = image::open(c_path).expect("clusters pnm").to_rgb8();
    let mut uf = components::connected_components(thr);
    let ours = clusters::gradient_clusters(thr, &mut uf);
    let mut painted = vec![false; thr.width * thr.height];
    for p in ours.iter().flatten() {
        painted[usize::from(p.y / 2) * thr.width + usize::from(p.x / 2)] = true;
    }
    let differing = c.pixels().zip(&painted).filter(|(px, ours)| (px.0 != [0, 0, 0]) != **ours).count();
    assert_eq!(differing, 0, "{label}: {differing} pixels differ in where cluster points lie");
    assert!(painted.iter().any(|&p| p), "{label}: no clusters at all");
}

/// C prints every fitted quad into `debug_lines.ps` (`x y moveto x y lineto … stroke`, in
/// the decimated image's coordinates, 15 decimals of its float corners). Ours must be the same
/// quads, corner for corner; only their order (C's hash order) may differ.
fn compare_quads(
    pre: &jawtrack_apriltag::Gray,
    thr: &jawtrack_apriltag::Gray,
    ps: &std::path::Path,
    decimate: f32,
    diff: i32,
    label: &str,
) -> usize {
    let text = std::fs::read_to_string(ps).expect("debug_lines.ps");
    let mut theirs: Vec<[f32; 8]> = text
        .lines()
        .filter(|l| l.contains("moveto"))
        .map(|l| {
            let v: Vec<f32> = l.split_whitespace().filter_map(|t| t.parse().ok()).collect();
            std::array::from_fn(|i| v[i])
        })
        .collect();
    let mut uf = components::connected_components(thr);
    let cl = clusters::gradient_clusters(thr, &mut uf);
    let q = QuadThreshold { min_white_black_diff: diff as u8, ..QuadThreshold::reference() };
    // Two threads: the pool must find C's quads just as one thread does.
    let mut ours: Vec<[f32; 8]> =
        quads::fit_quads(&cl, &pre.view().expect("non-empty"), &q, decimate, &Workers::new(2))
            .iter()
            .map(|q| [q.p[0][0], q.p[0][1], q.p[1][0], q.p[1][1], q.p[2][0], q.p[2][1], q.p[3][0], q.p[3][1]])
            .collect();
    let key = |a: &[f32; 8], b: &[f32; 8]| {
        a.iter().zip(b).map(|(x, y)| x.total_cmp(y)).find(|o| o.is_ne()).unwrap_or(std::cmp::Ordering::Equal)
    };
    theirs.sort_by(key);
    ours.sort_by(key);
    assert_eq!(ours.len(), theirs.len(), "{label}: {} quads, C has {}", ours.len(), theirs.len());
    for (a, b) in ours.iter().zip(&theirs) {
        let worst = a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
        assert!(worst < 1e-3, "{label}: quad {a:?} vs C {b:?}");
    }
    ours.len()
}

fn tempfile_dir() -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("jawtrack-stages-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temporary folder");
    d
}
