//! Comparing two renders: relative RMSE and a false-colour difference image.
//!
//! The relative RMSE is sqrt(Σ (a − b)² / Σ b²), summed over every pixel and channel, with `b`
//! the reference. It is a single number that is 0 for identical images, scale-invariant (so the
//! exposure does not matter), and weights bright pixels — where a viewer sees errors — most.
//! Two renders of the *same* material with different seeds give the noise floor: a comparison
//! can only resolve material differences well above it.

use super::image::{FalseColor, Image, false_color};
use brdftab::error::{Error, Result};

/// The result of [`compare`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompareResult {
    /// sqrt(Σ (a − b)² / Σ b²) over all pixels and channels (b = reference).
    pub rel_rmse: f64,
    /// sqrt(Σ (a − b)² / N), N = pixels × channels.
    pub rmse: f64,
    /// max |a − b| over all samples.
    pub max_abs: f64,
    /// Mean of a and of b over all samples (a ratio far from 1 points to an energy difference).
    pub mean_a: f64,
    /// Mean of b.
    pub mean_b: f64,
    /// Number of samples compared (pixels × channels).
    pub samples: usize,
}

fn same_shape(a: &Image, b: &Image) -> Result<()> {
    if (a.width, a.height, a.channels) != (b.width, b.height, b.channels) {
        return Err(Error::InvalidArgument {
            name: "images".into(),
            msg: format!(
                "cannot compare a {}×{}×{} image with a {}×{}×{} one",
                a.width, a.height, a.channels, b.width, b.height, b.channels
            ),
        });
    }
    Ok(())
}

/// Compares `a` with the reference `b` (same size and channel count). Non-finite samples count
/// as differences of 0 and are excluded from the sums (a NaN must not hide a result).
pub fn compare(a: &Image, b: &Image) -> Result<CompareResult> {
    same_shape(a, b)?;
    let (mut d2, mut b2, mut max_abs, mut sa, mut sb) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut n = 0usize;
    for (&x, &y) in a.data.iter().zip(&b.data) {
        let (x, y) = (x as f64, y as f64);
        if !(x.is_finite() && y.is_finite()) {
            continue;
        }
        let d = x - y;
        d2 += d * d;
        b2 += y * y;
        max_abs = max_abs.max(d.abs());
        sa += x;
        sb += y;
        n += 1;
    }
    let rel_rmse = if b2 > 0.0 {
        (d2 / b2).sqrt()
    } else if d2 == 0.0 {
        0.0
    } else {
        f64::INFINITY
    };
    let nf = n.max(1) as f64;
    Ok(CompareResult {
        rel_rmse,
        rmse: (d2 / nf).sqrt(),
        max_abs,
        mean_a: sa / nf,
        mean_b: sb / nf,
        samples: n,
    })
}

/// The per-pixel difference |a − b| (root mean square over channels) in log-scale false colour
/// with a colorbar, and its legend. The scale spans at most four decades below the largest
/// difference.
pub fn difference_image(a: &Image, b: &Image) -> Result<(Image, String)> {
    same_shape(a, b)?;
    let c = a.channels.max(1);
    let diff = Image::from_fn(a.width, a.height, 1, |x, y, o| {
        let (pa, pb) = (a.pixel(x, y), b.pixel(x, y));
        let s: f32 = pa.iter().zip(pb).map(|(u, v)| (u - v) * (u - v)).sum();
        o[0] = (s / c as f32).sqrt();
    });
    let (img, legend) = false_color(
        &diff,
        &FalseColor {
            decades: 4.0,
            ..Default::default()
        },
    );
    Ok((img, format!("|a − b|, {legend}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_compare_to_zero() {
        let a = Image::from_fn(5, 4, 3, |x, y, o| o.fill((x * y) as f32 * 0.1 + 0.2));
        let r = compare(&a, &a).unwrap();
        assert_eq!(r.rel_rmse, 0.0);
        assert_eq!(r.max_abs, 0.0);
        assert_eq!(r.samples, 60);
    }

    #[test]
    fn relative_rmse_of_a_scaled_image() {
        // a = 1.01 b → rel RMSE = 0.01 exactly, whatever b.
        let b = Image::from_fn(7, 3, 3, |x, y, o| o.fill(1.0 + x as f32 + y as f32));
        let mut a = b.clone();
        a.scale(1.01);
        let r = compare(&a, &b).unwrap();
        assert!((r.rel_rmse - 0.01).abs() < 1e-6, "{}", r.rel_rmse);
        assert!(compare(&a, &Image::new(7, 4, 3)).is_err());
    }

    #[test]
    fn difference_image_has_a_colorbar_and_legend() {
        let a = Image::new(12, 12, 3);
        let b = Image::from_fn(12, 12, 3, |x, _, o| o.fill(x as f32));
        let (d, legend) = difference_image(&a, &b).unwrap();
        assert_eq!(d.width, 12);
        assert!(d.height > 12);
        assert!(legend.contains("1.100e1"), "{legend}");
    }
}
