//! Colour conversions: 8-bit sRGB to CIELAB (D65) and to OpenCV-style 8-bit HSV.

use std::sync::OnceLock;

/// CIELAB planes of an image, one `f32` per pixel and channel, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct LabImage {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// Lightness L* in 0..=100.
    pub l: Vec<f32>,
    /// Green–red a*.
    pub a: Vec<f32>,
    /// Blue–yellow b*.
    pub b: Vec<f32>,
}

/// sRGB 8-bit value to linear light.
fn linear_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut linear = [0.0; 256];
        for (v, out) in linear.iter_mut().enumerate() {
            let c = v as f32 / 255.0;
            *out = if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            };
        }
        linear
    })
}

/// Cube root of a non-negative number: an exponent-thirding bit trick refined by three
/// Newton steps (relative error below 1e-6 on [1e-3, 1]). Branch-free and free of
/// table lookups, so a loop over a slice of them vectorises.
#[inline]
fn cbrt_fast(t: f32) -> f32 {
    let t = t.max(1e-12);
    let mut y = f32::from_bits(t.to_bits() / 3 + 0x2A51_4067);
    for _ in 0..3 {
        y = (2.0 * y + t / (y * y)) * (1.0 / 3.0);
    }
    y
}

/// CIELAB's f(t): the cube root above (6/29)³, a line below it.
#[inline]
fn lab_f(t: f32) -> f32 {
    const EPS: f32 = 216.0 / 24389.0;
    const KAPPA: f32 = 24389.0 / 27.0;
    let linear = (KAPPA * t + 16.0) / 116.0;
    let root = cbrt_fast(t);
    if t > EPS { root } else { linear }
}

/// Linear sRGB to XYZ with each row divided by the D65 white point's coordinate.
#[inline]
fn xyz(linear: &[f32; 256], rgb: [u8; 3]) -> [f32; 3] {
    let (r, g, b) = (
        linear[rgb[0] as usize],
        linear[rgb[1] as usize],
        linear[rgb[2] as usize],
    );
    [
        (0.412_456_4 * r + 0.357_576_1 * g + 0.180_437_5 * b) / 0.950_47,
        0.212_672_9 * r + 0.715_152_2 * g + 0.072_175 * b,
        (0.019_333_9 * r + 0.119_192 * g + 0.950_304_1 * b) / 1.088_83,
    ]
}

/// f(X), f(Y), f(Z) to L*, a*, b*.
#[inline]
fn lab_from_f(fx: f32, fy: f32, fz: f32) -> [f32; 3] {
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// Converts one 8-bit sRGB colour to CIELAB (D65 white).
///
/// ```
/// let [l, a, b] = ariadne_dlo::engine::color::rgb_to_lab([255, 255, 255]);
/// assert!((l - 100.0).abs() < 0.1 && a.abs() < 0.1 && b.abs() < 0.1);
/// ```
pub fn rgb_to_lab(rgb: [u8; 3]) -> [f32; 3] {
    let [x, y, z] = xyz(linear_table(), rgb);
    lab_from_f(lab_f(x), lab_f(y), lab_f(z))
}

impl LabImage {
    /// Converts an interleaved RGB8 buffer (`width * height * 3` bytes) to CIELAB planes.
    ///
    /// Two passes: table lookups to X, Y, Z planes (scalar), then f() and the Lab
    /// combination over whole planes (vectorised).
    pub fn from_rgb(rgb: &[u8], width: usize, height: usize) -> Self {
        let n = width * height;
        debug_assert_eq!(rgb.len(), n * 3);
        let linear = linear_table();
        let mut l = Vec::with_capacity(n);
        let mut a = Vec::with_capacity(n);
        let mut b = Vec::with_capacity(n);
        for px in rgb.chunks_exact(3) {
            let [x, y, z] = xyz(linear, [px[0], px[1], px[2]]);
            l.push(x);
            a.push(y);
            b.push(z);
        }
        for ((x, y), z) in l.iter_mut().zip(a.iter_mut()).zip(b.iter_mut()) {
            [*x, *y, *z] = lab_from_f(lab_f(*x), lab_f(*y), lab_f(*z));
        }
        Self {
            width,
            height,
            l,
            a,
            b,
        }
    }

    /// Lab colour of one pixel.
    #[inline]
    pub fn at(&self, index: usize) -> [f32; 3] {
        [self.l[index], self.a[index], self.b[index]]
    }

    /// Blurs each plane with a Gaussian of standard deviation `sigma` pixels
    /// (separable, kernel radius ceil(3 sigma), edges clamped). `sigma <= 0` is a no-op.
    pub fn gaussian_blur(&mut self, sigma: f32) {
        if sigma <= 0.0 {
            return;
        }
        let kernel = gaussian_kernel(sigma);
        let mut scratch = vec![0.0; self.width * self.height];
        for plane in [&mut self.l, &mut self.a, &mut self.b] {
            blur_plane(plane, &mut scratch, self.width, self.height, &kernel);
        }
    }
}

/// A normalised Gaussian kernel of standard deviation `sigma` pixels, radius ceil(3 sigma).
pub(crate) fn gaussian_kernel(sigma: f32) -> Vec<f32> {
    let radius = (3.0 * sigma).ceil() as i32;
    let mut k: Vec<f32> = (-radius..=radius)
        .map(|i| (-(i * i) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f32 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= sum);
    k
}

/// Horizontal pass into `scratch`, vertical pass back into `plane`. Each pass adds one
/// kernel tap over a whole row at a time (edge-clamped via a padded row), so the inner
/// loops are plain slice arithmetic the compiler vectorises.
pub(crate) fn blur_plane(
    plane: &mut [f32],
    scratch: &mut [f32],
    w: usize,
    h: usize,
    kernel: &[f32],
) {
    let r = kernel.len() / 2;
    let mut padded = vec![0.0; w + 2 * r];
    for y in 0..h {
        let row = &plane[y * w..(y + 1) * w];
        padded[..r].fill(row[0]);
        padded[r..r + w].copy_from_slice(row);
        padded[r + w..].fill(row[w - 1]);
        let out = &mut scratch[y * w..(y + 1) * w];
        out.fill(0.0);
        for (k, &wk) in kernel.iter().enumerate() {
            for (o, &s) in out.iter_mut().zip(&padded[k..k + w]) {
                *o += wk * s;
            }
        }
    }
    for y in 0..h {
        let out = &mut plane[y * w..(y + 1) * w];
        out.fill(0.0);
        for (k, &wk) in kernel.iter().enumerate() {
            let yi = (y + k).saturating_sub(r).min(h - 1);
            let src = &scratch[yi * w..(yi + 1) * w];
            for (o, &s) in out.iter_mut().zip(src) {
                *o += wk * s;
            }
        }
    }
}

/// Converts one 8-bit RGB colour to HSV in OpenCV's 8-bit ranges:
/// H in 0..180 (degrees halved), S and V in 0..=255.
///
/// ```
/// assert_eq!(ariadne_dlo::engine::color::rgb_to_hsv([255, 0, 0]), [0, 255, 255]);
/// assert_eq!(ariadne_dlo::engine::color::rgb_to_hsv([0, 0, 255]), [120, 255, 255]);
/// ```
#[inline]
pub fn rgb_to_hsv(rgb: [u8; 3]) -> [u8; 3] {
    let (r, g, b) = (rgb[0] as i32, rgb[1] as i32, rgb[2] as i32);
    let v = r.max(g).max(b);
    let min = r.min(g).min(b);
    let delta = v - min;
    if delta == 0 {
        return [0, 0, v as u8];
    }
    let s = div_exact_small(255 * delta + v / 2, v);
    // Halved hue = base + 30 * num / delta, base in halved degrees; a negative hue
    // (red sector, b > g) wraps by 180.
    let (base, num) = if v == r {
        (if g < b { 180 } else { 0 }, g - b)
    } else if v == g {
        (60, b - r)
    } else {
        (120, r - g)
    };
    // Rounded half up, in integers: the value is never negative, so this is the
    // nearest integer with ties away from zero, as OpenCV's rounding of the float.
    let h = div_exact_small(2 * base * delta + 60 * num + delta, 2 * delta);
    [(h % 180) as u8, s as u8, v as u8]
}

/// ⌈2⁴⁰ / d⌉ for every divisor d < 512 that [`rgb_to_hsv`] divides by.
const RECIPROCALS: [u64; 512] = {
    let mut t = [0u64; 512];
    let mut d = 1;
    while d < 512 {
        t[d] = (1u64 << 40).div_ceil(d as u64);
        d += 1;
    }
    t
};

/// ⌊a / d⌋ for 0 ≤ a < 2¹⁸ and 0 < d < 512, by a multiply: the reciprocal's rounding
/// error, at most d / 2⁴⁰ per unit of a, stays below the 1 / d that would change
/// the quotient (the exhaustive hue test checks every colour).
#[inline]
fn div_exact_small(a: i32, d: i32) -> i32 {
    debug_assert!((0..1 << 18).contains(&a) && (1..512).contains(&d));
    ((a as u64 * RECIPROCALS[d as usize]) >> 40) as i32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lab_matches_reference_values() {
        // Reference values from the CIE formulas in f64.
        let cases = [
            ([255, 0, 0], [53.24, 80.09, 67.20]),
            ([0, 255, 0], [87.73, -86.18, 83.18]),
            ([0, 0, 255], [32.30, 79.19, -107.86]),
            ([128, 128, 128], [53.59, 0.0, 0.0]),
            ([0, 0, 0], [0.0, 0.0, 0.0]),
        ];
        for (rgb, want) in cases {
            let got = rgb_to_lab(rgb);
            for c in 0..3 {
                assert!(
                    (got[c] - want[c]).abs() < 0.15,
                    "{rgb:?}: {got:?} vs {want:?}"
                );
            }
        }
    }

    #[test]
    fn fast_cube_root_is_accurate_where_lab_uses_it() {
        for i in 0..=10_000 {
            let t = 0.008 + 0.992 * i as f32 / 10_000.0;
            let (got, want) = (cbrt_fast(t), t.cbrt());
            assert!((got - want).abs() <= 2e-6 * want, "{t}: {got} vs {want}");
        }
    }

    #[test]
    fn plane_conversion_matches_the_per_pixel_one() {
        let rgb: Vec<u8> = (0..=255u8).flat_map(|v| [v, 255 - v, v / 3]).collect();
        let lab = LabImage::from_rgb(&rgb, 16, 16);
        for (i, px) in rgb.chunks_exact(3).enumerate() {
            assert_eq!(lab.at(i), rgb_to_lab([px[0], px[1], px[2]]));
        }
    }

    /// The float formula the integer hue must reproduce exactly.
    fn hsv_hue_in_floats(rgb: [u8; 3]) -> u8 {
        let (r, g, b) = (rgb[0] as i32, rgb[1] as i32, rgb[2] as i32);
        let v = r.max(g).max(b);
        let delta = v - r.min(g).min(b);
        if delta == 0 {
            return 0;
        }
        let h = if v == r {
            60.0 * (g - b) as f32 / delta as f32
        } else if v == g {
            120.0 + 60.0 * (b - r) as f32 / delta as f32
        } else {
            240.0 + 60.0 * (r - g) as f32 / delta as f32
        };
        let h = if h < 0.0 { h + 360.0 } else { h };
        (((h / 2.0).round() as i32) % 180) as u8
    }

    #[test]
    fn integer_hsv_matches_the_float_formula_for_every_colour() {
        for c in 0u32..1 << 24 {
            let rgb = [(c >> 16) as u8, (c >> 8) as u8, c as u8];
            let [h, s, v] = rgb_to_hsv(rgb);
            assert_eq!(h, hsv_hue_in_floats(rgb), "{rgb:?}");
            let (max, min) = (
                *rgb.iter().max().unwrap() as i32,
                *rgb.iter().min().unwrap() as i32,
            );
            let expected_s = if max == 0 {
                0
            } else {
                (255 * (max - min) + max / 2) / max
            };
            assert_eq!((s as i32, v as i32), (expected_s, max), "{rgb:?}");
        }
    }

    #[test]
    fn small_divisions_are_exact() {
        for d in 1..512 {
            for a in (0..1 << 18).step_by(7).chain([(1 << 18) - 1]) {
                assert_eq!(div_exact_small(a, d), a / d, "{a} / {d}");
            }
        }
    }

    #[test]
    fn hsv_follows_opencv_ranges() {
        assert_eq!(rgb_to_hsv([0, 255, 0]), [60, 255, 255]);
        assert_eq!(rgb_to_hsv([255, 255, 255]), [0, 0, 255]);
        assert_eq!(rgb_to_hsv([255, 0, 255]), [150, 255, 255]);
        assert_eq!(rgb_to_hsv([128, 64, 64])[0], 0);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
        /// The row-tap blur equals a direct 2-D convolution with the separable kernel
        /// and clamped edges.
        #[test]
        fn row_tap_blur_matches_a_naive_convolution(
            w in 1usize..24, h in 1usize..24, sigma in 0.3f32..3.0,
            values in proptest::collection::vec(-50.0f32..100.0, 24 * 24)
        ) {
            let mut plane: Vec<f32> = values[..w * h].to_vec();
            let original = plane.clone();
            let kernel = gaussian_kernel(sigma);
            let r = (kernel.len() / 2) as isize;
            let mut scratch = vec![0.0; w * h];
            blur_plane(&mut plane, &mut scratch, w, h, &kernel);
            let clamp = |v: isize, n: usize| v.clamp(0, n as isize - 1) as usize;
            for y in 0..h {
                for x in 0..w {
                    let mut want = 0.0f64;
                    for (j, &ky) in kernel.iter().enumerate() {
                        for (i, &kx) in kernel.iter().enumerate() {
                            let sx = clamp(x as isize + i as isize - r, w);
                            let sy = clamp(y as isize + j as isize - r, h);
                            want += (ky * kx) as f64 * original[sy * w + sx] as f64;
                        }
                    }
                    let got = plane[y * w + x] as f64;
                    proptest::prop_assert!((got - want).abs() < 1e-3, "({x}, {y}): {got} vs {want}");
                }
            }
        }
    }

    #[test]
    fn blur_preserves_constant_planes_and_mass() {
        let rgb = vec![200u8; 7 * 5 * 3];
        let mut lab = LabImage::from_rgb(&rgb, 7, 5);
        let before = lab.l[0];
        lab.gaussian_blur(1.0);
        assert!(lab.l.iter().all(|v| (v - before).abs() < 1e-3));
    }
}
