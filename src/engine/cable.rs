//! Modelling one cable from its chosen walk: data points, penalised B-spline fit,
//! refinement on the image, and the measurements reported with it.

use image::RgbImage;

use super::Params;
use super::chains::Course;
use super::color::LabImage;
use super::field::CableField;
use super::geometry::{border_exit, crosses_itself, dist, heading, median, polyline_length};
use super::graph::Graph;
use super::pairing::{FarEnd, Pairing};
use super::refine;
use super::spline::BSpline;
use super::superpixels::Superpixels;
use super::walk::{Seed, Terrain, Walk};

/// One cable found in the image.
#[derive(Debug, Clone, PartialEq)]
pub struct Cable {
    /// Index in [`Segmentation::cables`]; label masks use `id + 1`.
    pub id: usize,
    /// First and last point of the centreline, pixels.
    pub ends: [[f32; 2]; 2],
    /// For each of `ends`, the index of the given end it is, or `None` where the cable
    /// leaves the frame or was lost.
    pub end_indices: [Option<usize>; 2],
    /// For the second of two twins split from one cable (`twins`), the ends its sibling
    /// holds at each of its sides: one terminal peak stood for both twins' terminals
    /// there ([`Segmentation::twin_ends`](super::Segmentation::twin_ends)).
    pub twin_ends: [Option<usize>; 2],
    /// The centreline model.
    pub spline: BSpline,
    /// Dense samples of the spline from `ends[0]` to `ends[1]`.
    pub polyline: Vec<[f32; 2]>,
    /// Length of the polyline, pixels.
    pub length_px: f32,
    /// Width measured across the curve on the image, pixels.
    pub width_px: f32,
    /// Median sRGB colour along the centreline.
    pub color: [u8; 3],
    /// Share of the profiles read across the centreline that show a cable rather than
    /// a step between two backgrounds (`refine::Refined::ridge_share`; 1 when none
    /// could be read).
    pub ridge_share: f32,
    /// Confidence in 0..=1: the quality of the walk (colour agreement, smoothness,
    /// lateral contrast, mean cable probability; see `Walk::quality`) times a factor
    /// for how it ended (confirmed by the walk from the other end: 1; unconfirmed,
    /// through the border or joined across a gap: the pairing factors), times the
    /// confidence of its start end when no second end confirms it, times, with a cable
    /// field, the share of its centreline on cable pixels.
    pub score: f32,
}

/// Everything the modelling of one cable reads: the earlier stages' results.
#[derive(Clone, Copy)]
pub(super) struct Scene<'a> {
    pub walks: &'a [Walk],
    pub seeds: &'a [Seed],
    pub terrain: Terrain<'a>,
    pub field: Option<&'a CableField>,
    pub sp: &'a Superpixels,
    pub image: &'a RgbImage,
}

/// Builds the spline model of one chosen walk: data points from the walk, fit,
/// refinement on the image, final fit and measurements.
pub(super) fn model_cable(scene: &Scene<'_>, choice: &Pairing) -> Option<Cable> {
    model_course(scene, &Course::of(scene.walks, choice))
}

/// The spline model of a cable along `course` (see [`model_cable`]). A course that
/// starts at a seed starts exactly there, held as firmly as an end; one that starts
/// open (a cable run on past the end of a piece of the field, [`super::chains`]) at its
/// first superpixel; one that starts at the border (run on out of the frame) where its
/// first superpixels head out of it, held there like the far end's exit.
pub(super) fn model_course(scene: &Scene<'_>, course: &Course) -> Option<Cable> {
    let start_seed = match course.ends[0] {
        FarEnd::Seed(s) => Some(s),
        FarEnd::Open | FarEnd::Border => None,
    };
    let Scene {
        seeds,
        terrain,
        field,
        sp,
        image,
        ..
    } = *scene;
    let Terrain {
        graph, lab, params, ..
    } = terrain;
    let centroid = |v: u32| graph.vertices[v as usize].centroid;
    let start = start_seed.map(|s| seeds[s].point);
    let mut points = vec![start.unwrap_or_else(|| centroid(course.vertices[0]))];
    let mut weights = vec![start.map_or(1.0, |_| params.end_weight)];
    points.extend(course.vertices[1..].iter().map(|&v| centroid(v)));
    weights.resize(points.len(), 1.0);
    // The far end's point and weight, kept through the refinement: a seed exactly, the
    // frame's edge where the cable leaves it.
    let mut far_anchor = None;
    let far_index = match course.ends[1] {
        FarEnd::Seed(t) => {
            let target = seeds[t].point;
            // Centroids next to the far end may lie beside or beyond it: the end is exact.
            while points.len() > 2
                && dist(points[points.len() - 1], target)
                    < params.close_radius_px * params.far_end_trim
            {
                points.pop();
                weights.pop();
            }
            points.push(target);
            weights.push(params.end_weight);
            far_anchor = Some((target, params.end_weight));
            Some(t)
        }
        FarEnd::Border => {
            // Held there as firmly as an end ([`fit_refined`]).
            far_anchor = exit_past(&mut points, &mut weights, sp, params)
                .map(|exit| (exit, params.end_weight));
            None
        }
        FarEnd::Open => None,
    };
    let mut start_anchor = start.map(|p| (p, params.end_weight));
    if course.ends[0] == FarEnd::Border {
        points.reverse();
        weights.reverse();
        start_anchor =
            exit_past(&mut points, &mut weights, sp, params).map(|exit| (exit, params.end_weight));
        points.reverse();
        weights.reverse();
    }
    let anchors = [start_anchor, far_anchor];
    let Fitted {
        spline,
        polyline,
        width,
        ridge_share,
    } = fit_refined(&points, &weights, anchors, lab, params)?;
    let width_px = width.unwrap_or_else(|| fallback_width(&course.vertices, graph, sp));
    let length_px = polyline_length(&polyline);
    // With a field, the cable must lie on cable pixels: its score is scaled by the share
    // of its centreline that does, and a walk that wandered onto the background is dropped.
    let on_cable = field.map_or(1.0, |f| f.share_on_cable(&polyline, params.field_level));
    if on_cable < params.field_min_share {
        return None;
    }
    Some(Cable {
        id: 0,
        ends: [polyline[0], polyline[polyline.len() - 1]],
        end_indices: [start_seed, far_index],
        twin_ends: [None, None],
        color: median_rgb(image, &polyline),
        spline,
        polyline,
        length_px,
        width_px,
        ridge_share: ridge_share.unwrap_or(1.0),
        score: (course.score * on_cable).clamp(0.0, 1.0),
    })
}

/// Appends to `points` (fit weight 1) where their last ones, heading out of the
/// frame, leave it within `border_exit_steps` superpixel steps, and returns it.
fn exit_past(
    points: &mut Vec<[f32; 2]>,
    weights: &mut Vec<f32>,
    sp: &Superpixels,
    params: &Params,
) -> Option<[f32; 2]> {
    let dir = heading(points, params.heading_span_px);
    let reach = params.border_exit_steps * sp.step;
    let last = *points.last()?;
    let exit = border_exit(last, dir, sp.width, sp.height, reach)?;
    points.push(exit);
    weights.push(1.0);
    Some(exit)
}

/// A centreline fitted and refined on the image ([`fit_refined`]).
pub(super) struct Fitted {
    /// The final spline.
    pub spline: BSpline,
    /// Its dense samples.
    pub polyline: Vec<[f32; 2]>,
    /// The width the refinement read, when it read one.
    pub width: Option<f32>,
    /// The share of its profiles that read a ridge, when it read any.
    pub ridge_share: Option<f32>,
}

/// Shortest loop, nominal widths along its course (a circle about 2 widths across:
/// tighter than a cable bends).
pub(super) const LOOP_MIN_WIDTHS: f32 = 12.0;
/// A cable that crosses itself (round a loop at least [`LOOP_MIN_WIDTHS`] long) is
/// fitted with knots this share of `knot_spacing_px` apart: a loop is tighter than the
/// bends the spacing is made for (one of 30 px in radius, fitted with the usual knots,
/// shrank to a third of its size; one of 40 px read half a cable's width inside it).
const LOOP_KNOT_SHARE: f32 = 0.5;

/// The spline through `points` (fit weights `weights`), then, with `params.refine`,
/// `refine_passes` times refined on `lab` and fitted again; `anchors` (a point and its
/// weight) hold the first and the last point where they are through every pass: a
/// given end exactly, an exit on the frame's edge (profiles cannot be read past the
/// frame, and the refinement would otherwise carry the last points out of it). Knots
/// lie `knot_spacing_px` apart along the points, [`LOOP_KNOT_SHARE`] of that where
/// they cross themselves.
pub(super) fn fit_refined(
    points: &[[f32; 2]],
    weights: &[f32],
    anchors: [Option<([f32; 2], f32)>; 2],
    lab: &LabImage,
    params: &Params,
) -> Option<Fitted> {
    let knots = if crosses_itself(points, LOOP_MIN_WIDTHS * params.nominal_width_px) {
        LOOP_KNOT_SHARE * params.knot_spacing_px
    } else {
        params.knot_spacing_px
    };
    let mut spline = BSpline::fit(points, weights, knots, params.smoothing)?;
    let mut polyline = spline.sample(params.polyline_step_px);
    let (mut width, mut ridge_share) = (None, None);
    if params.refine {
        let mut lit_read: Option<usize> = None;
        for _ in 0..params.refine_passes {
            let refined = refine::refine(&polyline, lab, params);
            // Moved off its shadow onto a pale cable of nearly the table's colour, a
            // line that the next pass reads at under half as many profiles is kept:
            // few profiles there tell the cable from the table, and offsets spread
            // from those few would undo the move.
            if lit_read.is_some_and(|n| refined.read < n.div_ceil(2)) {
                break;
            }
            lit_read = refined.lit_side.then_some(refined.read);
            width = refined.width_px.or(width);
            ridge_share = refined.ridge_share.or(ridge_share);
            let mut pts = refined.points;
            let mut w = vec![1.0; pts.len()];
            let last = pts.len() - 1;
            for (i, anchor) in [0, last].into_iter().zip(anchors) {
                if let Some((point, weight)) = anchor {
                    pts[i] = point;
                    w[i] = weight;
                }
            }
            spline = BSpline::fit(&pts, &w, knots, params.smoothing)?;
            polyline = spline.sample(params.polyline_step_px);
        }
    }
    Some(Fitted {
        spline,
        polyline,
        width,
        ridge_share,
    })
}

/// Cap of the fallback width, in superpixel steps (a merged superpixel can be large).
const FALLBACK_MAX_STEPS: f32 = 2.0;

/// Width from the cable's superpixels when the image could not be read: a superpixel on
/// a cable spans about its width, so the side of the mean superpixel's square.
fn fallback_width(vertices: &[u32], graph: &Graph, sp: &Superpixels) -> f32 {
    let n = vertices.len().max(1) as f32;
    let area: f32 = vertices
        .iter()
        .map(|&v| graph.vertices[v as usize].pixels as f32)
        .sum::<f32>()
        / n;
    area.sqrt().min(sp.step * FALLBACK_MAX_STEPS)
}

/// Per-channel median sRGB colour of `image` along `line`.
pub(super) fn median_rgb(image: &RgbImage, line: &[[f32; 2]]) -> [u8; 3] {
    let (w, h) = image.dimensions();
    let mut channels: [Vec<u8>; 3] = Default::default();
    for p in line {
        let (x, y) = (p[0].round(), p[1].round());
        if x >= 0.0 && y >= 0.0 && (x as u32) < w && (y as u32) < h {
            let px = image.get_pixel(x as u32, y as u32).0;
            for c in 0..3 {
                channels[c].push(px[c]);
            }
        }
    }
    channels.map(|mut ch| median(&mut ch, u8::cmp).unwrap_or(0))
}

/// Removes the cables of `cables` flagged in `dropped` (one flag each) and renumbers
/// the rest in order; `end_cables` (given end to cable) follows, the ends of dropped
/// cables left without one.
pub(super) fn drop_cables(
    cables: &mut Vec<Cable>,
    end_cables: &mut [Option<usize>],
    dropped: &[bool],
) {
    debug_assert_eq!(cables.len(), dropped.len());
    let mut id = vec![None; cables.len()];
    let mut next = 0;
    for (k, gone) in dropped.iter().enumerate() {
        if !gone {
            id[k] = Some(next);
            next += 1;
        }
    }
    for end in end_cables.iter_mut() {
        *end = end.and_then(|old| id[old]);
    }
    let kept = std::mem::take(cables);
    *cables = kept
        .into_iter()
        .zip(id)
        .filter_map(|(mut cable, id)| {
            cable.id = id?;
            Some(cable)
        })
        .collect();
}

/// Drops the cables shorter than [`Params::field_short_widths`] nominal widths that
/// score under [`Params::field_short_min_score`] (a field's floor for short cables:
/// walks over photographed clutter end soon and score low), and the cables between two
/// ends shorter than [`Params::field_pair_short_widths`] that score under
/// [`Params::field_pair_short_min_score`] (two false terminals on a texture joined);
/// their ends are left free.
pub(super) fn drop_short_weak(
    cables: &mut Vec<Cable>,
    end_cables: &mut [Option<usize>],
    params: &Params,
) {
    let short = params.field_short_widths * params.nominal_width_px;
    let pair_short = params.field_pair_short_widths * params.nominal_width_px;
    let weak: Vec<bool> = cables
        .iter()
        .map(|c| {
            let paired = c.end_indices.iter().all(Option::is_some);
            (c.length_px < short && c.score < params.field_short_min_score)
                || (paired
                    && c.length_px < pair_short
                    && c.score < params.field_pair_short_min_score)
        })
        .collect();
    if weak.contains(&true) {
        drop_cables(cables, end_cables, &weak);
    }
}

/// A 640x480 segmentation at `working_scale` of `cables` and its `end_cables`, for the
/// engine's unit tests.
#[cfg(test)]
pub(super) fn found(
    working_scale: f32,
    cables: Vec<Cable>,
    end_cables: Vec<Option<usize>>,
) -> super::Segmentation {
    super::Segmentation {
        width: 640,
        height: 480,
        cables,
        end_cables,
        superpixels: 0,
        working_scale,
        mask_scale: 1.0,
        timings: Default::default(),
    }
}

/// A straight cable from `ends[0]` to `ends[1]` (eleven points, 8 px wide, score 0.5),
/// for the engine's unit tests.
#[cfg(test)]
pub(super) fn straight(id: usize, ends: [[f32; 2]; 2], end_indices: [Option<usize>; 2]) -> Cable {
    Cable {
        id,
        ends,
        end_indices,
        twin_ends: [None, None],
        spline: BSpline {
            degree: 3,
            knots: Vec::new(),
            control_points: Vec::new(),
        },
        polyline: (0..=10)
            .map(|i| {
                let t = i as f32 / 10.0;
                [0, 1].map(|j| ends[0][j] + t * (ends[1][j] - ends[0][j]))
            })
            .collect(),
        length_px: dist(ends[0], ends[1]),
        width_px: 8.0,
        color: [0, 0, 0],
        ridge_share: 1.0,
        score: 0.5,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pale_cable_read_off_its_shadow_is_not_moved_again_by_a_few_profiles() {
        // A pale cable (rows 17-20, centre 18.5) of nearly the card's colour (ΔE 8.9,
        // under `refine_min_background_de`) and its grey shadow below it (rows 22-28),
        // of far more contrast; along a quarter of it a darker stain on the card above
        // (rows 6-10). The first pass reads the shadow, takes the lit cable beside it
        // and moves the line onto the cable (19 profiles read); centred there, the
        // second pass can read only the 5 profiles that end on the stain, and its
        // offsets, interpolated from those few, carried the whole line off the cable
        // (to row 15.7) before the second pass was refused.
        let (w, h) = (80, 40);
        let rgb: Vec<u8> = (0..w * h)
            .flat_map(|i| match (i % w, i / w) {
                (_, 17..=20) => [218, 238, 230],
                (_, 22..=28) => [120, 130, 122],
                (26..=45, 6..=10) => [90, 110, 160],
                _ => [190, 214, 208],
            })
            .collect();
        let lab = LabImage::from_rgb(&rgb, w, h);
        let params = Params {
            refine_radius_px: 10.0,
            ..Params::default()
        };
        let points: Vec<[f32; 2]> = (5..75).map(|x| [x as f32, 23.0]).collect();
        let fitted = fit_refined(
            &points,
            &vec![1.0; points.len()],
            [None, None],
            &lab,
            &params,
        )
        .expect("a spline");
        let rows: Vec<f32> = fitted.polyline.iter().map(|p| p[1]).collect();
        let (lo, hi) = rows
            .iter()
            .fold((f32::MAX, f32::MIN), |(lo, hi), &y| (lo.min(y), hi.max(y)));
        assert!(lo > 17.0 && hi < 20.5, "rows {lo}..{hi}");
    }

    #[test]
    fn only_a_cable_both_short_and_weak_is_dropped_and_its_ends_freed() {
        let params = Params::default();
        let short = params.field_short_widths * params.nominal_width_px;
        let weak = params.field_short_min_score;
        // Each from an end to a free end (the border, a lost walk): only the floor for
        // every cable applies.
        let cable = |id: usize, length: f32, score: f32| Cable {
            score,
            ..straight(
                id,
                [[100.0, 100.0], [100.0 + length, 100.0]],
                [Some(id), None],
            )
        };
        let mut cables = vec![
            cable(0, 0.8 * short, 0.5 * weak),
            cable(1, 1.2 * short, 0.5 * weak),
            cable(2, 0.8 * short, 2.0 * weak),
            cable(3, 0.5 * short, 0.9 * weak),
        ];
        let mut end_cables: Vec<Option<usize>> = (0..4).map(Some).collect();
        drop_short_weak(&mut cables, &mut end_cables, &params);
        // The long weak one and the short strong one stay, renumbered.
        let scores: Vec<f32> = cables.iter().map(|c| c.score).collect();
        assert_eq!(scores, [0.5 * weak, 2.0 * weak]);
        assert_eq!(cables.iter().map(|c| c.id).collect::<Vec<_>>(), [0, 1]);
        assert_eq!(end_cables, [None, Some(0), Some(1), None]);
        let mut none = vec![cable(0, 0.5 * short, 0.0)];
        let off = Params {
            field_short_min_score: 0.0,
            ..params
        };
        drop_short_weak(&mut none, &mut [Some(0)], &off);
        assert_eq!(none.len(), 1, "a floor of 0 drops nothing");
    }

    #[test]
    fn a_short_weak_cable_between_two_ends_is_dropped_and_its_ends_freed() {
        let params = Params::default();
        let short = params.field_pair_short_widths * params.nominal_width_px;
        let weak = params.field_pair_short_min_score;
        // Longer and stronger than the floor for every cable asks.
        assert!(0.9 * short > params.field_short_widths * params.nominal_width_px);
        assert!(0.5 * weak > params.field_short_min_score);
        let cable = |id: usize, length: f32, score: f32, far_end: Option<usize>| Cable {
            score,
            ..straight(
                id,
                [[100.0, 100.0], [100.0 + length, 100.0]],
                [Some(2 * id), far_end],
            )
        };
        let mut cables = vec![
            cable(0, 0.9 * short, 0.5 * weak, Some(1)),
            cable(1, 0.9 * short, 0.5 * weak, None),
            cable(2, 1.1 * short, 0.5 * weak, Some(5)),
            cable(3, 0.9 * short, 1.5 * weak, Some(7)),
        ];
        let mut end_cables: Vec<Option<usize>> = [0, 0, 1, 9, 2, 2, 3, 3]
            .map(|c| (c < 4).then_some(c))
            .to_vec();
        drop_short_weak(&mut cables, &mut end_cables, &params);
        // Kept: the one with a free end, the longer one, the stronger one.
        let tenths = |v: f32| (v * 10.0).round() / 10.0;
        let kept: Vec<(f32, f32)> = cables
            .iter()
            .map(|c| (tenths(c.length_px / short), tenths(c.score / weak)))
            .collect();
        assert_eq!(kept, [(0.9, 0.5), (1.1, 0.5), (0.9, 1.5)]);
        assert_eq!(
            end_cables,
            [
                None,
                None,
                Some(0),
                None,
                Some(1),
                Some(1),
                Some(2),
                Some(2)
            ]
        );
        let mut off = vec![cable(0, 0.5 * short, 0.0, Some(1))];
        let params = Params {
            field_pair_short_min_score: 0.0,
            field_short_min_score: 0.0,
            ..params
        };
        drop_short_weak(&mut off, &mut [Some(0), Some(0)], &params);
        assert_eq!(off.len(), 1, "floors of 0 drop nothing");
    }
}
