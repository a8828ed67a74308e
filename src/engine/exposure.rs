//! Exposure: a dim photo is brightened before the network and the engine read it.
//!
//! SLIC's colour distance, the histograms' saturation and value bins and the lateral
//! contrast are all absolute: in an underexposed photo (a dark cell, a black
//! background the camera's auto-exposure did not lift) every colour difference shrinks,
//! the compactness term takes over and superpixels stop following the cables. One gain
//! on all three channels, so hues are kept, brings the photo's bright end up to
//! `exposure_level`; a photo already that bright is left as it is. The pipeline applies
//! it to the working image before the network and the engine see it.

use std::borrow::Cow;

use image::RgbImage;

/// Share of the pixels whose brightest channel may lie above the level the gain is
/// computed from: the photo's "bright end" ignores specular glints and stray pixels.
const BRIGHT_END_SHARE: f64 = 0.005;

/// The gain that brings the brightest channel of the photo's pixels at the
/// [`BRIGHT_END_SHARE`] quantile up to `level` (0..=255), at most `max_gain`, at least 1
/// (1 for a black photo).
pub fn gain(image: &RgbImage, level: f32, max_gain: f32) -> f32 {
    let mut histogram = [0usize; 256];
    for p in image.pixels() {
        histogram[usize::from(p.0[0].max(p.0[1]).max(p.0[2]))] += 1;
    }
    let above = (image.pixels().len() as f64 * BRIGHT_END_SHARE) as usize;
    let mut seen = 0;
    let bright_end = (0..256usize)
        .rev()
        .find(|&v| {
            seen += histogram[v];
            seen > above
        })
        .unwrap_or(0);
    if bright_end == 0 {
        return 1.0;
    }
    (level / bright_end as f32).clamp(1.0, max_gain.max(1.0))
}

/// `image` with every channel multiplied by `gain` (clipped at 255); borrowed unchanged
/// for a gain of 1 or less.
pub fn apply(image: &RgbImage, gain: f32) -> Cow<'_, RgbImage> {
    if gain <= 1.0 {
        return Cow::Borrowed(image);
    }
    let table: Vec<u8> = (0..=255u16)
        .map(|v| (f32::from(v) * gain).round().min(255.0) as u8)
        .collect();
    let mut out = image.clone();
    for v in out.iter_mut() {
        *v = table[usize::from(*v)];
    }
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Rgb;

    fn brighten(image: &RgbImage, level: f32, max_gain: f32) -> Cow<'_, RgbImage> {
        apply(image, gain(image, level, max_gain))
    }

    fn scene(scale: f32) -> RgbImage {
        RgbImage::from_fn(64, 48, |x, y| {
            let base = if (20..28).contains(&y) {
                [200.0, 60.0, 40.0]
            } else {
                [230.0, 225.0, 210.0 - x as f32]
            };
            Rgb(base.map(|c| (c * scale).round() as u8))
        })
    }

    #[test]
    fn a_well_exposed_photo_is_left_alone() {
        let photo = scene(1.0);
        assert!(matches!(brighten(&photo, 230.0, 4.0), Cow::Borrowed(_)));
    }

    #[test]
    fn a_dim_photo_is_brought_back_with_its_hues() {
        let bright = scene(1.0);
        let dim = scene(0.3);
        let lifted = brighten(&dim, 230.0, 4.0);
        for (a, b) in bright.pixels().zip(lifted.pixels()) {
            for c in 0..3 {
                assert!(
                    (i32::from(a.0[c]) - i32::from(b.0[c])).abs() <= 3,
                    "{a:?} vs {b:?}"
                );
            }
        }
    }

    #[test]
    fn the_gain_is_capped_and_a_black_photo_is_unchanged() {
        let dim = scene(0.1);
        let lifted = brighten(&dim, 230.0, 2.0);
        let (d, l) = (dim.get_pixel(5, 5).0, lifted.get_pixel(5, 5).0);
        assert_eq!(l, d.map(|c| c * 2));
        let black = RgbImage::new(32, 32);
        assert!(matches!(brighten(&black, 235.0, 4.0), Cow::Borrowed(_)));
    }
}
