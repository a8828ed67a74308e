//! Sub-pixel refinement of a centreline on the image, and the cable's measured width
//! and colour.
//!
//! Across the curve, every few pixels, a colour profile is sampled (bilinear, half-pixel
//! steps). Each sample is called "cable" when it is closer in Lab to the cable's colour
//! (the median along the curve) than to the background at either end of the profile.
//! The run of cable samples nearest the curve gives both edges with sub-pixel
//! interpolation: their midpoint is the centre, their distance the width. Profiles that
//! cannot be read (a crossing, the frame, a cable of the background's colour) are
//! skipped; offsets are median- then mean-filtered along the curve so one bad profile
//! cannot bend it.

use super::color::LabImage;

/// Result of refining one centreline.
#[derive(Debug, Clone, PartialEq)]
pub struct Refined {
    /// The moved points, same count and order as the input.
    pub points: Vec<[f32; 2]>,
    /// Median measured width, pixels, when enough profiles could be read.
    pub width_px: Option<f32>,
    /// Fraction of profiles that could be read, 0..=1.
    pub coverage: f32,
}

/// Distance between profile samples, pixels.
const PROFILE_STEP: f32 = 0.5;
/// A profile is read every this many input points.
const PROFILE_STRIDE: usize = 2;
/// A profile end closer than this (Lab ΔE) to the cable colour is not background.
const MIN_BACKGROUND_DE: f32 = 10.0;
/// Smallest plausible cable width, pixels.
const MIN_WIDTH: f32 = 2.0;

/// Bilinear Lab sample at (x, y); `None` outside the image.
pub fn sample_lab(lab: &LabImage, x: f32, y: f32) -> Option<[f32; 3]> {
    let (w, h) = (lab.width, lab.height);
    if !(x >= 0.0 && y >= 0.0 && x <= (w - 1) as f32 && y <= (h - 1) as f32) {
        return None;
    }
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let mut out = [0.0; 3];
    for (c, plane) in [&lab.l, &lab.a, &lab.b].into_iter().enumerate() {
        let top = plane[y0 * w + x0] * (1.0 - fx) + plane[y0 * w + x1] * fx;
        let bottom = plane[y1 * w + x0] * (1.0 - fx) + plane[y1 * w + x1] * fx;
        out[c] = top * (1.0 - fy) + bottom * fy;
    }
    Some(out)
}

/// Per-channel median Lab colour along `line`.
pub fn median_colour(lab: &LabImage, line: &[[f32; 2]]) -> Option<[f32; 3]> {
    let samples: Vec<[f32; 3]> = line
        .iter()
        .filter_map(|p| sample_lab(lab, p[0], p[1]))
        .collect();
    if samples.is_empty() {
        return None;
    }
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let mut v: Vec<f32> = samples.iter().map(|s| s[c]).collect();
        v.sort_by(f32::total_cmp);
        *o = v[v.len() / 2];
    }
    Some(out)
}

/// Unit normals of a polyline (central differences).
pub fn normals(line: &[[f32; 2]]) -> Vec<[f32; 2]> {
    let n = line.len();
    (0..n)
        .map(|i| {
            let a = line[i.saturating_sub(1)];
            let b = line[(i + 1).min(n - 1)];
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len = (dx * dx + dy * dy).sqrt();
            if len < 1e-6 {
                [0.0, 0.0]
            } else {
                [-dy / len, dx / len]
            }
        })
        .collect()
}

/// Moves each point of `line` onto the cable centre found across it (see module docs);
/// `radius` is the half-length of the profiles in pixels.
pub fn refine(line: &[[f32; 2]], lab: &LabImage, radius: f32) -> Refined {
    let Some(cable) = median_colour(lab, line) else {
        return Refined {
            points: line.to_vec(),
            width_px: None,
            coverage: 0.0,
        };
    };
    let normal = normals(line);
    let steps = (radius / PROFILE_STEP).round() as i32;
    let mut profile = Vec::with_capacity(2 * steps as usize + 1);
    let mut offsets: Vec<(usize, f32)> = Vec::new();
    let mut widths = Vec::new();
    let mut read = 0usize;
    for i in (0..line.len()).step_by(PROFILE_STRIDE) {
        read += 1;
        let (p, nrm) = (line[i], normal[i]);
        profile.clear();
        for j in -steps..=steps {
            let o = j as f32 * PROFILE_STEP;
            match sample_lab(lab, p[0] + o * nrm[0], p[1] + o * nrm[1]) {
                Some(s) => profile.push(s),
                None => break,
            }
        }
        if profile.len() != 2 * steps as usize + 1 {
            continue;
        }
        if let Some((centre, width)) = read_profile(&profile, cable, steps as usize) {
            offsets.push((i, centre));
            widths.push(width);
        }
    }
    let coverage = if read == 0 {
        0.0
    } else {
        offsets.len() as f32 / read as f32
    };
    let width_px = (widths.len() >= 3).then(|| {
        widths.sort_by(f32::total_cmp);
        widths[widths.len() / 2]
    });
    if offsets.len() < 3 {
        return Refined {
            points: line.to_vec(),
            width_px,
            coverage,
        };
    }
    let smooth = smooth_offsets(&offsets, line.len(), radius * 0.5);
    let points = line
        .iter()
        .zip(&normal)
        .zip(&smooth)
        .map(|((p, n), &d)| [p[0] + d * n[0], p[1] + d * n[1]])
        .collect();
    Refined {
        points,
        width_px,
        coverage,
    }
}

/// Finds the cable across one profile; returns its centre offset and width in pixels,
/// or `None` when the profile cannot be read.
///
/// Each sample's "foreground" is its Lab distance to the nearer of the two profile ends
/// (the local background on either side). The cable is the run around the centre where
/// foreground exceeds half its peak (a full-width-at-half-maximum reading, so shading and
/// highlights on the insulation do not bias the edges); the edges are interpolated to
/// sub-pixel precision.
fn read_profile(profile: &[[f32; 3]], cable: [f32; 3], centre: usize) -> Option<(f32, f32)> {
    let (left_bg, right_bg) = (profile[0], profile[profile.len() - 1]);
    if de(left_bg, cable) < MIN_BACKGROUND_DE || de(right_bg, cable) < MIN_BACKGROUND_DE {
        return None;
    }
    let fg: Vec<f32> = profile
        .iter()
        .map(|&s| de(s, left_bg).min(de(s, right_bg)))
        .collect();
    let search = centre / 2;
    let peak = fg[centre - search..=centre + search]
        .iter()
        .copied()
        .fold(0.0f32, f32::max);
    if peak < MIN_BACKGROUND_DE {
        return None;
    }
    let half = 0.5 * peak;
    let m: Vec<f32> = fg.iter().map(|f| f - half).collect();
    let start = (0..=search)
        .flat_map(|d| [centre - d, centre + d])
        .find(|&j| m[j] > 0.0)?;
    let mut lo = start;
    while lo > 0 && m[lo - 1] > 0.0 {
        lo -= 1;
    }
    let mut hi = start;
    while hi + 1 < m.len() && m[hi + 1] > 0.0 {
        hi += 1;
    }
    if lo == 0 || hi == m.len() - 1 {
        return None;
    }
    // Zero crossings between the last cable sample and the first background one.
    let left = lo as f32 - m[lo] / (m[lo] - m[lo - 1]);
    let right = hi as f32 + m[hi] / (m[hi] - m[hi + 1]);
    let width = (right - left) * PROFILE_STEP;
    if width < MIN_WIDTH {
        return None;
    }
    Some((((left + right) * 0.5 - centre as f32) * PROFILE_STEP, width))
}

/// Offsets at every point: read ones median-filtered (5) and mean-filtered (5), the
/// gaps filled by linear interpolation, all clamped to ±`limit`.
fn smooth_offsets(read: &[(usize, f32)], n: usize, limit: f32) -> Vec<f32> {
    let vals: Vec<f32> = read.iter().map(|r| r.1).collect();
    let med: Vec<f32> = (0..vals.len())
        .map(|i| {
            let mut w: Vec<f32> = vals[i.saturating_sub(2)..(i + 3).min(vals.len())].to_vec();
            w.sort_by(f32::total_cmp);
            w[w.len() / 2]
        })
        .collect();
    let mean: Vec<f32> = (0..med.len())
        .map(|i| {
            let w = &med[i.saturating_sub(2)..(i + 3).min(med.len())];
            w.iter().sum::<f32>() / w.len() as f32
        })
        .collect();
    let mut out = vec![0.0; n];
    for (i, o) in out.iter_mut().enumerate() {
        let k = read.partition_point(|r| r.0 < i);
        let v = if k == 0 {
            mean[0]
        } else if k == read.len() {
            mean[k - 1]
        } else {
            let (i0, i1) = (read[k - 1].0 as f32, read[k].0 as f32);
            let t = (i as f32 - i0) / (i1 - i0).max(1e-6);
            mean[k - 1] * (1.0 - t) + mean[k] * t
        };
        *o = v.clamp(-limit, limit);
    }
    out
}

#[inline]
fn de(a: [f32; 3], b: [f32; 3]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A white image with a red horizontal band covering rows 20.5 ± 4.
    fn band() -> LabImage {
        let (w, h) = (60, 40);
        let mut rgb = vec![245u8; w * h * 3];
        for y in 17..=24 {
            for x in 0..w {
                rgb[(y * w + x) * 3..(y * w + x) * 3 + 3].copy_from_slice(&[210, 30, 30]);
            }
        }
        LabImage::from_rgb(&rgb, w, h)
    }

    #[test]
    fn moves_an_offset_line_onto_the_band_and_measures_it() {
        let lab = band();
        let line: Vec<[f32; 2]> = (10..50).map(|x| [x as f32, 18.0]).collect();
        let r = refine(&line, &lab, 10.0);
        for p in &r.points {
            assert!((p[1] - 20.5).abs() < 0.3, "{p:?}");
        }
        let w = r.width_px.unwrap();
        assert!((w - 8.0).abs() < 1.0, "width {w}");
        assert!(r.coverage > 0.9);
    }

    #[test]
    fn bilinear_sampling_interpolates_and_bounds() {
        let lab = band();
        assert!(sample_lab(&lab, -0.1, 3.0).is_none());
        assert!(sample_lab(&lab, 59.0, 39.0).is_some());
        let mid = sample_lab(&lab, 5.0, 16.5).unwrap()[0];
        let (a, b) = (lab.l[16 * 60 + 5], lab.l[17 * 60 + 5]);
        assert!((mid - (a + b) / 2.0).abs() < 1e-3);
    }
}
