//! Converting a SOURCE to an RGL `.bsdf` file ([`to_rgl`]): not a table bake, but the other
//! file `convert` writes, here so that every host converts the same way.

use crate::error::Result;
use crate::measured::rgl_write;
use crate::progress::Progress;
use crate::source::{self, OpenOptions};
use crate::spectrum::Channels;

/// What [`to_rgl`] did: the file written, the source's description, the seconds it took and,
/// when asked for, the error of the file read back against the source.
#[derive(Debug, Clone)]
pub struct Converted {
    /// The file written.
    pub written: rgl_write::Written,
    /// The source's description.
    pub source: String,
    /// Wall-clock seconds of the encoding and writing.
    pub seconds: f64,
    /// The written file (through brdftab's reader) against the source, within 80°.
    pub error: Option<rgl_write::Report>,
}

/// Opens SOURCE (with `channels`, `None` = its own), writes it to `output` as an RGL file (a
/// `.bsdf` source keeps its own layout unless `opts` change it, see
/// [`rgl_write::Options::reuse_source_file`]) and, with `pairs > 0`, reports the written file's error.
pub fn to_rgl(
    source: impl AsRef<std::ffi::OsStr>,
    channels: Option<Channels>,
    output: impl AsRef<std::path::Path>,
    opts: &rgl_write::Options,
    pairs: usize,
    progress: &dyn Progress,
) -> Result<Converted> {
    let (source, output) = (source.as_ref(), output.as_ref());
    let open = OpenOptions {
        channels,
        ..Default::default()
    };
    crate::files::refuse_input(output, &[source])?;
    let brdf = source::open_with(source, &open)?;
    crate::table::fill::tabulable(brdf.as_ref())?;
    let opts = opts.clone().reuse_source_file(source)?;
    let t = std::time::Instant::now();
    let fields = rgl_write::encode(&*brdf, &opts, progress)?;
    // A source that failed while it was read (a corrupt table chunk) gave zeros: write nothing.
    brdf.health()?;
    let bytes = fields.to_bytes();
    let mut seconds = t.elapsed().as_secs_f64();
    // The file's error is measured on its bytes before they are written, so that a stop asked
    // during the report (seconds) leaves `output` as it was.
    let error = match pairs {
        0 => None,
        n => {
            let tf = crate::measured::tensor::TensorFile::from_bytes(
                output.to_string_lossy(),
                bytes.clone(),
            )?;
            let file = crate::measured::RglBrdf::from_tensor(&tf, None)?;
            Some(rgl_write::report_with(&file, &*brdf, n, 1, progress)?)
        }
    };
    let t = std::time::Instant::now();
    crate::files::write_atomic(output, &bytes)?;
    seconds += t.elapsed().as_secs_f64();
    let written = rgl_write::Written {
        bytes: bytes.len(),
        fields,
    };
    Ok(Converted {
        written,
        source: brdf.describe(),
        seconds,
        error,
    })
}
