//! The staging file a measured bake writes beside its output ([`Staging`]), so that a stop
//! during the accuracy report leaves the output as it was.

use std::path::Path;

use crate::error::{Error, Result};
use crate::store::db;

use super::BakeTarget;

/// A streamed table written beside its output before it is measured (removed when dropped
/// unless committed): a stop during the accuracy report leaves the output as it was.
pub(super) struct Staging(std::path::PathBuf);

impl Staging {
    /// Beside the file `output` names (where it is a link, beside its target, which the
    /// commit renames over: the same file system).
    pub(super) fn beside(output: &Path) -> Result<Staging> {
        let out = crate::files::resolve_links(output)?;
        Ok(Staging(crate::files::temp_path(&out)?))
    }

    /// The staging file's path.
    pub(super) fn path(&self) -> &Path {
        &self.0
    }

    /// Moves the measured table into `target`: renamed over a file, imported (its chunks
    /// copied as they are) into a database — a copy `progress` may stop, the database then
    /// as it was.
    pub(super) fn commit(
        self,
        target: &BakeTarget,
        name: &str,
        progress: &dyn crate::progress::Progress,
    ) -> Result<()> {
        match target {
            BakeTarget::Db { path, replace, .. } => {
                let store = crate::store::Store::open(&self.0)?;
                db::import_with(path, &store, name, name, *replace, progress)
            }
            t => {
                let out = crate::files::resolve_links(t.path())?;
                crate::files::rename_over(&self.0, &out).map_err(|e| Error::io(&out, e))
            }
        }
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}
