//! SLIC superpixels (Achanta et al. 2012) with connectivity enforcement.
//!
//! k-means on (L, a, b, x, y) restricted to a 2S x 2S window around each centre, with
//! distance D² = d_lab² + (d_xy / S)² · m². The assignment loop runs over contiguous row
//! slices of structure-of-arrays planes with a branch-free select, which the compiler
//! vectorises. Afterwards every label is made one 4-connected region: fragments smaller
//! than `min_size_factor · S²` join the region they touch, larger ones get labels of
//! their own.

use super::color::LabImage;
use super::connectivity::enforce_connectivity;
use super::{Deadline, EngineError};

/// A label image: one superpixel id per pixel, ids dense in `0..count`.
#[derive(Debug, Clone, PartialEq)]
pub struct Superpixels {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// Row-major superpixel id of each pixel.
    pub labels: Vec<u32>,
    /// Number of superpixels; every id below it labels at least one pixel.
    pub count: usize,
    /// Nominal grid step S in pixels (sqrt of pixels per superpixel).
    pub step: f32,
}

/// SLIC settings (see [`crate::engine::Params`] for their meaning and defaults).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlicSettings {
    /// Wanted number of superpixels.
    pub n_segments: u32,
    /// Compactness m.
    pub compactness: f32,
    /// k-means iterations.
    pub iterations: u32,
    /// Minimum fragment size as a fraction of S².
    pub min_size_factor: f32,
}

#[derive(Clone, Copy)]
struct Centre {
    l: f32,
    a: f32,
    b: f32,
    x: f32,
    y: f32,
}

/// Over-segments `lab` (already blurred if wanted) into about `n_segments` superpixels.
pub fn slic(lab: &LabImage, s: &SlicSettings) -> Superpixels {
    match slic_until(lab, s, Deadline::NONE) {
        Ok(sp) => sp,
        Err(_) => unreachable!("no deadline to pass"),
    }
}

/// [`slic`], giving up between iterations once `deadline` has passed.
pub fn slic_until(
    lab: &LabImage,
    s: &SlicSettings,
    deadline: Deadline,
) -> Result<Superpixels, EngineError> {
    let (w, h) = (lab.width, lab.height);
    let n = w * h;
    let step = ((n as f32) / s.n_segments.max(1) as f32).sqrt().max(1.0);
    let nx = ((w as f32 / step).round() as usize).max(1);
    let ny = ((h as f32 / step).round() as usize).max(1);
    let (cw, ch) = (w as f32 / nx as f32, h as f32 / ny as f32);

    let mut centres = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let x = ((i as f32 + 0.5) * cw).min(w as f32 - 1.0);
            let y = ((j as f32 + 0.5) * ch).min(h as f32 - 1.0);
            let idx = y as usize * w + x as usize;
            centres.push(Centre {
                l: lab.l[idx],
                a: lab.a[idx],
                b: lab.b[idx],
                x,
                y,
            });
        }
    }
    // Initial labels: the grid cell, so that a pixel no window reaches still has one.
    let column: Vec<u32> = (0..w)
        .map(|x| ((x as f32 / cw) as usize).min(nx - 1) as u32)
        .collect();
    let mut labels = Vec::with_capacity(n);
    for y in 0..h {
        let j = ((y as f32 / ch) as usize).min(ny - 1) as u32;
        labels.extend(column.iter().map(|&i| j * nx as u32 + i));
    }
    let mut dist = vec![f32::INFINITY; n];
    let spatial = (s.compactness / step).powi(2);
    let radius = step.ceil() as isize;
    let mut sums = vec![[0.0f64; 6]; centres.len()];
    let mut dx2 = Vec::with_capacity(2 * radius as usize + 1);

    for _ in 0..s.iterations {
        deadline.check()?;
        dist.fill(f32::INFINITY);
        for (k, c) in centres.iter().enumerate() {
            let x0 = (c.x as isize - radius).max(0) as usize;
            let x1 = ((c.x as isize + radius + 1) as usize).min(w);
            let y0 = (c.y as isize - radius).max(0) as usize;
            let y1 = ((c.y as isize + radius + 1) as usize).min(h);
            if x0 >= x1 || y0 >= y1 {
                continue;
            }
            dx2.clear();
            dx2.extend((x0..x1).map(|x| (x as f32 - c.x).powi(2) * spatial));
            for y in y0..y1 {
                let dy2 = (y as f32 - c.y).powi(2) * spatial;
                let range = y * w + x0..y * w + x1;
                assign_row(
                    RowPlanes {
                        l: &lab.l[range.clone()],
                        a: &lab.a[range.clone()],
                        b: &lab.b[range.clone()],
                        dx2: &dx2,
                    },
                    c,
                    dy2,
                    k as u32,
                    &mut dist[range.clone()],
                    &mut labels[range],
                );
            }
        }
        accumulate(lab, &labels, &mut sums);
        for (c, s) in centres.iter_mut().zip(&sums) {
            if s[5] > 0.0 {
                let inv = 1.0 / s[5];
                *c = Centre {
                    l: (s[0] * inv) as f32,
                    a: (s[1] * inv) as f32,
                    b: (s[2] * inv) as f32,
                    x: (s[3] * inv) as f32,
                    y: (s[4] * inv) as f32,
                };
            }
        }
    }
    let min_size = ((s.min_size_factor * step * step) as usize).max(1);
    let (labels, count) = enforce_connectivity(&labels, w, h, min_size);
    Ok(Superpixels {
        width: w,
        height: h,
        labels,
        count,
        step,
    })
}

/// One window row of the Lab planes and the squared, weighted x offsets from the centre.
struct RowPlanes<'a> {
    l: &'a [f32],
    a: &'a [f32],
    b: &'a [f32],
    dx2: &'a [f32],
}

/// Assigns the pixels of one window row to centre `k` where it is nearer than their
/// current best. Zipped slices and a branch-free select let the compiler vectorise it.
#[inline]
fn assign_row(
    row: RowPlanes<'_>,
    c: &Centre,
    dy2: f32,
    k: u32,
    dist: &mut [f32],
    labels: &mut [u32],
) {
    let pixels = row.l.iter().zip(row.a).zip(row.b).zip(row.dx2);
    for ((((&l, &a), &b), &dx2), (d_best, label)) in pixels.zip(dist.iter_mut().zip(labels)) {
        let (dl, da, db) = (l - c.l, a - c.a, b - c.b);
        let d = dl * dl + da * da + db * db + dx2 + dy2;
        let better = d < *d_best;
        let mask = (better as u32).wrapping_neg();
        *d_best = if better { d } else { *d_best };
        *label = (*label & !mask) | (k & mask);
    }
}

/// Per-label sums of L, a, b, x, y and pixel count. Labels come in runs along a row,
/// so colour is summed in f32 per run and x from the run's bounds.
fn accumulate(lab: &LabImage, labels: &[u32], sums: &mut [[f64; 6]]) {
    sums.iter_mut().for_each(|s| *s = [0.0; 6]);
    let w = lab.width;
    for y in 0..lab.height {
        let row = y * w..(y + 1) * w;
        let (rl, ra, rb) = (
            &lab.l[row.clone()],
            &lab.a[row.clone()],
            &lab.b[row.clone()],
        );
        let labels = &labels[row];
        let mut start = 0;
        while start < w {
            let k = labels[start];
            let end = start + labels[start..].iter().take_while(|&&l| l == k).count();
            let sum = |plane: &[f32]| plane[start..end].iter().sum::<f32>() as f64;
            let count = (end - start) as f64;
            let s = &mut sums[k as usize];
            s[0] += sum(rl);
            s[1] += sum(ra);
            s[2] += sum(rb);
            s[3] += (start + end - 1) as f64 * count / 2.0;
            s[4] += y as f64 * count;
            s[5] += count;
            start = end;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    use crate::engine::connectivity::enforce_connectivity;

    /// Every label is one 4-connected region and ids are dense.
    pub(crate) fn assert_connected_dense(sp: &Superpixels) {
        let (w, h) = (sp.width, sp.height);
        let mut seen = vec![false; sp.count];
        let (_, components) = enforce_connectivity(&sp.labels, w, h, 1);
        assert_eq!(
            components, sp.count,
            "a label has more than one connected region"
        );
        for &a in &sp.labels {
            assert!((a as usize) < sp.count);
            seen[a as usize] = true;
        }
        assert!(seen.iter().all(|&s| s), "label ids are not dense");
    }

    fn two_colour_image(w: usize, h: usize) -> LabImage {
        let mut rgb = vec![240u8; w * h * 3];
        for y in 0..h {
            for x in w / 2..w {
                let p = (y * w + x) * 3;
                rgb[p..p + 3].copy_from_slice(&[200, 20, 20]);
            }
        }
        LabImage::from_rgb(&rgb, w, h)
    }

    #[test]
    fn superpixels_respect_a_strong_edge() {
        let lab = two_colour_image(64, 48);
        let settings = SlicSettings {
            n_segments: 48,
            compactness: 10.0,
            iterations: 10,
            min_size_factor: 0.25,
        };
        let sp = slic(&lab, &settings);
        assert!(sp.count >= 30 && sp.count <= 70, "count {}", sp.count);
        assert_connected_dense(&sp);
        // No superpixel straddles the colour edge at x = 32.
        let mut side = vec![None; sp.count];
        for (p, &l) in sp.labels.iter().enumerate() {
            let right = p % 64 >= 32;
            let s = side[l as usize].get_or_insert(right);
            assert_eq!(*s, right, "superpixel {l} straddles the edge");
        }
    }

    /// A random Lab image (the planes hold arbitrary values; SLIC does not care).
    fn random_lab(w: usize, h: usize, seed: u64) -> LabImage {
        let mut state = seed | 1;
        let rgb: Vec<u8> = (0..w * h * 3)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 56) as u8
            })
            .collect();
        LabImage::from_rgb(&rgb, w, h)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// The vectorised row assignment equals a plain per-pixel comparison.
        #[test]
        fn assign_row_matches_a_naive_loop(
            len in 1usize..40, seed in any::<u64>(), k in 0u32..1000,
            cx in -5.0f32..45.0, dy2 in 0.0f32..500.0, spatial in 0.0f32..5.0
        ) {
            let lab = random_lab(len, 1, seed);
            let c = Centre { l: lab.l[len / 2] + 3.0, a: lab.a[0], b: lab.b[len - 1], x: cx, y: 0.0 };
            let dx2: Vec<f32> = (0..len).map(|x| (x as f32 - cx).powi(2) * spatial).collect();
            // Existing bests: some beaten, some not.
            let mut dist: Vec<f32> = (0..len).map(|i| (i as f32 * 37.0) % 400.0).collect();
            let mut labels: Vec<u32> = (0..len as u32).collect();
            let (mut naive_dist, mut naive_labels) = (dist.clone(), labels.clone());
            for i in 0..len {
                let d = (lab.l[i] - c.l).powi(2) + (lab.a[i] - c.a).powi(2)
                    + (lab.b[i] - c.b).powi(2) + dx2[i] + dy2;
                if d < naive_dist[i] {
                    naive_dist[i] = d;
                    naive_labels[i] = k;
                }
            }
            let row = RowPlanes { l: &lab.l, a: &lab.a, b: &lab.b, dx2: &dx2 };
            assign_row(row, &c, dy2, k, &mut dist, &mut labels);
            prop_assert_eq!(labels, naive_labels);
            for (got, want) in dist.iter().zip(&naive_dist) {
                prop_assert!((got - want).abs() <= 1e-3 * want.abs().max(1.0));
            }
        }

        /// Run-based centre sums equal per-pixel sums.
        #[test]
        fn accumulate_matches_per_pixel_sums(
            w in 1usize..30, h in 1usize..20, seed in any::<u64>(), n in 1u32..6
        ) {
            let lab = random_lab(w, h, seed);
            let labels: Vec<u32> = (0..w * h).map(|i| ((i / 3 + i / w) as u32) % n).collect();
            let mut sums = vec![[0.0f64; 6]; n as usize];
            accumulate(&lab, &labels, &mut sums);
            let mut naive = vec![[0.0f64; 6]; n as usize];
            for (i, &k) in labels.iter().enumerate() {
                let s = &mut naive[k as usize];
                s[0] += lab.l[i] as f64;
                s[1] += lab.a[i] as f64;
                s[2] += lab.b[i] as f64;
                s[3] += (i % w) as f64;
                s[4] += (i / w) as f64;
                s[5] += 1.0;
            }
            for (got, want) in sums.iter().zip(&naive) {
                for c in 0..6 {
                    prop_assert!((got[c] - want[c]).abs() <= 1e-3 * want[c].abs().max(1.0), "{got:?} vs {want:?}");
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        #[test]
        fn every_pixel_labelled_and_labels_connected(
            w in 8usize..48, h in 8usize..48, seed in any::<u64>(), n in 4u32..80, m in 1.0f32..40.0
        ) {
            let lab = random_lab(w, h, seed);
            let sp = slic(&lab, &SlicSettings { n_segments: n, compactness: m, iterations: 5, min_size_factor: 0.25 });
            prop_assert_eq!(sp.labels.len(), w * h);
            assert_connected_dense(&sp);
        }
    }
}
