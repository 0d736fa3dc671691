//! Writes a fixture folder's frames as binary PGM (P5) luma, for tests in languages with no PNG
//! decoder at hand (the iPhone app's Swift tests on Linux read them with a few lines).
//!
//!     cargo run -p jawtrack-test-support --example luma-pgm -- fixtures/static-1080p OUT_DIR

use std::path::{Path, PathBuf};
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [input, output] = args.as_slice() else {
        eprintln!("usage: luma-pgm FIXTURE_DIR OUT_DIR");
        return ExitCode::from(2);
    };
    match convert(Path::new(input), Path::new(output)) {
        Ok(n) => {
            println!("{n} frames written to {output}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("luma-pgm: {e}");
            ExitCode::FAILURE
        }
    }
}

fn convert(input: &Path, output: &Path) -> Result<usize, String> {
    let mut frames: Vec<PathBuf> = std::fs::read_dir(input)
        .map_err(|e| format!("{}: {e}", input.display()))?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    frames.sort();
    if frames.is_empty() {
        return Err(format!("{}: no PNG frames", input.display()));
    }
    std::fs::create_dir_all(output).map_err(|e| format!("{}: {e}", output.display()))?;
    for frame in &frames {
        let luma = image::open(frame).map_err(|e| format!("{}: {e}", frame.display()))?.into_luma8();
        let name = frame.with_extension("pgm");
        let target = output.join(name.file_name().unwrap_or_default());
        // P5 written out: image's own PNM encoder picks P7 (PAM) for a .pgm name.
        let mut bytes = format!("P5\n{} {}\n255\n", luma.width(), luma.height()).into_bytes();
        bytes.extend_from_slice(luma.as_raw());
        std::fs::write(&target, bytes).map_err(|e| format!("{}: {e}", target.display()))?;
    }
    Ok(frames.len())
}
