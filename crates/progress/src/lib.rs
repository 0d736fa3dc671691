//! The one progress bar of JawTrack's command-line tools (`jawtrack`, `jawtrack-bench`, the
//! tracker benchmark): what is being done, how far, the time so far and, when the length is
//! known, the time to go. indicatif draws it on stderr only when that is a terminal, so piped
//! and CI output stays clean.
//!
//! # Examples
//!
//! ```
//! let bar = jawtrack_progress::bar("tracking", Some(3), "frames");
//! for _ in 0..3 {
//!     bar.inc(1);
//! }
//! bar.finish_and_clear();
//! assert_eq!(bar.position(), 3);
//! ```

use indicatif::{HumanDuration, ProgressState, ProgressStyle};
use std::fmt::Write;

pub use indicatif::ProgressBar;

/// The bar's width in characters.
const WIDTH: usize = 30;

/// Whether the bar has a length to draw against: indicatif draws a length of 0 as a full bar.
fn sized(s: &ProgressState) -> bool {
    s.len().is_some_and(|len| len > 0)
}

/// A bar labelled `what` over `len` items called `unit` (e.g. "frames"; empty for none), or a
/// counter while the length is not known or 0; a length set later turns the counter into the bar.
pub fn bar(what: &str, len: Option<u64>, unit: &str) -> ProgressBar {
    let unit = if unit.is_empty() { String::new() } else { format!(" {unit}") };
    let template = format!("{{msg}} {{progress}}{unit}, {{elapsed}} elapsed{{left}}");
    let style = ProgressStyle::with_template(&template)
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .with_key("progress", |s: &ProgressState, w: &mut dyn Write| {
            let _ = match s.len() {
                Some(len) if sized(s) => {
                    let done = ((s.fraction() * WIDTH as f32) as usize).min(WIDTH);
                    let head = if done < WIDTH { ">" } else { "" };
                    let rest = WIDTH - done - head.len();
                    write!(w, "[{}{head}{}] {}/{len}", "=".repeat(done), " ".repeat(rest), s.pos())
                }
                _ => write!(w, "{}", s.pos()),
            };
        })
        .with_key("left", |s: &ProgressState, w: &mut dyn Write| {
            if sized(s) {
                let _ = write!(w, ", ~{:#} left", HumanDuration(s.eta()));
            }
        });
    let bar = ProgressBar::new(len.unwrap_or(0));
    bar.set_style(style);
    bar.set_message(what.to_owned());
    bar
}

#[cfg(test)]
mod tests {
    use super::*;
    use indicatif::{ProgressDrawTarget, TermLike};
    use std::sync::{Arc, Mutex};

    #[test]
    fn a_bar_counts_with_or_without_a_length() {
        let known = bar("tracking", Some(10), "frames");
        known.inc(3);
        assert_eq!((known.position(), known.length()), (3, Some(10)));
        let unknown = bar("tracking", None, "frames");
        unknown.inc(2);
        assert_eq!(unknown.position(), 2);
    }

    /// A terminal that keeps the line drawn last.
    #[derive(Debug, Clone, Default)]
    struct Screen(Arc<Mutex<String>>);

    impl TermLike for Screen {
        fn width(&self) -> u16 {
            120
        }
        fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn write_line(&self, s: &str) -> std::io::Result<()> {
            self.write_str(s)
        }
        fn write_str(&self, s: &str) -> std::io::Result<()> {
            self.0.lock().expect("screen").push_str(s);
            Ok(())
        }
        fn clear_line(&self) -> std::io::Result<()> {
            self.0.lock().expect("screen").clear();
            Ok(())
        }
        fn flush(&self) -> std::io::Result<()> {
            Ok(())
        }
    }

    /// What a bar over `len` shows at `pos`, its length set to `later` once drawn if given.
    fn drawn(len: Option<u64>, pos: u64, later: Option<u64>) -> String {
        let screen = Screen::default();
        let b = bar("rendering", len, "frames");
        b.set_draw_target(ProgressDrawTarget::term_like(Box::new(screen.clone())));
        b.set_position(pos);
        b.tick();
        if let Some(len) = later {
            b.set_length(len);
            b.tick();
        }
        screen.0.lock().expect("screen").clone()
    }

    #[test]
    fn a_bar_is_never_full_before_there_is_anything_to_do() {
        let empty = drawn(Some(0), 0, None);
        assert!(!empty.contains("==") && empty.contains("rendering 0 frames"), "{empty}");
        let unknown = drawn(None, 2, None);
        assert!(!unknown.contains('[') && unknown.contains("rendering 2 frames"), "{unknown}");
        let half = drawn(Some(10), 5, None);
        assert!(half.contains(&format!("[{}>", "=".repeat(15))) && half.contains("5/10 frames"), "{half}");
        let known_later = drawn(Some(0), 5, Some(10));
        assert!(known_later.contains("5/10 frames") && known_later.contains("left"), "{known_later}");
    }
}
