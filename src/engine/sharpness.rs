//! Sharpness: a soft photo (a lens out of focus, a camera that shook) is sharpened
//! before the network and the engine read it.
//!
//! On a soft photo the colours of a cable and of what lies beside it blend over several
//! pixels: superpixels straddle the cable's edge and a crossing's colours run into each
//! other, so walks lose cables and pair the wrong ends. The photo's softness is read
//! as the width of its edges ([`edge_width`]); one that is much softer than the photos
//! the engine was tuned on (`sharp_edge_px`) gets an unsharp mask of the missing
//! width ([`sharpen`]). A sharp photo is left as it is. The pipeline applies it to the
//! working image after the exposure, before the network and the engine see it.

use std::borrow::Cow;

use image::RgbImage;

use super::Params;
use super::color::{blur_plane, gaussian_kernel};
use super::resample::nearest_byte;

/// A photo is sharpened when its edges are wider than `sharp_edge_px` by more than
/// this factor. The development photos read 1.02-1.09 px against 1.05; the same
/// photos under a Gaussian blur of 1.5 px read 1.72-1.87.
const SOFT_FACTOR: f32 = 1.3;

/// Half the window an edge's contrast is read over, pixels (an edge as soft as σ = 3 px
/// still fits).
const HALF_WINDOW: usize = 4;

/// Least contrast (luma levels) of an edge that is read: texture and noise are not.
const MIN_EDGE_CONTRAST: f32 = 30.0;

/// Slopes gentler than this are not read as an edge's peak: a rise of
/// [`MIN_EDGE_CONTRAST`] over the window's `2 HALF_WINDOW` steps is about that steep
/// on average, so steeper somewhere.
const MIN_PEAK_SLOPE: f32 = MIN_EDGE_CONTRAST / (2 * HALF_WINDOW) as f32;

/// Fewest edges for a reading.
const MIN_EDGES: usize = 50;

/// The photo's edge width: the σ, pixels, of the Gaussian blur that would make a sharp
/// step look like its edges, or `None` when it shows too few edges to tell.
///
/// Along every other row (for edges across x) and every other column (edges across
/// y), each peak of the luma's central-difference slope that is the steepest within
/// [`HALF_WINDOW`] and at least twice the slope across (an edge facing that way) is one
/// edge. A step of contrast C blurred by σ has a steepest slope of C / (σ √(2π)), so
/// each edge gives σ = C / (slope √(2π)), with C the luma's range over the window;
/// the median over the edges of at least [`MIN_EDGE_CONTRAST`] is the reading.
pub fn edge_width(image: &RgbImage) -> Option<f32> {
    let (w, h) = (image.width() as usize, image.height() as usize);
    if w < 4 * HALF_WINDOW || h < 4 * HALF_WINDOW {
        return None;
    }
    let luma: Vec<f32> = image
        .pixels()
        .map(|p| 0.299 * f32::from(p.0[0]) + 0.587 * f32::from(p.0[1]) + 0.114 * f32::from(p.0[2]))
        .collect();
    let mut ratios = Vec::new();
    // Rows: along x (stride 1) within a row, across y (stride w) for the other slope;
    // then columns, the roles swapped.
    for (lines, len, along, across) in [(h, w, 1, w), (w, h, w, 1)] {
        let start = |line: usize| if along == 1 { line * w } else { line };
        for line in (1..lines - 1).step_by(2) {
            let at = |i: usize| start(line) + i * along;
            let slope = |i: usize| 0.5 * (luma[at(i + 1)] - luma[at(i - 1)]).abs();
            let slopes: Vec<f32> = (1..len - 1).map(slope).collect();
            for i in HALF_WINDOW + 1..len - HALF_WINDOW - 1 {
                let s = slopes[i - 1];
                let window = i - HALF_WINDOW..=i + HALF_WINDOW;
                if s < MIN_PEAK_SLOPE || window.clone().any(|j| slopes[j - 1] > s) {
                    continue;
                }
                let k = at(i);
                if s < 2.0 * 0.5 * (luma[k + across] - luma[k - across]).abs() {
                    continue;
                }
                let (lo, hi) = window.fold((f32::MAX, f32::MIN), |(lo, hi), j| {
                    let v = luma[at(j)];
                    (lo.min(v), hi.max(v))
                });
                if hi - lo >= MIN_EDGE_CONTRAST {
                    ratios.push((hi - lo) / s);
                }
            }
        }
    }
    if ratios.len() < MIN_EDGES {
        return None;
    }
    let mid = ratios.len() / 2;
    let (_, median, _) = ratios.select_nth_unstable_by(mid, f32::total_cmp);
    Some(*median / (2.0 * std::f32::consts::PI).sqrt())
}

/// `image` with an unsharp mask: each channel plus `amount` times its difference from
/// its Gaussian blur of `sigma` pixels, clipped to 0..=255.
pub fn sharpen(image: &RgbImage, sigma: f32, amount: f32) -> RgbImage {
    let (w, h) = (image.width() as usize, image.height() as usize);
    let kernel = gaussian_kernel(sigma);
    let mut out = image.clone();
    let (mut blurred, mut scratch) = (vec![0.0f32; w * h], vec![0.0f32; w * h]);
    for c in 0..3 {
        for (v, p) in blurred.iter_mut().zip(image.pixels()) {
            *v = f32::from(p.0[c]);
        }
        blur_plane(&mut blurred, &mut scratch, w, h, &kernel);
        for (p, b) in out.pixels_mut().zip(&blurred) {
            let v = f32::from(p.0[c]);
            p.0[c] = nearest_byte(v + amount * (v - b));
        }
    }
    out
}

/// `image` under a Gaussian blur of `sigma` pixels (a soft lens): an unsharp mask of
/// amount −1.
pub fn blurred(image: &RgbImage, sigma: f32) -> RgbImage {
    sharpen(image, sigma, -1.0)
}

/// `image` sharpened by what its edges lack against `params.sharp_edge_px` when it is
/// soft (see module docs); borrowed unchanged when it is sharp, shows too few edges, or
/// `params.sharpen_amount` is 0.
pub fn apply<'a>(image: &'a RgbImage, params: &Params) -> Cow<'a, RgbImage> {
    let reference = params.sharp_edge_px;
    if params.sharpen_amount <= 0.0 {
        return Cow::Borrowed(image);
    }
    match edge_width(image) {
        Some(width) if width > SOFT_FACTOR * reference => {
            let missing = (width * width - reference * reference).sqrt();
            Cow::Owned(sharpen(image, missing, params.sharpen_amount))
        }
        _ => Cow::Borrowed(image),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Rgb;

    /// Dark bands on a pale board, blurred by `sigma` (0: as drawn).
    fn bands(sigma: f32) -> RgbImage {
        let sharp = RgbImage::from_fn(160, 120, |x, y| {
            let on = (x / 10) % 3 == 1 || (y / 12) % 4 == 2;
            Rgb(if on { [60, 40, 150] } else { [225, 220, 205] })
        });
        if sigma > 0.0 {
            blurred(&sharp, sigma)
        } else {
            sharp
        }
    }

    #[test]
    fn edge_width_reads_the_blur() {
        // A step as drawn reads about 0.8 px (the central difference spreads it over
        // two pixels); blurs add to that in quadrature, as `apply` assumes.
        let sharp = edge_width(&bands(0.0)).unwrap();
        assert!(sharp < 0.9, "{sharp}");
        for sigma in [1.0f32, 1.5, 2.5] {
            let read = edge_width(&bands(sigma)).unwrap();
            let expected = sigma.hypot(sharp);
            assert!(
                (read - expected).abs() < 0.15 * expected,
                "σ {sigma}: read {read}"
            );
        }
        assert_eq!(edge_width(&RgbImage::new(160, 120)), None);
    }

    #[test]
    fn a_soft_photo_is_sharpened_and_a_sharp_one_left_alone() {
        let params = Params::default();
        let sharp = bands(params.sharp_edge_px);
        assert!(matches!(apply(&sharp, &params), Cow::Borrowed(_)));
        let soft = bands(2.0);
        let restored = apply(&soft, &params);
        assert!(matches!(restored, Cow::Owned(_)));
        let (read, was) = (edge_width(&restored).unwrap(), edge_width(&soft).unwrap());
        assert!(read < 0.9 * was, "{read} from {was}");
        // Nearer the bands as drawn than the soft photo was.
        let drawn = bands(0.0);
        let off = |image: &RgbImage| -> f64 {
            let pairs = image.as_raw().iter().zip(drawn.as_raw());
            pairs.map(|(a, b)| f64::from(a.abs_diff(*b))).sum()
        };
        assert!(
            off(&restored) < 0.8 * off(&soft),
            "{} vs {}",
            off(&restored),
            off(&soft)
        );
        let none = Params {
            sharpen_amount: 0.0,
            ..Params::default()
        };
        assert!(matches!(apply(&soft, &none), Cow::Borrowed(_)));
    }
}
