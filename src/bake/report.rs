//! What a bake tells its caller: [`BakeReport`] — the grid, the notes and warnings, what was
//! written, and the lines a CLI prints — and [`Accuracy`], the written table against its source.

use std::time::Instant;

use crate::brdf::Brdf;
use crate::codec::Codec;
use crate::error::Result;
use crate::table::Grid;
use crate::table::target::TargetSearch;

use super::BakeRequest;
use super::choices::BakeTarget;

/// What a bake did and what was written.
#[derive(Debug, Clone)]
pub struct BakeReport {
    /// The source's description.
    pub source: String,
    /// The table's name.
    pub name: String,
    /// What was written: a file, `DB#NAME`, or a raw file, as text (a path that is not UTF-8
    /// shown lossily; [`written`](Self::written) is the path itself).
    pub output: String,
    /// The grid baked on.
    pub grid: Grid,
    /// Stored values.
    pub values: u64,
    /// Wall-clock seconds of the bake.
    pub seconds: f64,
    /// Set when symmetry detection disagreed with what the source declares.
    pub symmetry_note: Option<String>,
    /// The symmetry violation that `force` overrode, if any.
    pub forced: Option<String>,
    /// True when a MERL file's own cells were stored (no resampling).
    pub merl_cells: bool,
    /// The written table against its source, when asked for.
    pub accuracy: Option<Accuracy>,
    /// What `brdftab info --json` reports of the written table (null for raw files).
    pub info: serde_json::Value,
    /// The error-target search that chose the grid, if the request had a target.
    pub target: Option<TargetSearch>,
    /// Where it was written (`None` for a table built in memory, [`BakeRequest::table`]): the
    /// file's path as a path, which `output`, the display string, is not for a database entry
    /// (`DB#NAME`).
    pub written: Option<BakeTarget>,
}

impl BakeReport {
    /// What `brdftab info --json` reports of the written brdftab file — every table of a
    /// single-table file, the entry of a database — read from the path written (`Null` for a
    /// raw or MERL file, or nothing written). Not `info::file_info(&output)`: a `DB#NAME` string
    /// is looked up whole first, and a file named `db.btdb#m` beside the database would be read.
    pub fn output_info(&self) -> Result<serde_json::Value> {
        match &self.written {
            Some(BakeTarget::File(path)) => crate::store::info::file_info_at(path, None),
            Some(BakeTarget::Db { path, name, .. }) => {
                crate::store::info::file_info_at(path, Some(name))
            }
            _ => Ok(serde_json::Value::Null),
        }
    }

    /// The grid line of a report: the grid's summary, and whether a MERL file's cells were kept.
    pub fn grid_line(&self) -> String {
        let cells = if self.merl_cells {
            ", the file's own cells"
        } else {
            ""
        };
        format!("{}{cells}", self.grid.summary())
    }

    /// What the bake did, in a few lines for people: notes and warnings first, then the source,
    /// grid, reduction, output and throughput (`codec` names the quantization).
    pub fn summary(&self, codec: &Codec) -> String {
        let mut s = String::new();
        if let Some(n) = &self.symmetry_note {
            s += &format!("note: {n}\n");
        }
        if let Some(f) = &self.forced {
            s += &format!("warning: forced past a symmetry violation: {f}\n");
        }
        if let Some(t) = &self.target {
            let kind = if t.met { "note" } else { "warning" };
            s += &format!("{kind}: {}\n", t.summary());
        }
        let full = self.grid.full_values();
        s += &format!(
            "baked {}\n  grid: {}\n  {} stored values ({full} unreduced, {:.1}x reduction)\n",
            self.source,
            self.grid_line(),
            self.values,
            full as f64 / self.values.max(1) as f64
        );
        s + &format!(
            "wrote {} ({} values in {:.2} s, {:.1} M values/s, codec {})\n",
            self.output,
            self.values,
            self.seconds,
            self.values as f64 / self.seconds.max(1e-9) / 1e6,
            codec.quant.name()
        )
    }
}

/// Cosine-weighted accuracy of a table against its source.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Accuracy {
    /// Random pairs compared.
    pub pairs: usize,
    /// Relative RMSE of f_r weighted by cos θi cos θo, whole hemisphere.
    pub rel_rmse: f64,
    /// Largest relative error, whole hemisphere.
    pub max_rel: f64,
    /// The same RMSE with both directions within 80° of the normal (Ngan et al.'s cut; the
    /// grazing f_r of measured data grows as 1/cos θo).
    pub rel_rmse_80: f64,
    /// Largest relative error within 80°.
    pub max_rel_80: f64,
}

impl Accuracy {
    /// Compares `table` with `source` on `pairs` random pairs (seed 1); zero pairs is an
    /// argument error (its zero error read as a perfect match).
    pub fn measure(table: &dyn Brdf, source: &dyn Brdf, pairs: usize) -> Result<Accuracy> {
        Self::measure_with(table, source, pairs, &crate::progress::Silent)
    }

    /// [`measure`](Self::measure), asking `progress` to stop before each block of pairs
    /// ([`crate::progress::Progress::cancelled`]: [`crate::Error::Cancelled`]).
    pub fn measure_with(
        table: &dyn Brdf,
        source: &dyn Brdf,
        pairs: usize,
        progress: &dyn crate::progress::Progress,
    ) -> Result<Accuracy> {
        if pairs == 0 {
            return Err(crate::Error::arg("pairs", "0: no pairs to measure on"));
        }
        // Both cosines: f_r cos θi has no finite RMS for measured data, Ward or Cook-Torrance
        // (the figure the struct's fields say; it read f_r cos θi until session 26).
        use crate::analysis::accuracy::{Region, Weight, compare_region_with};
        let w = Weight::CosInCosOut;
        let cmp =
            |t: f64| compare_region_with(table, source, pairs, 1, Region::Cap(t), w, progress);
        let all = cmp(std::f64::consts::FRAC_PI_2)?;
        let cap = cmp(80f64.to_radians())?;
        Ok(Accuracy {
            pairs: all.pairs,
            rel_rmse: all.rel_rmse,
            max_rel: all.max_rel,
            rel_rmse_80: cap.rel_rmse,
            max_rel_80: cap.max_rel,
        })
    }
}

impl BakeRequest {
    pub(super) fn report_for(
        &self,
        src: &dyn Brdf,
        grid: &Grid,
        note: Option<String>,
        t0: Instant,
        merl_cells: bool,
    ) -> BakeReport {
        BakeReport {
            source: src.describe(),
            name: String::new(),
            output: String::new(),
            grid: grid.clone(),
            values: grid.stored_values() as u64,
            seconds: t0.elapsed().as_secs_f64(),
            symmetry_note: note,
            forced: None,
            merl_cells,
            accuracy: None,
            info: serde_json::Value::Null,
            target: None,
            written: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::tmp;
    use crate::progress::Silent;
    use crate::table::presets::Preset;

    /// The report's file info (what Python's `bake` and `convert` return) is read from the path
    /// written: a file named `db.btdb#m` beside the database is what the string `db.btdb#m`
    /// names as a SOURCE (`info` of it reads that file), not the entry the bake wrote.
    #[test]
    fn the_reports_file_info_is_of_the_path_written() {
        let d = tmp("info");
        let path = |f: &str| d.join(f).to_str().unwrap().to_owned();
        let req = BakeRequest::new(r#"{"model":"lambert","kd":0.3}"#).preset(Preset::Small);
        req.run(&BakeTarget::file(path("decoy.btdb"))).unwrap();
        std::fs::copy(path("decoy.btdb"), path("db.btdb#m")).unwrap();
        let r = req.run(&BakeTarget::db(path("db.btdb"), "m")).unwrap();
        assert_eq!(r.output, path("db.btdb#m"));
        let as_source = crate::store::info::file_info(&r.output).unwrap();
        assert_eq!(as_source["tables"][0]["name"], "decoy");
        let info = r.output_info().unwrap();
        assert_eq!(info["file"], path("db.btdb"));
        assert_eq!(info["tables"][0]["name"], "m");
        assert_eq!(info["tables"].as_array().map(Vec::len), Some(1));
        // A single-table file: every table of it; a table built in memory: nothing.
        let f = req.run(&BakeTarget::file(path("x.btdb#x"))).unwrap();
        assert_eq!(f.output_info().unwrap()["file"], path("x.btdb#x"));
        let (_, mem) = req.table(&Silent).unwrap();
        assert!(mem.output_info().unwrap().is_null());
    }
}
