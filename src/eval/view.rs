//! A sample as a camera of another resolution would see it: the photo, its masks and
//! its terminals resized together by one factor.

use image::{GrayImage, ImageFormat, Luma, imageops};

use super::dataset::{DatasetError, Sample, terminal_ends};

/// What the evaluation of one sample reads, at one scale.
pub struct View {
    /// The photo file: the original at scale 1, else the resized photo as PNG.
    pub bytes: Vec<u8>,
    /// Width and height of the photo.
    pub size: (u32, u32),
    /// The union mask.
    pub mask_all: GrayImage,
    /// One mask per cable.
    pub cable_masks: Vec<GrayImage>,
    /// The true terminals (found at the original size, then scaled).
    pub terminals: Vec<[f64; 2]>,
}

impl View {
    /// `sample` resized by `scale` (1: as it is, bytes untouched). The photo is
    /// enlarged with Catmull-Rom (sharp, as a finer sensor would see it) and shrunk
    /// with a triangle filter (averaging, as a coarser one would); masks are resampled
    /// with a triangle filter and thresholded at half.
    pub fn of(sample: &Sample, scale: f64) -> Result<Self, DatasetError> {
        let path = &sample.image;
        let bytes = std::fs::read(path).map_err(|e| DatasetError::io(path, e))?;
        let image_err = |e: String| DatasetError::Image(path.clone(), e);
        let (w, h) = crate::decode::dimensions(&bytes).map_err(|e| image_err(e.to_string()))?;
        let terminals = terminal_ends(&sample.cables, w, h);
        let (mask_all, cable_masks) = (sample.mask_all()?, sample.cable_masks()?);
        if scale == 1.0 {
            return Ok(Self {
                bytes,
                size: (w, h),
                mask_all,
                cable_masks,
                terminals,
            });
        }
        let size = (
            ((w as f64 * scale).round() as u32).max(1),
            ((h as f64 * scale).round() as u32).max(1),
        );
        let photo = image::load_from_memory(&bytes).map_err(|e| image_err(e.to_string()))?;
        let filter = if scale > 1.0 {
            imageops::FilterType::CatmullRom
        } else {
            imageops::FilterType::Triangle
        };
        let resized = imageops::resize(&photo.into_rgb8(), size.0, size.1, filter);
        let mut png = std::io::Cursor::new(Vec::new());
        resized
            .write_to(&mut png, ImageFormat::Png)
            .map_err(|e| image_err(e.to_string()))?;
        let mask = |m: &GrayImage| {
            let mut out = imageops::resize(m, size.0, size.1, imageops::FilterType::Triangle);
            out.pixels_mut()
                .for_each(|p| *p = Luma([if p[0] > 127 { 255 } else { 0 }]));
            out
        };
        Ok(Self {
            bytes: png.into_inner(),
            size,
            mask_all: mask(&mask_all),
            cable_masks: cable_masks.iter().map(mask).collect(),
            terminals: terminals
                .iter()
                .map(|p| p.map(|v| (v + 0.5) * scale - 0.5))
                .collect(),
        })
    }
}
