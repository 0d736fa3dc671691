//! Where a command writes a recording: never over an existing file unless the user gave
//! `--force`, and the refusal says so.

use jawtrack_recording::{Overwrite, RecordingError};

/// The `--force` flag of commands that write a recording.
#[derive(clap::Args, Clone, Copy, Debug)]
pub(crate) struct ForceArgs {
    /// Replace --out if it exists (by default an existing file is never overwritten).
    #[arg(long)]
    pub(crate) force: bool,
}

impl ForceArgs {
    pub(crate) fn overwrite(self) -> Overwrite {
        if self.force { Overwrite::Replace } else { Overwrite::Refuse }
    }

    /// `e`, with the way out when it is a refusal to overwrite.
    pub(crate) fn explain(self, e: RecordingError) -> anyhow::Error {
        match e {
            RecordingError::Exists { .. } => anyhow::anyhow!("{e} (add --force to replace it)"),
            other => other.into(),
        }
    }
}
