//! Reports: the accuracy suite (tables vs their sources, per grid and codec) and its plots.
//!
//! - [`suite`]: which sources, grids and codecs; running them ([`suite::run`]); the rows and
//!   their CSV and Markdown forms;
//! - [`measured`]: RGL files against their default tables (error, bytes, memory, speed);
//! - [`plot`]: rate–distortion PNGs (error vs bytes stored) with plotters and an embedded font.

pub mod measured;
pub mod plot;
pub mod suite;

pub use suite::{CodecDef, Report, Row, SourceDef, SuiteConfig, run};

use std::path::{Path, PathBuf};

use brdftab::error::{Error, Result};

// Here rather than in `suite`, so that `plot` (which draws suite rows) and `suite` do not import
// each other.
impl Report {
    /// Writes `accuracy.csv`, `accuracy.md` and one rate–distortion PNG per source
    /// (`rd_<source>.png`) into `dir` (created if missing). Returns the files written.
    pub fn write_all(&self, dir: impl AsRef<Path>) -> Result<Vec<PathBuf>> {
        let dir = dir.as_ref();
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let mut out = Vec::new();
        let csv = dir.join("accuracy.csv");
        std::fs::write(&csv, self.csv()).map_err(|e| Error::io(&csv, e))?;
        out.push(csv);
        let md = dir.join("accuracy.md");
        std::fs::write(&md, self.markdown()).map_err(|e| Error::io(&md, e))?;
        out.push(md);
        let mut sources: Vec<&str> = Vec::new();
        for r in &self.rows {
            if !sources.contains(&r.source.as_str()) {
                sources.push(&r.source);
            }
        }
        for s in sources {
            let rows: Vec<&Row> = self.rows.iter().filter(|r| r.source == s).collect();
            let p = dir.join(format!("rd_{}.png", suite::file_safe(s)));
            plot::rate_distortion(s, &rows, &p)?;
            out.push(p);
        }
        Ok(out)
    }
}
