//! Floating-point images and their files: OpenEXR (f32 or f16, any channel names) and 8-bit sRGB
//! PNG, with exposure, a log-scale false-colour mode through viridis, and side-by-side composition.
//!
//! [`Image`] is deliberately plain — width, height, a channel count and row-major `f32` samples
//! (`data[(y * width + x) * channels + c]`, y = 0 at the top) — so any room can fill one (slice
//! images of a table, renders, difference maps) without learning the renderer.
//!
//! Two kinds of values go through it:
//! - *scene-referred* linear radiance (renders, environment maps), stored losslessly in EXR and
//!   displayed in PNG through [`write_png`]: multiply by 2^exposure, clamp to [0, 1], encode with
//!   the sRGB transfer curve;
//! - *display-referred* images made by [`false_color`]: their linear values are chosen so that
//!   the same sRGB encoding (exposure 0) reproduces the colormap exactly, so they compose with
//!   renders in one [`Image::hstack`] and are written with the same [`write_png`].
//!
//! Why log scale for false colour: BRDF values and render differences span decades (a glossy
//! peak is 10³ times the diffuse floor), and a linear map shows only the peak.

use std::path::Path;

use brdftab::error::{Error, Result};

/// A floating-point image: `channels` samples per pixel, row-major, top row first.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Samples per pixel.
    pub channels: usize,
    /// Channel names, one per channel (written to EXR; `R`, `G`, `B` for RGB).
    pub names: Vec<String>,
    /// `width * height * channels` samples, `data[(y * width + x) * channels + c]`.
    pub data: Vec<f32>,
}

/// Default channel names for a channel count: `Y` for 1, `R G B` for 3, `R G B A` for 4,
/// `C0 C1 ...` otherwise.
pub fn default_names(channels: usize) -> Vec<String> {
    match channels {
        1 => vec!["Y".into()],
        3 => vec!["R".into(), "G".into(), "B".into()],
        4 => vec!["R".into(), "G".into(), "B".into(), "A".into()],
        n => (0..n).map(|i| format!("C{i}")).collect(),
    }
}

impl Image {
    /// A black image with default channel names (see [`default_names`]).
    pub fn new(width: usize, height: usize, channels: usize) -> Self {
        Image {
            width,
            height,
            channels,
            names: default_names(channels),
            data: vec![0.0; width * height * channels],
        }
    }

    /// An image from row-major samples; errors when the length does not match.
    pub fn from_data(width: usize, height: usize, channels: usize, data: Vec<f32>) -> Result<Self> {
        if data.len() != width * height * channels {
            return Err(Error::InvalidArgument {
                name: "data".into(),
                msg: format!(
                    "{} samples for a {width}×{height} image with {channels} channels (expected {})",
                    data.len(),
                    width * height * channels
                ),
            });
        }
        Ok(Image {
            width,
            height,
            channels,
            names: default_names(channels),
            data,
        })
    }

    /// An image whose pixel (x, y) is filled by `f(x, y, out)`.
    pub fn from_fn(
        width: usize,
        height: usize,
        channels: usize,
        mut f: impl FnMut(usize, usize, &mut [f32]),
    ) -> Self {
        let mut img = Image::new(width, height, channels);
        for y in 0..height {
            for x in 0..width {
                f(x, y, img.pixel_mut(x, y));
            }
        }
        img
    }

    /// Replaces the channel names (must be one per channel).
    pub fn with_names(mut self, names: &[&str]) -> Result<Self> {
        if names.len() != self.channels {
            return Err(Error::InvalidArgument {
                name: "names".into(),
                msg: format!("{} names for {} channels", names.len(), self.channels),
            });
        }
        self.names = names.iter().map(|s| s.to_string()).collect();
        Ok(self)
    }

    /// The samples of pixel (x, y). Panics when out of bounds (a programming error).
    #[inline]
    pub fn pixel(&self, x: usize, y: usize) -> &[f32] {
        let i = (y * self.width + x) * self.channels;
        &self.data[i..i + self.channels]
    }

    /// The samples of pixel (x, y), mutable.
    #[inline]
    pub fn pixel_mut(&mut self, x: usize, y: usize) -> &mut [f32] {
        let i = (y * self.width + x) * self.channels;
        &mut self.data[i..i + self.channels]
    }

    /// Number of pixels.
    pub fn pixel_count(&self) -> usize {
        self.width * self.height
    }

    /// Rec. 709 luminance of pixel (x, y): 0.2126 R + 0.7152 G + 0.0722 B for 3+ channels, the
    /// value itself for 1 channel, the channel mean otherwise.
    pub fn luminance(&self, x: usize, y: usize) -> f32 {
        luminance_of(self.pixel(x, y))
    }

    /// Multiplies every sample by `k`.
    pub fn scale(&mut self, k: f32) {
        for v in &mut self.data {
            *v *= k;
        }
    }

    /// This image as 3-channel RGB: 1 channel is replicated, 3 or more keep the first three
    /// (after [`read_exr`] these are R, G, B), 2 channels are an error.
    pub fn to_rgb(&self) -> Result<Image> {
        match self.channels {
            3 => Ok(Image {
                names: default_names(3),
                ..self.clone()
            }),
            1 => Ok(Image::from_fn(self.width, self.height, 3, |x, y, o| {
                o.fill(self.pixel(x, y)[0])
            })),
            c if c > 3 => Ok(Image::from_fn(self.width, self.height, 3, |x, y, o| {
                o.copy_from_slice(&self.pixel(x, y)[..3])
            })),
            c => Err(Error::Unsupported(format!(
                "cannot convert a {c}-channel image to RGB"
            ))),
        }
    }

    /// Places images left to right, top-aligned, separated by `gap` pixels; uncovered pixels get
    /// `background` in every channel. All images must have the same channel count.
    pub fn hstack(images: &[&Image], gap: usize, background: f32) -> Result<Image> {
        let Some(first) = images.first() else {
            return Err(Error::InvalidArgument {
                name: "images".into(),
                msg: "nothing to compose".into(),
            });
        };
        let c = first.channels;
        if let Some(bad) = images.iter().find(|i| i.channels != c) {
            return Err(Error::InvalidArgument {
                name: "images".into(),
                msg: format!(
                    "cannot compose images with {} and {} channels",
                    c, bad.channels
                ),
            });
        }
        let width = images.iter().map(|i| i.width).sum::<usize>() + gap * (images.len() - 1);
        let height = images.iter().map(|i| i.height).max().unwrap_or(0);
        let mut out = Image::new(width, height, c);
        out.names = first.names.clone();
        out.data.fill(background);
        let mut x0 = 0;
        for img in images {
            for y in 0..img.height {
                let src = &img.data[y * img.width * c..(y + 1) * img.width * c];
                let d = (y * width + x0) * c;
                out.data[d..d + src.len()].copy_from_slice(src);
            }
            x0 += img.width + gap;
        }
        Ok(out)
    }

    /// Places images top to bottom, left-aligned (see [`Image::hstack`]).
    pub fn vstack(images: &[&Image], gap: usize, background: f32) -> Result<Image> {
        let Some(first) = images.first() else {
            return Err(Error::InvalidArgument {
                name: "images".into(),
                msg: "nothing to compose".into(),
            });
        };
        let c = first.channels;
        if let Some(bad) = images.iter().find(|i| i.channels != c) {
            return Err(Error::InvalidArgument {
                name: "images".into(),
                msg: format!(
                    "cannot compose images with {} and {} channels",
                    c, bad.channels
                ),
            });
        }
        let width = images.iter().map(|i| i.width).max().unwrap_or(0);
        let height = images.iter().map(|i| i.height).sum::<usize>() + gap * (images.len() - 1);
        let mut out = Image::new(width, height, c);
        out.names = first.names.clone();
        out.data.fill(background);
        let mut y0 = 0;
        for img in images {
            for y in 0..img.height {
                let src = &img.data[y * img.width * c..(y + 1) * img.width * c];
                let d = ((y0 + y) * width) * c;
                out.data[d..d + src.len()].copy_from_slice(src);
            }
            y0 += img.height + gap;
        }
        Ok(out)
    }
}

/// Rec. 709 luminance of one pixel's samples (see [`Image::luminance`]).
#[inline]
pub fn luminance_of(p: &[f32]) -> f32 {
    match p.len() {
        0 => 0.0,
        1 => p[0],
        2 => 0.5 * (p[0] + p[1]),
        _ => 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2],
    }
}

// ---------------------------------------------------------------------------------------------
// OpenEXR

/// Sample precision of an EXR file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ExrPrecision {
    /// 32-bit float, lossless.
    #[default]
    F32,
    /// 16-bit half float: half the size, about 3 significant digits, range ±65504.
    F16,
}

fn exr_error(path: &Path, e: exr::error::Error) -> Error {
    match e {
        exr::error::Error::Io(source) => Error::io(path, source),
        other => Error::format(path.display().to_string(), None, None, other.to_string()),
    }
}

/// Writes `img` as a single-layer OpenEXR file (ZIP-compressed scan lines) with the image's
/// channel names. For [`ExrPrecision::F16`], finite values beyond the half range are an
/// [`Error::Encode`] (rather than silently becoming infinity); NaN and infinities pass through.
pub fn write_exr(img: &Image, path: impl AsRef<Path>, precision: ExrPrecision) -> Result<()> {
    use exr::prelude::{
        AnyChannel, AnyChannels, Encoding, FlatSamples, Layer, LayerAttributes, SmallVec,
        WritableImage, f16,
    };
    let path = path.as_ref();
    if img.width == 0 || img.height == 0 || img.channels == 0 {
        return Err(Error::InvalidArgument {
            name: "image".into(),
            msg: format!(
                "cannot write an empty image ({}×{}, {} channels) to EXR",
                img.width, img.height, img.channels
            ),
        });
    }
    if img.names.len() != img.channels {
        return Err(Error::InvalidArgument {
            name: "image.names".into(),
            msg: format!("{} names for {} channels", img.names.len(), img.channels),
        });
    }
    let n = img.pixel_count();
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (c, name) in img.names.iter().enumerate() {
        let values = (0..n).map(|i| img.data[i * img.channels + c]);
        let samples = match precision {
            ExrPrecision::F32 => FlatSamples::F32(values.collect()),
            ExrPrecision::F16 => {
                let mut out = Vec::with_capacity(n);
                for (i, v) in values.enumerate() {
                    if v.is_finite() && v.abs() > f16::MAX.to_f32() {
                        return Err(Error::Encode {
                            msg: format!(
                                "{}: channel {name} pixel ({}, {}) = {v:e} exceeds the f16 range \
                                 (±65504); write f32 or scale the image",
                                path.display(),
                                i % img.width,
                                i / img.width
                            ),
                        });
                    }
                    out.push(f16::from_f32(v));
                }
                FlatSamples::F16(out)
            }
        };
        list.push(AnyChannel::new(name.as_str(), samples));
    }
    let layer = Layer::new(
        (img.width, img.height),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    // In memory, then a temporary file renamed into place (`to_file` truncated the old file
    // first: a kill mid-write left a truncated image).
    let mut bytes = std::io::Cursor::new(Vec::new());
    exr::prelude::Image::from_layer(layer)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| exr_error(path, e))?;
    brdftab::store::write_file_atomic(path, bytes.get_ref())
}

/// Reads the first layer of an OpenEXR file at full resolution, all channels, as f32.
///
/// Channels are ordered R, G, B, A first (those present), then the rest in the file's
/// (alphabetical) order; `names` records them. A lat-long environment map typically comes back
/// with 3 or 4 channels; use [`Image::to_rgb`] to drop alpha or replicate a luminance channel.
pub fn read_exr(path: impl AsRef<Path>) -> Result<Image> {
    use exr::prelude::{ReadChannels, ReadLayers, read};
    let path = path.as_ref();
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| exr_error(path, e))?;
    let layer = image.layer_data;
    let (width, height) = (layer.size.width(), layer.size.height());
    let list = &layer.channel_data.list;
    let rank = |name: &str| match name {
        "R" => 0,
        "G" => 1,
        "B" => 2,
        "A" => 3,
        _ => 4,
    };
    let mut order: Vec<usize> = (0..list.len()).collect();
    order.sort_by_key(|&i| rank(&list[i].name.to_string()));
    let channels = order.len();
    let mut img = Image::new(width, height, channels);
    img.names = order.iter().map(|&i| list[i].name.to_string()).collect();
    for (c, &i) in order.iter().enumerate() {
        let samples = &list[i].sample_data;
        if samples.len() != width * height {
            return Err(Error::format(
                path.display().to_string(),
                Some(&list[i].name.to_string()),
                None,
                "channel is subsampled; only full-resolution channels are supported",
            ));
        }
        for (p, v) in samples.values_as_f32().enumerate() {
            img.data[p * channels + c] = v;
        }
    }
    Ok(img)
}

// ---------------------------------------------------------------------------------------------
// PNG and tone mapping

/// The sRGB transfer curve (linear [0, 1] → encoded [0, 1]).
#[inline]
pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse sRGB transfer curve (encoded [0, 1] → linear [0, 1]).
#[inline]
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear value → 8-bit sRGB: scale by 2^exposure, clamp to [0, 1] (NaN → 0), encode, round.
#[inline]
pub fn to_srgb8(v: f32, exposure_scale: f32) -> u8 {
    let v = v * exposure_scale;
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (linear_to_srgb(v) * 255.0 + 0.5) as u8
}

/// Encodes `img` as 8-bit sRGB bytes (see [`to_srgb8`]) with the PNG colour type for its channel
/// count: 1 → grey, 2 → grey + alpha, 3 → RGB, 4 → RGBA (alpha written linearly). Returns the
/// bytes and the colour type.
pub fn to_srgb8_bytes(img: &Image, exposure: f32) -> Result<(Vec<u8>, png::ColorType)> {
    let color = match img.channels {
        1 => png::ColorType::Grayscale,
        2 => png::ColorType::GrayscaleAlpha,
        3 => png::ColorType::Rgb,
        4 => png::ColorType::Rgba,
        c => {
            return Err(Error::Unsupported(format!(
                "PNG output of a {c}-channel image (convert to RGB first)"
            )));
        }
    };
    let k = exposure.exp2();
    let alpha = matches!(img.channels, 2 | 4);
    let bytes = img
        .data
        .chunks_exact(img.channels)
        .flat_map(|p| {
            p.iter().enumerate().map(move |(c, &v)| {
                if alpha && c == p.len() - 1 {
                    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
                } else {
                    to_srgb8(v, k)
                }
            })
        })
        .collect();
    Ok((bytes, color))
}

/// Writes `img` as an 8-bit sRGB PNG: linear values × 2^`exposure` (in stops), clamped to [0, 1],
/// sRGB-encoded (an sRGB chunk marks the file). See [`to_srgb8_bytes`] for channel counts.
pub fn write_png(img: &Image, path: impl AsRef<Path>, exposure: f32) -> Result<()> {
    let path = path.as_ref();
    if img.width == 0 || img.height == 0 {
        return Err(Error::InvalidArgument {
            name: "image".into(),
            msg: "cannot write an empty image to PNG".into(),
        });
    }
    let (bytes, color) = to_srgb8_bytes(img, exposure)?;
    let (w, h) = (
        u32::try_from(img.width).map_err(|_| too_large(path))?,
        u32::try_from(img.height).map_err(|_| too_large(path))?,
    );
    let mut file = Vec::new();
    let mut enc = png::Encoder::new(&mut file, w, h);
    enc.set_color(color);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let png_err = |e: png::EncodingError| match e {
        png::EncodingError::IoError(source) => Error::io(path, source),
        other => Error::format(path.display().to_string(), None, None, other.to_string()),
    };
    let mut writer = enc.write_header().map_err(png_err)?;
    writer.write_image_data(&bytes).map_err(png_err)?;
    writer.finish().map_err(png_err)?;
    // Replaced atomically, as every other output.
    brdftab::store::write_file_atomic(path, &file)
}

fn too_large(path: &Path) -> Error {
    Error::InvalidArgument {
        name: path.display().to_string(),
        msg: "image too large for PNG".into(),
    }
}

/// Writes `img` to `path`, choosing the format by extension: `.exr` (f32) or `.png` (see
/// [`write_png`]). Both scale the linear values by 2^`exposure` (stops), as pbrt-v4's
/// `imgtool convert --exposure` does for every format: an EXR holds the radiance × 2^exposure
/// (exactly the radiance at exposure 0), a PNG its sRGB encoding. (The EXR ignored the
/// exposure until session 41.)
pub fn write_auto(img: &Image, path: impl AsRef<Path>, exposure: f32) -> Result<()> {
    let path = path.as_ref();
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("exr") if exposure != 0.0 => {
            let k = exposure.exp2();
            let scaled = Image {
                data: img.data.iter().map(|v| v * k).collect(),
                ..img.clone()
            };
            write_exr(&scaled, path, ExrPrecision::F32)
        }
        Some("exr") => write_exr(img, path, ExrPrecision::F32),
        Some("png") => write_png(img, path, exposure),
        _ => Err(Error::InvalidArgument {
            name: path.display().to_string(),
            msg: "output must end in .png or .exr".into(),
        }),
    }
}

// ---------------------------------------------------------------------------------------------
// False colour

/// Perceptual colormaps (sRGB-encoded output).
pub mod colormap {
    /// Viridis (matplotlib's default; perceptually uniform, readable in grey and by colour-blind
    /// viewers): the ten sRGB stops of `viridis(linspace(0, 1, 10))`, interpolated linearly.
    const VIRIDIS: [u32; 10] = [
        0x440154, 0x482878, 0x3e4989, 0x31688e, 0x26828e, 0x1f9e89, 0x35b779, 0x6ece58, 0xb5de2b,
        0xfde725,
    ];

    /// The viridis colour at `t` ∈ [0, 1] (clamped; NaN → 0), as sRGB-encoded values in [0, 1].
    pub fn viridis(t: f32) -> [f32; 3] {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let x = t * (VIRIDIS.len() - 1) as f32;
        let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
        let f = x - i as f32;
        let rgb = |c: u32| {
            [
                ((c >> 16) & 0xff) as f32 / 255.0,
                ((c >> 8) & 0xff) as f32 / 255.0,
                (c & 0xff) as f32 / 255.0,
            ]
        };
        let (a, b) = (rgb(VIRIDIS[i]), rgb(VIRIDIS[i + 1]));
        [
            a[0] + f * (b[0] - a[0]),
            a[1] + f * (b[1] - a[1]),
            a[2] + f * (b[2] - a[2]),
        ]
    }
}

/// Options of [`false_color`].
#[derive(Debug, Clone, PartialEq)]
pub struct FalseColor {
    /// Map log10 of the value (true) or the value itself (false).
    pub log: bool,
    /// The value range mapped to the ends of the colormap; `None` = from the data (for log scale
    /// the smallest positive value, but at most `decades` below the maximum).
    pub range: Option<(f32, f32)>,
    /// With automatic range on a log scale, the widest span in decades.
    pub decades: f32,
    /// Append a colorbar strip (bottom) running from the low end (left) to the high end (right).
    pub colorbar: bool,
}

impl Default for FalseColor {
    fn default() -> Self {
        FalseColor {
            log: true,
            range: None,
            decades: 6.0,
            colorbar: true,
        }
    }
}

/// Maps a scalar per pixel (luminance, see [`luminance_of`]) through viridis.
///
/// Returns a 3-channel display-referred image — linear values that [`write_png`] at exposure 0
/// turns back into exactly the colormap's sRGB colours — and a legend naming the range, e.g.
/// `log10 scale (viridis): dark purple = 1.00e-3 … yellow = 1.00e1`. Values at or below the low
/// end (zero, negative and NaN included on a log scale) get the darkest colour. With
/// `colorbar`, a strip of height max(4, height/12) separated by a 1-pixel black gap is added
/// below the image.
pub fn false_color(img: &Image, opts: &FalseColor) -> (Image, String) {
    let values: Vec<f32> = img
        .data
        .chunks_exact(img.channels.max(1))
        .map(luminance_of)
        .collect();
    let (lo, hi) = match opts.range {
        Some(r) => r,
        None => {
            let max = values
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .fold(f32::NEG_INFINITY, f32::max);
            if opts.log {
                let floor = max * 10f32.powf(-opts.decades.max(0.1));
                let min_pos = values
                    .iter()
                    .copied()
                    .filter(|v| v.is_finite() && *v > 0.0)
                    .fold(f32::INFINITY, f32::min);
                (min_pos.max(floor), max)
            } else {
                let min = values
                    .iter()
                    .copied()
                    .filter(|v| v.is_finite())
                    .fold(f32::INFINITY, f32::min);
                (min, max)
            }
        }
    };
    // Degenerate ranges (empty, all-zero on a log scale) get a nominal range and say so.
    let degenerate = !(lo.is_finite() && hi.is_finite()) || (opts.log && hi <= 0.0);
    let (lo, hi) = if !(lo.is_finite() && hi.is_finite()) || (opts.log && hi <= 0.0) {
        if opts.log { (1.0, 10.0) } else { (0.0, 1.0) }
    } else if opts.log && lo <= 0.0 {
        (hi * 1e-6, hi)
    } else {
        (lo, hi)
    };
    let t_of = |v: f32| -> f32 {
        if opts.log {
            if v.is_nan() || v <= 0.0 {
                return 0.0;
            }
            let (a, b) = (lo.log10(), hi.log10());
            if b > a {
                (v.log10() - a) / (b - a)
            } else {
                0.5
            }
        } else if hi > lo {
            (v - lo) / (hi - lo)
        } else {
            0.5
        }
    };
    let lin = |t: f32| colormap::viridis(t).map(srgb_to_linear);
    let mapped = Image::from_fn(img.width, img.height, 3, |x, y, o| {
        o.copy_from_slice(&lin(t_of(values[y * img.width + x])))
    });
    let out = if opts.colorbar && img.width > 0 {
        let h = (img.height / 12).max(4);
        let w = img.width;
        let bar = Image::from_fn(w, h, 3, |x, _, o| {
            let t = if w > 1 {
                x as f32 / (w - 1) as f32
            } else {
                0.5
            };
            o.copy_from_slice(&lin(t))
        });
        Image::vstack(&[&mapped, &bar], 1, 0.0).unwrap_or(mapped)
    } else {
        mapped
    };
    if degenerate {
        let legend = format!(
            "{} scale (viridis): no {} values — all pixels at the low end",
            if opts.log { "log10" } else { "linear" },
            if opts.log { "positive" } else { "finite" }
        );
        return (out, legend);
    }
    let legend = format!(
        "{} scale (viridis): dark purple = {lo:.3e} … yellow = {hi:.3e}{}",
        if opts.log { "log10" } else { "linear" },
        if opts.colorbar {
            " (colorbar left → right)"
        } else {
            ""
        }
    );
    (out, legend)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs::File;

    /// `name` in a fresh scratch directory, removed when the returned guard drops.
    fn tmp(name: &str) -> (brdftab::testkit::TempDir, std::path::PathBuf) {
        let dir = brdftab::testkit::TempDir::new("image");
        let p = dir.join(name);
        (dir, p)
    }

    fn ramp(w: usize, h: usize, c: usize) -> Image {
        Image::from_fn(w, h, c, |x, y, o| {
            for (k, v) in o.iter_mut().enumerate() {
                *v = x as f32 * 0.25 + y as f32 * 3.0 + k as f32 * 0.125 - 1.0;
            }
        })
    }

    #[test]
    fn exr_f32_round_trip_is_exact_and_keeps_channel_order() {
        let img = ramp(7, 5, 3);
        let (_dir, p) = tmp("rt32.exr");
        write_exr(&img, &p, ExrPrecision::F32).unwrap();
        let back = read_exr(&p).unwrap();
        assert_eq!(back.names, ["R", "G", "B"]);
        assert_eq!(back, img);
    }

    #[test]
    fn exr_f16_round_trip_within_half_precision() {
        let img = ramp(6, 4, 4);
        let (_dir, p) = tmp("rt16.exr");
        write_exr(&img, &p, ExrPrecision::F16).unwrap();
        let back = read_exr(&p).unwrap();
        assert_eq!(back.names, ["R", "G", "B", "A"]);
        for (a, b) in img.data.iter().zip(&back.data) {
            // f16 has an 11-bit significand: relative error ≤ 2^-11.
            assert!((a - b).abs() <= a.abs() * 4.9e-4 + 1e-7, "{a} vs {b}");
        }
    }

    #[test]
    fn exr_arbitrary_channel_names() {
        let img = ramp(3, 2, 2).with_names(&["theta", "value"]).unwrap();
        let (_dir, p) = tmp("named.exr");
        write_exr(&img, &p, ExrPrecision::F32).unwrap();
        let back = read_exr(&p).unwrap();
        assert_eq!(back.names, ["theta", "value"]);
        assert_eq!(back.data, img.data);
    }

    #[test]
    fn exr_f16_overflow_is_an_error_not_infinity() {
        let mut img = Image::new(2, 2, 1);
        img.data[3] = 1e6;
        let (_dir, p) = tmp("big.exr");
        assert!(matches!(
            write_exr(&img, &p, ExrPrecision::F16),
            Err(Error::Encode { .. })
        ));
    }

    #[test]
    fn read_missing_or_garbage_exr_is_an_error() {
        let (_dir, p) = tmp("garbage.exr");
        assert!(read_exr(&p).is_err()); // not there yet
        std::fs::write(&p, b"not an exr file at all").unwrap();
        assert!(read_exr(&p).is_err());
    }

    #[test]
    fn images_replace_the_file_and_leave_another_hard_link_alone() {
        // `to_file` / `File::create` truncated the old file and wrote into it: a kill mid-write
        // left a truncated image, and another hard link to it saw the half-written bytes.
        let (dir, _) = tmp("x");
        let img = Image::new(4, 3, 3);
        for name in ["out.exr", "out.png"] {
            let (out, keep) = (dir.join(name), dir.join(format!("keep-{name}")));
            std::fs::write(&out, b"old contents").unwrap();
            std::fs::hard_link(&out, &keep).unwrap();
            write_auto(&img, &out, 0.0).unwrap();
            assert_eq!(std::fs::read(&keep).unwrap(), b"old contents", "{name}");
            assert_ne!(std::fs::read(&out).unwrap(), b"old contents", "{name}");
        }
        // No temporary file is left beside them.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 4);
    }

    #[test]
    fn exposure_scales_the_exr_too() {
        // `render --exposure 1 -o x.exr` wrote the unscaled radiance: the flag was ignored.
        let mut img = Image::new(3, 2, 3);
        img.pixel_mut(0, 0).copy_from_slice(&[0.25, 1.5, 3.0]);
        img.pixel_mut(2, 1).copy_from_slice(&[1e-3, 0.0, 7.0]);
        let (_dir, p) = tmp("exposed.exr");
        for ev in [0.0f32, 1.0, -2.0, 0.5] {
            write_auto(&img, &p, ev).unwrap();
            let back = read_exr(&p).unwrap();
            let k = ev.exp2();
            // f32 in and out; a product of two f32 rounded once, as the writer does.
            let want: Vec<f32> = img.data.iter().map(|v| v * k).collect();
            assert_eq!(back.data, want, "exposure {ev}");
        }
    }

    #[test]
    fn png_decodes_with_the_right_size_and_srgb_values() {
        let mut img = Image::new(9, 4, 3);
        img.pixel_mut(0, 0).copy_from_slice(&[0.0, 0.5, 1.0]);
        img.pixel_mut(1, 0).copy_from_slice(&[2.0, -1.0, f32::NAN]);
        img.pixel_mut(2, 0).copy_from_slice(&[0.25, 0.25, 0.25]);
        let (_dir, p) = tmp("rgb.png");
        write_png(&img, &p, 0.0).unwrap();
        let dec = png::Decoder::new(File::open(&p).unwrap());
        let mut reader = dec.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (9, 4));
        assert_eq!(info.color_type, png::ColorType::Rgb);
        // sRGB(0.5) = 0.7354 → 188; clamp above 1 and below 0; NaN → 0.
        assert_eq!(&buf[0..6], &[0, 188, 255, 255, 0, 0]);
        // exposure +1 stop doubles: 0.25 → 0.5 → 188.
        write_png(&img, &p, 1.0).unwrap();
        let mut reader = png::Decoder::new(File::open(&p).unwrap())
            .read_info()
            .unwrap();
        reader.next_frame(&mut buf).unwrap();
        assert_eq!(buf[6], 188);
    }

    #[test]
    fn srgb_curves_invert() {
        for i in 0..=100 {
            let v = i as f32 / 100.0;
            assert!((srgb_to_linear(linear_to_srgb(v)) - v).abs() < 1e-5);
        }
    }

    #[test]
    fn false_color_log_range_and_colorbar() {
        let img = Image::from_fn(10, 12, 1, |x, _, o| o[0] = 10f32.powi(x as i32 - 3));
        let (fc, legend) = false_color(&img, &FalseColor::default());
        assert_eq!(fc.channels, 3);
        assert_eq!(fc.width, 10);
        assert_eq!(fc.height, 12 + 1 + 4);
        // Default: at most six decades below the maximum, so the low end is 1e0, not 1e-3.
        assert!(
            legend.contains("1.000e0") && legend.contains("1.000e6"),
            "{legend}"
        );
        // Left end → first viridis stop, right end → last, exactly after sRGB encoding.
        let (bytes, _) = to_srgb8_bytes(&fc, 0.0).unwrap();
        assert_eq!(&bytes[0..3], &[0x44, 0x01, 0x54]);
        assert_eq!(&bytes[27..30], &[0xfd, 0xe7, 0x25]);
        // With decades = 2 the low end clamps to max/100.
        let (_, legend) = false_color(
            &img,
            &FalseColor {
                decades: 2.0,
                colorbar: false,
                ..Default::default()
            },
        );
        assert!(legend.contains("1.000e4"), "{legend}");
    }

    #[test]
    fn false_color_degenerate_inputs_do_not_panic() {
        for img in [
            Image::new(3, 3, 3),
            Image::new(0, 0, 3),
            Image::new(1, 1, 1),
        ] {
            let (_, legend) = false_color(&img, &FalseColor::default());
            assert!(legend.contains("no positive values"), "{legend}");
            let _ = false_color(
                &img,
                &FalseColor {
                    log: false,
                    ..Default::default()
                },
            );
        }
    }

    #[test]
    fn hstack_places_side_by_side() {
        let a = Image::from_fn(2, 2, 1, |_, _, o| o[0] = 1.0);
        let b = Image::from_fn(3, 1, 1, |_, _, o| o[0] = 2.0);
        let s = Image::hstack(&[&a, &b], 1, -1.0).unwrap();
        assert_eq!((s.width, s.height), (6, 2));
        assert_eq!(
            s.data,
            [1., 1., -1., 2., 2., 2., 1., 1., -1., -1., -1., -1.]
        );
        assert!(Image::hstack(&[&a, &Image::new(1, 1, 3)], 0, 0.0).is_err());
        assert!(Image::hstack(&[], 0, 0.0).is_err());
    }
}
