//! Resampling a photo to the working size, fast.
//!
//! [`resize`] computes what `image::imageops::resize` does for the Catmull-Rom and
//! triangle filters, to the bit (the same weights, the same order of f32 sums: a
//! vertical pass into f32 rows, then a horizontal pass, rounded to the nearest value),
//! but a whole row at a time: `imageops` walks the image a column at a time through a
//! four-channel f32 copy, which took 37-40 ms to enlarge a 640x480 photo 1.6 times on
//! this project's machine. [`box_shrink`] averages boxes, for factors of a half and
//! less.

use image::RgbImage;

/// A resampling filter's kernel, as `image::imageops::FilterType` defines it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// The Catmull-Rom cubic (B = 0, C = 0.5 in Mitchell and Netravali's family),
    /// support 2: for enlarging.
    CatmullRom,
    /// The triangle (bilinear), support 1: for shrinking, widened by the factor.
    Triangle,
}

impl Kernel {
    fn support(self) -> f32 {
        match self {
            Kernel::CatmullRom => 2.0,
            Kernel::Triangle => 1.0,
        }
    }

    /// The kernel at `x` input samples from the centre. The cubic's coefficients are
    /// those of `B = 0, C = 0.5` folded, in `image`'s order of operations.
    fn at(self, x: f32) -> f32 {
        let a = x.abs();
        match self {
            Kernel::CatmullRom if a < 1.0 => (9.0 * a.powi(3) - 15.0 * a.powi(2) + 6.0) / 6.0,
            Kernel::CatmullRom if a < 2.0 => {
                (-3.0 * a.powi(3) + 15.0 * a.powi(2) - 24.0 * a + 12.0) / 6.0
            }
            Kernel::Triangle if a < 1.0 => 1.0 - a,
            _ => 0.0,
        }
    }
}

/// For each of `dst` output samples over `src` input samples: the first input index and
/// the normalised weights of `kernel`, widened by the reduction factor when shrinking
/// (antialiased), as `image::imageops::resize` computes them.
pub fn weights(src: usize, dst: usize, kernel: Kernel) -> Vec<(usize, Vec<f32>)> {
    let ratio = src as f32 / dst as f32;
    let stretch = ratio.max(1.0);
    let support = kernel.support() * stretch;
    (0..dst)
        .map(|o| {
            let centre = (o as f32 + 0.5) * ratio;
            let lo = ((centre - support).floor() as i64).clamp(0, src as i64 - 1) as usize;
            let hi = ((centre + support).ceil() as i64).clamp(lo as i64 + 1, src as i64) as usize;
            let centre = centre - 0.5;
            let mut weights: Vec<f32> = (lo..hi)
                .map(|i| kernel.at((i as f32 - centre) / stretch))
                .collect();
            let sum: f32 = weights.iter().fold(0.0, |s, &w| s + w);
            weights.iter_mut().for_each(|w| *w /= sum);
            (lo, weights)
        })
        .collect()
}

/// `src` resized to `w` x `h` with `kernel`: `image::imageops::resize` to the bit.
pub fn resize(src: &RgbImage, w: u32, h: u32, kernel: Kernel) -> RgbImage {
    let (sw, sh) = (src.width() as usize, src.height() as usize);
    let (w, h) = (w as usize, h as usize);
    if (w, h) == (sw, sh) {
        return src.clone();
    }
    let row_len = sw * 3;
    let raw = src.as_raw();
    // Vertical pass: each output row from whole input rows, kept in f32.
    let mut tall = vec![0.0f32; h * row_len];
    for (out, (first, ws)) in tall.chunks_exact_mut(row_len).zip(weights(sh, h, kernel)) {
        for (k, &wk) in ws.iter().enumerate() {
            let row = &raw[(first + k) * row_len..(first + k + 1) * row_len];
            for (o, &v) in out.iter_mut().zip(row) {
                *o += f32::from(v) * wk;
            }
        }
    }
    // Horizontal pass, rounded to the nearest byte.
    let columns = weights(sw, w, kernel);
    let mut out = Vec::with_capacity(w * h * 3);
    for row in tall.chunks_exact(row_len) {
        for (first, ws) in &columns {
            let mut acc = [0.0f32; 3];
            let taps = &row[first * 3..(first + ws.len()) * 3];
            for (px, &wk) in taps.chunks_exact(3).zip(ws) {
                acc[0] += px[0] * wk;
                acc[1] += px[1] * wk;
                acc[2] += px[2] * wk;
            }
            out.extend(acc.map(nearest_byte));
        }
    }
    RgbImage::from_raw(w as u32, h as u32, out).expect("w x h x 3 bytes")
}

/// `src` resized to `w` x `h` with the filter its direction asks for: Catmull-Rom when
/// it grows wider (sharp edges, as a finer sensor would see them), the triangle when
/// it does not (averaging, as a coarser one would).
pub fn resize_to(src: &RgbImage, w: u32, h: u32) -> RgbImage {
    let kernel = if w > src.width() {
        Kernel::CatmullRom
    } else {
        Kernel::Triangle
    };
    resize(src, w, h, kernel)
}

/// `v` clamped to [0, 255] and rounded half away from zero, as `f32::round` does, with
/// a truncating cast: `round` is a library call on x86-64 without SSE4.1, and one per
/// channel cost about 3 ms of the horizontal pass's 13 when enlarging 640x480 1.6 times.
pub(crate) fn nearest_byte(v: f32) -> u8 {
    let v = v.clamp(0.0, 255.0);
    let up = (v + 0.5) as u8;
    // v + 0.5 itself rounds up when v lies just under a half (0.49999997 + 0.5 = 1.0);
    // `up - 0.5` is exact, so the test is too.
    if f32::from(up) - 0.5 > v { up - 1 } else { up }
}

/// `src` shrunk to `w` x `h` (each at most half of `src`'s): output pixel (x, y) is
/// the mean of the source pixels from `x·W/w` to `(x+1)·W/w` (and likewise in y).
pub fn box_shrink(src: &RgbImage, w: u32, h: u32) -> RgbImage {
    let (sw, sh) = (src.width() as usize, src.height() as usize);
    let (w, h) = (w as usize, h as usize);
    // The source columns of each output column, as byte offsets into a row.
    let cols: Vec<(usize, usize)> = (0..w)
        .map(|x| (x * sw / w * 3, (x + 1) * sw / w * 3))
        .collect();
    let raw = src.as_raw();
    let mut sums = vec![0u32; sw * 3];
    let mut out = Vec::with_capacity(w * h * 3);
    for y in 0..h {
        let (y0, y1) = (y * sh / h, (y + 1) * sh / h);
        sums.fill(0);
        for row in raw[y0 * sw * 3..y1 * sw * 3].chunks_exact(sw * 3) {
            for (s, &v) in sums.iter_mut().zip(row) {
                *s += v as u32;
            }
        }
        for &(a, b) in &cols {
            let n = ((b - a) / 3 * (y1 - y0)) as u32;
            for c in 0..3 {
                let total: u32 = sums[a + c..b].iter().step_by(3).sum();
                out.push(((total + n / 2) / n) as u8);
            }
        }
    }
    RgbImage::from_raw(w as u32, h as u32, out).expect("w x h x 3 bytes")
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::imageops::{self, FilterType};

    /// A photo-like pattern: gradients, sharp edges and a busy texture.
    fn scene(w: u32, h: u32) -> RgbImage {
        RgbImage::from_fn(w, h, |x, y| {
            let edge = if (x / 7 + y / 5) % 3 == 0 { 200 } else { 30 };
            image::Rgb([
                (x * 255 / w.max(1)) as u8,
                edge,
                ((x * 37 + y * 91) % 256) as u8,
            ])
        })
    }

    #[test]
    fn resizing_is_imageops_to_the_bit() {
        let sizes = [
            (64, 48, 105, 79),
            (64, 48, 45, 34),
            (37, 23, 64, 40),
            (50, 40, 26, 39),
        ];
        for (sw, sh, w, h) in sizes {
            let src = scene(sw, sh);
            for (kernel, filter) in [
                (Kernel::CatmullRom, FilterType::CatmullRom),
                (Kernel::Triangle, FilterType::Triangle),
            ] {
                let ours = resize(&src, w, h, kernel);
                let theirs = imageops::resize(&src, w, h, filter);
                assert_eq!(ours.dimensions(), (w, h));
                assert!(
                    ours.as_raw() == theirs.as_raw(),
                    "{sw}x{sh} → {w}x{h} with {kernel:?}"
                );
            }
        }
    }

    #[test]
    fn bytes_round_as_f32_round_does() {
        // Every half and its neighbours (0.49999997 + 0.5 rounds to 1.0 in f32), and
        // values outside the byte range.
        let halves = (-2..=257).map(|k| k as f32 + 0.5);
        let near = halves.flat_map(|h| [h.next_down(), h, h.next_up()]);
        for v in near.chain([-3.0, -0.0, 0.0, 127.49, 300.0]) {
            let expected = v.clamp(0.0, 255.0).round() as u8;
            assert_eq!(nearest_byte(v), expected, "{v}");
        }
    }

    #[test]
    fn weights_sum_to_one_and_stay_inside() {
        for (src, dst) in [(640, 1050), (640, 300), (7, 3), (3, 7)] {
            for kernel in [Kernel::CatmullRom, Kernel::Triangle] {
                for (first, ws) in weights(src, dst, kernel) {
                    assert!(first + ws.len() <= src);
                    let sum: f32 = ws.iter().sum();
                    assert!((sum - 1.0).abs() < 1e-5, "{src} → {dst}: {sum}");
                }
            }
        }
    }

    #[test]
    fn shrinking_averages_boxes() {
        // 6x4 → 3x2: each output pixel is the mean of a 2x2 block.
        let src = RgbImage::from_fn(6, 4, |x, y| image::Rgb([(10 * x + 60 * y) as u8, 0, 255]));
        let out = box_shrink(&src, 3, 2);
        assert_eq!(out.dimensions(), (3, 2));
        for (x, y, p) in out.enumerate_pixels() {
            let mean = (10 * (2 * x) + 5 + 60 * (2 * y) + 30) as u8;
            assert_eq!(p.0, [mean, 0, 255], "({x}, {y})");
        }
        // Uneven boxes: 5 → 2 columns averages 2 then 3 of them.
        let row = RgbImage::from_fn(5, 2, |x, _| {
            image::Rgb([[0, 10, 20, 30, 40][x as usize]; 3])
        });
        assert_eq!(box_shrink(&row, 2, 1).as_raw(), &[5, 5, 5, 30, 30, 30]);
    }
}
