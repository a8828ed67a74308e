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

/// Samples of f(t) = t^(1/3) on [0, 1], for linear interpolation.
const CBRT_LUT_SIZE: usize = 2048;

struct Tables {
    /// sRGB 8-bit value to linear light.
    linear: [f32; 256],
    /// CIELAB's f(t) sampled on [0, 1].
    cbrt: Vec<f32>,
}

fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(|| {
        let mut linear = [0.0; 256];
        for (v, out) in linear.iter_mut().enumerate() {
            let c = v as f32 / 255.0;
            *out = if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            };
        }
        let cbrt = (0..=CBRT_LUT_SIZE + 1)
            .map(|i| lab_f_exact(i as f32 / CBRT_LUT_SIZE as f32))
            .collect();
        Tables { linear, cbrt }
    })
}

fn lab_f_exact(t: f32) -> f32 {
    const EPS: f32 = 216.0 / 24389.0;
    const KAPPA: f32 = 24389.0 / 27.0;
    if t > EPS {
        t.cbrt()
    } else {
        (KAPPA * t + 16.0) / 116.0
    }
}

#[inline]
fn lab_f(cbrt: &[f32], t: f32) -> f32 {
    let x = t.clamp(0.0, 1.0) * CBRT_LUT_SIZE as f32;
    let i = x as usize;
    let frac = x - i as f32;
    cbrt[i] + (cbrt[i + 1] - cbrt[i]) * frac
}

/// Converts one 8-bit sRGB colour to CIELAB (D65 white).
///
/// ```
/// let [l, a, b] = ariadne_dlo::engine::color::rgb_to_lab([255, 255, 255]);
/// assert!((l - 100.0).abs() < 0.1 && a.abs() < 0.1 && b.abs() < 0.1);
/// ```
#[inline]
pub fn rgb_to_lab(rgb: [u8; 3]) -> [f32; 3] {
    let t = tables();
    let (r, g, b) = (
        t.linear[rgb[0] as usize],
        t.linear[rgb[1] as usize],
        t.linear[rgb[2] as usize],
    );
    // sRGB → XYZ, each row divided by the D65 white point's coordinate.
    let x = (0.412_456_4 * r + 0.357_576_1 * g + 0.180_437_5 * b) / 0.950_47;
    let y = 0.212_672_9 * r + 0.715_152_2 * g + 0.072_175 * b;
    let z = (0.019_333_9 * r + 0.119_192 * g + 0.950_304_1 * b) / 1.088_83;
    let (fx, fy, fz) = (lab_f(&t.cbrt, x), lab_f(&t.cbrt, y), lab_f(&t.cbrt, z));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

impl LabImage {
    /// Converts an interleaved RGB8 buffer (`width * height * 3` bytes) to CIELAB planes.
    pub fn from_rgb(rgb: &[u8], width: usize, height: usize) -> Self {
        let n = width * height;
        debug_assert_eq!(rgb.len(), n * 3);
        let mut l = Vec::with_capacity(n);
        let mut a = Vec::with_capacity(n);
        let mut b = Vec::with_capacity(n);
        for px in rgb.chunks_exact(3) {
            let [pl, pa, pb] = rgb_to_lab([px[0], px[1], px[2]]);
            l.push(pl);
            a.push(pa);
            b.push(pb);
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

fn gaussian_kernel(sigma: f32) -> Vec<f32> {
    let radius = (3.0 * sigma).ceil() as i32;
    let mut k: Vec<f32> = (-radius..=radius)
        .map(|i| (-(i * i) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f32 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= sum);
    k
}

/// Horizontal pass into `scratch`, vertical pass back into `plane`.
fn blur_plane(plane: &mut [f32], scratch: &mut [f32], w: usize, h: usize, kernel: &[f32]) {
    let r = kernel.len() / 2;
    for y in 0..h {
        let row = &plane[y * w..(y + 1) * w];
        let out = &mut scratch[y * w..(y + 1) * w];
        for (x, o) in out.iter_mut().enumerate() {
            let mut acc = 0.0;
            for (k, &wk) in kernel.iter().enumerate() {
                let xi = (x + k).saturating_sub(r).min(w - 1);
                acc += wk * row[xi];
            }
            *o = acc;
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
    let s = (255 * delta + v / 2) / v;
    // Hue in degrees, 0..360, then halved.
    let h = if v == r {
        60.0 * (g - b) as f32 / delta as f32
    } else if v == g {
        120.0 + 60.0 * (b - r) as f32 / delta as f32
    } else {
        240.0 + 60.0 * (r - g) as f32 / delta as f32
    };
    let h = if h < 0.0 { h + 360.0 } else { h };
    let h = ((h / 2.0).round() as i32) % 180;
    [h as u8, s as u8, v as u8]
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
    fn hsv_follows_opencv_ranges() {
        assert_eq!(rgb_to_hsv([0, 255, 0]), [60, 255, 255]);
        assert_eq!(rgb_to_hsv([255, 255, 255]), [0, 0, 255]);
        assert_eq!(rgb_to_hsv([255, 0, 255]), [150, 255, 255]);
        assert_eq!(rgb_to_hsv([128, 64, 64])[0], 0);
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
