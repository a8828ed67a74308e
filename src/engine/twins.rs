//! Two cables of one colour lying side by side, found as one. A pair of wires laid
//! together, or two cables run along each other, is one band to the network (one
//! terminal peak per pair of ends, one cable in its field) and to the superpixels; the
//! walk follows the band and the fit draws one centreline down its middle, on the gap
//! between the two cables. Across the band the photo still shows two cables: two runs
//! of one colour with a valley between them (their rims, or a sliver of background).
//!
//! Every few pixels along each cable a colour profile is read across it. The band is
//! the run of samples standing out from the background at the profile's ends (short
//! holes closed: a gap between the twins, a pale cable's core as light as the table;
//! where that band reads as one cable, once more with a gap as wide as a cable closed:
//! two cables laid a sliver of table apart, one band to the walks and the network). Two
//! alike cables side by side make the band repeat itself: shifted by their separation,
//! its first cable lies on the second. So the band is compared with itself shifted
//! (between its outer edges, where each twin's contrast first reaches half its peak:
//! beyond them one twin's blurred edge meets the table where the other's meets its
//! sibling), by every separation from [`MIN_SEPARATION`] nominal widths up, against its
//! own variation; the best shift is taken when it matches (`twin_max_cost`), the two
//! cables it implies are each at least [`MIN_TWIN`] nominal widths wide, the gap
//! between them no wider than [`MAX_GAP`] of a cable ([`WIDE_MAX_GAP`] in the second
//! reading), and the valley between them unlike their cores ([`VALLEY`]): darker than
//! them, nearer the table's colour, or flanked by rims darker than them ([`RIM_DIP`]).
//! One cable, shaded or glossy, does not repeat itself at a shift of half its width
//! (its rim would lie on its core), a flat one has no valley, and a glossy one's
//! highlight is lighter than its cores, unlike the table and flanked by its body, no
//! darker than them. A cable whose profiles read as twins in at least `twin_min_share`
//! of those that read at all is replaced by the two cables, each drawn through the twin
//! centres read along it.

use image::RgbImage;

use super::Cable;
use super::Params;
use super::cable::median_rgb;
use super::color::LabImage;
use super::geometry::{dist, dist3, median, polyline_length, runs_along};
use super::refine::{normals, read_across, smooth_offsets};
use super::spline::BSpline;

/// Distance between the samples of a profile, pixels.
const STEP: f32 = 0.5;
/// Half-length of a profile, nominal widths: room for two cables beside a centreline
/// on either of them.
const REACH: f32 = 3.0;
/// The background at either end of a profile: the mean of this many pixels.
const END_PX: f32 = 3.0;
/// Least contrast (Lab ΔE to the nearer profile end) of the profile's peak, within
/// [`PEAK_REACH`] nominal widths of its centre, for the profile to be read.
const MIN_PEAK_DE: f32 = 12.0;
/// Reach of that peak from the centre, nominal widths.
const PEAK_REACH: f32 = 1.5;
/// A sample belongs to the band when its contrast exceeds this share of the peak...
const BAND_SHARE: f32 = 0.3;
/// ... and this ΔE.
const MIN_BAND_DE: f32 = 6.0;
/// Holes in the band up to this many nominal widths are closed...
const HOLE: f32 = 0.6;
/// Shortest separation of twins (centre to centre), nominal widths.
const MIN_SEPARATION: f32 = 0.8;
/// Longest separation tried, as a share of the band.
const MAX_SEPARATION_SHARE: f32 = 0.65;
/// Least width of each twin, nominal widths.
const MIN_TWIN: f32 = 0.8;
/// Widest gap between twins, as a share of a twin's width...
const MAX_GAP: f32 = 0.6;
/// ... or, where the band so read is one cable, the hole of a second reading (two
/// cables laid a sliver of table apart, too near for the walks and the network to
/// tell apart)...
const WIDE_HOLE: f32 = 1.0;
/// ... and the widest gap it allows: as wide as a cable.
const WIDE_MAX_GAP: f32 = 1.0;
/// The valley between twins differs from the mean of their cores by at least this
/// share of the band's variation.
const VALLEY: f32 = 0.4;
/// A rim flanking a valley lighter than the cores is darker than them by at least this
/// share of the valley's least contrast (`VALLEY` times the band's variation).
const RIM_DIP: f32 = 0.5;
/// A profile is read every this many pixels along the cable...
const SPACING_PX: f32 = 4.0;
/// ... but not within this many pixels of its ends (a terminal, the frame).
const END_SKIP_PX: f32 = 10.0;
/// Fewest profiles that must read for a cable to be judged.
const MIN_READINGS: usize = 4;

/// Twins read across one profile.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Twins {
    /// The two cables' centres, pixels from the profile's centre along its direction.
    offsets: [f32; 2],
    /// Their width, pixels: the band's span between its outer edges ([`outer_span`])
    /// less their separation, and no more than that separation (side by side, two
    /// cables do not overlap).
    width: f32,
}

/// Replaces every cable that lies over twins (module docs) by the two, each right
/// after the other in `cables` with the first's score, and renumbers the cables;
/// `end_cables` (given end to cable) follows, the ends going to the twin nearer the
/// cable found. A twin that runs along a cable found on its own, or along an earlier
/// twin, is that cable (the walks found one or both twins as well) and is dropped.
/// `lab` is `image` in Lab, as the cables were found on it.
pub(super) fn split_twins(
    cables: &mut Vec<Cable>,
    end_cables: &mut [Option<usize>],
    lab: &LabImage,
    image: &RgbImage,
    params: &Params,
) {
    // Every cable found, or its twins with the index of the cable they came from.
    let mut candidates: Vec<(Cable, Option<usize>)> = Vec::with_capacity(cables.len());
    let mut first = Vec::with_capacity(cables.len());
    for (k, cable) in cables.drain(..).enumerate() {
        first.push(candidates.len());
        match twin_cables(&cable, lab, image, params) {
            Some(pair) => candidates.extend(pair.map(|c| (c, Some(k)))),
            None => candidates.push((cable, None)),
        }
    }
    // For each candidate, the candidate it repeats (itself when it is kept).
    let mut same: Vec<usize> = (0..candidates.len()).collect();
    for i in 0..candidates.len() {
        let (twin, Some(parent)) = &candidates[i] else {
            continue;
        };
        let tolerance = 0.5 * twin.width_px.max(params.nominal_width_px);
        let repeated = (0..candidates.len()).find(|&j| {
            let (other, from) = &candidates[j];
            let comparable = match from {
                None => true,
                Some(p) => p != parent && j < i && same[j] == j,
            };
            comparable && runs_along(&twin.polyline, &other.polyline, tolerance)
        });
        if let Some(j) = repeated {
            same[i] = j;
        }
    }
    let mut id = vec![0; candidates.len()];
    let mut next = 0;
    for i in 0..candidates.len() {
        if same[i] == i {
            id[i] = next;
            next += 1;
        }
    }
    for end in end_cables.iter_mut() {
        *end = end.map(|old| id[same[first[old]]]);
    }
    *cables = candidates
        .into_iter()
        .enumerate()
        .filter(|&(i, _)| same[i] == i)
        .map(|(i, (mut cable, _))| {
            cable.id = id[i];
            cable
        })
        .collect();
}

/// Whether `cable` lies over twins ([`split_twins`] would split it): across such a pair
/// the refinement reads the crease between them, not a ridge.
pub(super) fn lies_over_twins(
    cable: &Cable,
    lab: &LabImage,
    image: &RgbImage,
    params: &Params,
) -> bool {
    params.twins && twin_cables(cable, lab, image, params).is_some()
}

/// The two cables `cable` lies over, the one nearer it first and with its ends; `None`
/// when its profiles do not read as twins.
fn twin_cables(
    cable: &Cable,
    lab: &LabImage,
    image: &RgbImage,
    params: &Params,
) -> Option<[Cable; 2]> {
    let line = &cable.polyline;
    let nominal = params.nominal_width_px;
    let normal = normals(line);
    let steps = (REACH * nominal / STEP).round() as i32;
    let mut profile = Vec::with_capacity(2 * steps as usize + 1);
    let (mut read, mut twins) = (0usize, Vec::new());
    let length = polyline_length(line);
    let mut along = 0.0;
    let mut next = END_SKIP_PX;
    for i in 0..line.len() {
        if i > 0 {
            along += dist(line[i - 1], line[i]);
        }
        if along < next || along > length - END_SKIP_PX {
            continue;
        }
        next = along + SPACING_PX;
        if !read_across(lab, line[i], normal[i], (steps, STEP), &mut profile) {
            continue;
        }
        if let Some(reading) = read_twins(&profile, nominal, params.twin_max_cost) {
            read += 1;
            twins.extend(reading.map(|t| (i, t)));
        }
    }
    if read < MIN_READINGS || (twins.len() as f32) < params.twin_min_share * read as f32 {
        return None;
    }
    let limit = REACH * nominal;
    let side = |k: usize| {
        let offsets: Vec<(usize, f32)> = twins.iter().map(|&(i, t)| (i, t.offsets[k])).collect();
        smooth_offsets(&offsets, line.len(), limit)
    };
    let mut widths: Vec<f32> = twins.iter().map(|t| t.1.width).collect();
    let width = median(&mut widths, f32::total_cmp)?;
    let mut sides = [side(0), side(1)];
    let mean_abs = |s: &[f32]| s.iter().map(|v| v.abs()).sum::<f32>() / s.len() as f32;
    if mean_abs(&sides[1]) < mean_abs(&sides[0]) {
        sides.swap(0, 1);
    }
    let [near, far] = sides.map(|offsets| {
        let points: Vec<[f32; 2]> = line
            .iter()
            .zip(&normal)
            .zip(&offsets)
            .map(|((p, n), &d)| [p[0] + d * n[0], p[1] + d * n[1]])
            .collect();
        beside(cable, &points, width, image, params)
    });
    let mut far = far?;
    far.twin_ends = far.end_indices;
    far.end_indices = [None, None];
    Some([near?, far])
}

/// A cable like `cable` along `points`, `width` wide, its colour read on `image`.
fn beside(
    cable: &Cable,
    points: &[[f32; 2]],
    width: f32,
    image: &RgbImage,
    params: &Params,
) -> Option<Cable> {
    let weights = vec![1.0; points.len()];
    let spline = BSpline::fit(points, &weights, params.knot_spacing_px, params.smoothing)?;
    let polyline = spline.sample(params.polyline_step_px);
    Some(Cable {
        ends: [polyline[0], polyline[polyline.len() - 1]],
        length_px: polyline_length(&polyline),
        width_px: width,
        color: median_rgb(image, &polyline),
        spline,
        polyline,
        ..cable.clone()
    })
}

/// Reads one profile (Lab samples [`STEP`] apart, centred on the cable found):
/// `None` when it shows nothing to read, `Some(None)` one cable, `Some(Some(_))` twins
/// (module docs).
fn read_twins(profile: &[[f32; 3]], nominal: f32, max_cost: f32) -> Option<Option<Twins>> {
    let n = profile.len();
    let centre = n / 2;
    let samples = |widths: f32| samples(widths, nominal);
    let end = ((END_PX / STEP) as usize).clamp(1, n / 4);
    let (left, right) = (mean(&profile[..end]), mean(&profile[n - end..]));
    let fg: Vec<f32> = profile
        .iter()
        .map(|&s| dist3(s, left).min(dist3(s, right)))
        .collect();
    let reach = samples(PEAK_REACH).min(centre);
    let peak = fg[centre - reach..=centre + reach]
        .iter()
        .copied()
        .fold(0.0f32, f32::max);
    if peak < MIN_PEAK_DE {
        return None;
    }
    let level = MIN_BAND_DE.max(BAND_SHARE * peak);
    let on = |i: usize| fg[i] > level;
    let start = (0..=samples(1.0).min(centre))
        .flat_map(|d| [centre - d, centre + d])
        .find(|&i| on(i))?;
    let grow = |hole: usize, indices: &mut dyn Iterator<Item = usize>| {
        let (mut last, mut gap) = (start, 0);
        for i in indices {
            if on(i) {
                (last, gap) = (i, 0);
            } else {
                gap += 1;
                if gap > hole {
                    break;
                }
            }
        }
        last
    };
    // The band with short holes closed; where it is one cable, with a gap as wide as
    // a cable closed (kept one cable when that band runs off the profile). Where the
    // wider hole closes nothing more, the band read already is judged again by the
    // wider gap alone.
    let mut reading = None;
    let mut last: Option<([usize; 2], Option<Candidate>)> = None;
    for (hole, max_gap) in [(HOLE, MAX_GAP), (WIDE_HOLE, WIDE_MAX_GAP)] {
        let band = [
            grow(samples(hole), &mut (0..start).rev()),
            grow(samples(hole), &mut (start + 1..n)),
        ];
        if band[0] < end || band[1] + end >= n {
            return reading;
        }
        let candidate = match last {
            Some((read, candidate)) if read == band => candidate,
            _ => twins_in(profile, &fg, band, nominal, max_cost),
        };
        last = Some((band, candidate));
        if let Some(c) = candidate.filter(|c| c.gap <= max_gap * c.width) {
            return Some(Some(c.twins));
        }
        reading = Some(None);
    }
    reading
}

/// Twins read in a band, before the gap between them is judged.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    twins: Twins,
    /// The gap between them and the width of each, as the band's span and the shift
    /// that matches it read them, pixels.
    gap: f32,
    width: f32,
}

/// Twins in the band `lo..=hi` of `profile` (`fg`: each sample's contrast to the
/// profile's ends), whatever the gap between them, or `None`: one cable
/// ([`read_twins`]).
fn twins_in(
    profile: &[[f32; 3]],
    fg: &[f32],
    [lo, hi]: [usize; 2],
    nominal: f32,
    max_cost: f32,
) -> Option<Candidate> {
    let centre = profile.len() / 2;
    let samples = |widths: f32| samples(widths, nominal);
    let band = &profile[lo..=hi];
    // Compared with itself between its outer edges: beyond them a twin's blurred edge
    // meets the table, where at the same place the other twin meets its sibling.
    let [from, to] = outer_edges(fg, lo, hi, samples(MIN_TWIN / 2.0));
    let inner = &profile[from..=to];
    let inner_mean = mean(inner);
    let variation = inner.iter().map(|&s| dist3(s, inner_mean)).sum::<f32>() / inner.len() as f32;
    if variation <= f32::EPSILON {
        return None;
    }
    let shifts = samples(MIN_SEPARATION).max(1)
        ..=((MAX_SEPARATION_SHARE * band.len() as f32) as usize).min(inner.len() - 1);
    let cost = |shift: usize| {
        let k = inner.len() - shift;
        (0..k)
            .map(|t| dist3(inner[t], inner[t + shift]))
            .sum::<f32>()
            / (k as f32 * variation)
    };
    let (cost, shift) = shifts
        .map(|s| (cost(s), s))
        .min_by(|a, b| a.0.total_cmp(&b.0))?;
    let separation = shift as f32 * STEP;
    let width = band.len() as f32 * STEP - separation;
    let gap = separation - width;
    if cost > max_cost || width < MIN_TWIN * nominal {
        return None;
    }
    let w = (width / STEP).round() as usize;
    let core = mean(&[band[w / 2], band[band.len() - 1 - w / 2]]);
    let (a, b) = (
        w.saturating_sub(2),
        (band.len() - 1).saturating_sub(w).saturating_add(2),
    );
    let (a, b) = (a.min(b).max(1), a.max(b).min(band.len() - 2));
    // What counts as valley: a sample darker than the cores (two shaded cables' rims
    // meeting), nearer the table's colour than theirs (a sliver of table between
    // them), or lighter but flanked on both sides, between the cores, by a rim darker
    // than them (a blurred sliver); not a glossy cable's highlight, which its body
    // flanks at the cores' lightness.
    let (first, last) = (w / 2, band.len() - 1 - w / 2);
    let dip = RIM_DIP * VALLEY * variation;
    let rim = |r: &[[f32; 3]]| r.iter().any(|s| s[0] < core[0] - dip);
    let counts = |i: usize| {
        band[i][0] < core[0]
            || fg[lo + i] < dist3(band[i], core)
            || (first < i && i < last && rim(&band[first..i]) && rim(&band[i + 1..=last]))
    };
    let valley = (a..=b)
        .filter(|&i| counts(i))
        .map(|i| dist3(band[i], core))
        .fold(0.0f32, f32::max);
    if valley < VALLEY * variation {
        return None;
    }
    let offset = |i: f32| (lo as f32 + i - centre as f32) * STEP;
    let twins = Twins {
        offsets: [
            offset(w as f32 / 2.0),
            offset((band.len() - 1) as f32 - w as f32 / 2.0),
        ],
        width: (outer_span(fg, lo, hi, w / 2) - separation).min(separation),
    };
    Some(Candidate { twins, gap, width })
}

/// Profile samples in `widths` nominal widths of `nominal` pixels.
fn samples(widths: f32, nominal: f32) -> usize {
    (widths * nominal / STEP).round() as usize
}

/// The mean colour of `samples`.
fn mean(samples: &[[f32; 3]]) -> [f32; 3] {
    let k = samples.len() as f32;
    [0, 1, 2].map(|c| samples.iter().map(|v| v[c]).sum::<f32>() / k)
}

/// The span, pixels, of the band `lo..=hi` of profile contrasts `fg` between its outer
/// edges, each where the contrast first reaches half the peak of its own cable (the
/// highest within `reach` samples inside the band), as the refinement reads one
/// cable's width at half its peak. The band's own ends, where the contrast passes a
/// share of the whole profile's peak, take in the blur of the photo and of the Lab
/// image: twins 9-11 px wide read 11.5-12, and a photo of such pairs was shrunk for
/// them until the pairs ran together (docs/ENGINE.md, "Two cables laid together"). The
/// whole profile's peak would not do either: between two pale cables their rims meet and
/// outdo the outer ones.
fn outer_span(fg: &[f32], lo: usize, hi: usize, reach: usize) -> f32 {
    let [first, last] = outer_edges(fg, lo, hi, reach);
    (last - first + 1) as f32 * STEP
}

/// The first and last samples of the band `lo..=hi` at its outer edges ([`outer_span`]).
fn outer_edges(fg: &[f32], lo: usize, hi: usize, reach: usize) -> [usize; 2] {
    let reach = reach.max(1);
    let peak = |s: &[f32]| s.iter().copied().fold(0.0f32, f32::max);
    let left = 0.5 * peak(&fg[lo..=(lo + reach).min(hi)]);
    let right = 0.5 * peak(&fg[hi.saturating_sub(reach).max(lo)..=hi]);
    let first = (lo..=hi).find(|&i| fg[i] >= left).unwrap_or(lo);
    let last = (first..=hi).rev().find(|&i| fg[i] >= right).unwrap_or(hi);
    [first, last]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A profile across `cables` (centre, width, Lab core, Lab rim) on a background,
    /// [`STEP`] apart, `reach` pixels either side of 0.
    fn profile(
        cables: &[(f32, f32, [f32; 3], [f32; 3])],
        background: [f32; 3],
        reach: f32,
    ) -> Vec<[f32; 3]> {
        let steps = (reach / STEP).round() as i32;
        (-steps..=steps)
            .map(|j| {
                let x = j as f32 * STEP;
                cables
                    .iter()
                    .find(|c| (x - c.0).abs() <= c.1 / 2.0)
                    .map_or(background, |c| {
                        if (x - c.0).abs() > c.1 / 2.0 - 1.5 {
                            c.3
                        } else {
                            c.2
                        }
                    })
            })
            .collect()
    }

    const RED: [f32; 3] = [45.0, 60.0, 40.0];
    const DARK_RED: [f32; 3] = [28.0, 45.0, 30.0];
    const TABLE: [f32; 3] = [88.0, 0.0, 2.0];
    const INK: [f32; 3] = [12.0, 0.0, -1.0];

    #[test]
    fn two_touching_cables_read_as_twins_and_one_cable_does_not() {
        let reach = REACH * 7.8;
        let pair = profile(
            &[(-4.0, 8.0, RED, DARK_RED), (4.0, 8.0, RED, DARK_RED)],
            TABLE,
            reach,
        );
        let t = read_twins(&pair, 7.8, 0.5).unwrap().expect("twins");
        assert!(
            (t.offsets[0] + 4.0).abs() <= 1.0 && (t.offsets[1] - 4.0).abs() <= 1.0,
            "{t:?}"
        );
        assert!((t.width - 8.0).abs() <= 1.5, "{t:?}");
        let one = profile(&[(0.0, 10.0, RED, DARK_RED)], TABLE, reach);
        assert_eq!(read_twins(&one, 7.8, 0.5), Some(None));
        let wide = profile(&[(0.0, 16.0, RED, DARK_RED)], TABLE, reach);
        assert_eq!(read_twins(&wide, 7.8, 0.5), Some(None));
        // A dark glossy cable 11 px wide, its highlight as light as the table. (Drawn,
        // blurred and noisy, the synthetic `DarkOnDark` case reads as twins 5.5 px
        // wide but for `MIN_TWIN`: `tests/e2e.rs` finds it as one cable.)
        let glossy = profile(
            &[(0.0, 3.0, TABLE, TABLE), (0.0, 11.0, INK, INK)],
            TABLE,
            reach,
        );
        assert_eq!(read_twins(&glossy, 7.8, 0.5), Some(None));
        let plain = profile(&[], TABLE, reach);
        assert_eq!(read_twins(&plain, 7.8, 0.5), None);
    }

    /// `profile` blurred by a Gaussian `sigma` pixels wide, as a photo and the Lab
    /// image blur the cables' edges.
    fn blurred(profile: &[[f32; 3]], sigma: f32) -> Vec<[f32; 3]> {
        let radius = (3.0 * sigma / STEP).ceil() as i32;
        let weights: Vec<f32> = (-radius..=radius)
            .map(|k| (-0.5 * (k as f32 * STEP / sigma).powi(2)).exp())
            .collect();
        let total: f32 = weights.iter().sum();
        let last = profile.len() as i32 - 1;
        (0..=last)
            .map(|i| {
                let mut sum = [0.0; 3];
                for (k, w) in (-radius..=radius).zip(&weights) {
                    let s = profile[(i + k).clamp(0, last) as usize];
                    for c in 0..3 {
                        sum[c] += w * s[c] / total;
                    }
                }
                sum
            })
            .collect()
    }

    #[test]
    fn blurred_twins_read_as_wide_as_they_are() {
        // Red pairs (a darker rim) and a white pair (grey rims, a core of the table's
        // colour), `width` px each, `gap` px apart, blurred by 1 px. The band's ends read
        // them 1.5 px wider than they are; the outer edges, 0.5 px (this profile's
        // sampling: it takes a sample on each cable's edge).
        const GREY_RIM: [f32; 3] = [60.0, 0.0, 2.0];
        let reach = REACH * 7.8;
        for (core, rim, width, gap) in [
            (RED, DARK_RED, 9.0, 1.0),
            (RED, DARK_RED, 10.0, 2.0),
            (RED, DARK_RED, 11.0, 1.0),
            (TABLE, GREY_RIM, 8.0, 0.0),
        ] {
            let c = (width + gap) / 2.0;
            let cables = [(-c, width, core, rim), (c, width, core, rim)];
            let pair = blurred(&profile(&cables, TABLE, reach), 1.0);
            let t = read_twins(&pair, 7.8, 0.8).unwrap().expect("twins");
            assert!((t.width - width).abs() <= 0.75, "{width} {gap} {t:?}");
        }
    }

    /// A profile of the Lab samples `band` centred on the cable, on a table of colour
    /// `table`, as long as `read_twins` reads at the nominal width 7.8 px.
    fn padded(band: &[[f32; 3]], table: [f32; 3]) -> Vec<[f32; 3]> {
        let n = 2 * (REACH * 7.8 / STEP).round() as usize + 1;
        let before = (n - band.len()) / 2;
        (0..n)
            .map(|i| {
                i.checked_sub(before)
                    .and_then(|j| band.get(j).copied())
                    .unwrap_or(table)
            })
            .collect()
    }

    /// [`padded`] grey: lightness `band` on a table of lightness `table`.
    fn grey(band: &[f32], table: f32) -> Vec<[f32; 3]> {
        let band: Vec<[f32; 3]> = band.iter().map(|&l| [l, 0.0, 0.0]).collect();
        padded(&band, [table, 0.0, 0.0])
    }

    #[test]
    fn a_gap_between_dark_twins_is_a_valley_and_a_glossy_cable_s_highlight_is_not() {
        // Read across two stress scenes (`scripts/stress.py --seed 18`): a glossy black
        // power cable about 20 px wide (mixed/00005), its highlight a soft band down
        // the middle, and two black cables side by side (pairs/00006), the 1 px gap
        // between them blurred to about half the table's lightness. Their middles are
        // alike; the rims that flank the gap, darker than the cables' cores, are not.
        let glossy = grey(
            &[
                66., 54., 42., 31., 23., 18., 15., 15., 14., 14., 14., 14., 15., 17., 19., 21.,
                24., 25., 26., 27., 25., 24., 22., 19., 17., 16., 15., 14., 14., 14., 14., 14.,
                17., 21., 28., 38., 50., 63.,
            ],
            95.0,
        );
        let pair = grey(
            &[
                60., 46., 34., 24., 18., 16., 15., 17., 19., 21., 24., 25., 26., 25., 23., 21.,
                20., 21., 24., 32., 40., 50., 59., 59., 58., 47., 36., 27., 19., 17., 15., 16.,
                18., 21., 23., 25., 26., 25., 24., 22., 20., 21., 22., 29., 38., 50., 63.,
            ],
            93.0,
        );
        for cost in [Params::default().twin_max_cost, 1.0] {
            assert_eq!(read_twins(&glossy, 7.8, cost), Some(None), "{cost}");
            let t = read_twins(&pair, 7.8, cost).unwrap().expect("twins");
            assert!((t.offsets[1] - t.offsets[0] - 11.0).abs() <= 1.5, "{t:?}");
        }
    }

    #[test]
    fn twins_a_sliver_of_table_apart_read_as_twins_and_cables_farther_apart_do_not() {
        // Read across a stress scene (`scripts/stress.py --seed 12`, pairs/00011): two
        // grey cables on black card, a sliver of card about 4 px wide between them, read
        // as one band by the walks and the network. Closing only short holes, the band
        // is one of them.
        let sliver = grey(
            &[
                13., 14., 16., 19., 22., 26., 29., 32., 35., 36., 36., 36., 33., 30., 27., 23.,
                19., 16., 14., 12., 11., 10., 10., 10., 10., 10., 11., 12., 14., 16., 18., 21.,
                25., 28., 32., 34., 36., 37., 36., 34., 31., 27., 23., 19., 16., 14., 12.,
            ],
            11.0,
        );
        let cost = Params::default().twin_max_cost;
        let t = read_twins(&sliver, 7.8, cost).unwrap().expect("twins");
        assert!((t.offsets[1] - t.offsets[0] - 13.0).abs() <= 1.5, "{t:?}");
        assert!(t.width >= 5.0 && t.width <= 9.0, "{t:?}");
        let apart = profile(
            &[(-9.0, 8.0, RED, DARK_RED), (9.0, 8.0, RED, DARK_RED)],
            TABLE,
            REACH * 7.8,
        );
        assert_eq!(read_twins(&apart, 7.8, cost), Some(None));
    }

    #[test]
    fn touching_twins_on_a_light_table_read_as_twins_despite_their_outer_edges() {
        // Read across a stress scene (`scripts/stress.py --seed 12`, pairs/00005): two
        // brown cables about 11 px wide touching on white card. Each twin's outer edge
        // is blurred into the table (lightness 93), where at the same place across the
        // other twin its sibling's rim is (30): compared over the whole band, the pair
        // matched itself shifted at 1.0-1.4 of its variation on two profiles in three,
        // this one among them (its lightness, a and b).
        let l = [
            90., 87., 82., 73., 62., 52., 42., 35., 33., 32., 34., 37., 41., 44., 47., 49., 50.,
            50., 48., 46., 43., 40., 36., 33., 30., 29., 28., 28., 28., 28., 29., 30., 32., 35.,
            39., 42., 46., 48., 49., 50., 48., 46., 43., 40., 37., 36., 35., 37., 43., 50., 59.,
            69., 78., 85., 89., 91.,
        ];
        let a = [
            0., 1., 2., 3., 5., 7., 9., 11., 13., 14., 16., 17., 18., 19., 19., 19., 20., 20., 20.,
            19., 19., 18., 18., 17., 16., 15., 14., 13., 13., 13., 13., 14., 15., 17., 18., 19.,
            19., 20., 20., 20., 20., 19., 19., 18., 17., 15., 13., 11., 9., 7., 5., 3., 2., 1., 0.,
            -1.,
        ];
        let b = [
            3., 4., 5., 7., 9., 12., 14., 17., 19., 22., 23., 25., 27., 27., 28., 29., 29., 29.,
            29., 28., 28., 27., 25., 24., 22., 20., 19., 18., 18., 18., 19., 20., 22., 24., 25.,
            27., 28., 28., 28., 29., 28., 28., 27., 26., 25., 23., 21., 19., 16., 14., 11., 9., 7.,
            5., 4., 3.,
        ];
        let band: Vec<[f32; 3]> = (0..l.len()).map(|i| [l[i], a[i], b[i]]).collect();
        let pair = padded(&band, [93.0, -1.0, 3.0]);
        let t = read_twins(&pair, 7.8, Params::default().twin_max_cost)
            .unwrap()
            .expect("twins");
        assert!((t.offsets[1] - t.offsets[0] - 11.0).abs() <= 1.5, "{t:?}");
    }

    #[test]
    fn twins_a_shade_apart_read_at_the_default_cost_and_one_cable_does_not() {
        // Two cables of one colour 2 px apart, one a shade darker (uneven light, or
        // wear): their band matches itself shifted less well than identical twins' does,
        // above the former default cost of 0.5.
        let cost = Params::default().twin_max_cost;
        let reach = REACH * 7.8;
        const SHADE: [f32; 3] = [40.0, 52.0, 34.0];
        const DARK_SHADE: [f32; 3] = [25.0, 40.0, 27.0];
        let pair = profile(
            &[(-5.0, 8.0, RED, DARK_RED), (5.0, 8.0, SHADE, DARK_SHADE)],
            TABLE,
            reach,
        );
        let t = read_twins(&pair, 7.8, cost).unwrap().expect("twins");
        assert!(
            (t.offsets[0] + 5.0).abs() <= 1.0 && (t.offsets[1] - 5.0).abs() <= 1.0,
            "{t:?}"
        );
        assert_eq!(read_twins(&pair, 7.8, 0.5), Some(None));
        for one in [
            profile(&[(0.0, 10.0, RED, DARK_RED)], TABLE, reach),
            profile(&[(0.0, 16.0, RED, DARK_RED)], TABLE, reach),
            profile(
                &[(0.0, 3.0, TABLE, TABLE), (0.0, 11.0, INK, INK)],
                TABLE,
                reach,
            ),
        ] {
            assert_eq!(read_twins(&one, 7.8, cost), Some(None));
        }
    }
}
