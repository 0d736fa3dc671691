//! Contact maps a clinician reads: an arch's occlusal view ([`crate::occlusal_view`]) as an SVG
//! with what a raster alone does not say: the arch and the view's side, where the patient's left
//! is, each tooth's number (FDI and Universal) at its place, a 10 mm scale bar, and the colour
//! scale in millimetres of depth or in percent of frames. The rendering is embedded as a PNG, so
//! the file stands alone (a report inlines it, a browser opens it).

use crate::contacts::Arch;
use crate::occlusal_view::{View, render};
use crate::session::ContactSession;
use crate::teeth::Tooth;
use base64::Engine as _;
use image::RgbImage;
use jawtrack_pose::Pose;
use nalgebra::{Point3, Vector3};
use std::fmt::Write as _;

/// What the colours say.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scale {
    /// The deepest contact per vertex: blue at a gap of `threshold_mm`, green touching, red at
    /// `full_scale_mm` penetration ([`crate::contacts::ContactMap::depth_colours`]).
    Depth {
        /// The contact threshold (mm).
        threshold_mm: f64,
        /// The penetration drawn full red (mm).
        full_scale_mm: f64,
    },
    /// The share of frames in contact, blue (few) to red (all).
    Frequency,
}

/// What a map shows besides the rendering.
#[derive(Debug, Clone, PartialEq)]
pub struct Annotations {
    /// The title: "Upper arch, seen from below (occlusal view)".
    pub title: String,
    /// Each tooth's name and a point of it (its centroid), in the mesh's frame.
    pub teeth: Vec<(String, Point3<f64>)>,
    /// The patient's left as a direction in the mesh's frame, when known.
    pub patients_left: Option<Vector3<f64>>,
    /// The colour scale.
    pub scale: Scale,
}

/// The patient's left in the mesh's frame from the teeth's FDI numbers: from the mean of the
/// right side's teeth to the mean of the left side's; `None` unless both sides have a numbered
/// tooth.
pub fn left_from_teeth(teeth: &[(String, Point3<f64>)]) -> Option<Vector3<f64>> {
    let mean = |left: bool| {
        let p: Vec<Vector3<f64>> = teeth
            .iter()
            .filter(|(n, _)| Tooth::from_name(n).is_some_and(|t| t.on_patients_left() == left))
            .map(|(_, p)| p.coords)
            .collect();
        (!p.is_empty()).then(|| p.iter().sum::<Vector3<f64>>() / p.len() as f64)
    };
    (mean(true)? - mean(false)?).try_normalize(1e-9)
}

const MARGIN_TOP: f64 = 34.0;
const MARGIN_BOTTOM: f64 = 74.0;
const MARGIN_SIDE: f64 = 80.0;

/// The map as an SVG document (text).
pub fn svg(image: &RgbImage, view: &View, a: &Annotations) -> String {
    let (w, h) = (f64::from(image.width()), f64::from(image.height()));
    let (tw, th) = (w + 2.0 * MARGIN_SIDE, h + MARGIN_TOP + MARGIN_BOTTOM);
    let mut png = Vec::new();
    let encoded = image::codecs::png::PngEncoder::new(&mut png);
    let data = match image.write_with_encoder(encoded) {
        Ok(()) => base64::engine::general_purpose::STANDARD.encode(&png),
        Err(_) => String::new(),
    };
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {tw} {th}\" width=\"{tw}\" height=\"{th}\" \
         font-family=\"sans-serif\" font-size=\"12\"><rect width=\"{tw}\" height=\"{th}\" fill=\"white\"/>\
         <text x=\"{}\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">{}</text>\
         <image x=\"{MARGIN_SIDE}\" y=\"{MARGIN_TOP}\" width=\"{w}\" height=\"{h}\" href=\"data:image/png;base64,{data}\"/>",
        tw / 2.0,
        esc(&a.title)
    );
    let at = |p: &Point3<f64>| {
        let q = view.pixel(p);
        (MARGIN_SIDE + q[0], MARGIN_TOP + q[1])
    };
    for (name, p) in &a.teeth {
        let (x, y) = at(p);
        let label = Tooth::from_name(name).map_or_else(|| name.clone(), Tooth::label);
        let _ = write!(
            s,
            "<text x=\"{x:.1}\" y=\"{y:.1}\" text-anchor=\"middle\" font-weight=\"bold\" stroke=\"white\" \
             stroke-width=\"3\" paint-order=\"stroke\">{}</text>",
            esc(&label)
        );
    }
    s += &sides(view, a.patients_left, (w, h));
    // The scale bar: 10 mm.
    let bar = 10.0 * view.px_per_mm;
    let y = MARGIN_TOP + h + 18.0;
    let _ = write!(
        s,
        "<line x1=\"{MARGIN_SIDE}\" y1=\"{y}\" x2=\"{}\" y2=\"{y}\" stroke=\"black\" stroke-width=\"3\"/>\
         <text x=\"{}\" y=\"{}\" text-anchor=\"middle\">10 mm</text>",
        MARGIN_SIDE + bar,
        MARGIN_SIDE + bar / 2.0,
        y + 16.0
    );
    s += &colour_scale(a.scale, MARGIN_SIDE + bar + 40.0, y - 8.0);
    s += "</svg>";
    s
}

/// "patient's left" and "patient's right" on the image's edges, or "side unknown".
fn sides(view: &View, left: Option<Vector3<f64>>, (w, h): (f64, f64)) -> String {
    let Some(l) = left else {
        return format!(
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" fill=\"#8a5a00\">the patient's side is unknown: name \
             the teeth by FDI, or give --points</text>",
            MARGIN_SIDE + w / 2.0,
            MARGIN_TOP + h + 60.0
        );
    };
    let (x, y) = (l.dot(&view.right), l.dot(&view.down));
    let (cx, cy) = (MARGIN_SIDE + w / 2.0, MARGIN_TOP + h / 2.0);
    let place = |sign: f64, text: &str| {
        if x.abs() >= y.abs() {
            let px = if x * sign > 0.0 { MARGIN_SIDE + w + 4.0 } else { MARGIN_SIDE - 4.0 };
            let anchor = if x * sign > 0.0 { "start" } else { "end" };
            format!("<text x=\"{px}\" y=\"{cy}\" text-anchor=\"{anchor}\" fill=\"#1f3f8f\">{text}</text>")
        } else {
            let py = if y * sign > 0.0 { MARGIN_TOP + h + 12.0 } else { MARGIN_TOP - 4.0 };
            format!("<text x=\"{cx}\" y=\"{py}\" text-anchor=\"middle\" fill=\"#1f3f8f\">{text}</text>")
        }
    };
    place(1.0, "patient's left") + &place(-1.0, "patient's right")
}

/// The colour bar with its meaning in words and numbers.
fn colour_scale(scale: Scale, x: f64, y: f64) -> String {
    let mut s = String::from("<defs><linearGradient id=\"ramp\">");
    for (k, c) in ["#0000ff", "#00ffff", "#00ff00", "#ffff00", "#ff0000"].iter().enumerate() {
        let _ = write!(s, "<stop offset=\"{}%\" stop-color=\"{c}\"/>", k * 25);
    }
    let grey = crate::contacts::GREY;
    let _ = write!(
        s,
        "</linearGradient></defs><rect x=\"{x}\" y=\"{y}\" width=\"14\" height=\"12\" fill=\"rgb({},{},{})\"/>\
         <text x=\"{x}\" y=\"{}\" font-size=\"10\">none</text>\
         <rect x=\"{}\" y=\"{y}\" width=\"220\" height=\"12\" fill=\"url(#ramp)\"/>",
        grey[0],
        grey[1],
        grey[2],
        y + 26.0,
        x + 30.0
    );
    let bar = x + 30.0;
    let ticks: Vec<(f64, String)> = match scale {
        Scale::Depth { threshold_mm, full_scale_mm } => vec![
            (0.0, format!("{threshold_mm:.2} mm gap")),
            (110.0, "touching".into()),
            (220.0, format!("{full_scale_mm:.2} mm deep")),
        ],
        Scale::Frequency => vec![(0.0, "0 %".into()), (110.0, "50 %".into()), (220.0, "100 % of frames".into())],
    };
    // The end labels run inward from the bar's ends, so none reaches the swatch's label.
    for (dx, label) in ticks {
        let anchor = match dx {
            0.0 => "start",
            220.0 => "end",
            _ => "middle",
        };
        let _ = write!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"{anchor}\" font-size=\"10\">{}</text>",
            bar + dx,
            y + 26.0,
            esc(&label)
        );
    }
    s
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// One of a session's maps.
#[derive(Debug, Clone, PartialEq)]
pub struct Map {
    /// `maxilla` or `mandible`.
    pub arch: &'static str,
    /// `depth` or `frequency`.
    pub what: &'static str,
    /// What it shows, in words.
    pub caption: String,
    /// The SVG document.
    pub svg: String,
    /// Whether it says where the patient's left is.
    pub sided: bool,
}

/// The four maps of a session (each arch by deepest contact and by share of frames), each arch
/// seen from the other at `first_pose` (`maxilla_scan_from_mandible_scan`). The patient's left
/// comes from the teeth's FDI numbers, else from `upper_left` (the upper scan's frame).
pub fn session_maps(
    session: &ContactSession,
    arches: [&Arch; 2],
    first_pose: &Pose,
    teeth: [&[(String, Point3<f64>)]; 2],
    upper_left: Option<Vector3<f64>>,
) -> Vec<Map> {
    let views = View::occlusal_pair(&arches[0].mesh, &arches[1].mesh, first_pose, 800);
    let lefts = [
        left_from_teeth(teeth[0]).or(upper_left),
        left_from_teeth(teeth[1]).or_else(|| upper_left.map(|l| first_pose.inverse().rotation() * l)),
    ];
    let s = session.summary();
    let titles = [
        "Upper arch, occlusal view (seen from the lower arch)",
        "Lower arch, occlusal view (seen from the upper arch)",
    ];
    let mut maps = Vec::new();
    for (k, arch) in ["maxilla", "mandible"].into_iter().enumerate() {
        let depth =
            Scale::Depth { threshold_mm: session.settings().threshold_mm, full_scale_mm: s.depth_colour_full_scale_mm };
        for (what, colours, scale, words) in [
            ("depth", session.depth_colours(k), depth, "deepest contact"),
            ("frequency", session.frequency_colours(k), Scale::Frequency, "share of frames in contact"),
        ] {
            let a = Annotations {
                title: format!("{}: {words}", titles[k]),
                teeth: teeth[k].to_vec(),
                patients_left: lefts[k],
                scale,
            };
            let image = render(&arches[k].mesh, &colours, &views[k]);
            maps.push(Map {
                arch,
                what,
                caption: a.title.clone(),
                svg: svg(&image, &views[k], &a),
                sided: lefts[k].is_some(),
            });
        }
    }
    maps
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A view looking down −Z at the XY plane, x to the right, 2 px/mm, from (−50, −50).
    fn view() -> View {
        View {
            right: Vector3::x(),
            down: -Vector3::y(),
            forward: -Vector3::z(),
            origin: [-50.0, -50.0],
            px_per_mm: 2.0,
            width: 200,
            height: 200,
        }
    }

    #[test]
    fn the_left_comes_from_the_teeth_numbers() {
        let teeth = vec![
            ("26".to_string(), Point3::new(-20.0, 0.0, 0.0)),
            ("16".to_string(), Point3::new(20.0, 0.0, 0.0)),
            ("crown".to_string(), Point3::new(0.0, 9.0, 0.0)),
        ];
        let l = left_from_teeth(&teeth).expect("both sides numbered");
        assert!((l - Vector3::new(-1.0, 0.0, 0.0)).norm() < 1e-12);
        assert!(left_from_teeth(&teeth[..1]).is_none());
    }

    #[test]
    fn the_map_names_teeth_sides_and_scales() {
        let a = Annotations {
            title: "Upper arch <occlusal>".into(),
            teeth: vec![("26".into(), Point3::new(-20.0, 0.0, 0.0)), ("16".into(), Point3::new(20.0, 0.0, 0.0))],
            patients_left: Some(Vector3::new(-1.0, 0.0, 0.0)),
            scale: Scale::Depth { threshold_mm: 0.05, full_scale_mm: 0.2 },
        };
        let s = svg(&RgbImage::new(200, 200), &view(), &a);
        assert!(s.contains("Upper arch &lt;occlusal&gt;") && s.contains("data:image/png;base64,iVBOR"));
        // 26 at x = (−20 + 50) · 2 = 60 px into the image, 16 at 140 px.
        assert!(s.contains(&format!("x=\"{:.1}\"", MARGIN_SIDE + 60.0)) && s.contains(">26 (Univ. 14)<"), "{s}");
        assert!(s.contains(&format!("x=\"{:.1}\"", MARGIN_SIDE + 140.0)) && s.contains(">16 (Univ. 3)<"));
        // The left is −X, the image's left edge.
        let left = s.find("patient's left").expect("left named");
        assert!(
            s[..left].ends_with(&format!(
                "x=\"{}\" y=\"{}\" text-anchor=\"end\" fill=\"#1f3f8f\">",
                MARGIN_SIDE - 4.0,
                MARGIN_TOP + 100.0
            )),
            "{s}"
        );
        // The 10 mm bar is 20 px long; the scale is in mm.
        assert!(
            s.contains(&format!("x2=\"{}\"", MARGIN_SIDE + 20.0))
                && s.contains("0.05 mm gap")
                && s.contains("0.20 mm deep")
        );
        let unknown = svg(&RgbImage::new(10, 10), &view(), &Annotations { patients_left: None, ..a });
        assert!(unknown.contains("side is unknown"));
    }
}
