//! The parameterization of an existing `.bsdf` file ([`Parameterization`]), read back so that a
//! re-encoded file's values are resampled where they were stored.

use std::path::Path;

use crate::error::{Error, Result};

/// The parameterization of an existing `.bsdf` file: its incident directions, NDF, σ and VNDF
/// slices, and its reflectance resolution.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameterization {
    /// Incident azimuths.
    pub phi_i: Vec<f32>,
    /// Incident elevations.
    pub theta_i: Vec<f32>,
    /// NDF/σ shape [rows, columns].
    pub ndf_shape: [usize; 2],
    /// The NDF.
    pub ndf: Vec<f32>,
    /// The projected area.
    pub sigma: Vec<f32>,
    /// VNDF slice shape [rows, columns].
    pub vndf_shape: [usize; 2],
    /// The VNDF slices, φi × θi × rows × columns.
    pub vndf: Vec<f32>,
    /// The file's reflectance resolution.
    pub resolution: usize,
    /// The file's channels (`None`: RGB, else its wavelengths) and stored values
    /// (φi × θi × channels × N × N): kept as they are at the grid points whose ωo is below the
    /// horizon, where no source can be evaluated (they matter only as corners of cells readers
    /// interpolate in), when the source has the same channels and N.
    pub values: (Option<Vec<f32>>, Vec<f32>),
}

impl Parameterization {
    /// Reads the parameterization of a `.bsdf` file.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Self> {
        Self::from_tensor(&crate::measured::tensor::TensorFile::open(path)?)
    }

    /// Reads the parameterization of a parsed tensor file (the shapes are checked as the
    /// reader checks them).
    pub fn from_tensor(tf: &crate::measured::tensor::TensorFile) -> Result<Self> {
        // The reader validates every shape and value range; reuse it as the check.
        crate::measured::RglBrdf::from_tensor(tf, None)?;
        let get = |name: &str| -> Result<(Vec<usize>, Vec<f32>)> {
            let f = tf.field(name)?;
            Ok((f.shape.clone(), tf.to_f32(f)?))
        };
        let (_, phi_i) = get("phi_i")?;
        let (_, theta_i) = get("theta_i")?;
        let (ns, ndf) = get("ndf")?;
        let (_, sigma) = get("sigma")?;
        let (vs, vndf) = get("vndf")?;
        let table = tf
            .get("rgb")
            .or_else(|| tf.get("spectra"))
            .ok_or_else(|| Error::format(tf.file_name(), Some("rgb"), None, "missing"))?;
        let resolution = table.shape[3];
        let square = table.shape[3] == table.shape[4];
        let wavelengths = match tf.get("wavelengths") {
            Some(w) if table.name == "spectra" => Some(tf.to_f32(w)?),
            _ => None,
        };
        let values = (wavelengths, tf.to_f32(table)?);
        if !square || vs.len() != 4 || ns.len() != 2 {
            return Err(Error::Unsupported(format!(
                "{}: only square reflectance tables can be re-encoded",
                tf.file_name()
            )));
        }
        Ok(Parameterization {
            phi_i,
            theta_i,
            ndf_shape: [ns[0], ns[1]],
            ndf,
            sigma,
            vndf_shape: [vs[2], vs[3]],
            vndf,
            resolution,
            values,
        })
    }
}
