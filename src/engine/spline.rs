//! Cubic B-splines: a penalised least-squares smoothing fit, chord-length
//! parameterised, and evaluation by de Boor's algorithm.
//!
//! The fit minimises Σ wᵢ |C(uᵢ) − pᵢ|² + λ Σ |Δ²cⱼ|² over the control points cⱼ, with
//! a clamped knot vector whose interior knots are spaced evenly in chord length
//! (a P-spline in the sense of Eilers and Marx). λ is `smoothing` scaled by the data
//! density, so its meaning does not change with the number of points.

use super::geometry::dist;

/// Degree of the fitted splines (cubic, as the paper's splprep).
const DEGREE: usize = 3;
/// Penalty per unit of `smoothing` and of mean weight per control point: fixes what
/// `smoothing = 1` means, not a tuning knob (that is `smoothing`).
const PENALTY_SCALE: f64 = 0.1;

/// A clamped B-spline curve in the plane, parameter domain [0, 1].
#[derive(Debug, Clone, PartialEq)]
pub struct BSpline {
    /// Polynomial degree (3 for cubic).
    pub degree: usize,
    /// Knot vector, non-decreasing, `control_points.len() + degree + 1` entries.
    pub knots: Vec<f64>,
    /// Control points (x, y), pixels.
    pub control_points: Vec<[f64; 2]>,
}

impl BSpline {
    /// Fits a cubic spline through `points` (in order) with per-point `weights`
    /// (same length; larger pulls harder), interior knots about `knot_spacing` pixels
    /// apart along the data, and second-difference penalty `smoothing`.
    /// Returns `None` for fewer than two distinct points.
    pub fn fit(
        points: &[[f32; 2]],
        weights: &[f32],
        knot_spacing: f32,
        smoothing: f32,
    ) -> Option<Self> {
        let mut u = Vec::with_capacity(points.len());
        let mut acc = 0.0f64;
        u.push(0.0);
        for w in points.windows(2) {
            acc += (((w[1][0] - w[0][0]) as f64).powi(2) + ((w[1][1] - w[0][1]) as f64).powi(2))
                .sqrt();
            u.push(acc);
        }
        if points.len() < 2 || acc < 1e-6 {
            return None;
        }
        u.iter_mut().for_each(|v| *v /= acc);
        let spans = ((acc / knot_spacing.max(1.0) as f64).ceil() as usize).max(1);
        let mut knots = vec![0.0; DEGREE + 1];
        knots.extend((1..spans).map(|j| j as f64 / spans as f64));
        knots.extend(std::iter::repeat_n(1.0, DEGREE + 1));
        let n = spans + DEGREE;

        // Normal equations A c = b, A = BᵀWB + λDᵀD (n×n, banded but small: dense).
        let mut a = vec![0.0f64; n * n];
        let mut b = vec![[0.0f64; 2]; n];
        let mut basis = [0.0f64; DEGREE + 1];
        let mut weight_sum = 0.0;
        for ((&ui, p), &wi) in u.iter().zip(points).zip(weights) {
            let span = find_span(&knots, DEGREE, n, ui);
            basis_functions(&knots, DEGREE, span, ui, &mut basis);
            let wi = wi as f64;
            weight_sum += wi;
            for r in 0..=DEGREE {
                let row = span - DEGREE + r;
                b[row][0] += wi * basis[r] * p[0] as f64;
                b[row][1] += wi * basis[r] * p[1] as f64;
                for c in 0..=DEGREE {
                    a[row * n + span - DEGREE + c] += wi * basis[r] * basis[c];
                }
            }
        }
        // Penalty scaled by mean weight per control point, so `smoothing` is unit-free.
        let lambda = smoothing as f64 * weight_sum / n as f64 * PENALTY_SCALE + 1e-9;
        for j in 0..n.saturating_sub(2) {
            let coeffs = [1.0, -2.0, 1.0];
            for (r, cr) in coeffs.iter().enumerate() {
                for (c, cc) in coeffs.iter().enumerate() {
                    a[(j + r) * n + j + c] += lambda * cr * cc;
                }
            }
        }
        let control_points = solve_spd(&mut a, &b, n)?;
        Some(Self {
            degree: DEGREE,
            knots,
            control_points,
        })
    }

    /// Point at parameter `u` (clamped to [0, 1]).
    pub fn eval(&self, u: f64) -> [f64; 2] {
        let n = self.control_points.len();
        let u = u.clamp(0.0, 1.0);
        let span = find_span(&self.knots, self.degree, n, u);
        let mut basis = vec![0.0; self.degree + 1];
        basis_functions(&self.knots, self.degree, span, u, &mut basis);
        let mut p = [0.0, 0.0];
        for (r, bv) in basis.iter().enumerate() {
            let c = self.control_points[span - self.degree + r];
            p[0] += bv * c[0];
            p[1] += bv * c[1];
        }
        p
    }

    /// Samples the curve about every `step` pixels of arc length, both ends included,
    /// in parameter order.
    pub fn sample(&self, step: f32) -> Vec<[f32; 2]> {
        // Dense evaluation, then resampling by arc length.
        let polygon_len: f64 = self
            .control_points
            .windows(2)
            .map(|w| ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt())
            .sum();
        let dense_n = ((polygon_len * 2.0) as usize).clamp(16, 20_000);
        let dense: Vec<[f32; 2]> = (0..=dense_n)
            .map(|i| {
                let p = self.eval(i as f64 / dense_n as f64);
                [p[0] as f32, p[1] as f32]
            })
            .collect();
        resample(&dense, step)
    }
}

/// Resamples a polyline at `step` pixels of arc length, keeping both ends.
pub fn resample(line: &[[f32; 2]], step: f32) -> Vec<[f32; 2]> {
    let Some(&first) = line.first() else {
        return Vec::new();
    };
    let mut out = vec![first];
    let mut carried = 0.0f32;
    for w in line.windows(2) {
        let seg = dist(w[0], w[1]);
        let mut at = step - carried;
        while at <= seg {
            let t = at / seg;
            out.push([
                w[0][0] + t * (w[1][0] - w[0][0]),
                w[0][1] + t * (w[1][1] - w[0][1]),
            ]);
            at += step;
        }
        carried = (carried + seg) % step;
    }
    let last = line[line.len() - 1];
    if out.last() != Some(&last) && line.len() > 1 {
        let tail = out.last().map_or(f32::MAX, |&p| dist(p, last));
        if tail < step * 0.5 && out.len() > 1 {
            out.pop();
        }
        out.push(last);
    }
    out
}

/// Index of the knot span containing `u` (The NURBS Book, A2.1).
fn find_span(knots: &[f64], degree: usize, n: usize, u: f64) -> usize {
    if u >= knots[n] {
        return n - 1;
    }
    let (mut lo, mut hi) = (degree, n);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if u < knots[mid] { hi = mid } else { lo = mid }
    }
    lo
}

/// The degree+1 non-zero basis functions at `u` in `span` (The NURBS Book, A2.2).
fn basis_functions(knots: &[f64], degree: usize, span: usize, u: f64, out: &mut [f64]) {
    let mut left = [0.0f64; 8];
    let mut right = [0.0f64; 8];
    out[0] = 1.0;
    for j in 1..=degree {
        left[j] = u - knots[span + 1 - j];
        right[j] = knots[span + j] - u;
        let mut saved = 0.0;
        for r in 0..j {
            let denom = right[r + 1] + left[j - r];
            let temp = if denom.abs() < 1e-300 {
                0.0
            } else {
                out[r] / denom
            };
            out[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        out[j] = saved;
    }
}

/// Solves the symmetric positive definite system `a x = b` (two right-hand sides) by
/// Cholesky factorisation in place. `None` when `a` is not positive definite.
fn solve_spd(a: &mut [f64], b: &[[f64; 2]], n: usize) -> Option<Vec<[f64; 2]>> {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d <= 0.0 || !d.is_finite() {
            return None;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    let mut y = b.to_vec();
    for i in 0..n {
        for k in 0..i {
            let l = a[i * n + k];
            y[i][0] -= l * y[k][0];
            y[i][1] -= l * y[k][1];
        }
        y[i][0] /= a[i * n + i];
        y[i][1] /= a[i * n + i];
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            let l = a[k * n + i];
            y[i][0] -= l * y[k][0];
            y[i][1] -= l * y[k][1];
        }
        y[i][0] /= a[i * n + i];
        y[i][1] /= a[i * n + i];
    }
    Some(y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::geometry::polyline_length;
    use proptest::prelude::*;

    #[test]
    fn fits_a_circle_arc_closely() {
        let pts: Vec<[f32; 2]> = (0..=40)
            .map(|i| {
                let t = i as f32 / 40.0 * std::f32::consts::PI;
                [200.0 + 100.0 * t.cos(), 200.0 + 100.0 * t.sin()]
            })
            .collect();
        let w = vec![1.0; pts.len()];
        let s = BSpline::fit(&pts, &w, 30.0, 0.01).unwrap();
        assert_eq!(s.knots.len(), s.control_points.len() + 4);
        for i in 0..=100 {
            let p = s.eval(i as f64 / 100.0);
            let r = ((p[0] - 200.0).powi(2) + (p[1] - 200.0).powi(2)).sqrt();
            assert!((r - 100.0).abs() < 0.5, "radius {r}");
        }
        let line = s.sample(2.0);
        let len = polyline_length(&line);
        assert!(
            (len - 100.0 * std::f32::consts::PI).abs() < 2.0,
            "length {len}"
        );
    }

    #[test]
    fn degenerate_input_gives_none() {
        assert!(BSpline::fit(&[[1.0, 1.0]], &[1.0], 10.0, 1.0).is_none());
        assert!(BSpline::fit(&[[1.0, 1.0], [1.0, 1.0]], &[1.0, 1.0], 10.0, 1.0).is_none());
    }

    #[test]
    fn resample_keeps_ends_and_spacing() {
        let line = [[0.0, 0.0], [10.0, 0.0], [10.0, 7.0]];
        let r = resample(&line, 2.0);
        assert_eq!(r[0], [0.0, 0.0]);
        assert_eq!(*r.last().unwrap(), [10.0, 7.0]);
        assert!(r.len() >= 9 && r.len() <= 10);
    }

    proptest! {
        #[test]
        fn spline_passes_near_its_data(
            ys in proptest::collection::vec(-10.0f32..10.0, 3..10), scale in 20.0f32..60.0
        ) {
            // A smooth function sampled densely: the fit must stay within a pixel of it.
            let pts: Vec<[f32; 2]> = (0..=60).map(|i| {
                let x = i as f32 * 5.0;
                let k = (x / 300.0 * (ys.len() - 1) as f32).min((ys.len() - 1) as f32 - 1e-3);
                let (j, f) = (k as usize, k.fract());
                let s = 0.5 - 0.5 * (f * std::f32::consts::PI).cos();
                [x, 200.0 + (ys[j] * (1.0 - s) + ys[j + 1] * s) * scale / 40.0]
            }).collect();
            let spline = BSpline::fit(&pts, &vec![1.0; pts.len()], 20.0, 0.001).unwrap();
            let line = spline.sample(1.0);
            for p in &pts {
                let d = line.iter().map(|q| ((p[0]-q[0]).powi(2) + (p[1]-q[1]).powi(2)).sqrt()).fold(f32::MAX, f32::min);
                prop_assert!(d < 1.5, "point {p:?} is {d} px from the curve");
            }
        }
    }
}
