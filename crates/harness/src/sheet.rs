//! Printable tag sheets: one A4 SVG per jaw body, in true millimetres (1 user unit = 1 mm),
//! with every tag printed on a polygon the size of its face (a dodecahedron's pentagon, a
//! cube's square), ready to cut out and glue on.
//!
//! Each polygon is the face seen from outside with the tag upright (x right, y down, as in
//! the upright tag image), so the face's apex — the vertex the tag's +y axis points at — is
//! at the bottom of the printed pentagon, and cell row 0 of the tag is at the top. Labels,
//! the scale bar and the instructions are all outside the cut lines.

use crate::body::{checked_post, face_2d};
use crate::{HarnessError, HarnessParams, common_tag_size};
use jawtrack_apriltag::TagFamily;
use jawtrack_marker::{BodyKind, Marker, MarkerError, Solid, Tag};
use nalgebra::{Vector2, Vector3};
use std::fmt::Write as _;

/// Page width (mm), A4 portrait.
pub const PAGE_WIDTH_MM: f64 = 210.0;
/// Page height (mm), A4 portrait.
pub const PAGE_HEIGHT_MM: f64 = 297.0;
/// Length of the printed scale bar (mm).
pub const SCALE_BAR_MM: f64 = 10.0;

/// Blank border kept round the page (mm): most printers cannot print the outer 5 mm.
const MARGIN: f64 = 12.0;
/// Top of the tag grid (mm), under the heading.
const GRID_TOP: f64 = 40.0;
/// Bottom of the tag grid (mm), above the scale bars.
const GRID_BOTTOM: f64 = 258.0;
/// Height of the 10 mm scale bar's line (mm from the top of the page).
const SCALE_Y: f64 = 267.0;
/// Height of the 100 mm scale bar's line: ten times longer, so a scaling error of a fraction
/// of a percent shows as a measurable length.
const LONG_SCALE_Y: f64 = 279.0;
/// Width of the cut line's stroke (mm). It is drawn centred on the pentagon's outline and
/// the white face is painted over it, so only its outer half (0.1 mm) shows, wholly outside
/// the face: cutting along the inside of the grey line gives the exact pentagon and the tag's
/// white margin keeps its full width.
const CUT_STROKE: f64 = 0.2;
/// Font size of the per-tag labels (mm).
const LABEL_FONT: f64 = 2.5;
/// Room (mm) kept above and below each pentagon for its labels.
const LABEL_ROOM: f64 = 5.0;
/// Most columns of tags: more would crowd the labels of small tags.
const MAX_COLUMNS: usize = 4;
const FONT_FAMILY: &str = "Helvetica, Arial, sans-serif";
const CUT_GREY: &str = "#808080";

/// A number for SVG: up to 9 decimals (nanometres), trailing zeros dropped.
fn num(v: f64) -> String {
    let s = format!("{v:.9}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".to_string() } else { s.to_string() }
}

/// Text content made safe for XML.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// A closed polygon as path data.
fn polygon_d(points: &[Vector2<f64>]) -> String {
    let mut d = String::new();
    for (i, p) in points.iter().enumerate() {
        let _ = write!(d, "{}{} {} ", if i == 0 { "M" } else { "L" }, num(p.x), num(p.y));
    }
    d.push('Z');
    d
}

/// The ids of a body as a short text: a range when consecutive.
fn id_list(tags: &[&Tag]) -> String {
    let ids: Vec<u32> = tags.iter().map(|t| t.id).collect();
    match (ids.first(), ids.last()) {
        (Some(&a), Some(&b)) if ids.windows(2).all(|w| w[1] == w[0] + 1) && a != b => format!("{a}–{b}"),
        _ => ids.iter().map(u32::to_string).collect::<Vec<_>>().join(", "),
    }
}

/// The tag sheet of one body of `marker`: every tag of that body on its face's pentagon, with
/// cut lines, labels, print instructions and a 10 mm scale bar, as an A4 SVG in millimetres.
///
/// Tags are printed centred on their faces as the nominal marker has them, at their own size.
/// This sheet knows nothing of the mounting post; [`tag_sheet_svg_with_post`] also marks
/// where the post leaves the bottom faces.
pub fn tag_sheet_svg(marker: &Marker, body: BodyKind) -> Result<String, HarnessError> {
    render(marker, body, &[])
}

/// Like [`tag_sheet_svg`], and on the three faces the post leaves (faces 9–11 of a
/// dodecahedron, 3–5 of a cube) a dashed line marks the notch to cut out of the face's corner
/// at the −Z vertex so the paper fits round the post.
/// Errors as [`crate::body_mesh`] does when the post does not fit.
pub fn tag_sheet_svg_with_post(
    marker: &Marker,
    body: BodyKind,
    params: &HarnessParams,
) -> Result<String, HarnessError> {
    let post = checked_post(marker.solid, marker.edge, common_tag_size(marker)?, params)?;
    let notches = post.layout.footprints(&post.solid, post.radius);
    render(marker, body, &notches)
}

/// Draws the sheet; `notches` holds, per bottom face, the post's footprint (the −Z vertex,
/// then the ring corners on the face).
fn render(marker: &Marker, body: BodyKind, notches: &[(usize, Vec<Vector3<f64>>)]) -> Result<String, HarnessError> {
    if !marker.edge.is_finite() || marker.edge <= 0.0 {
        return Err(MarkerError::Params(format!(
            "the edge length must be a positive number of mm, got {}",
            marker.edge
        ))
        .into());
    }
    let b = marker.body(body).ok_or(HarnessError::MissingBody(body))?;
    let mut tags: Vec<&Tag> = b.tags.iter().collect();
    if tags.is_empty() {
        return Err(HarnessError::NoTags);
    }
    tags.sort_by_key(|t| t.face);
    let solid = marker.geometry();
    for t in &tags {
        if t.face >= solid.faces().len() {
            return Err(HarnessError::BadFace { id: t.id, face: t.face, last: solid.faces().len() - 1 });
        }
        if !t.size.is_finite() || t.size <= 0.0 {
            return Err(MarkerError::Params(format!(
                "tag {}: the tag size must be a positive number of mm, got {}",
                t.id, t.size
            ))
            .into());
        }
    }

    // Every face is the same regular polygon in its own frame; lay the sheet out on face 0's.
    let outline: Vec<Vector2<f64>> = solid.faces()[0].vertices.iter().map(|v| face_2d(&solid.faces()[0], v)).collect();
    let (xmin, xmax) =
        outline.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.x), hi.max(p.x)));
    let (ymin, ymax) =
        outline.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.y), hi.max(p.y)));
    let usable_w = PAGE_WIDTH_MM - 2.0 * MARGIN;
    let need_w = xmax - xmin + 6.0;
    let need_h = ymax - ymin + 2.0 * LABEL_ROOM + 2.0;
    let columns = ((usable_w / need_w).floor() as usize).min(MAX_COLUMNS).min(tags.len());
    if columns == 0 {
        return Err(HarnessError::SheetTooSmall { edge: marker.edge });
    }
    let rows = tags.len().div_ceil(columns);
    let grid_h = GRID_BOTTOM - GRID_TOP;
    if rows as f64 * need_h > grid_h {
        return Err(HarnessError::SheetTooSmall { edge: marker.edge });
    }
    let cell_w = usable_w / columns as f64;
    // Spread the rows a little when there is room, but keep them together near the top.
    let cell_h = (grid_h / rows as f64).min(need_h + 15.0);

    let mut svg = String::new();
    let _ = writeln!(svg, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{w}mm" height="{h}mm" viewBox="0 0 {w} {h}">"#,
        w = num(PAGE_WIDTH_MM),
        h = num(PAGE_HEIGHT_MM)
    );
    let _ = writeln!(svg, "<title>JawTrack tag sheet: {}</title>", body.name());
    let _ = writeln!(
        svg,
        r##"<rect x="0" y="0" width="{}" height="{}" fill="#ffffff"/>"##,
        num(PAGE_WIDTH_MM),
        num(PAGE_HEIGHT_MM)
    );
    heading(&mut svg, marker, body, &tags);

    for (slot, tag) in tags.iter().enumerate() {
        let (col, row) = (slot % columns, slot / columns);
        // Page position of the face centre: the pentagon's bounding box centred in its cell,
        // below the room for its label.
        let origin = Vector2::new(
            MARGIN + (col as f64 + 0.5) * cell_w - 0.5 * (xmin + xmax),
            GRID_TOP + row as f64 * cell_h + LABEL_ROOM - ymin,
        );
        let notch = notches.iter().find(|(f, _)| *f == tag.face).map(|(_, p)| p.as_slice());
        draw_tag(&mut svg, &solid, &marker.family, tag, origin, notch)?;
    }

    scale_bar(&mut svg);
    svg.push_str("</svg>\n");
    Ok(svg)
}

/// Body label and print instructions at the top of the page.
fn heading(svg: &mut String, marker: &Marker, body: BodyKind, tags: &[&Tag]) {
    let jaw = match body {
        BodyKind::Maxilla => "upper jaw",
        BodyKind::Mandible => "lower jaw",
    };
    let sizes: Vec<String> = {
        let mut s: Vec<String> = tags.iter().map(|t| format!("{:.3}", t.size)).collect();
        s.dedup();
        s
    };
    let lines = [
        (5.0, "bold", format!("JawTrack marker — {} ({jaw})", body.name())),
        (
            3.0,
            "normal",
            format!(
                "{} ids {} · {} edge {} mm · tag (black square) {} mm",
                marker.family.name,
                id_list(tags),
                marker.solid,
                num(marker.edge),
                sizes.join("/")
            ),
        ),
        (
            3.2,
            "bold",
            "Print at 100 % (actual size), no fit-to-page, no scaling; check the 10 mm bar below with calipers."
                .to_string(),
        ),
        (
            2.6,
            "normal",
            format!(
                "Cut each {} along the inside of its grey line; glue tag id N on face {}, the vertex marked “apex” on the face's apex.",
                marker.solid.face_shape(),
                if body.first_id() == 0 { "N".to_string() } else { format!("N − {}", body.first_id()) }
            ),
        ),
    ];
    let mut y = 17.0;
    for (size, weight, text) in lines {
        let _ = writeln!(
            svg,
            r#"<text class="heading" x="{}" y="{}" font-family="{FONT_FAMILY}" font-size="{}" font-weight="{weight}">{}</text>"#,
            num(MARGIN),
            num(y),
            num(size),
            esc(&text)
        );
        y += size + 2.4;
    }
}

/// One tag: cut line, white face, black square and white cells, labels, and the post's
/// notch if the post leaves this face.
fn draw_tag(
    svg: &mut String,
    solid: &Solid,
    family: &TagFamily,
    tag: &Tag,
    origin: Vector2<f64>,
    notch: Option<&[Vector3<f64>]>,
) -> Result<(), HarnessError> {
    let unknown = || HarnessError::UnknownTag { id: tag.id, family: family.name, last: family.count() - 1 };
    let bitmap = family.bitmap(tag.id).ok_or_else(unknown)?;
    let face = &solid.faces()[tag.face];
    // Face points in page coordinates: the face's 2D frame (x right, y toward the apex, both as
    // on the page) shifted to this tag's place.
    let page = |p: &Vector3<f64>| origin + face_2d(face, p);
    let pentagon: Vec<Vector2<f64>> = face.vertices.iter().map(page).collect();
    let d = polygon_d(&pentagon);
    let _ = writeln!(svg, r#"<g class="tag" data-tag-id="{}" data-face="{}">"#, tag.id, tag.face);
    let _ = writeln!(
        svg,
        r#"<path class="cut-line" d="{d}" fill="none" stroke="{CUT_GREY}" stroke-width="{}" stroke-linejoin="miter"/>"#,
        num(CUT_STROKE)
    );
    let _ = writeln!(svg, r##"<path class="face" d="{d}" fill="#ffffff" stroke="none"/>"##);

    // The black-border square centred on the face; cell row 0 at the top (tag y = −size/2).
    let cell = tag.size / bitmap.width() as f64;
    let corner = origin - Vector2::new(tag.size / 2.0, tag.size / 2.0);
    let _ = writeln!(
        svg,
        r##"<rect class="tag-black" x="{}" y="{}" width="{}" height="{}" fill="#000000" shape-rendering="crispEdges"/>"##,
        num(corner.x),
        num(corner.y),
        num(tag.size),
        num(tag.size)
    );
    // All white cells in one path: a renderer fills one path in one pass, so cells sharing an
    // edge leave no anti-aliasing seam between them, as separate rectangles could.
    let mut white = String::new();
    for y in 0..bitmap.width() {
        for x in 0..bitmap.width() {
            if bitmap.is_white(x, y) {
                let x0 = corner.x + x as f64 * cell;
                let y0 = corner.y + y as f64 * cell;
                let _ =
                    write!(white, "M{} {} H{} V{} H{} Z ", num(x0), num(y0), num(x0 + cell), num(y0 + cell), num(x0));
            }
        }
    }
    let _ = writeln!(
        svg,
        r##"<path class="tag-white" d="{}" fill="#ffffff" fill-rule="nonzero" shape-rendering="crispEdges"/>"##,
        white.trim_end()
    );

    if let Some(foot) = notch {
        // The ring corners only: the notch is the region between this arc and the apex.
        let arc: Vec<Vector2<f64>> = foot.iter().skip(1).map(page).collect();
        let mut d = String::new();
        for (i, p) in arc.iter().enumerate() {
            let _ = write!(d, "{}{} {} ", if i == 0 { "M" } else { "L" }, num(p.x), num(p.y));
        }
        let _ = writeln!(
            svg,
            r#"<path class="post-notch" d="{}" fill="none" stroke="{CUT_GREY}" stroke-width="0.1" stroke-dasharray="0.6 0.4"/>"#,
            d.trim_end()
        );
    }

    // Labels outside the cut line: the id above the top edge, "apex" below the apex vertex.
    let top = pentagon.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    let bottom = pentagon.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
    let _ = writeln!(
        svg,
        r#"<text class="tag-label" x="{}" y="{}" font-family="{FONT_FAMILY}" font-size="{}" text-anchor="middle">id {} → face {}</text>"#,
        num(origin.x),
        num(top - 1.0),
        num(LABEL_FONT),
        tag.id,
        tag.face
    );
    let apex_text = if notch.is_some() { "apex ▲ · cut out the dashed notch" } else { "apex ▲" };
    let _ = writeln!(
        svg,
        r#"<text class="apex-label" x="{}" y="{}" font-family="{FONT_FAMILY}" font-size="{}" text-anchor="middle">{}</text>"#,
        num(pentagon[0].x),
        num(bottom + 0.8 + 0.8 * LABEL_FONT),
        num(0.8 * LABEL_FONT),
        esc(apex_text)
    );
    svg.push_str("</g>\n");
    Ok(())
}

/// A 10 mm bar with millimetre ticks and a 100 mm bar with centimetre ticks, labelled, to
/// check the printer's scaling.
fn scale_bar(svg: &mut String) {
    let _ = writeln!(svg, r#"<g class="scale">"#);
    let bars = [
        (
            "scale-bar",
            SCALE_BAR_MM,
            SCALE_Y,
            1.0,
            "10 mm — check your printer's scaling: this bar must measure 10.0 mm.",
        ),
        ("scale-bar-100mm", 10.0 * SCALE_BAR_MM, LONG_SCALE_Y, 10.0, "must measure 100.0 mm (±0.3)"),
    ];
    for (id, length, y, step, note) in bars {
        let (x0, x1) = (MARGIN, MARGIN + length);
        // Butt caps: the drawn line is exactly as long as it says.
        let _ = writeln!(
            svg,
            r##"<line id="{id}" x1="{}" y1="{}" x2="{}" y2="{}" stroke="#000000" stroke-width="0.3" stroke-linecap="butt"/>"##,
            num(x0),
            num(y),
            num(x1),
            num(y)
        );
        let mut ticks = String::new();
        for i in 0..=10 {
            let x = x0 + f64::from(i) * step;
            let len = match i {
                0 | 10 => 3.0,
                5 => 2.0,
                _ => 1.0,
            };
            let _ = write!(ticks, "M{} {} V{} ", num(x), num(y - len), num(y));
        }
        let _ = writeln!(
            svg,
            r##"<path class="scale-ticks" d="{}" stroke="#000000" stroke-width="0.1" fill="none"/>"##,
            ticks.trim_end()
        );
        for (x, value) in [(x0, 0.0), (x0 + 5.0 * step, 5.0 * step), (x1, length)] {
            let _ = writeln!(
                svg,
                r#"<text class="scale-label" x="{}" y="{}" font-family="{FONT_FAMILY}" font-size="2.5" text-anchor="middle">{}</text>"#,
                num(x),
                num(y + 3.5),
                num(value)
            );
        }
        let _ = writeln!(
            svg,
            r#"<text class="scale-note" x="{}" y="{}" font-family="{FONT_FAMILY}" font-size="3">{}</text>"#,
            num(x1 + 6.0),
            num(y + 1.0),
            esc(note)
        );
    }
    let _ = writeln!(
        svg,
        r#"<text class="scale-note" x="{}" y="{}" font-family="{FONT_FAMILY}" font-size="2.5">Print at 100 %, no fit-to-page. Matte paper or label stock, laser printer.</text>"#,
        num(MARGIN + SCALE_BAR_MM + 6.0),
        num(SCALE_Y + 5.5)
    );
    svg.push_str("</g>\n");
}

#[cfg(test)]
mod tests {
    use super::*;
    use jawtrack_marker::{DEFAULT_EDGE_MM, SolidKind};

    /// Absolute path data (M, L, H, V, Z) as a list of subpaths of points.
    fn parse_path(d: &str) -> Vec<Vec<Vector2<f64>>> {
        let spaced: String =
            d.chars().flat_map(|c| if c.is_ascii_alphabetic() { vec![' ', c, ' '] } else { vec![c] }).collect();
        let toks: Vec<&str> = spaced.split(|c: char| c.is_whitespace() || c == ',').filter(|t| !t.is_empty()).collect();
        let mut subpaths: Vec<Vec<Vector2<f64>>> = Vec::new();
        let mut cur = Vector2::zeros();
        let mut i = 0;
        let number = |i: usize| -> f64 { toks[i].parse().unwrap_or_else(|_| panic!("not a number: {}", toks[i])) };
        while i < toks.len() {
            let cmd = toks[i];
            i += 1;
            match cmd {
                "M" | "L" => {
                    cur = Vector2::new(number(i), number(i + 1));
                    i += 2;
                    if cmd == "M" {
                        subpaths.push(Vec::new());
                    }
                }
                "H" => {
                    cur.x = number(i);
                    i += 1;
                }
                "V" => {
                    cur.y = number(i);
                    i += 1;
                }
                "Z" => continue,
                other => panic!("unexpected path command {other}"),
            }
            subpaths.last_mut().expect("path starts with M").push(cur);
        }
        subpaths
    }

    fn attr(n: &roxmltree::Node, name: &str) -> f64 {
        n.attribute(name).unwrap_or_else(|| panic!("{name} missing")).parse().expect("number")
    }

    fn by_class<'a>(g: roxmltree::Node<'a, 'a>, class: &str) -> Vec<roxmltree::Node<'a, 'a>> {
        g.descendants().filter(|n| n.attribute("class") == Some(class)).collect()
    }

    /// Both bodies' sheets, with and without the post, of the default marker and of a cube
    /// marker (whose one-cell margins leave room for a 2 mm post).
    fn sheets() -> Vec<(Marker, BodyKind, String)> {
        let cube = Marker::nominal_on(SolidKind::Cube, TagFamily::TAG36H11, DEFAULT_EDGE_MM, None).expect("cube");
        let mut out = Vec::new();
        for (m, post) in [(Marker::default(), 4.0), (cube, 2.0)] {
            let params = HarnessParams { post_diameter: post, ..HarnessParams::default() };
            for kind in BodyKind::ALL {
                out.push((m.clone(), kind, tag_sheet_svg(&m, kind).expect("sheet")));
                out.push((m.clone(), kind, tag_sheet_svg_with_post(&m, kind, &params).expect("sheet")));
            }
        }
        out
    }

    #[test]
    fn sheet_is_xml_in_millimetres_with_a_10_mm_bar() {
        for (_, _, svg) in sheets() {
            let doc = roxmltree::Document::parse(&svg).expect("valid XML");
            let root = doc.root_element();
            assert_eq!(root.tag_name().name(), "svg");
            assert_eq!(root.attribute("width"), Some("210mm"));
            assert_eq!(root.attribute("height"), Some("297mm"));
            assert_eq!(root.attribute("viewBox"), Some("0 0 210 297"), "1 user unit = 1 mm");
            let bar = doc.descendants().find(|n| n.attribute("id") == Some("scale-bar")).expect("scale bar");
            assert_eq!(attr(&bar, "y1"), attr(&bar, "y2"));
            assert!((attr(&bar, "x2") - attr(&bar, "x1") - 10.0).abs() < 1e-9);
            let long = doc.descendants().find(|n| n.attribute("id") == Some("scale-bar-100mm")).expect("long bar");
            assert!((attr(&long, "x2") - attr(&long, "x1") - 100.0).abs() < 1e-9);
            let text: String = doc.descendants().filter_map(|n| n.text()).collect();
            assert!(text.contains("100 %") && text.contains("no fit-to-page"), "print instruction");
            assert!(text.contains("check your printer's scaling"));
        }
    }

    #[test]
    fn pentagons_match_the_faces_and_cells_match_the_bitmaps() {
        let mut shapes = Vec::new();
        for (marker, kind, svg) in sheets() {
            shapes.push(marker.solid);
            let doc = roxmltree::Document::parse(&svg).expect("valid XML");
            let text: String = doc.descendants().filter_map(|n| n.text()).collect();
            assert!(text.contains(kind.name()), "body label");
            let groups: Vec<_> = doc.descendants().filter(|n| n.attribute("class") == Some("tag")).collect();
            assert_eq!(groups.len(), marker.solid.face_count());
            assert!(text.contains(&format!("{} edge", marker.solid)), "the solid named in the heading");
            for g in groups {
                let id: u32 = g.attribute("data-tag-id").expect("id").parse().expect("number");
                let (body, tag) = marker.find_tag(id).expect("a tag of the marker");
                assert_eq!(body, kind);

                // The face: a pentagon or a square, each edge the marker's edge.
                let face = by_class(g, "face");
                let pent = parse_path(face[0].attribute("d").expect("d")).remove(0);
                let sides = marker.solid.face_sides();
                assert_eq!(pent.len(), sides);
                for i in 0..sides {
                    let len = (pent[(i + 1) % sides] - pent[i]).norm();
                    assert!((len - marker.edge).abs() < 1e-6, "tag {id} edge {i}: {len}");
                }
                assert_eq!(
                    by_class(g, "cut-line")[0].attribute("d"),
                    face[0].attribute("d"),
                    "cut line on the outline"
                );
                for p in &pent {
                    assert!(p.x > 5.0 && p.x < 205.0 && p.y > 5.0 && p.y < 292.0, "on the printable page");
                }

                // The square: the tag's size, upright, where the tag's corners are on the face.
                let rect = by_class(g, "tag-black")[0];
                let (x0, y0, w, h) = (attr(&rect, "x"), attr(&rect, "y"), attr(&rect, "width"), attr(&rect, "height"));
                assert!((w - tag.size).abs() < 1e-9 && (h - tag.size).abs() < 1e-9);
                // Detection order: bottom-left, bottom-right, top-right, top-left (y down).
                let svg_corners = [
                    Vector2::new(x0, y0 + h),
                    Vector2::new(x0 + w, y0 + h),
                    Vector2::new(x0 + w, y0),
                    Vector2::new(x0, y0),
                ];
                // Same distances to the same pentagon vertices as on the solid: the printed
                // layout is congruent to the face, neither mirrored nor turned.
                for (c2, c3) in svg_corners.iter().zip(&tag.corners) {
                    for (p2, p3) in pent.iter().zip(&tag.face_polygon) {
                        assert!(((c2 - p2).norm() - (c3 - p3).norm()).abs() < 1e-6, "tag {id} layout");
                    }
                }

                // The cells, read back.
                let cell = tag.size / 8.0;
                let mut white = [[false; 8]; 8];
                for sub in parse_path(by_class(g, "tag-white")[0].attribute("d").expect("d")) {
                    let (lo, hi) = sub
                        .iter()
                        .fold((Vector2::repeat(f64::INFINITY), Vector2::repeat(f64::NEG_INFINITY)), |(lo, hi), p| {
                            (lo.inf(p), hi.sup(p))
                        });
                    assert!((hi.x - lo.x - cell).abs() < 1e-6 && (hi.y - lo.y - cell).abs() < 1e-6, "one cell");
                    let cx = (lo.x - x0) / cell;
                    let cy = (lo.y - y0) / cell;
                    assert!((cx - cx.round()).abs() < 1e-6 && (cy - cy.round()).abs() < 1e-6, "on the grid");
                    let (cx, cy) = (cx.round() as usize, cy.round() as usize);
                    assert!(!white[cy][cx], "cell drawn twice");
                    white[cy][cx] = true;
                }
                let bm = TagFamily::TAG36H11.bitmap(id).expect("known id");
                for (y, row) in white.iter().enumerate() {
                    for (x, &w) in row.iter().enumerate() {
                        assert_eq!(w, bm.is_white(x, y), "tag {id} cell ({x}, {y})");
                    }
                }

                // Labels outside the pentagon: the id above its top, "apex" below its apex.
                let top = pent.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
                let bottom = pent.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
                let label = by_class(g, "tag-label")[0];
                assert!(label.text().expect("text").contains(&format!("id {id} ")));
                assert!(attr(&label, "y") < top - CUT_STROKE, "id label outside the cut line");
                let apex = by_class(g, "apex-label")[0];
                assert!(attr(&apex, "y") - attr(&apex, "font-size") > bottom + CUT_STROKE, "apex label outside");
                assert!((pent[0].y - bottom).abs() < 1e-9, "the apex is the lowest vertex on the page");
            }
        }
        assert_eq!(shapes.iter().filter(|&&k| k == SolidKind::Cube).count(), 4, "four cube sheets checked");
        assert_eq!(shapes.len(), 8, "sheets checked");
    }

    #[test]
    fn the_post_notch_is_marked_on_the_bottom_faces_only() {
        let marker = Marker::default();
        let svg = tag_sheet_svg_with_post(&marker, BodyKind::Mandible, &HarnessParams::default()).expect("sheet");
        let doc = roxmltree::Document::parse(&svg).expect("valid XML");
        let mut faces = Vec::new();
        for g in doc.descendants().filter(|n| n.attribute("class") == Some("tag")) {
            let Some(notch) = by_class(g, "post-notch").first().copied() else { continue };
            faces.push(g.attribute("data-face").expect("face").parse::<usize>().expect("number"));
            let arc = parse_path(notch.attribute("d").expect("d")).remove(0);
            let pent = parse_path(by_class(g, "face")[0].attribute("d").expect("d")).remove(0);
            let rect = by_class(g, "tag-black")[0];
            // The arc runs from one edge at the apex to the other, below the black square.
            assert!(
                (arc[0] - pent[0]).norm() < 0.6 * marker.edge
                    && (arc[arc.len() - 1] - pent[0]).norm() < 0.6 * marker.edge
            );
            for p in &arc {
                assert!(p.y > attr(&rect, "y") + attr(&rect, "height"), "clear of the square");
            }
        }
        assert_eq!(faces, [9, 10, 11]);
        assert!(!tag_sheet_svg(&marker, BodyKind::Mandible).expect("sheet").contains("post-notch"));
    }

    #[test]
    fn unusable_markers_say_why() {
        let huge = Marker::nominal(80.0, None).expect("valid marker");
        assert!(matches!(tag_sheet_svg(&huge, BodyKind::Maxilla), Err(HarnessError::SheetTooSmall { .. })));
        let mut one = Marker::default();
        one.bodies.retain(|b| b.kind == BodyKind::Maxilla);
        assert!(matches!(tag_sheet_svg(&one, BodyKind::Mandible), Err(HarnessError::MissingBody(BodyKind::Mandible))));
        let mut odd = Marker::default();
        odd.bodies[0].tags[0].id = 5000;
        let err = tag_sheet_svg(&odd, BodyKind::Maxilla).expect_err("id 5000");
        assert!(matches!(err, HarnessError::UnknownTag { id: 5000, .. }), "{err}");
        assert!(err.to_string().contains("not in the tag36h11 family (ids 0–586)"), "{err}");
        let too_thick = HarnessParams { post_diameter: 30.0, ..HarnessParams::default() };
        let err = tag_sheet_svg_with_post(&Marker::default(), BodyKind::Maxilla, &too_thick).expect_err("too thick");
        assert!(err.to_string().contains("post_diameter"), "{err}");
    }

    #[test]
    fn numbers_are_plain() {
        assert_eq!(num(10.0), "10");
        assert_eq!(num(-0.0000000001), "0");
        assert_eq!(num(1.25), "1.25");
        assert_eq!(num(-3.5), "-3.5");
    }
}
