//! Where a command writes a recording or a result: never over an existing file unless the
//! user gave `--force`, and the refusal says so, before any work is done.

use anyhow::bail;
use jawtrack_recording::{Overwrite, RecordingError};
use std::path::Path;

/// The `--force` flag of commands that write a recording or a result.
#[derive(clap::Args, Clone, Copy, Debug)]
pub(crate) struct ForceArgs {
    /// Replace what --out already holds (by default an existing output is never overwritten).
    #[arg(long)]
    pub(crate) force: bool,
}

impl ForceArgs {
    pub(crate) fn overwrite(self) -> Overwrite {
        if self.force { Overwrite::Replace } else { Overwrite::Refuse }
    }

    /// Refuses an existing output file, unless --force; `-` (standard output) is never refused.
    pub(crate) fn check_file(self, path: &Path) -> anyhow::Result<()> {
        if !self.force && path.as_os_str() != "-" && path.exists() {
            bail!("{} already exists: give another name, or add --force to replace it", path.display());
        }
        Ok(())
    }

    /// Refuses to write into the folder `dir` when it already holds one of the outputs
    /// `names`, unless --force.
    pub(crate) fn check_folder(self, dir: &Path, names: &[&str]) -> anyhow::Result<()> {
        if let Some(name) = names.iter().find(|n| dir.join(n).exists()).filter(|_| !self.force) {
            bail!(
                "{} already holds {name} from an earlier run: give another folder, or add --force to replace its results",
                dir.display()
            );
        }
        Ok(())
    }

    /// Writes `bytes` to `path` whole or not at all (`jawtrack_recording::write_file_atomic`),
    /// replacing an existing file only with --force.
    pub(crate) fn write_file(self, path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
        jawtrack_recording::write_file_atomic(path, bytes, self.overwrite()).map_err(|e| self.explain(e))
    }

    /// `e`, with the way out when it is a refusal to overwrite.
    pub(crate) fn explain(self, e: RecordingError) -> anyhow::Error {
        match e {
            RecordingError::Exists { .. } => anyhow::anyhow!("{e} (add --force to replace it)"),
            other => other.into(),
        }
    }
}
