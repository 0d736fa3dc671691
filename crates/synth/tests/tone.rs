//! The phone's processing of a rendered frame ([`post::develop`]): tone curves that the
//! detector can undo, sharpening halos of the expected size, a local tone map that lifts
//! shadows and lowers highlights, and renders that only change when asked to.

use jawtrack_synth::post::{self, encode_u8, local_tone_map};
use jawtrack_synth::realism::Sharpen;
use jawtrack_synth::{LinearImage, Realism, SceneKind, SceneOptions, SynthConfig, Synthesizer};
use jawtrack_tone::ToneCurve;

/// An image of `w` × `h` px whose radiance depends on the column only.
fn columns(w: usize, h: usize, radiance: impl Fn(usize) -> f32) -> LinearImage {
    LinearImage {
        width: w as u32,
        height: h as u32,
        radiance: (0..w * h).map(|i| radiance(i % w)).collect(),
        depth: vec![150.0; w * h],
    }
}

#[test]
fn each_curves_frame_decodes_back_to_the_radiance_within_a_quantum() {
    // Dense in the shadows, where the curves differ most.
    let ramp = columns(4096, 1, |x| (x as f32 / 4095.0).powi(2));
    let curves = [
        ToneCurve::Srgb,
        ToneCurve::Gamma { gamma: 1.8 },
        ToneCurve::Gamma { gamma: 2.6 },
        ToneCurve::SCurve { gamma: 2.2, contrast: 0.5 },
    ];
    // Does every byte's quantisation interval, decoded with `curve`, hold its radiance?
    let decodes = |bytes: &[u8], curve: ToneCurve| {
        bytes.iter().zip(&ramp.radiance).all(|(&q, &l)| {
            let (lo, hi) = (curve.decode((f64::from(q) - 0.5) / 255.0), curve.decode((f64::from(q) + 0.5) / 255.0));
            (lo - 1e-6..=hi + 1e-6).contains(&f64::from(l))
        })
    };
    for curve in curves {
        let bytes = encode_u8(&ramp, Some(curve), None);
        assert!(decodes(&bytes, curve), "{curve} does not decode back");
        for other in curves.into_iter().filter(|&c| c != curve) {
            assert!(!decodes(&bytes, other), "{curve} frame also decodes as {other}: the curve is not applied");
        }
    }
    let linear = encode_u8(&ramp, None, None);
    assert!(linear.iter().zip(&ramp.radiance).all(|(&q, &l)| q == (255.0 * l).round() as u8));
    // The old name draws with the same, standard, curve: IEC 61966-2-1's mid-grey.
    assert!((post::srgb_encode(0.214_041_140_5) - 0.5).abs() < 1e-6);
}

/// The detail a Gaussian of σ takes out of a unit step at the first pixel past it: the weight
/// of the kernel's taps beyond its centre, (1 − k₀)/2, the kernel sampled at whole pixels.
fn step_detail(sigma: f64) -> f64 {
    let weight = |i: i32| (-f64::from(i * i) / (2.0 * sigma * sigma)).exp();
    let k0 = 1.0 / (-40..=40).map(weight).sum::<f64>();
    (1.0 - k0) / 2.0
}

#[test]
fn sharpening_overshoots_a_step_by_the_unsharp_masks_amount_and_leaves_flat_parts_alone() {
    let (w, edge) = (64, 32);
    let (dark, bright) = (0.05, 0.5);
    let step = columns(w, 8, |x| if x < edge { dark } else { bright });
    let (amount, radius_px) = (1.0, 1.5);
    let plain = encode_u8(&step, Some(ToneCurve::Srgb), None);
    let sharp = encode_u8(&step, Some(ToneCurve::Srgb), Some(Sharpen { amount, radius_px }));
    // On the encoded values (sRGB 0.248 → 0.735): the halo is amount · step · (1 − k₀)/2,
    // 45.6 DN at σ = 1.5 px, either side of the edge.
    let (e_dark, e_bright) = (ToneCurve::Srgb.encode(f64::from(dark)), ToneCurve::Srgb.encode(f64::from(bright)));
    let halo = amount * (e_bright - e_dark) * step_detail(radius_px);
    assert!((halo * 255.0 - 45.6).abs() < 0.5, "{}", halo * 255.0);
    let row = 4 * w;
    let expect = |e: f64| (255.0 * e).round();
    assert!((f64::from(sharp[row + edge]) - expect(e_bright + halo)).abs() <= 1.0, "{}", sharp[row + edge]);
    assert!((f64::from(sharp[row + edge - 1]) - expect(e_dark - halo)).abs() <= 1.0, "{}", sharp[row + edge - 1]);
    assert_eq!(sharp.iter().max(), Some(&sharp[row + edge]), "the overshoot peaks at the edge");
    // The kernel reaches ⌈3σ⌉ = 5 px either side and no further: beyond, nothing changes.
    for x in (0..edge - 5).chain(edge + 5..w) {
        assert_eq!(sharp[row + x], plain[row + x], "x = {x}");
    }
    let flat = columns(w, 8, |_| 0.3);
    assert_eq!(
        encode_u8(&flat, Some(ToneCurve::Srgb), Some(Sharpen { amount: 4.0, radius_px: 5.0 })),
        encode_u8(&flat, Some(ToneCurve::Srgb), None)
    );
    // A black-to-white step overshoots past both ends: clipped, not wrapped around.
    let full = columns(w, 8, |x| if x < edge { 0.0 } else { 1.0 });
    let clipped = encode_u8(&full, None, Some(Sharpen { amount: 2.0, radius_px: 1.0 }));
    assert_eq!((clipped[row + edge - 1], clipped[row + edge]), (0, 255));
}

#[test]
fn the_local_tone_map_lifts_the_dark_half_lowers_the_bright_half_and_keeps_a_uniform_image() {
    let (w, h) = (256, 128);
    let (dark, bright) = (0.05f32, 0.6f32);
    let mut img = columns(w, h, |x| if x < w / 2 { dark } else { bright });
    let before = img.radiance.clone();
    local_tone_map(&mut img, 0.0);
    assert_eq!(img.radiance, before, "strength 0 is off");
    let strength = 0.5;
    local_tone_map(&mut img, strength);
    let at = |x: usize| img.radiance[(h / 2) * w + x];
    // σ = 286/16 = 17.9 px: the outer columns are 7σ from the edge, so B is their own radiance
    // there, and m the two halves' mean.
    let mean = f64::from(dark + bright) / 2.0;
    let expect = |l: f32| f64::from(l) * (mean / f64::from(l)).powf(strength);
    for (got, want) in [(at(0), expect(dark)), (at(w - 1), expect(bright))] {
        assert!((f64::from(got) / want - 1.0).abs() < 0.02, "{got} against {want}");
    }
    assert!(at(0) > 2.0 * dark && at(w - 1) < 0.8 * bright, "{} {}", at(0), at(w - 1));
    // Smooth across the edge: its two sides keep their contrast (12:1) to within a few per cent.
    let contrast = at(w / 2) / at(w / 2 - 1);
    assert!((contrast / (bright / dark) - 1.0).abs() < 0.05, "{contrast}");
    let mut uniform = columns(w, h, |_| 0.3);
    local_tone_map(&mut uniform, 1.0);
    assert!(uniform.radiance.iter().all(|&v| (v - 0.3).abs() < 1e-5));
}

#[test]
fn a_phones_processing_changes_a_render_and_a_linear_frame_refuses_a_curve() {
    let config = |realism: Realism| {
        let mut c = SynthConfig::new(SceneKind::Static);
        c.options = SceneOptions { frames_per_view: 1, ..SceneOptions::default() };
        c.realism = realism;
        c.max_frames = Some(1);
        c
    };
    let render = |realism| Synthesizer::new(config(realism)).expect("valid").render(0).expect("renders").luma;
    let plain = render(Realism::default());
    let processed = Realism {
        tone: ToneCurve::SCurve { gamma: 2.2, contrast: 0.4 },
        sharpen: Some(Sharpen { amount: 1.0, radius_px: 1.2 }),
        local_tone_map: 0.5,
        ..Realism::default()
    };
    let phone = render(processed);
    let differing = plain.iter().zip(&phone).filter(|(a, b)| a != b).count();
    assert!(differing > plain.len() / 2, "{differing} of {} pixels changed", plain.len());
    let linear_with_a_curve = Realism { gamma: false, tone: ToneCurve::Gamma { gamma: 1.8 }, ..Realism::default() };
    let e = Synthesizer::new(config(linear_with_a_curve)).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("realism.tone") && e.contains("realism.gamma"), "{e}");
}
