//! `jawtrack plan`: where and how to film with a given phone (`jawtrack_devices::plan`): the
//! camera, format and zoom, the distance to hold it at beyond where its lens can focus, and
//! the band the markers stay sharp in once focus is locked there. The app makes the same plan
//! from what the phone reports; this is for planning a session, or a phone the table lacks.

use anyhow::{Context, Result, bail};
use clap::Args;
use jawtrack_devices::{CameraFacts, Lens, PlanRequest, optics, plan};
use jawtrack_marker::Marker;
use std::path::PathBuf;

/// Arguments of `jawtrack plan`.
#[derive(Args)]
pub(crate) struct PlanArgs {
    /// The phone's hardware identifier (Settings › General › About does not show it; the app's
    /// recordings name it, e.g. `iPhone16,1` for an iPhone 15 Pro).
    #[arg(long, value_name = "MODEL")]
    phone: String,
    /// The nearest its wide camera focuses (mm), as the phone reports it
    /// (`AVCaptureDevice.minimumFocusDistance`); default: the device table's, else 200.
    #[arg(long, value_name = "MM", allow_hyphen_values = true)]
    min_focus_mm: Option<f64>,
    /// Frames per second (60 for chewing).
    #[arg(long, default_value_t = 60.0)]
    fps: f64,
    /// The marker file (its tag size); default: the nominal 12.7 mm marker.
    #[arg(long)]
    marker: Option<PathBuf>,
    /// Print the plan as JSON.
    #[arg(long)]
    json: bool,
}

pub(crate) fn run(a: &PlanArgs) -> Result<()> {
    if let Some(m) = a.min_focus_mm
        && !(m.is_finite() && (20.0..=2000.0).contains(&m))
    {
        bail!("--min-focus-mm must be within 20–2000 mm, got {m}");
    }
    let marker = match &a.marker {
        Some(p) => Marker::load(p)?,
        None => Marker::default(),
    };
    let tag_mm = marker.tags().next().map(|(_, t)| t.size).context("the marker file has no tags")?;
    let lens = optics(&a.phone, Lens::Wide);
    let camera = CameraFacts { reported_min_focus_mm: a.min_focus_mm, ..CameraFacts::typical(Lens::Wide, lens) };
    let p = plan(&[camera], &PlanRequest { fps: a.fps, ..PlanRequest::chewing(tag_mm) })?;
    if a.json {
        say!(
            "{}",
            serde_json::json!({
                "phone": lens.phone, "lens": "wide", "width": p.width, "height": p.height, "fps": p.fps,
                "zoom": p.zoom, "distance_mm": p.distance_mm, "near_mm": p.near_mm, "far_mm": p.far_mm,
                "min_focus_mm": p.min_focus_mm, "cell_px": p.cell_px, "fx_px": p.fx_px, "notes": p.notes,
            })
        );
        return Ok(());
    }
    say!("{} ({}): {}", lens.phone, a.phone.trim(), p.summary());
    say!(
        "keep the markers between {:.0} and {:.0} mm once focus is locked: nearer or farther they blur beyond a tenth of a cell",
        p.near_mm,
        p.far_mm
    );
    say!("optics: {:.2} mm at f/{}; {}", lens.focal_length_mm, lens.f_number, lens.source);
    for note in &p.notes {
        say!("note: {note}");
    }
    Ok(())
}
