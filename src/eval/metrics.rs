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
/// (see [`matched_truth`]).
pub fn match_points(found: &[[f64; 2]], truth: &[[f64; 2]], radius: f64) -> usize {
    matched_truth(found, truth, radius)
        .into_iter()
        .filter(|&m| m)
        .count()
}

/// Which `truth` points a `found` point is matched to one-to-one within `radius`,
/// taking `found` in order (most confident first) and each its nearest free truth.
pub fn matched_truth(found: &[[f64; 2]], truth: &[[f64; 2]], radius: f64) -> Vec<bool> {
    let mut used = vec![false; truth.len()];
    for f in found {
        let nearest = truth
            .iter()
            .enumerate()
            .filter(|(j, _)| !used[*j])
            .map(|(j, t)| (j, (t[0] - f[0]).hypot(t[1] - f[1])))
            .filter(|&(_, d)| d <= radius)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((j, _)) = nearest {
            used[j] = true;
        }
    }
    used
}

/// A true terminal that no end was matched to, with what lies near it: an end found a
/// little too far away (the same terminal marked at another point: its metal tip
/// rather than the insulation's end) or the image border (an annotated end short of
/// the frame where the cable leaves it).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MissedTerminal {
    /// The terminal, photo pixels.
    pub point: [f64; 2],
    /// Distance to the nearest end found, matched or not; `None` when none was found.
    pub nearest_end_px: Option<f64>,
    /// Distance to the nearest image border.
    pub border_px: f64,
}

/// The terminals of `truth` left unmatched in `matched`, described against `found`
/// in a `width` x `height` photo.
pub fn missed_terminals(
    found: &[[f64; 2]],
    truth: &[[f64; 2]],
    matched: &[bool],
    width: u32,
    height: u32,
) -> Vec<MissedTerminal> {
    truth
        .iter()
        .zip(matched)
        .filter(|&(_, &m)| !m)
        .map(|(t, _)| MissedTerminal {
            point: *t,
            nearest_end_px: found
                .iter()
                .map(|f| (t[0] - f[0]).hypot(t[1] - f[1]))
                .min_by(f64::total_cmp),
            border_px: t[0]
                .min(t[1])
                .min(width as f64 - 1.0 - t[0])
                .min(height as f64 - 1.0 - t[1]),
        })
        .collect()
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
        let first = matched_truth(&[[3.0, 4.0], [1.0, 0.0]], &truth, 15.0);
        assert_eq!(first, [true, false]);
        assert_eq!(match_points(&[[3.0, 4.0], [90.0, 0.0]], &truth, 15.0), 2);
        assert_eq!(matched_truth(&[[20.0, 0.0]], &truth, 15.0), [false, false]);
        assert_eq!(match_points(&[], &truth, 15.0), 0);
    }

    #[test]
    fn a_missed_terminal_reports_the_nearest_end_and_border() {
        let truth = [[50.0, 13.0], [200.0, 100.0]];
        let found = [[50.0, 33.0], [203.0, 104.0]];
        let matched = matched_truth(&found, &truth, 15.0);
        let missed = missed_terminals(&found, &truth, &matched, 640, 480);
        assert_eq!(
            missed,
            [MissedTerminal {
                point: [50.0, 13.0],
                nearest_end_px: Some(20.0),
                border_px: 13.0,
            }]
        );
        let alone = missed_terminals(&[], &truth[1..], &[false], 640, 480);
        assert_eq!(alone[0].nearest_end_px, None);
        assert_eq!(alone[0].border_px, 100.0);
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
