//! The working resolution. The engine's lengths (step lengths, radii, mask width) are
//! in pixels and suit cables about [`Params::nominal_width_px`] wide, as in a photo of a
//! work cell at 640x480. A photo of another size is resampled to about
//! [`Params::working_pixels`] pixels (enlarged at most [`Params::max_upscale`] times),
//! segmented there, and its cables are mapped back to the photo's pixels. When the
//! cables found there are much wider or thinner than nominal (a camera closer to the
//! table or farther from it), the photo is segmented once more at the scale that makes
//! them nominal ([`Segmentation::width_correction`]); superpixels keep their size in
//! working pixels ([`WorkingFrame::params`]). Cables so wide that the network does not
//! see them at the working size leave no cable to measure; the network's field at half
//! that size tells them ([`too_wide_for_the_field`]).

use std::borrow::Cow;
use std::cmp::Ordering;

use image::RgbImage;

use super::cable::drop_cables;
use super::geometry::{border_inset, dist, points_near_any, polyline_length};
use super::resample::{box_shrink, resize_to};
use super::{Cable, CableField, MIN_SIDE, Params, Segmentation};

/// Smallest and largest factor on the working scale that a closer or a farther
/// camera gets (a photo segmented at most 4 times smaller or 2 times larger).
pub const MIN_CORRECTION: f64 = 0.25;
/// See [`MIN_CORRECTION`].
pub const MAX_CORRECTION: f64 = 2.0;

/// Share of the best cable's score from which a cable's width counts in the width
/// reading ([`Segmentation::width_correction`], [`Segmentation::mask_correction`]).
/// Thin strokes of a printed background that the network takes for short cables score
/// far below the real cables beside them (0.02-0.07, once 0.49, against 0.65-0.75 on
/// the synthetic textured scenes), and as the many they decided the median: a photo of
/// 8-12 px cables read 3.1 px and was enlarged twice, where hardly anything was found.
const CREDIBLE_SCORE_SHARE: f32 = 0.25;

/// Share of the best cable's score from which a whole cable's width counts in
/// bounding how far the photo is shrunk ([`thin_width`]): lower than
/// [`CREDIBLE_SCORE_SHARE`], because a wire beside a power cable scores less than it
/// (a wire from the border to a missed terminal, walked from the border, 0.19 of the
/// power cable's score: left out of the bound, the wires were shrunk to 3 px). On the
/// zoomed development photos, walks along the edges of cables too wide for the first
/// pass or along wood grain score 0.04-0.07 of the best and would hold the shrink back.
const THIN_SCORE_SHARE: f32 = 0.1;

/// Cable probability from which a field cell counts as cable for
/// [`too_wide_for_the_field`].
const FIELD_CABLE_LEVEL: f32 = 0.5;

/// Fewest cable cells the field at half the working size must show to say the cables
/// are too wide: about 150 px of one cable at 640x480 (a cell is 16 photo px there).
const WIDE_MIN_CELLS: usize = 10;

/// Share of cable cells from which the field at the working size is taken to see the
/// photo's cables, so that nothing is asked at half the size: the development photos'
/// fields call 6.6-13.3 % of their cells cable, those of two cables 24 or 32 px wide at
/// 640x480 under 1.4 %.
const SEEN_SHARE: f32 = 0.02;

/// Whether the cables might be too wide for the network, judged from its field at the
/// working size alone: it calls under [`SEEN_SHARE`] of the photo cable. Only then is
/// the field at half the size worth computing for [`too_wide_for_the_field`].
pub fn field_may_miss_wide_cables(full: &CableField) -> bool {
    full.cable_share(FIELD_CABLE_LEVEL) < SEEN_SHARE
}

/// Share of a cable's centreline points near the cables of a pass at another working
/// scale from which that pass is taken to have found it ([`Segmentation::adopt_lost`]).
const EXPLAINED_SHARE: f32 = 0.5;

/// Shortest cable, in nominal widths at its own pass's scale, taken for a whole cable:
/// a pass at a scale that does not suit every cable also finds short pieces of the
/// wide ones (along an edge, across a highlight). Only such cables are taken in from
/// another pass ([`Segmentation::adopt_lost`]) and bound how far a photo is shrunk
/// ([`thin_width`]).
const WHOLE_MIN_LENGTH: f32 = 20.0;

/// Relative size changes smaller than this are not worth a resampling.
const SAME_SIZE: f64 = 0.05;

/// A photo's size and the size it is segmented at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorkingFrame {
    /// The photo's width and height, pixels.
    pub photo: [u32; 2],
    /// The working image's width and height, pixels.
    pub working: [u32; 2],
}

impl WorkingFrame {
    /// The working size of a `width` x `height` photo under `params`.
    pub fn choose(width: u32, height: u32, params: &Params) -> Self {
        Self::corrected(width, height, params, 1.0)
    }

    /// [`Self::choose`] with the scale multiplied by `correction` (from
    /// [`Segmentation::width_correction`]).
    pub fn corrected(width: u32, height: u32, params: &Params, correction: f64) -> Self {
        let pixels = width as f64 * height as f64;
        let scale = ((params.working_pixels as f64 / pixels.max(1.0)).sqrt() * correction)
            .min(params.max_upscale as f64);
        let side = |v: u32| {
            let scaled = (v as f64 * scale).round().max(1.0) as u32;
            scaled.max(v.min(MIN_SIDE))
        };
        let working = if (scale - 1.0).abs() < SAME_SIZE {
            [width, height]
        } else {
            [side(width), side(height)]
        };
        Self {
            photo: [width, height],
            working,
        }
    }

    /// Working pixels per photo pixel along x and y.
    fn factors(&self) -> [f64; 2] {
        [0, 1].map(|i| self.working[i] as f64 / self.photo[i] as f64)
    }

    /// Working pixels per photo pixel (the geometric mean of the two axes): 1 when the
    /// photo is segmented as it is.
    pub fn scale(&self) -> f32 {
        let [sx, sy] = self.factors();
        (sx * sy).sqrt() as f32
    }

    /// `params` for this frame: the superpixel count scaled with the working image's
    /// area, so that superpixels keep the size they have in a `working_pixels` image
    /// (a zoomed photo, segmented smaller, gets fewer of them).
    pub fn params<'a>(&self, params: &'a Params) -> Cow<'a, Params> {
        let area = self.working[0] as f64 * self.working[1] as f64;
        let share = area / params.working_pixels as f64;
        if (share - 1.0).abs() < SAME_SIZE {
            return Cow::Borrowed(params);
        }
        let n = (params.n_segments as f64 * share).round().max(16.0);
        Cow::Owned(Params {
            n_segments: n.min(20_000.0) as u32,
            ..params.clone()
        })
    }

    /// True when the photo is segmented at its own size.
    pub fn is_identity(&self) -> bool {
        self.photo == self.working
    }

    /// True when the working image is the photo enlarged.
    pub fn enlarges(&self) -> bool {
        self.working[0] > self.photo[0]
    }

    /// A photo point (pixel centres at integers) in working pixels, kept inside the image.
    pub fn working_point(&self, p: [f64; 2]) -> [f64; 2] {
        let f = self.factors();
        [0, 1].map(|i| ((p[i] + 0.5) * f[i] - 0.5).clamp(0.0, (self.working[i] - 1) as f64))
    }

    /// A working point in photo pixels.
    pub fn photo_point(&self, p: [f64; 2]) -> [f64; 2] {
        let f = self.factors();
        [0, 1].map(|i| (p[i] + 0.5) / f[i] - 0.5)
    }

    /// [`Self::photo_point`] for `f32` points.
    fn photo_point_f32(&self, p: [f32; 2]) -> [f32; 2] {
        self.photo_point(p.map(f64::from)).map(|v| v as f32)
    }

    /// The photo resampled to the working size: the mean of each output pixel's box of
    /// photo pixels when it shrinks at least twofold (one pass over the photo), a
    /// triangle filter when it shrinks less, Catmull-Rom when it is enlarged (sharper
    /// edges between superpixels than a triangle's), the photo itself when the sizes
    /// agree.
    pub fn resample<'a>(&self, photo: &'a RgbImage) -> Cow<'a, RgbImage> {
        let [w, h] = self.working;
        if self.is_identity() {
            Cow::Borrowed(photo)
        } else if 2 * w <= self.photo[0] && 2 * h <= self.photo[1] {
            Cow::Owned(box_shrink(photo, w, h))
        } else {
            Cow::Owned(resize_to(photo, w, h))
        }
    }
}

impl Segmentation {
    /// These cables, found in the working image of `frame`, in the photo's pixels:
    /// points, splines (an affine map moves control points alone), lengths, widths.
    pub fn into_photo(mut self, frame: &WorkingFrame) -> Self {
        if frame.is_identity() {
            return self;
        }
        let scale = frame.scale();
        for cable in &mut self.cables {
            cable.ends = cable.ends.map(|p| frame.photo_point_f32(p));
            for p in &mut cable.polyline {
                *p = frame.photo_point_f32(*p);
            }
            for p in &mut cable.spline.control_points {
                *p = frame.photo_point(*p);
            }
            cable.length_px = polyline_length(&cable.polyline);
            cable.width_px /= scale;
        }
        [self.width, self.height] = frame.photo;
        self.working_scale = scale;
        self
    }

    /// The factor to multiply the working scale by so that these cables (in photo
    /// pixels, found at `frame`) would be [`Params::nominal_width_px`] wide: `None`
    /// when their width ([`measured_width`]) is within [`Params::width_tolerance`] of
    /// nominal, or when there is no cable to measure. Bounded to
    /// [`MIN_CORRECTION`]..=[`MAX_CORRECTION`].
    pub fn width_correction(&self, frame: &WorkingFrame, params: &Params) -> Option<f64> {
        let ratio = self.width_ratio(frame, params)?;
        off_by_more(ratio, params.width_tolerance)
            .then(|| ratio.clamp(MIN_CORRECTION, MAX_CORRECTION))
    }

    /// The factor to draw these cables' masks wider by (found at `frame`, not to be
    /// segmented again): their width ([`measured_width`]) over nominal when that is
    /// off by more than `tolerance` (bounded to 0.5..=4, as the second pass's scale),
    /// else 1. With [`Params::mask_width_tolerance`], a camera a little closer than the
    /// development photos' (cables up to `width_tolerance` times nominal) asks for no
    /// second pass, but its cables are wider all the same; after a second pass that
    /// shrank the photo, the pipeline passes 1: the cables' width is known to be off
    /// nominal, and what is left of it is the sub-linear reading of wide cables.
    pub fn mask_correction(&self, frame: &WorkingFrame, params: &Params, tolerance: f32) -> f32 {
        match self.width_ratio(frame, params) {
            Some(ratio) if off_by_more(ratio, tolerance) => {
                (1.0 / ratio.clamp(MIN_CORRECTION, MAX_CORRECTION)) as f32
            }
            _ => 1.0,
        }
    }

    /// Nominal over measured width of these cables in working pixels of `frame`, or,
    /// where that asks to shrink the photo, no less than keeps its thin cables
    /// ([`thin_width`]) at least `nominal_width_px / width_tolerance` wide (and at most
    /// 1): power cables among signal wires would have the photo shrunk until the wires
    /// are 2-3 px wide and lost, where at this scale both are followed (docs/CAMERAS.md,
    /// "Power cables do not shrink a photo past its wires"). `None` when there is no cable
    /// to measure.
    fn width_ratio(&self, frame: &WorkingFrame, params: &Params) -> Option<f64> {
        let scale = frame.scale();
        let all: Vec<Reading> = self
            .cables
            .iter()
            .map(|c| Reading {
                width: c.width_px * scale,
                length: c.length_px * scale,
                score: c.score,
            })
            .filter(|r| r.width.is_finite() && r.width > 0.0)
            .collect();
        let nominal = params.nominal_width_px;
        let thin = thin_width(
            &credible(&all, THIN_SCORE_SHARE),
            WHOLE_MIN_LENGTH * nominal,
        );
        let readings = credible(&all, CREDIBLE_SCORE_SHARE);
        let ratio = f64::from(nominal) / measured_width(readings, nominal)?;
        let floor = thin.map_or(0.0, |thin| {
            (f64::from(nominal / params.width_tolerance) / thin).min(1.0)
        });
        Some(if ratio < 1.0 { ratio.max(floor) } else { ratio })
    }

    /// The mask stroke width in the photo's pixels for `mask_width_px` working pixels,
    /// times [`Segmentation::mask_scale`] (0 stays 0: each cable's measured width).
    pub fn mask_width(&self, mask_width_px: f32) -> f32 {
        mask_width_px * self.mask_scale / self.working_scale
    }

    /// Takes in the cables of `earlier`, a pass over the same photo at another working
    /// scale (both in the photo's pixels), that this pass lost because its scale does
    /// not suit them: a power cable beside signal wires reads wide and the photo is
    /// segmented again smaller for it, where the wires are too thin to follow; or the
    /// wires decide, the photo is enlarged, and the power cable is too wide there.
    /// A cable of `earlier` is taken when its width at this scale is off
    /// `nominal_width_px` by more than `width_tolerance`, or when it starts at an end
    /// this pass left without a cable (a pale wire that scores under the floor at this
    /// pass's size: the end is the same one, and the other pass followed it), or when
    /// it has no end and, when this pass is the smaller, runs from border to border
    /// (within `border_margin_px` of the frame at both ends): a cable crossing the
    /// frame that this pass lost (two thin wires side by side, whose gap widens in an
    /// enlarged pass; a pale cable on a pale board, whose contrast a shrunk pass blurs
    /// into the board), not a walk at a scale too large for the cables that ends along
    /// one of their edges or over the background's texture; provided
    /// it is at least [`WHOLE_MIN_LENGTH`] nominal widths long at its own scale and
    /// fewer than [`EXPLAINED_SHARE`] of its points lie near this pass's cables (within
    /// half their width plus its own). Its ends come along: an end of this pass within
    /// the cable's width of one of its ends is that end (the caller's ends are the same
    /// in both passes), unless a cable of this pass ends there already, and then the
    /// cable is not taken; a detected end of `earlier` with no such match is appended to
    /// `points` and `confidences` (this pass's ends, aligned with `end_cables`).
    /// One exception: where both this pass's cable at such an end and the cable of
    /// `earlier` read too thin for this pass's scale (beyond `width_tolerance`: a photo
    /// shrunk for wide cables), the latter having suited its own pass's scale,
    /// `earlier`'s is taken and this pass's dropped: a wire beside a power cable,
    /// walked astray where it is 2-3 px wide (docs/CAMERAS.md, "A wire walked too
    /// thin").
    /// Returns how many cables were taken where this pass had none (a cable replaced
    /// is not counted: this pass did see it, and the count tells the pipeline whether
    /// this pass's scale lost cables).
    pub fn adopt_lost(
        &mut self,
        points: &mut Vec<[f64; 2]>,
        confidences: &mut Vec<f32>,
        earlier: Segmentation,
        earlier_ends: (&[[f64; 2]], &[f32]),
        params: &Params,
    ) -> usize {
        let own = self.cables.len();
        let min_length = WHOLE_MIN_LENGTH * params.nominal_width_px / earlier.working_scale;
        let enlarged = self.working_scale > earlier.working_scale;
        let [width, height] = [self.width, self.height].map(|v| v as usize);
        let margin = params.border_margin_px / earlier.working_scale;
        let at_frame = |p: &[f32; 2]| border_inset(*p, width, height) <= margin;
        let mut taken = 0;
        // This pass's cables that a cable of `earlier` replaces.
        let mut replaced = vec![false; own];
        let here = self.working_scale;
        let ratio_at =
            |c: &Cable, scale: f32| f64::from(params.nominal_width_px / (c.width_px * scale));
        let too_thin = |ratio: f64| ratio > f64::from(params.width_tolerance);
        for mut cable in earlier.cables {
            let same = |i: usize| {
                let q = earlier_ends.0[i].map(|v| v as f32);
                points
                    .iter()
                    .position(|p| dist(p.map(|v| v as f32), q) <= cable.width_px)
            };
            let matched = cable.end_indices.map(|i| i.map(|i| (i, same(i))));
            let ends_here = || matched.iter().flatten().filter_map(|&(_, j)| j);
            let ratio = ratio_at(&cable, here);
            let unsuited = off_by_more(ratio, params.width_tolerance);
            // A cable of this pass at one of its ends stands, unless both read too thin
            // for this scale and `cable` suited its own: a wire walked in a photo shrunk
            // for a power cable, where it is too thin to follow.
            let suited_there = !off_by_more(
                ratio_at(&cable, earlier.working_scale),
                params.width_tolerance,
            );
            let rivals: Vec<usize> = ends_here().filter_map(|j| self.end_cables[j]).collect();
            let outdone = |c: usize| c < own && too_thin(ratio_at(&self.cables[c], here));
            let replaces = too_thin(ratio) && suited_there && rivals.iter().all(|&c| outdone(c));
            if !rivals.is_empty() && !replaces {
                continue;
            }
            let no_end = cable.end_indices.iter().all(Option::is_none)
                && (enlarged
                    || [cable.polyline.first(), cable.polyline.last()]
                        .into_iter()
                        .all(|p| p.is_some_and(at_frame)));
            if !(unsuited || no_end || ends_here().next().is_some()) || cable.length_px < min_length
            {
                continue;
            }
            let found: Vec<(&[[f32; 2]], f32)> = self.cables[..own]
                .iter()
                .filter(|c| !replaced[c.id] && !rivals.contains(&c.id))
                .map(|c| (&c.polyline[..], c.width_px / 2.0 + cable.width_px))
                .collect();
            let near = points_near_any(&cable.polyline, &found);
            if near as f32 >= EXPLAINED_SHARE * cable.polyline.len() as f32 {
                continue;
            }
            for &c in &rivals {
                replaced[c] = true;
                for end in self.end_cables.iter_mut().filter(|e| **e == Some(c)) {
                    *end = None;
                }
            }
            cable.id = self.cables.len();
            for (index, m) in cable.end_indices.iter_mut().zip(matched) {
                *index = m.map(|(i, j)| {
                    j.unwrap_or_else(|| {
                        points.push(earlier_ends.0[i]);
                        confidences.push(earlier_ends.1[i]);
                        self.end_cables.push(None);
                        points.len() - 1
                    })
                });
                if let Some(j) = *index {
                    self.end_cables[j] = Some(cable.id);
                }
            }
            taken += usize::from(rivals.is_empty());
            self.cables.push(cable);
        }
        // The cables taken in are kept.
        replaced.resize(self.cables.len(), false);
        drop_cables(&mut self.cables, &mut self.end_cables, &replaced);
        taken
    }
}

/// True when the cables look too wide for the network at the working size: its field
/// seen at half that size (`half`) calls more than `ratio` times the share of the
/// photo cable that its field at the working size (`full`) does, on at least
/// [`WIDE_MIN_CELLS`] cells. The network learnt cables about 5-16 px wide at 640x480;
/// cables two or three times wider it calls cable only along their edges, or not at
/// all, and the engine finds nothing to measure. At half the size a cell covers four
/// times the photo, so the shares of the two fields compare as they are; on the
/// development photos, as taken or enlarged up to twofold, the half-size field's share
/// is 0.9-1.9 times the other's (docs/CAMERAS.md).
pub fn too_wide_for_the_field(full: &CableField, half: &CableField, ratio: f32) -> bool {
    half.cable_cells(FIELD_CABLE_LEVEL) >= WIDE_MIN_CELLS
        && half.cable_share(FIELD_CABLE_LEVEL) > ratio * full.cable_share(FIELD_CABLE_LEVEL)
}

/// True when `ratio` lies outside `1 / tolerance ..= tolerance`.
fn off_by_more(ratio: f64, tolerance: f32) -> bool {
    let tolerance = f64::from(tolerance);
    ratio > tolerance || ratio < 1.0 / tolerance
}

/// One cable's width as [`measured_width`] reads it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Reading {
    /// Its width, working pixels.
    width: f32,
    /// Its length, working pixels.
    length: f32,
    /// Its score.
    score: f32,
}

/// The readings of `readings` that are credible cables: those scoring at least
/// `share` of the best score.
fn credible(readings: &[Reading], share: f32) -> Vec<Reading> {
    let best = readings.iter().map(|r| r.score).fold(0.0, f32::max);
    readings
        .iter()
        .filter(|r| r.score >= share * best)
        .copied()
        .collect()
}

/// The width at most which two cables of `readings` (those [`credible`] at
/// [`THIN_SCORE_SHARE`]) at least `min_length` long read (the second narrowest), in
/// working pixels; `None` when there are not two.
/// One reading can be wrong: zoomed 3x, a two-tone cable about 20 px wide walked along
/// one of its colours read 6.6 px (simple/00023), and bounding the shrink by it cost
/// the zoom rows up to 0.025.
fn thin_width(readings: &[Reading], min_length: f32) -> Option<f64> {
    let mut widths: Vec<f64> = readings
        .iter()
        .filter(|r| r.length >= min_length)
        .map(|r| f64::from(r.width))
        .collect();
    widths.sort_by(f64::total_cmp);
    widths.get(1).copied()
}

/// The width of the cables of `readings` ([`credible`] ones), in working pixels: their
/// median width, or their length-weighted median width when that lies farther from
/// `nominal` (by ratio); `None` for no cable. At the wrong scale the engine also finds stray cables
/// (a walk over superpixels much wider or narrower than the cables), and their measured
/// widths lean towards the nominal width; with few cables one of them can decide the
/// plain median (two thin rods measured 3.2 and 9.2 px: the median 9.2 asks for no
/// correction), so the estimate farther from nominal is the one taken.
fn measured_width(mut widths: Vec<Reading>, nominal: f32) -> Option<f64> {
    widths.sort_by(|a, b| a.width.partial_cmp(&b.width).unwrap_or(Ordering::Equal));
    let median = f64::from(widths.get(widths.len() / 2)?.width);
    let half = widths.iter().map(|w| w.length.max(0.0)).sum::<f32>() / 2.0;
    let mut seen = 0.0;
    let weighted = widths
        .iter()
        .find(|w| {
            seen += w.length.max(0.0);
            seen >= half
        })
        .map_or(median, |w| f64::from(w.width));
    let off = |w: f64| (f64::from(nominal) / w).ln().abs();
    Some(if off(weighted) > off(median) {
        weighted
    } else {
        median
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::Cable;
    use crate::engine::cable::{found, straight};

    /// [`straight`] `width_px` wide.
    fn wide(
        id: usize,
        ends: [[f32; 2]; 2],
        end_indices: [Option<usize>; 2],
        width_px: f32,
    ) -> Cable {
        Cable {
            width_px,
            ..straight(id, ends, end_indices)
        }
    }

    /// A second pass at half the size that found one cable `width_px` wide between its
    /// ends 0 and 1 and none from its end 2 at `free`: the pass, its ends and their
    /// confidences.
    fn second_pass(width_px: f32, free: [f64; 2]) -> (Segmentation, Vec<[f64; 2]>, Vec<f32>) {
        let ends = [[100.0, 400.0], [540.0, 400.0]];
        let cable = wide(0, ends, [Some(0), Some(1)], width_px);
        let seg = found(0.5, vec![cable], vec![Some(0), Some(0), None]);
        let points = vec![ends[0].map(f64::from), ends[1].map(f64::from), free];
        (seg, points, vec![0.9, 0.9, 0.4])
    }

    #[test]
    fn cables_the_second_pass_s_scale_does_not_suit_are_taken_in_with_their_ends() {
        // The second pass, shrunk by half for a 20 px power cable, found it alone.
        let (mut seg, mut points, mut confidences) = second_pass(20.0, [300.0, 100.0]);
        let earlier = found(
            1.0,
            vec![
                // A piece along the power cable: explained by it.
                wide(0, [[120.0, 402.0], [500.0, 402.0]], [None, None], 8.0),
                // A wire from this pass's free end 2 down to the power cable: taken.
                wide(1, [[300.0, 100.0], [300.0, 380.0]], [Some(0), None], 4.0),
                // A wire whose ends this pass has not: taken, its ends appended.
                wide(2, [[50.0, 50.0], [250.0, 60.0]], [Some(1), Some(2)], 4.0),
                // Too short to be more than a piece of something wider.
                wide(3, [[500.0, 100.0], [560.0, 100.0]], [None, None], 4.0),
                // Ends where the power cable ends: that end is the power cable's.
                wide(4, [[101.0, 399.0], [100.0, 150.0]], [Some(3), None], 4.0),
                // As wide as the second pass's scale suits: it would have found it.
                wide(5, [[50.0, 200.0], [400.0, 250.0]], [None, None], 16.0),
            ],
            Vec::new(),
        );
        let earlier_points = [[300.0, 101.0], [50.0, 50.0], [250.0, 60.0], [101.0, 399.0]];
        let earlier_confidences = [0.5, 0.6, 0.7, 0.8];
        let taken = seg.adopt_lost(
            &mut points,
            &mut confidences,
            earlier,
            (&earlier_points, &earlier_confidences),
            &Params::default(),
        );
        assert_eq!(taken, 2);
        assert_eq!(seg.cables.len(), 3);
        assert_eq!(seg.cables[1].ends[0], [300.0, 100.0]);
        assert_eq!(seg.cables[1].end_indices, [Some(2), None]);
        assert_eq!(seg.cables[2].end_indices, [Some(3), Some(4)]);
        assert_eq!(
            seg.cables.iter().map(|c| c.id).collect::<Vec<_>>(),
            [0, 1, 2]
        );
        assert_eq!(
            seg.end_cables,
            [Some(0), Some(0), Some(1), Some(2), Some(2)]
        );
        assert_eq!(points[3..], [[50.0, 50.0], [250.0, 60.0]]);
        assert_eq!(confidences, [0.9, 0.9, 0.4, 0.6, 0.7]);
    }

    #[test]
    fn a_cable_from_an_end_the_second_pass_left_alone_is_taken_at_any_width() {
        // The second pass, at half the size, found one cable and nothing from end 2 (a
        // pale wire it scores below the floor there).
        let (mut seg, mut points, mut confidences) = second_pass(16.0, [300.0, 300.0]);
        let earlier = found(
            1.0,
            vec![
                // From end 2 to the border, as wide as this scale suits: taken.
                wide(0, [[300.0, 300.0], [300.0, 0.0]], [Some(0), None], 16.0),
                // From end 0, which has its cable here: not taken.
                wide(1, [[100.0, 400.0], [100.0, 100.0]], [Some(1), None], 16.0),
                // From no end: the second pass would have found it.
                wide(2, [[50.0, 200.0], [400.0, 250.0]], [None, None], 16.0),
            ],
            Vec::new(),
        );
        let taken = seg.adopt_lost(
            &mut points,
            &mut confidences,
            earlier,
            (&[[301.0, 301.0], [101.0, 399.0]], &[0.5, 0.8]),
            &Params::default(),
        );
        assert_eq!(taken, 1);
        assert_eq!(seg.cables[1].ends[1], [300.0, 0.0]);
        assert_eq!(seg.cables[1].end_indices, [Some(2), None]);
        assert_eq!(seg.end_cables, [Some(0), Some(0), Some(1)]);
        assert_eq!(points.len(), 3);
    }

    #[test]
    fn a_wire_walked_too_thin_in_a_shrunk_pass_gives_way_to_the_one_that_suited_its_scale() {
        // The second pass, at half the size for a 20 px power cable (ends 0 and 1),
        // walked a wire 6 px wide (3 working px: too thin to follow there) from end 2
        // off its course, and another from end 3.
        let (mut seg, mut points, mut confidences) = second_pass(20.0, [300.0, 100.0]);
        let astray = wide(1, [[300.0, 100.0], [600.0, 100.0]], [Some(2), None], 6.0);
        seg.cables.push(astray);
        seg.cables
            .push(wide(2, [[50.0, 50.0], [50.0, 300.0]], [Some(3), None], 6.0));
        seg.end_cables[2] = Some(1);
        seg.end_cables.push(Some(2));
        points.push([50.0, 50.0]);
        confidences.push(0.6);
        let earlier = found(
            1.0,
            vec![
                // The wire from end 2 as the first pass read it, at a width its scale
                // suits: it replaces the stray walk.
                wide(0, [[300.0, 100.0], [300.0, 380.0]], [Some(0), None], 7.0),
                // From end 3, but 3 px wide at the first pass too: it suited neither
                // scale, so the second pass's walk stands.
                wide(1, [[50.0, 50.0], [300.0, 50.0]], [Some(1), None], 3.0),
            ],
            Vec::new(),
        );
        let taken = seg.adopt_lost(
            &mut points,
            &mut confidences,
            earlier,
            (&[[300.0, 101.0], [50.0, 51.0]], &[0.5, 0.6]),
            &Params::default(),
        );
        assert_eq!(taken, 0, "a cable replaced is not counted as taken");
        assert_eq!(seg.cables.len(), 3);
        assert_eq!(
            seg.cables.iter().map(|c| c.id).collect::<Vec<_>>(),
            [0, 1, 2]
        );
        assert_eq!(seg.cables[1].ends, [[50.0, 50.0], [50.0, 300.0]]);
        assert_eq!(seg.cables[2].ends, [[300.0, 100.0], [300.0, 380.0]]);
        assert_eq!(seg.cables[2].end_indices, [Some(2), None]);
        assert_eq!(seg.end_cables, [Some(0), Some(0), Some(2), Some(1)]);
        assert_eq!(points.len(), 4);
    }

    #[test]
    fn a_cable_with_no_end_in_view_that_an_enlarged_pass_lost_is_taken() {
        // The second pass, enlarged twofold for thin wires, found one cable between its
        // ends 0 and 1.
        let ends = [[100.0, 400.0], [540.0, 400.0]];
        let cable = wide(0, ends, [Some(0), Some(1)], 4.0);
        let mut seg = found(2.0, vec![cable], vec![Some(0), Some(0)]);
        let mut points = vec![ends[0].map(f64::from), ends[1].map(f64::from)];
        let mut confidences = vec![0.9, 0.9];
        // The first pass's cables with no end, as wide as the second pass's scale
        // suits (4 px there is nominal).
        let earlier = found(
            1.0,
            vec![
                // Across a corner of the frame (two wires side by side, whose gap the
                // enlarged pass took for background): taken.
                wide(0, [[400.0, 0.0], [639.0, 300.0]], [None, None], 4.0),
                // Along this pass's cable: explained by it.
                wide(1, [[100.0, 402.0], [540.0, 402.0]], [None, None], 4.0),
                // Inside the frame all along (ends the network missed): an enlarged
                // pass takes it too.
                wide(2, [[50.0, 100.0], [400.0, 150.0]], [None, None], 4.0),
            ],
            Vec::new(),
        );
        let p = Params::default();
        let no_ends: (&[[f64; 2]], &[f32]) = (&[], &[]);
        let taken = seg.adopt_lost(&mut points, &mut confidences, earlier, no_ends, &p);
        assert_eq!(taken, 2);
        assert_eq!(seg.cables[1].ends, [[400.0, 0.0], [639.0, 300.0]]);
        assert_eq!(seg.cables[1].end_indices, [None, None]);
        assert_eq!(seg.cables[2].ends, [[50.0, 100.0], [400.0, 150.0]]);
        assert_eq!((points.len(), seg.end_cables.len()), (2, 2));
    }

    #[test]
    fn a_shrunk_pass_takes_only_cables_with_no_end_that_cross_the_frame() {
        // The second pass, at half the size, found one cable between its ends 0 and 1.
        let (mut seg, mut points, mut confidences) = second_pass(16.0, [300.0, 100.0]);
        let earlier = found(
            1.0,
            vec![
                // Across the frame (a pale cable on a pale board that the shrunk pass
                // blurred into it): taken.
                wide(0, [[200.0, 0.0], [639.0, 250.0]], [None, None], 16.0),
                // From inside the frame to the border (an edge of something wider, or
                // a stroke of the background, walked at a scale that suits neither).
                wide(1, [[50.0, 200.0], [0.0, 450.0]], [None, None], 16.0),
                // Inside the frame all along.
                wide(2, [[50.0, 100.0], [400.0, 150.0]], [None, None], 16.0),
            ],
            Vec::new(),
        );
        let no_ends: (&[[f64; 2]], &[f32]) = (&[], &[]);
        let p = Params::default();
        let taken = seg.adopt_lost(&mut points, &mut confidences, earlier, no_ends, &p);
        assert_eq!(taken, 1);
        assert_eq!(seg.cables[1].ends, [[200.0, 0.0], [639.0, 250.0]]);
        assert_eq!(seg.cables[1].end_indices, [None, None]);
    }

    /// Readings of `(width, length, score)`.
    fn readings(cables: &[(f32, f32, f32)]) -> Vec<Reading> {
        cables
            .iter()
            .map(|&(width, length, score)| Reading {
                width,
                length,
                score,
            })
            .collect()
    }

    #[test]
    fn a_photo_is_shrunk_no_further_than_keeps_its_wires_followable() {
        let p = Params::default();
        let vga = WorkingFrame::choose(640, 480, &p);
        let line = |id: usize, y: f32, length: f32, width: f32| {
            wide(id, [[20.0, y], [20.0 + length, y]], [None, None], width)
        };
        // Four pieces of 19 px power cables decide the width read: shrunk to 0.41.
        let power: Vec<Cable> = (0..4)
            .map(|i| line(i, 60.0 * i as f32, 600.0, 19.0))
            .collect();
        let alone = found(1.0, power, vec![]);
        let shrink = alone.width_correction(&vga, &p).unwrap();
        assert!((shrink - 7.8 / 19.0).abs() < 1e-6, "{shrink}");
        let with = |wires: &[(f32, f32)]| {
            let mut seg = alone.clone();
            for (k, &(length, width)) in wires.iter().enumerate() {
                seg.cables
                    .push(line(4 + k, 300.0 + 40.0 * k as f32, length, width));
            }
            seg
        };
        // With two 7 px wires, no further than makes them 5.6 px (nominal /
        // width_tolerance): within tolerance of this scale, so not at all, and their
        // masks are not widened for the power cables either.
        let wires = with(&[(600.0, 6.5), (600.0, 7.0)]);
        assert_eq!(wires.width_correction(&vga, &p), None);
        assert_eq!(wires.mask_correction(&vga, &p, p.mask_width_tolerance), 1.0);
        // Wires of 9.5 and 10 px allow 0.56.
        let bounded = with(&[(600.0, 9.5), (600.0, 10.0)])
            .width_correction(&vga, &p)
            .unwrap();
        assert!((bounded - 7.8 / 1.4 / 10.0).abs() < 1e-6, "{bounded}");
        // One wire may be a misread wide cable; a short one may be a piece of one.
        for wires in [with(&[(600.0, 7.0)]), with(&[(600.0, 7.0), (130.0, 7.0)])] {
            assert_eq!(wires.width_correction(&vga, &p), Some(shrink));
        }
        // Wires scoring a fifth of the power cables' are left out of the width read but
        // still bound the shrink; strokes at a twentieth bound nothing.
        let scored = |score: f32| {
            let mut seg = with(&[(600.0, 6.5), (600.0, 7.0)]);
            for wire in &mut seg.cables[4..] {
                wire.score = score;
            }
            seg.width_correction(&vga, &p)
        };
        assert_eq!(scored(0.1), None);
        assert_eq!(scored(0.025), Some(shrink));
        // Thin rods ask for an enlargement, which nothing bounds.
        let rods = found(
            1.0,
            vec![line(0, 100.0, 600.0, 3.0), line(1, 200.0, 600.0, 3.0)],
            vec![],
        );
        assert_eq!(rods.width_correction(&vga, &p), Some(2.0));
    }

    #[test]
    fn the_width_estimate_farther_from_nominal_is_taken() {
        // Two thin rods, the longer measured right (3.2 px), a short stray at 9.2.
        let rods = readings(&[(9.2, 80.0, 0.5), (3.2, 500.0, 0.5)]);
        assert_eq!(measured_width(rods, 8.5), Some(3.2f32.into()));
        // A long stray walk near nominal does not outvote the wide cables.
        let wide = readings(&[(11.9, 1000.0, 0.5), (14.7, 50.0, 0.5), (14.9, 130.0, 0.5)]);
        assert_eq!(measured_width(wide, 8.5), Some(14.7f32.into()));
        assert_eq!(measured_width(Vec::new(), 8.5), None);
    }

    #[test]
    fn strokes_far_less_credible_than_the_cables_are_not_measured() {
        // Two 8 px cables and three strokes of a printed background taken for cables
        // (a synthetic textured scene): the strokes' 3.1 px was the median.
        let scene = [
            (8.0, 283.0, 0.74),
            (8.0, 314.0, 0.65),
            (3.1, 71.0, 0.49),
            (3.1, 57.0, 0.03),
            (3.1, 77.0, 0.02),
        ];
        assert_eq!(
            measured_width(credible(&readings(&scene), CREDIBLE_SCORE_SHARE), 7.8),
            Some(8.0)
        );
        // Scored alike, the strokes are the median.
        let alike = scene.map(|(w, l, _)| (w, l, 0.5));
        assert_eq!(
            measured_width(credible(&readings(&alike), CREDIBLE_SCORE_SHARE), 7.8),
            Some(3.1f32.into())
        );
    }

    #[test]
    fn photos_are_brought_to_the_working_size() {
        let p = Params::default();
        let vga = WorkingFrame::choose(640, 480, &p);
        assert!(vga.is_identity());
        assert_eq!(vga.scale(), 1.0);
        let big = WorkingFrame::choose(4000, 3000, &p);
        assert_eq!(big.working, [640, 480]);
        let portrait = WorkingFrame::choose(1080, 1920, &p);
        assert_eq!(portrait.working, [416, 739]);
        // Small photos are enlarged, at most max_upscale times.
        assert_eq!(WorkingFrame::choose(320, 240, &p).working, [640, 480]);
        assert!(WorkingFrame::choose(320, 240, &p).enlarges());
        assert!(!big.enlarges() && !vga.enlarges());
        assert_eq!(WorkingFrame::choose(160, 120, &p).working, [640, 480]);
        assert_eq!(WorkingFrame::choose(100, 100, &p).working, [400, 400]);
        assert_eq!(WorkingFrame::choose(10, 10, &p).working, [40, 40]);
    }

    #[test]
    fn points_map_both_ways_and_stay_inside() {
        let frame = WorkingFrame::choose(1280, 960, &Params::default());
        assert_eq!(frame.scale(), 0.5);
        for p in [[1.0, 2.0], [1278.0, 958.0], [100.25, 733.5]] {
            let back = frame.photo_point(frame.working_point(p));
            assert!((back[0] - p[0]).abs() < 1e-9 && (back[1] - p[1]).abs() < 1e-9);
        }
        assert_eq!(frame.working_point([1279.0, 959.0]), [639.0, 479.0]);
        assert_eq!(frame.working_point([0.0, 0.0]), [0.0, 0.0]);
    }

    /// A `w` x `h` field whose first `cable` cells are cable (probability 0.9).
    fn field(w: usize, h: usize, cable: usize) -> CableField {
        CableField {
            width: w,
            height: h,
            cell_px: [8.0, 8.0],
            cable: (0..w * h)
                .map(|i| if i < cable { 0.9 } else { 0.1 })
                .collect(),
            orientation: vec![[0.0, 0.0]; w * h],
        }
    }

    #[test]
    fn a_field_that_sees_cables_only_at_half_size_says_they_are_too_wide() {
        // 80x60 cells at the working size, 40x30 at half: the same cables cover four
        // times fewer cells there, so equal shares mean the network sees them alike.
        let (seen, faint) = (field(80, 60, 480), field(80, 60, 40));
        assert!(!field_may_miss_wide_cables(&seen), "10 % of the cells");
        assert!(field_may_miss_wide_cables(&faint), "0.8 %");
        assert!(!too_wide_for_the_field(&seen, &field(40, 30, 120), 2.5));
        assert!(too_wide_for_the_field(&faint, &field(40, 30, 60), 2.5));
        assert!(
            !too_wide_for_the_field(&faint, &field(40, 30, 20), 2.5),
            "2.5 times"
        );
        // An empty field at the working size and a few stray cells at half: not enough.
        assert!(!too_wide_for_the_field(
            &field(80, 60, 0),
            &field(40, 30, 9),
            2.5
        ));
        assert!(too_wide_for_the_field(
            &field(80, 60, 0),
            &field(40, 30, 10),
            2.5
        ));
    }
}
