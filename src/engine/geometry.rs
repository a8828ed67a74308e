//! Plane geometry shared by the engine's stages: distances, headings, medians.

/// Euclidean distance between two points, pixels.
#[inline]
pub fn dist(a: [f32; 2], b: [f32; 2]) -> f32 {
    norm([a[0] - b[0], a[1] - b[1]])
}

/// Length of a 2-D vector.
#[inline]
pub fn norm(v: [f32; 2]) -> f32 {
    (v[0] * v[0] + v[1] * v[1]).sqrt()
}

/// Euclidean distance between two colours (e.g. CIELAB ΔE76).
#[inline]
pub fn dist3(a: [f32; 3], b: [f32; 3]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// `v` scaled to unit length, or `fallback` when it is (nearly) zero.
#[inline]
pub fn unit_or(v: [f32; 2], fallback: [f32; 2]) -> [f32; 2] {
    let n = norm(v);
    if n < 1e-6 {
        fallback
    } else {
        [v[0] / n, v[1] / n]
    }
}

/// Length of a polyline, pixels.
pub fn polyline_length(line: &[[f32; 2]]) -> f32 {
    line.windows(2).map(|w| dist(w[0], w[1])).sum()
}

/// How many points of `line` lie within `tolerance` of a point of `other` (both
/// sampled densely: a point between two of `other`'s is not near either).
pub fn points_near(line: &[[f32; 2]], other: &[[f32; 2]], tolerance: f32) -> usize {
    points_near_any(line, &[(other, tolerance)])
}

/// How many points of `line` lie near any of `others`: within its tolerance of one of
/// its points (each line with its own, all sampled densely).
pub fn points_near_any(line: &[[f32; 2]], others: &[(&[[f32; 2]], f32)]) -> usize {
    line.iter()
        .filter(|&&p| {
            others
                .iter()
                .any(|&(other, tolerance)| other.iter().any(|&q| dist(p, q) <= tolerance))
        })
        .count()
}

/// Least share of a centreline's points near another's for it to run along it.
const REPEAT_SHARE: f32 = 0.5;

/// Whether at least [`REPEAT_SHARE`] of the points of `line` lie within `tolerance`
/// of a point of `other` (both sampled densely): a cable over `line` repeats the one
/// over `other`.
pub fn runs_along(line: &[[f32; 2]], other: &[[f32; 2]], tolerance: f32) -> bool {
    points_near(line, other, tolerance) as f32 >= REPEAT_SHARE * line.len() as f32
}

/// Unit heading of a path: from the last point at least `span` pixels back (or the
/// first point) to the newest point; `[1, 0]` for a path too short to have one.
pub fn heading(points: &[[f32; 2]], span: f32) -> [f32; 2] {
    let Some(&head) = points.last() else {
        return [1.0, 0.0];
    };
    let mut from = points[0];
    let mut acc = 0.0;
    for w in points.windows(2).rev() {
        acc += dist(w[0], w[1]);
        from = w[0];
        if acc >= span {
            break;
        }
    }
    unit_or([head[0] - from[0], head[1] - from[1]], [1.0, 0.0])
}

/// The median of `values` under `cmp` (the upper one of an even count), reordering
/// them; `None` when empty. Use `f32::total_cmp` for floats.
pub fn median<T: Copy>(
    values: &mut [T],
    mut cmp: impl FnMut(&T, &T) -> std::cmp::Ordering,
) -> Option<T> {
    if values.is_empty() {
        return None;
    }
    let mid = values.len() / 2;
    Some(*values.select_nth_unstable_by(mid, &mut cmp).1)
}

/// The per-channel [`median`] of `colours`; `None` when empty.
pub fn median_colour_of(colours: &[[f32; 3]]) -> Option<[f32; 3]> {
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let mut v: Vec<f32> = colours.iter().map(|s| s[c]).collect();
        *o = median(&mut v, f32::total_cmp)?;
    }
    Some(out)
}

/// Where a ray from `from` along the unit `dir` leaves a `width` x `height` image (the
/// last pixel centre on each side), if that is within `max_px` and more than half a
/// pixel away.
pub fn border_exit(
    from: [f32; 2],
    dir: [f32; 2],
    width: usize,
    height: usize,
    max_px: f32,
) -> Option<[f32; 2]> {
    let (w, h) = ((width - 1) as f32, (height - 1) as f32);
    let mut t = f32::INFINITY;
    if dir[0] > 1e-6 {
        t = t.min((w - from[0]) / dir[0]);
    } else if dir[0] < -1e-6 {
        t = t.min(-from[0] / dir[0]);
    }
    if dir[1] > 1e-6 {
        t = t.min((h - from[1]) / dir[1]);
    } else if dir[1] < -1e-6 {
        t = t.min(-from[1] / dir[1]);
    }
    (t.is_finite() && t > 0.5 && t <= max_px).then(|| [from[0] + t * dir[0], from[1] + t * dir[1]])
}

/// Arc length along `line` at each of its points.
pub fn arc_lengths(line: &[[f32; 2]]) -> Vec<f32> {
    std::iter::once(0.0)
        .chain(line.windows(2).scan(0.0, |s, w| {
            *s += dist(w[0], w[1]);
            Some(*s)
        }))
        .collect()
}

/// Whether `line` crosses itself: two of its segments at least `min_apart` pixels apart
/// along it (a loop at least that long between them) intersect.
pub fn crosses_itself(line: &[[f32; 2]], min_apart: f32) -> bool {
    let arc = arc_lengths(line);
    let cross = |a: [f32; 2], b: [f32; 2], p: [f32; 2]| {
        (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
    };
    let n = line.len();
    (0..n.saturating_sub(1)).any(|i| {
        let (a, b) = (line[i], line[i + 1]);
        (i + 1..n - 1)
            .filter(|&j| arc[j] - arc[i + 1] >= min_apart)
            .any(|j| {
                let (c, d) = (line[j], line[j + 1]);
                cross(a, b, c) * cross(a, b, d) < 0.0 && cross(c, d, a) * cross(c, d, b) < 0.0
            })
    })
}

/// Distances from `p` to the left, top, right and bottom sides of a `width` x `height`
/// image (pixel centres at integers).
fn insets(p: [f32; 2], width: usize, height: usize) -> [f32; 4] {
    let (w, h) = ((width - 1) as f32, (height - 1) as f32);
    [p[0], p[1], w - p[0], h - p[1]]
}

/// Distance from `p` to the nearest side of a `width` x `height` image (pixel centres
/// at integers).
pub fn border_inset(p: [f32; 2], width: usize, height: usize) -> f32 {
    insets(p, width, height)
        .into_iter()
        .fold(f32::INFINITY, f32::min)
}

/// True when every point of `line` lies within `margin` of one and the same side of a
/// `width` x `height` image (false for an empty line).
pub fn along_one_side(line: &[[f32; 2]], width: usize, height: usize, margin: f32) -> bool {
    !line.is_empty()
        && (0..4).any(|side| {
            line.iter()
                .all(|&p| insets(p, width, height)[side] <= margin)
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heading_uses_the_span() {
        let pts = [[0.0, 0.0], [10.0, 0.0], [20.0, 0.0], [20.0, 5.0]];
        let h = heading(&pts, 5.0);
        assert!((h[0] - 0.0).abs() < 1e-6 && (h[1] - 1.0).abs() < 1e-6);
        let h = heading(&pts, 12.0);
        assert!((h[0] - 0.894).abs() < 1e-3 && (h[1] - 0.447).abs() < 1e-3);
        assert_eq!(heading(&[], 3.0), [1.0, 0.0]);
    }

    #[test]
    fn medians_and_exits() {
        assert_eq!(median(&mut [3.0f32, 1.0, 2.0], f32::total_cmp), Some(2.0));
        assert_eq!(median(&mut [4u8, 1, 3, 2], u8::cmp), Some(3));
        assert_eq!(median(&mut [] as &mut [f32], f32::total_cmp), None);
        assert_eq!(
            border_exit([5.0, 5.0], [1.0, 0.0], 10, 10, 100.0),
            Some([9.0, 5.0])
        );
        assert_eq!(border_exit([5.0, 5.0], [1.0, 0.0], 10, 10, 2.0), None);
        assert!((polyline_length(&[[0.0, 0.0], [3.0, 4.0], [3.0, 5.0]]) - 6.0).abs() < 1e-6);
    }

    #[test]
    fn lines_along_one_side() {
        // 100x50: the last pixel centres are x = 99 and y = 49.
        let bottom = [[10.0, 45.0], [50.0, 48.0], [90.0, 44.0]];
        assert!(along_one_side(&bottom, 100, 50, 5.0));
        assert!(!along_one_side(&bottom, 100, 50, 4.0));
        // Near the top at one end and the bottom at the other: no one side.
        assert!(!along_one_side(
            &[[1.0, 1.0], [1.0, 48.0], [98.0, 48.0]],
            100,
            50,
            5.0
        ));
        assert!(along_one_side(&[[1.0, 1.0], [1.0, 48.0]], 100, 50, 5.0));
        assert!(!along_one_side(&[], 100, 50, 5.0));
    }

    #[test]
    fn a_line_round_a_loop_crosses_itself() {
        // Along y = 0 to x = 100, round most of a circle of radius 20 above it, then
        // down across the way in (at x = 73): a loop about 150 px long.
        let mut line: Vec<[f32; 2]> = (0..=10).map(|k| [10.0 * k as f32, 0.0]).collect();
        line.extend((1..=11).map(|k| {
            let t = std::f32::consts::PI * (0.5 + 1.5 * k as f32 / 11.0);
            [80.0 + 20.0 * t.cos(), -20.0 - 20.0 * t.sin()]
        }));
        line.extend([[60.0, 10.0], [60.0, 30.0]]);
        assert!(crosses_itself(&line, 50.0));
        // Not counted where the loop is shorter than asked for.
        assert!(!crosses_itself(&line, 400.0));
        // A bend that does not come back: no crossing.
        assert!(!crosses_itself(&line[..15], 10.0));
        assert!(!crosses_itself(&[], 10.0));
        assert!(!crosses_itself(&[[0.0, 0.0]], 10.0));
    }
}
