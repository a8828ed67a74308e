//! The paper's metric (IoU of union masks, weighted by cable count) and cable matching.

use image::GrayImage;
use serde::Serialize;

use super::ImageResult;

/// Intersection over union of two masks (foreground where > 127). Two empty masks
/// score 1.
pub fn iou(a: &GrayImage, b: &GrayImage) -> f64 {
    let (mut inter, mut union) = (0u64, 0u64);
    for (&x, &y) in a.as_raw().iter().zip(b.as_raw()) {
        let (x, y) = (x > 127, y > 127);
        inter += (x && y) as u64;
        union += (x || y) as u64;
    }
    if union == 0 {
        1.0
    } else {
        inter as f64 / union as f64
    }
}

/// One-to-one matches between `found` and `truth` masks with IoU ≥ `min_iou`, chosen
/// greedily from the best pair down: their number and the sum of their IoUs.
pub fn match_cables(found: &[GrayImage], truth: &[GrayImage], min_iou: f64) -> (usize, f64) {
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for (i, f) in found.iter().enumerate() {
        for (j, t) in truth.iter().enumerate() {
            let v = iou(f, t);
            if v >= min_iou {
                pairs.push((v, i, j));
            }
        }
    }
    pairs.sort_by(|a, b| b.0.total_cmp(&a.0));
    let (mut used_f, mut used_t) = (vec![false; found.len()], vec![false; truth.len()]);
    let (mut matched, mut sum) = (0, 0.0);
    for (v, i, j) in pairs {
        if !used_f[i] && !used_t[j] {
            used_f[i] = true;
            used_t[j] = true;
            matched += 1;
            sum += v;
        }
    }
    (matched, sum)
}

/// Totals over one set of images.
#[derive(Debug, Clone, Serialize)]
pub struct SetSummary {
    /// Set name.
    pub set: String,
    /// Number of images.
    pub images: usize,
    /// Σ Cᵢ·IoUᵢ / Σ Cᵢ, the paper's metric.
    pub weighted_iou: f64,
    /// Matched / true cables.
    pub cable_recall: f64,
    /// Matched / found cables.
    pub cable_precision: f64,
    /// Mean IoU of the matched cables (alignment of the curves that were found).
    pub matched_iou: f64,
    /// Matched / true terminals.
    pub terminal_recall: f64,
    /// Matched terminals / ends used.
    pub terminal_precision: f64,
    /// Median total milliseconds per image.
    pub median_total_ms: f64,
}

/// Number of `found` points matched one-to-one to a `truth` point within `radius`
/// (see [`pair_points`]).
pub fn match_points(found: &[[f64; 2]], truth: &[[f64; 2]], radius: f64) -> usize {
    pair_points(found, truth, radius)
        .truth
        .into_iter()
        .filter(|&m| m)
        .count()
}

/// Which points of each side were paired by [`pair_points`].
#[derive(Debug, Clone, PartialEq)]
pub struct Pairing {
    /// One flag per found point.
    pub found: Vec<bool>,
    /// One flag per true point.
    pub truth: Vec<bool>,
}

/// Pairs `found` points one-to-one with `truth` points within `radius`, taking `found`
/// in order (most confident first) and each its nearest free truth.
pub fn pair_points(found: &[[f64; 2]], truth: &[[f64; 2]], radius: f64) -> Pairing {
    let mut pairing = Pairing {
        found: vec![false; found.len()],
        truth: vec![false; truth.len()],
    };
    for (i, f) in found.iter().enumerate() {
        let nearest = truth
            .iter()
            .enumerate()
            .filter(|(j, _)| !pairing.truth[*j])
            .map(|(j, t)| (j, (t[0] - f[0]).hypot(t[1] - f[1])))
            .filter(|&(_, d)| d <= radius)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((j, _)) = nearest {
            pairing.truth[j] = true;
            pairing.found[i] = true;
        }
    }
    pairing
}

/// A true terminal that no end was paired with, with what lies near it: an end found a
/// little too far away (the same terminal marked at another point: its metal tip
/// rather than the insulation's end) or the image border (an annotated end short of
/// the frame where the cable leaves it).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MissedTerminal {
    /// The terminal, photo pixels.
    pub point: [f64; 2],
    /// Distance to the nearest end found, paired or not; `None` when none was found.
    pub nearest_end_px: Option<f64>,
    /// Distance to the nearest image border.
    pub border_px: f64,
}

/// An end found that no true terminal was paired with, with what lies near it: a
/// terminal a little too far away, an annotated cable, or neither (the background, or
/// a cable the annotation leaves out).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FalseEnd {
    /// The end, photo pixels.
    pub point: [f64; 2],
    /// Distance to the nearest true terminal, paired or not; `None` when there is none.
    pub nearest_terminal_px: Option<f64>,
    /// Distance to the nearest pixel of the annotated cables' union mask, searched up
    /// to [`CABLE_SEARCH_PX`]; `None` when none lies that near.
    pub nearest_cable_px: Option<f64>,
    /// Distance to the nearest image border.
    pub border_px: f64,
}

/// How far around a false end the annotated cables are looked for.
pub const CABLE_SEARCH_PX: f64 = 30.0;

/// What lies near the unpaired points of both sides.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Misses {
    /// The true terminals no end was paired with.
    pub terminals: Vec<MissedTerminal>,
    /// The ends no true terminal was paired with.
    pub ends: Vec<FalseEnd>,
}

/// Describes the points `pairing` left alone, against the other side and the union
/// mask `cables` of the annotated cables (its size is the photo's).
pub fn misses(
    found: &[[f64; 2]],
    truth: &[[f64; 2]],
    pairing: &Pairing,
    cables: &GrayImage,
) -> Misses {
    let (width, height) = cables.dimensions();
    let border = |p: &[f64; 2]| {
        p[0].min(p[1])
            .min(width as f64 - 1.0 - p[0])
            .min(height as f64 - 1.0 - p[1])
    };
    let nearest = |p: &[f64; 2], to: &[[f64; 2]]| {
        to.iter()
            .map(|q| (p[0] - q[0]).hypot(p[1] - q[1]))
            .min_by(f64::total_cmp)
    };
    Misses {
        terminals: truth
            .iter()
            .zip(&pairing.truth)
            .filter(|&(_, &paired)| !paired)
            .map(|(t, _)| MissedTerminal {
                point: *t,
                nearest_end_px: nearest(t, found),
                border_px: border(t),
            })
            .collect(),
        ends: found
            .iter()
            .zip(&pairing.found)
            .filter(|&(_, &paired)| !paired)
            .map(|(f, _)| FalseEnd {
                point: *f,
                nearest_terminal_px: nearest(f, truth),
                nearest_cable_px: nearest_foreground(cables, *f, CABLE_SEARCH_PX),
                border_px: border(f),
            })
            .collect(),
    }
}

/// Distance from `p` to the centre of the nearest foreground pixel (> 127) of `mask`
/// within `radius`, if any.
fn nearest_foreground(mask: &GrayImage, p: [f64; 2], radius: f64) -> Option<f64> {
    let (w, h) = mask.dimensions();
    let lo = |c: f64| (c - radius).floor().max(0.0) as u32;
    let (x0, y0) = (lo(p[0]), lo(p[1]));
    let x1 = ((p[0] + radius).ceil().max(0.0) as u32).min(w.saturating_sub(1));
    let y1 = ((p[1] + radius).ceil().max(0.0) as u32).min(h.saturating_sub(1));
    (y0..=y1)
        .flat_map(|y| (x0..=x1).map(move |x| (x, y)))
        .filter(|&(x, y)| mask.get_pixel(x, y)[0] > 127)
        .map(|(x, y)| (x as f64 - p[0]).hypot(y as f64 - p[1]))
        .filter(|&d| d <= radius)
        .min_by(f64::total_cmp)
}

/// Summaries per set, in first-seen order.
pub fn summarise(results: &[ImageResult]) -> Vec<SetSummary> {
    let mut sets: Vec<String> = Vec::new();
    for r in results {
        if !sets.contains(&r.set) {
            sets.push(r.set.clone());
        }
    }
    sets.into_iter()
        .map(|set| {
            let rs: Vec<&ImageResult> = results.iter().filter(|r| r.set == set).collect();
            let cables: usize = rs.iter().map(|r| r.gt_cables).sum();
            let found: usize = rs.iter().map(|r| r.found_cables).sum();
            let matched: usize = rs.iter().map(|r| r.matched_cables).sum();
            let matched_iou: f64 =
                rs.iter().map(|r| r.matched_iou_sum).sum::<f64>() / matched.max(1) as f64;
            let weighted: f64 = rs.iter().map(|r| r.gt_cables as f64 * r.iou).sum();
            let terminals: usize = rs.iter().map(|r| r.terminals).sum();
            let ends: usize = rs.iter().map(|r| r.ends).sum();
            let hits: usize = rs.iter().map(|r| r.terminals_matched).sum();
            let mut totals: Vec<f64> = rs.iter().map(|r| r.timings_ms.total).collect();
            totals.sort_by(f64::total_cmp);
            SetSummary {
                images: rs.len(),
                weighted_iou: weighted / cables.max(1) as f64,
                cable_recall: matched as f64 / cables.max(1) as f64,
                cable_precision: matched as f64 / found.max(1) as f64,
                matched_iou,
                terminal_recall: hits as f64 / terminals.max(1) as f64,
                terminal_precision: hits as f64 / ends.max(1) as f64,
                median_total_ms: totals.get(totals.len() / 2).copied().unwrap_or(0.0),
                set,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Luma;

    fn rect(x0: u32, x1: u32) -> GrayImage {
        GrayImage::from_fn(10, 10, |x, _| {
            Luma([if (x0..x1).contains(&x) { 255 } else { 0 }])
        })
    }

    #[test]
    fn points_match_one_to_one_within_the_radius() {
        let truth = [[0.0, 0.0], [100.0, 0.0]];
        let first = pair_points(&[[3.0, 4.0], [1.0, 0.0]], &truth, 15.0);
        assert_eq!(first.truth, [true, false]);
        assert_eq!(first.found, [true, false]);
        assert_eq!(match_points(&[[3.0, 4.0], [90.0, 0.0]], &truth, 15.0), 2);
        assert_eq!(match_points(&[[20.0, 0.0]], &truth, 15.0), 0);
        assert_eq!(match_points(&[], &truth, 15.0), 0);
    }

    #[test]
    fn unpaired_points_report_what_lies_near_them() {
        // One annotated cable: a horizontal band at rows 100..=104.
        let cables = GrayImage::from_fn(640, 480, |_, y| {
            Luma([if (100..=104).contains(&y) { 255 } else { 0 }])
        });
        let truth = [[50.0, 13.0], [200.0, 102.0]];
        let found = [[50.0, 33.0], [203.0, 106.0], [400.0, 110.0], [400.0, 300.0]];
        let pairing = pair_points(&found, &truth, 15.0);
        let m = misses(&found, &truth, &pairing, &cables);
        assert_eq!(
            m.terminals,
            [MissedTerminal {
                point: [50.0, 13.0],
                nearest_end_px: Some(20.0),
                border_px: 13.0,
            }]
        );
        let near: Vec<_> = m
            .ends
            .iter()
            .map(|e| (e.point, e.nearest_cable_px))
            .collect();
        assert_eq!(
            near,
            [
                ([50.0, 33.0], None),
                ([400.0, 110.0], Some(6.0)),
                ([400.0, 300.0], None),
            ]
        );
        assert_eq!(m.ends[0].nearest_terminal_px, Some(20.0));
        let none = misses(
            &[],
            &truth[1..],
            &pair_points(&[], &truth[1..], 15.0),
            &cables,
        );
        assert_eq!(none.terminals[0].nearest_end_px, None);
        assert!(none.ends.is_empty());
    }

    #[test]
    fn iou_and_matching() {
        assert!((iou(&rect(0, 4), &rect(2, 6)) - 2.0 / 6.0).abs() < 1e-9);
        assert_eq!(iou(&rect(0, 0), &rect(0, 0)), 1.0);
        let found = [rect(0, 4), rect(5, 9)];
        let truth = [rect(0, 5), rect(6, 9), rect(0, 2)];
        assert_eq!(match_cables(&found, &truth, 0.5).0, 2);
        assert_eq!(match_cables(&found, &truth, 0.9), (0, 0.0));
    }
}
