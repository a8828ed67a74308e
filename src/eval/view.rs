//! A sample as another camera would see it: of another resolution (the photo, its
//! masks and its terminals resized together) or closer (the centre of the frame
//! cropped and enlarged back to the frame's size, so cables look wider), or darker (an
//! underexposed photo), or softer (a lens out of focus).

use std::path::{Path, PathBuf};

use image::{GrayImage, ImageFormat, Luma, imageops};

use crate::engine::resample;
use crate::synth::Rng;

use super::dataset::{BORDER_TOLERANCE_PX, DatasetError, Sample, terminal_ends};

/// How the evaluated photos are made from the dataset's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Factor the (cropped) photo's size is multiplied by: a sensor of more or fewer
    /// pixels over the same field of view.
    pub scale: f64,
    /// Magnification: the central 1/zoom of the frame, each way, is kept (a camera
    /// closer to the table); 1 keeps the whole frame.
    pub zoom: f64,
    /// Factor every pixel value is multiplied by: below 1 an underexposed photo (a dim
    /// cell, a short exposure); 1 keeps the photo's brightness.
    pub exposure: f64,
    /// σ, pixels of the made photo, of a Gaussian blur over it (a soft lens); 0 keeps
    /// it as sharp as it is.
    pub blur: f64,
    /// σ, levels of 0-255, of Gaussian noise added to every channel of every pixel (a
    /// small or hot sensor, a dim cell at high gain), the same for a photo on every
    /// run; 0 adds none.
    pub noise: f64,
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            scale: 1.0,
            zoom: 1.0,
            exposure: 1.0,
            blur: 0.0,
            noise: 0.0,
        }
    }
}

/// What the evaluation of one sample reads, for one camera.
pub struct View {
    /// The photo file: the original for the default camera, else the made photo as PNG.
    pub bytes: Vec<u8>,
    /// Width and height of the photo.
    pub size: (u32, u32),
    /// The union mask.
    pub mask_all: GrayImage,
    /// One mask per cable in view.
    pub cable_masks: Vec<GrayImage>,
    /// The true terminals: those of the whole photo in view, off the view's border by
    /// the border tolerance (in the dataset's pixels).
    pub terminals: Vec<[f64; 2]>,
    /// The annotated centrelines in the view's pixels (points outside the view kept).
    pub centrelines: Vec<Vec<[f32; 2]>>,
}

impl View {
    /// `sample` as `camera` sees it (the default camera: as it is, bytes untouched).
    /// The photo is enlarged with Catmull-Rom (sharp, as a finer sensor would see it)
    /// and shrunk with a triangle filter (averaging, as a coarser one would), then its
    /// values are multiplied by the exposure factor, it is blurred and noise is added
    /// (seeded by the sample's set and name); masks are
    /// resampled with a triangle filter and thresholded at half; a cable whose mask
    /// leaves the view is dropped from the truth.
    pub fn of(sample: &Sample, camera: Camera) -> Result<Self, DatasetError> {
        let path = &sample.image;
        let bytes = std::fs::read(path).map_err(|e| DatasetError::io(path, e))?;
        let image_err = |e: String| DatasetError::Image(path.clone(), e);
        let (w, h) = crate::decode::dimensions(&bytes).map_err(|e| image_err(e.to_string()))?;
        let (mask_all, cable_masks) = (sample.mask_all()?, sample.cable_masks()?);
        if camera == Camera::default() {
            return Ok(Self {
                bytes,
                terminals: terminal_ends(&sample.cables, w, h),
                centrelines: sample.cables.clone(),
                size: (w, h),
                mask_all,
                cable_masks,
            });
        }
        // The crop, centred, and the size it is resampled to.
        let (cw, ch) = (
            ((w as f64 / camera.zoom).round() as u32).clamp(1, w),
            ((h as f64 / camera.zoom).round() as u32).clamp(1, h),
        );
        let (x0, y0) = ((w - cw) / 2, (h - ch) / 2);
        let size = (
            ((w as f64 * camera.scale).round() as u32).max(1),
            ((h as f64 * camera.scale).round() as u32).max(1),
        );
        let (fx, fy) = (size.0 as f64 / cw as f64, size.1 as f64 / ch as f64);
        let photo = image::load_from_memory(&bytes).map_err(|e| image_err(e.to_string()))?;
        let photo = imageops::crop_imm(&photo.into_rgb8(), x0, y0, cw, ch).to_image();
        let mut resized = resample::resize_to(&photo, size.0, size.1);
        if camera.exposure != 1.0 {
            for v in resized.iter_mut() {
                *v = (f64::from(*v) * camera.exposure).round().min(255.0) as u8;
            }
        }
        if camera.blur > 0.0 {
            resized = crate::engine::sharpness::blurred(&resized, camera.blur as f32);
        }
        if camera.noise > 0.0 {
            add_noise(&mut resized, camera.noise, seed(sample));
        }
        let mut png = std::io::Cursor::new(Vec::new());
        resized
            .write_to(&mut png, ImageFormat::Png)
            .map_err(|e| image_err(e.to_string()))?;
        let mask = |m: &GrayImage| {
            let crop = imageops::crop_imm(m, x0, y0, cw, ch).to_image();
            let mut out = imageops::resize(&crop, size.0, size.1, imageops::FilterType::Triangle);
            out.pixels_mut()
                .for_each(|p| *p = Luma([if p[0] > 127 { 255 } else { 0 }]));
            out
        };
        // The terminals of the whole photo that lie in the crop, off its border.
        let tol = BORDER_TOLERANCE_PX as f64;
        let in_view = |p: &[f64; 2]| {
            p[0] >= x0 as f64 + tol
                && p[1] >= y0 as f64 + tol
                && p[0] <= (x0 + cw) as f64 - 1.0 - tol
                && p[1] <= (y0 + ch) as f64 - 1.0 - tol
        };
        let to_view = |p: [f64; 2]| {
            [
                (p[0] - x0 as f64 + 0.5) * fx - 0.5,
                (p[1] - y0 as f64 + 0.5) * fy - 0.5,
            ]
        };
        let terminals = terminal_ends(&sample.cables, w, h)
            .into_iter()
            .filter(in_view)
            .map(to_view)
            .collect();
        let centrelines = sample
            .cables
            .iter()
            .map(|line| {
                line.iter()
                    .map(|p| to_view([f64::from(p[0]), f64::from(p[1])]).map(|v| v as f32))
                    .collect()
            })
            .collect();
        Ok(Self {
            bytes: png.into_inner(),
            size,
            mask_all: mask(&mask_all),
            cable_masks: cable_masks
                .iter()
                .map(mask)
                .filter(|m| m.pixels().any(|p| p[0] > 0))
                .collect(),
            terminals,
            centrelines,
        })
    }

    /// Writes the photo as evaluated into `dir` (created if missing), named after
    /// `sample` and `camera` (`SET_NAME_xSCALE_zZOOM`, with the extension of its
    /// format: the file itself for the default camera, else PNG), and returns the path.
    pub fn save(
        &self,
        dir: &Path,
        sample: &Sample,
        camera: Camera,
    ) -> Result<PathBuf, DatasetError> {
        std::fs::create_dir_all(dir).map_err(|e| DatasetError::io(dir, e))?;
        let extension = image::guess_format(&self.bytes)
            .ok()
            .and_then(|f| f.extensions_str().first().copied())
            .unwrap_or("img");
        let path = dir.join(format!(
            "{}_{}_x{}_z{}.{extension}",
            sample.set, sample.name, camera.scale, camera.zoom
        ));
        std::fs::write(&path, &self.bytes).map_err(|e| DatasetError::io(&path, e))?;
        Ok(path)
    }
}

/// A seed of `sample`'s set and name (FNV-1a), so that each photo gets its own noise,
/// the same on every run and machine.
fn seed(sample: &Sample) -> u64 {
    let text = format!("{}/{}", sample.set, sample.name);
    text.bytes().fold(0xCBF2_9CE4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01B3)
    })
}

/// Adds Gaussian noise of standard deviation `sigma` levels to every channel of
/// `image` (Box-Muller on [`Rng`] from `seed`), rounded and clipped to 0-255.
fn add_noise(image: &mut image::RgbImage, sigma: f64, seed: u64) {
    let mut rng = Rng::new(seed);
    for v in image.iter_mut() {
        let u1 = f64::from(rng.range(0.0, 1.0)).max(1e-12);
        let u2 = f64::from(rng.range(0.0, 1.0));
        let normal = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
        *v = (f64::from(*v) + sigma * normal).round().clamp(0.0, 255.0) as u8;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_has_the_asked_spread_and_repeats_with_its_seed() {
        let grey = image::RgbImage::from_pixel(200, 100, image::Rgb([128, 128, 128]));
        let (mut a, mut b, mut c) = (grey.clone(), grey.clone(), grey);
        add_noise(&mut a, 10.0, 7);
        add_noise(&mut b, 10.0, 7);
        add_noise(&mut c, 10.0, 8);
        assert_eq!(a, b);
        assert_ne!(a, c);
        let n = a.as_raw().len() as f64;
        let mean = a.as_raw().iter().map(|&v| f64::from(v)).sum::<f64>() / n;
        let var = a
            .as_raw()
            .iter()
            .map(|&v| (f64::from(v) - mean).powi(2))
            .sum::<f64>()
            / n;
        assert!((mean - 128.0).abs() < 0.3, "mean {mean}");
        assert!((var.sqrt() - 10.0).abs() < 0.3, "σ {}", var.sqrt());
    }

    #[test]
    fn a_saved_view_is_the_photo_the_engine_is_given() {
        let samples = super::super::load_dataset(&super::super::default_dataset_dir())
            .expect("dataset (set ARIADNE_DATASET)");
        let sample = &samples[0];
        let dir = std::env::temp_dir().join(format!("ariadne-views-{}", std::process::id()));
        let camera = Camera {
            scale: 0.5,
            ..Camera::default()
        };
        let view = View::of(sample, camera).unwrap();
        let path = view.save(&dir, sample, camera).unwrap();
        assert!(path.ends_with(format!("{}_{}_x0.5_z1.png", sample.set, sample.name)));
        assert_eq!(std::fs::read(&path).unwrap(), view.bytes);
        let saved = image::open(&path).unwrap();
        assert_eq!((saved.width(), saved.height()), view.size);
        // The default camera's view is the file itself, saved with its own extension.
        let original = View::of(sample, Camera::default()).unwrap();
        let path = original.save(&dir, sample, Camera::default()).unwrap();
        assert_eq!(path.extension().unwrap(), "jpg");
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(&sample.image).unwrap()
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
