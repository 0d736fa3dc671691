//! The report printed to PDF through headless Chromium.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Why the report could not be printed to PDF.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// No Chromium was found.
    #[error(
        "no Chromium to print the PDF with (set CHROMIUM, or install chromium); the HTML report {0} was written \
         and prints from any browser"
    )]
    NoChromium(String),
    /// The report's path could not be made absolute.
    #[error(transparent)]
    Path(std::io::Error),
    /// Chromium could not be started.
    #[error("starting {browser}")]
    Start {
        /// The browser.
        browser: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// Chromium ran but left no PDF.
    #[error("{browser} could not print {html}: {reason}")]
    Print {
        /// The browser.
        browser: String,
        /// The report.
        html: String,
        /// The last line Chromium wrote on its standard error.
        reason: String,
    },
}

/// The Chromium to print with: `CHROMIUM`, else the first of the usual names on the PATH.
pub fn chromium() -> Option<PathBuf> {
    if let Some(c) = std::env::var_os("CHROMIUM") {
        return Some(PathBuf::from(c));
    }
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser", "google-chrome", "google-chrome-stable"]
        .iter()
        .flat_map(|n| std::env::split_paths(&path).map(move |d| d.join(n)))
        .find(|p| p.is_file())
}

/// Prints the report `html` to `pdf` with headless Chromium ([`chromium`]), replacing `pdf`.
pub fn print_pdf(html: &Path, pdf: &Path) -> Result<(), ReportError> {
    let Some(browser) = chromium() else {
        return Err(ReportError::NoChromium(html.display().to_string()));
    };
    // What --force allowed to be replaced goes first, so an old file cannot pass for a print.
    let _ = std::fs::remove_file(pdf);
    let url = format!("file://{}", std::fs::canonicalize(html).map_err(ReportError::Path)?.display());
    // The page is ours, has no script and loads nothing, so the sandbox (which cannot start as
    // root) adds nothing here.
    let out = Command::new(&browser)
        .args(["--headless", "--disable-gpu", "--no-sandbox", "--no-pdf-header-footer"])
        .arg(format!("--print-to-pdf={}", pdf.display()))
        .arg(&url)
        .output()
        .map_err(|source| ReportError::Start { browser: browser.display().to_string(), source })?;
    let printed = std::fs::metadata(pdf).is_ok_and(|m| m.len() > 0);
    if !out.status.success() || !printed {
        return Err(ReportError::Print {
            browser: browser.display().to_string(),
            html: html.display().to_string(),
            reason: String::from_utf8_lossy(&out.stderr).lines().last().unwrap_or("no message").to_string(),
        });
    }
    Ok(())
}
