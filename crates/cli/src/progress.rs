//! The CLI's one progress bar: what is being done, how far, the time so far and, when the
//! length is known, the time to go. indicatif draws it on stderr only when that is a terminal.

use indicatif::{ProgressBar, ProgressStyle};

/// A bar labelled `what` over `len` items called `unit` (e.g. "frames"; empty for none), or a
/// counter when the length is not known.
pub(crate) fn bar(what: &str, len: Option<u64>, unit: &str) -> ProgressBar {
    let unit = if unit.is_empty() { String::new() } else { format!(" {unit}") };
    let template = match len {
        Some(_) => format!("{{msg}} [{{bar:30}}] {{pos}}/{{len}}{unit}, {{elapsed}} elapsed, ~{{eta}} left"),
        None => format!("{{msg}} {{pos}}{unit}, {{elapsed}} elapsed"),
    };
    let bar = ProgressBar::new(len.unwrap_or(0));
    bar.set_style(
        ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar()).progress_chars("=> "),
    );
    bar.set_message(what.to_owned());
    bar
}

/// A bar over `len` items labelled `what`.
pub(crate) fn progress_bar(what: &str, len: usize) -> ProgressBar {
    bar(what, Some(len as u64), "")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bar_counts_with_or_without_a_length() {
        let known = bar("tracking", Some(10), "frames");
        known.inc(3);
        assert_eq!((known.position(), known.length()), (3, Some(10)));
        let unknown = bar("tracking", None, "frames");
        unknown.inc(2);
        assert_eq!(unknown.position(), 2);
    }
}
