//! Sub-pixel refinement of a centreline on the image, and the cable's measured width
//! and colour.
//!
//! Across the curve, every few pixels, a colour profile is sampled (bilinear, half-pixel
//! steps). Each sample's contrast is its Lab distance to the nearer end of the profile
//! (the background on either side); the cable is the run nearest the curve where the
//! contrast exceeds half its peak, and its two edges, interpolated to sub-pixel, give
//! the centre (their midpoint) and the width (their distance). Cast shadows (darker
//! than the background by lightness alone) are told from the cable: a pale cable's
//! shadow on a pale table has more contrast than the cable and would otherwise pull the
//! centreline onto itself. The run's shadowed flanks, nearer the background's colour
//! than the cable's, are cut off; a run that is all shadow gives way to the lighter run
//! beside it, when the shadows read along the cable fall one way in the image, as one
//! light casts them; where most profiles find such a lighter run, a darker run with
//! none beside it is a stretch of the same shadow too coloured to read as one, and is
//! left out.
//! Profiles that cannot be read (a crossing, the frame, a cable of the background's
//! colour) are skipped; offsets are median- then mean-filtered along the curve so one
//! bad profile cannot bend it.

use super::Params;
use super::color::LabImage;
use super::geometry::{dist3, median, median_colour_of, unit_or};

/// Result of refining one centreline.
#[derive(Debug, Clone, PartialEq)]
pub struct Refined {
    /// The moved points, same count and order as the input.
    pub points: Vec<[f32; 2]>,
    /// Median measured width, pixels, when enough profiles could be read.
    pub width_px: Option<f32>,
    /// Share of the profiles showing anything that show a ridge (a cable: the two sides
    /// alike, the middle unlike them) rather than a step between two backgrounds (the
    /// edge of a board or a tray: the two sides differ more than anything between them
    /// differs from both; [`step_not_ridge`]); `None` when fewer than three show
    /// anything.
    pub ridge_share: Option<f32>,
    /// The cable was read as the lighter runs beside its shadows (a pale cable whose
    /// shadow shows more contrast than it does; `lit_beside_shadow`).
    pub lit_side: bool,
    /// How many profiles were read (gave a centre and a width).
    pub read: usize,
}

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
    median_colour_of(&samples)
}

/// Reads into `profile` the Lab samples across a curve at `p` along its unit normal
/// `n`: `steps` samples `step` pixels apart on either side of `p`, and `p`'s own; false
/// when the profile leaves the image (it is then cut short).
pub(super) fn read_across(
    lab: &LabImage,
    p: [f32; 2],
    n: [f32; 2],
    (steps, step): (i32, f32),
    profile: &mut Vec<[f32; 3]>,
) -> bool {
    profile.clear();
    profile.extend((-steps..=steps).map_while(|j| {
        let o = j as f32 * step;
        sample_lab(lab, p[0] + o * n[0], p[1] + o * n[1])
    }));
    profile.len() == 2 * steps as usize + 1
}

/// Unit normals of a polyline (central differences).
pub fn normals(line: &[[f32; 2]]) -> Vec<[f32; 2]> {
    let n = line.len();
    (0..n)
        .map(|i| {
            let a = line[i.saturating_sub(1)];
            let b = line[(i + 1).min(n - 1)];
            let t = unit_or([b[0] - a[0], b[1] - a[1]], [0.0, 0.0]);
            [-t[1], t[0]]
        })
        .collect()
}

/// What reading profiles needs from [`Params`].
#[derive(Debug, Clone, Copy)]
struct Profiles {
    step: f32,
    min_background_de: f32,
    min_width: f32,
    /// Widest core between the two halves of an outline ([`across_outline`]), pixels.
    max_core: f32,
}

/// Moves each point of `line` onto the cable centre found across it (see module docs),
/// reading profiles of half-length `refine_radius_px` every `refine_profile_stride`
/// points; the moves are clamped to half that radius.
pub fn refine(line: &[[f32; 2]], lab: &LabImage, params: &Params) -> Refined {
    let Some(cable) = median_colour(lab, line) else {
        return Refined {
            points: line.to_vec(),
            width_px: None,
            ridge_share: None,
            lit_side: false,
            read: 0,
        };
    };
    let radius = params.refine_radius_px;
    let settings = Profiles {
        step: params.refine_profile_step_px,
        min_background_de: params.refine_min_background_de,
        min_width: params.refine_min_width_px,
        max_core: OUTLINE_MAX_CORE * params.nominal_width_px,
    };
    let normal = normals(line);
    let steps = (radius / settings.step).round() as i32;
    let mut profile = Vec::with_capacity(2 * steps as usize + 1);
    let mut readings: Vec<(usize, Reading)> = Vec::new();
    let (mut shown, mut steps_seen) = (0usize, 0usize);
    for i in (0..line.len()).step_by(params.refine_profile_stride.max(1) as usize) {
        if !read_across(
            lab,
            line[i],
            normal[i],
            (steps, settings.step),
            &mut profile,
        ) {
            continue;
        }
        let contrast = Contrast::of(&profile, steps as usize);
        if let Some(step) = step_not_ridge(&profile, &contrast, settings.min_background_de) {
            shown += 1;
            steps_seen += usize::from(step);
        }
        if let Some(reading) = read_profile(&profile, contrast, cable, steps as usize, settings) {
            readings.push((i, reading));
        }
    }
    let trust_lit = shadows_agree(&readings, &normal);
    let lit_count = readings.iter().filter(|(_, r)| r.lit.is_some()).count();
    let mostly_lit = trust_lit && 2 * lit_count >= readings.len();
    let mut offsets: Vec<(usize, f32)> = Vec::with_capacity(readings.len());
    let mut widths = Vec::with_capacity(readings.len());
    for (i, reading) in readings {
        // Where the cable's shadows agree and most of its profiles found a lit run, a
        // darker run with none beside it is its shadow too (its colour, blended with
        // the cable's, too far from grey to read as one), not the cable: left out.
        let (centre, width) = match (trust_lit, reading.lit) {
            (true, Some(lit)) => lit,
            (true, None) if reading.darker && mostly_lit => continue,
            _ => reading.plain,
        };
        offsets.push((i, centre));
        widths.push(width);
    }
    let width_px = if widths.len() >= 3 {
        median(&mut widths, f32::total_cmp)
    } else {
        None
    };
    let ridge_share = (shown >= 3).then(|| 1.0 - steps_seen as f32 / shown as f32);
    let read = offsets.len();
    if read < 3 {
        return Refined {
            points: line.to_vec(),
            width_px,
            ridge_share,
            lit_side: false,
            read,
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
        ridge_share,
        lit_side: mostly_lit,
        read,
    }
}

/// What one profile shows against its ends (the local background on either side).
struct Contrast {
    /// Each sample's Lab distance to the nearer end of the profile.
    fg: Vec<f32>,
    /// The highest of them within half the reach of the profile's centre.
    peak: f32,
}

impl Contrast {
    /// The contrasts of `profile`, centred on sample `centre`.
    fn of(profile: &[[f32; 3]], centre: usize) -> Self {
        let (left, right) = (profile[0], profile[profile.len() - 1]);
        let fg: Vec<f32> = profile
            .iter()
            .map(|&s| dist3(s, left).min(dist3(s, right)))
            .collect();
        let search = centre / 2;
        let peak = fg[centre - search..=centre + search]
            .iter()
            .copied()
            .fold(0.0f32, f32::max);
        Self { fg, peak }
    }
}

/// Whether a profile crosses a step between two backgrounds rather than a ridge: its
/// two ends differ more than any sample of its middle half differs from the nearer end
/// (`contrast.peak`). Between two flat regions nothing can: every blend of them lies
/// nearer one of them than they lie to each other. `None` when the profile shows
/// nothing (ends and middle within `min_de` of each other).
fn step_not_ridge(profile: &[[f32; 3]], contrast: &Contrast, min_de: f32) -> Option<bool> {
    let across = dist3(profile[0], profile[profile.len() - 1]);
    let peak = contrast.peak;
    (across.max(peak) >= min_de).then_some(across >= peak)
}

/// One profile read: the cable's centre offset and width, pixels.
type Across = (f32, f32);

/// What one profile shows.
#[derive(Debug, Clone, Copy)]
struct Reading {
    /// The run of most contrast around the centre.
    plain: Across,
    /// When that run is a cast shadow, the lighter run beside it ([`lit_beside_shadow`]).
    lit: Option<Across>,
    /// That run is darker than the background by more lightness than colour (its
    /// mean a*b* difference within its mean lightness drop): a shadow, tinted or not,
    /// or a grey or black cable; not a coloured cable's own shade.
    darker: bool,
}

/// Finds the cable across one profile (its [`Contrast`]), or `None` when the profile
/// cannot be read.
///
/// Each sample's "foreground" is its Lab distance to the nearer of the two profile ends
/// (the local background on either side). The cable is the run around the centre where
/// foreground exceeds half its peak (a full-width-at-half-maximum reading, so shading and
/// highlights on the insulation do not bias the edges); the edges are interpolated to
/// sub-pixel precision.
fn read_profile(
    profile: &[[f32; 3]],
    Contrast { fg, peak }: Contrast,
    cable: [f32; 3],
    centre: usize,
    settings: Profiles,
) -> Option<Reading> {
    let (left_bg, right_bg) = (profile[0], profile[profile.len() - 1]);
    let min_de = settings.min_background_de;
    if dist3(left_bg, cable) < min_de || dist3(right_bg, cable) < min_de {
        return None;
    }
    let search = centre / 2;
    if peak < min_de {
        return None;
    }
    let half = 0.5 * peak;
    let m: Vec<f32> = fg.iter().map(|f| f - half).collect();
    let start = (0..=search)
        .flat_map(|d| [centre - d, centre + d])
        .find(|&j| m[j] > 0.0)?;
    let (lo, hi) = across_highlights(profile, &m, &fg, run_around(&m, start)?, min_de);
    let (lo, hi) = across_outline(profile, &m, (lo, hi), centre, settings);
    let across = |(m, lo, hi): (Vec<f32>, usize, usize)| edges(&m, lo, hi, centre, settings);
    let (dl, dab) = run_against_background(profile, [left_bg, right_bg], [lo, hi]);
    let darker = dl < 0.0 && dab <= -dl;
    Some(Reading {
        plain: across(with_bordering_highlights(
            profile,
            [left_bg, right_bg],
            &fg,
            without_shadowed_flanks(profile, [left_bg, right_bg], cable, (m, lo, hi)),
            min_de,
        ))?,
        lit: lit_beside_shadow(
            profile,
            [left_bg, right_bg],
            &fg,
            ([lo, hi], (dl, dab)),
            min_de,
        )
        .and_then(across),
        darker,
    })
}

/// The centre offset and width of the run `lo..=hi` of positive margins `m`, from the
/// zero crossings between its last samples and the first background ones; `None` when
/// narrower than the least width.
fn edges(m: &[f32], lo: usize, hi: usize, centre: usize, settings: Profiles) -> Option<Across> {
    let left = lo as f32 - m[lo] / (m[lo] - m[lo - 1]);
    let right = hi as f32 + m[hi] / (m[hi] - m[hi + 1]);
    let width = (right - left) * settings.step;
    (width >= settings.min_width).then_some((
        ((left + right) * 0.5 - centre as f32) * settings.step,
        width,
    ))
}

/// A profile sample against the nearer of the two backgrounds: its lightness and its
/// a*b* differences.
fn against_background(s: [f32; 3], bg: [[f32; 3]; 2]) -> (f32, f32) {
    let b = if dist3(s, bg[0]) <= dist3(s, bg[1]) {
        bg[0]
    } else {
        bg[1]
    };
    (s[0] - b[0], (s[1] - b[1]).hypot(s[2] - b[2]))
}

/// The mean of [`against_background`] over the run `lo..=hi` of `profile`.
fn run_against_background(
    profile: &[[f32; 3]],
    bg: [[f32; 3]; 2],
    [lo, hi]: [usize; 2],
) -> (f32, f32) {
    let n = (hi - lo + 1) as f32;
    profile[lo..=hi]
        .iter()
        .map(|&s| against_background(s, bg))
        .fold((0.0, 0.0), |(l, c), (dl, dc)| (l + dl / n, c + dc / n))
}

/// Whether a sample looks like a cast shadow: darker than the background by lightness
/// far more than by colour ([`SHADOW_CHROMA`]).
fn shadow_like(s: [f32; 3], bg: [[f32; 3]; 2]) -> bool {
    let (dl, dab) = against_background(s, bg);
    dl < 0.0 && dab <= SHADOW_CHROMA * -dl
}

/// The run `lo..=hi` (margins `m`) without the shadowed flanks it took in: samples at
/// its ends that are darker than the background by lightness alone and nearer the
/// background's colour than the cable's. A pale cable's shadow on either side has enough
/// contrast to join the run; the darker, self-shaded side of a coloured cable keeps the
/// cable's colour and stays. The cut samples' margins are made negative.
fn without_shadowed_flanks(
    profile: &[[f32; 3]],
    bg: [[f32; 3]; 2],
    cable: [f32; 3],
    (mut m, lo, hi): (Vec<f32>, usize, usize),
) -> (Vec<f32>, usize, usize) {
    let flank = |j: usize| {
        let s = profile[j];
        shadow_like(s, bg) && dist3(s, bg[0]).min(dist3(s, bg[1])) < dist3(s, cable)
    };
    let (mut a, mut b) = (lo, hi);
    while a < b && flank(a) {
        a += 1;
    }
    while b > a && flank(b) {
        b -= 1;
    }
    if a == b && flank(a) {
        return (m, lo, hi);
    }
    for j in (lo..a).chain(b + 1..=hi) {
        m[j] = -m[j];
    }
    (m, a, b)
}

/// The run `lo..=hi` (margins `m`) widened over a highlight beside it: samples lighter
/// than the background by more than half `min_de` and lighter than the run, the
/// cable's lit flank. A pale cable lit from one side shows less contrast there than on
/// its shaded flank, so half the profile's peak cuts its lit edge off and pulls the
/// centre toward the shade (a cream cable on pale blue card read its centre 1.7 px
/// into its shadow). A cast shadow is never lighter than what it falls on, and the
/// blurred edge of a light cable on a dark table is darker than the cable, so neither
/// is taken in. The highlight ends at half its own highest contrast (`fg`), and reaches
/// at most half the run's width beyond it.
fn with_bordering_highlights(
    profile: &[[f32; 3]],
    bg: [[f32; 3]; 2],
    fg: &[f32],
    (mut m, lo, hi): (Vec<f32>, usize, usize),
    min_de: f32,
) -> (Vec<f32>, usize, usize) {
    let run_light = mean_lab(&profile[lo..=hi])[0];
    let lit =
        |j: usize| against_background(profile[j], bg).0 > 0.5 * min_de && profile[j][0] > run_light;
    // Half the run's width of hi - lo + 1 samples, rounded down.
    let reach = (hi - lo).div_ceil(2);
    // The highlight's samples from `first` outward (`step` ±1), within the reach and
    // the profile (one sample kept beyond for the edge).
    let highlight = |first: usize, step: isize| -> Vec<usize> {
        (0..reach as isize)
            .map(|d| first as isize + step * d)
            .take_while(|&j| j >= 1 && (j as usize) + 1 < profile.len() && lit(j as usize))
            .map(|j| j as usize)
            .collect()
    };
    let mut widen = |run: Vec<usize>, end: usize| -> usize {
        let Some(peak) = run.iter().map(|&j| fg[j]).reduce(f32::max) else {
            return end;
        };
        let half = 0.5 * peak;
        let kept: Vec<usize> = run.into_iter().take_while(|&j| fg[j] > half).collect();
        let Some(&last) = kept.last() else {
            return end;
        };
        // Margins against the highlight's half maximum across its outer edge.
        let beyond = if last > end { last + 1 } else { last - 1 };
        for j in kept.iter().copied().chain([beyond]) {
            m[j] = fg[j] - half;
        }
        if m[beyond] > 0.0 {
            m[beyond] = -f32::EPSILON;
        }
        last
    };
    let new_lo = if lo >= 2 {
        widen(highlight(lo - 1, -1), lo)
    } else {
        lo
    };
    let new_hi = widen(highlight(hi + 1, 1), hi);
    (m, new_lo, new_hi)
}

/// The run of positive `m` around `start`; `None` when it reaches an end of the profile
/// (the cable is not crossed whole).
fn run_around(m: &[f32], start: usize) -> Option<(usize, usize)> {
    let mut lo = start;
    while lo > 0 && m[lo - 1] > 0.0 {
        lo -= 1;
    }
    let mut hi = start;
    while hi + 1 < m.len() && m[hi + 1] > 0.0 {
        hi += 1;
    }
    (lo > 0 && hi < m.len() - 1).then_some((lo, hi))
}

/// The run `lo..=hi` of positive margins `m` joined with a run beside it across a gap
/// no wider than the run that is a highlight: lighter than the run (mean lightness) but
/// not background (every sample at least `min_de` from it by `fg`), when the run beyond
/// has the run's colour (mean Lab within `2 min_de`). A glossy cable's
/// highlight, or a dark cable's lighter core, can fall below the half maximum and split
/// the cable in two halves, either of which alone would put the centre on one side.
/// The gap between two cables, or between a cable and its shadow, is background, a
/// darker cable crossing is no highlight, and a cable of another colour beside it is
/// not its other half: they stay apart.
fn across_highlights(
    profile: &[[f32; 3]],
    m: &[f32],
    fg: &[f32],
    (mut lo, mut hi): (usize, usize),
    min_de: f32,
) -> (usize, usize) {
    let mean = |a: usize, b: usize| mean_lab(&profile[a..=b]);
    loop {
        let colour = mean(lo, hi);
        let highlight = |j: usize| m[j] <= 0.0 && fg[j] >= min_de && profile[j][0] > colour[0];
        // The run past the gap on either side, when the gap is a highlight no wider than
        // the run and the run beyond has the run's colour (the cable's other half).
        let width = hi - lo + 1;
        let same_cable = |(a, b): (usize, usize)| dist3(mean(a, b), colour) < 2.0 * min_de;
        let left = (lo.saturating_sub(width + 1)..lo)
            .rev()
            .find(|&j| !highlight(j))
            .filter(|&j| j + 1 < lo && m[j] > 0.0)
            .and_then(|j| run_around(m, j))
            .filter(|&run| same_cable(run));
        let right = (hi + 1..(hi + width + 2).min(m.len()))
            .find(|&j| !highlight(j))
            .filter(|&j| j > hi + 1 && m[j] > 0.0)
            .and_then(|j| run_around(m, j))
            .filter(|&run| same_cable(run));
        if left.is_none() && right.is_none() {
            return (lo, hi);
        }
        lo = left.map_or(lo, |run| run.0);
        hi = right.map_or(hi, |run| run.1);
    }
}

/// The mean of Lab `samples` (at least one).
fn mean_lab(samples: &[[f32; 3]]) -> [f32; 3] {
    let n = samples.len() as f32;
    samples.iter().fold([0.0f32; 3], |acc, s| {
        [acc[0] + s[0] / n, acc[1] + s[1] / n, acc[2] + s[2] / n]
    })
}

/// Widest core of an outlined cable, nominal widths ([`across_outline`]).
const OUTLINE_MAX_CORE: f32 = 1.5;

/// The run `lo..=hi` of positive margins `m` joined with a run beside it when the two
/// are the outline of one cable: a cable of the background's own colour shows only its
/// darker rims (a white cable on a white table), each a thin run with the cable's light
/// core between them, which by contrast alone reads as a cable a third as wide, its
/// centre on one rim. Joined when the run beyond has the run's colour (mean Lab within
/// `2 min_de`), the core between them is wider than either run, no wider than
/// `max_core`, and lighter than both runs. Two cables side by side are wider than the
/// gap between them; of two such runs, the one whose join centres nearer the profile's
/// centre is taken.
fn across_outline(
    profile: &[[f32; 3]],
    m: &[f32],
    (lo, hi): (usize, usize),
    centre: usize,
    settings: Profiles,
) -> (usize, usize) {
    let mean = |a: usize, b: usize| mean_lab(&profile[a..=b]);
    let max_core = (settings.max_core / settings.step).round() as usize;
    let colour = mean(lo, hi);
    let width = hi - lo + 1;
    // The outline's other half across `core` (its first and last sample), given the
    // run `other` beyond it.
    let outline = |core: (usize, usize), other: (usize, usize)| {
        let core_width = core.1 + 1 - core.0;
        let lighter = mean(core.0, core.1)[0] > colour[0].max(mean(other.0, other.1)[0]);
        (core_width > width.max(other.1 + 1 - other.0)
            && core_width <= max_core
            && lighter
            && dist3(mean(other.0, other.1), colour) < 2.0 * settings.min_background_de)
            .then_some(other)
    };
    let left = (lo.saturating_sub(max_core + 1)..lo)
        .rev()
        .find(|&j| m[j] > 0.0)
        .and_then(|j| Some((j, run_around(m, j)?)))
        .and_then(|(j, run)| outline((j + 1, lo - 1), run))
        .map(|run| (run.0, hi));
    let right = (hi + 1..(hi + max_core + 2).min(m.len()))
        .find(|&j| m[j] > 0.0)
        .and_then(|j| Some((j, run_around(m, j)?)))
        .and_then(|(j, run)| outline((hi + 1, j - 1), run))
        .map(|run| (lo, run.1));
    let off = |(a, b): (usize, usize)| (a + b).abs_diff(2 * centre);
    match (left, right) {
        (Some(l), Some(r)) => {
            if off(l) <= off(r) {
                l
            } else {
                r
            }
        }
        (l, r) => l.or(r).unwrap_or((lo, hi)),
    }
}

/// A cast shadow differs from the background it falls on by lightness far more than by
/// colour: its a*b* difference (a sample's, or a run's mean) is at most this share of
/// its lightness drop.
const SHADOW_CHROMA: f32 = 0.5;

/// The least contrast of a lit run, as a share of `refine_min_background_de`: a pale
/// cable is barely lighter than a pale table, and the image's blur mixes a thin one
/// with its shadow (0.5, 0.75 and 1 tried on the development split: 0.75 kept the
/// pale cables' gain and cost wood grain least).
const LIT_SHARE: f32 = 0.75;

/// When the run `lo..=hi` of the profile is a cast shadow (darker than the background,
/// hardly another colour) and a run lighter than the background lies beside it, that
/// lighter run: a pale cable on a pale table casts a shadow of more contrast than its
/// own, which a reading by contrast alone takes for the cable. `(dl, dab)` is the run
/// against the background ([`run_against_background`]). Returns the lighter run's
/// half-maximum margins (as `m` in [`read_profile`]) and its bounds.
fn lit_beside_shadow(
    profile: &[[f32; 3]],
    bg: [[f32; 3]; 2],
    fg: &[f32],
    ([lo, hi], (dl, dab)): ([usize; 2], (f32, f32)),
    min_de: f32,
) -> Option<(Vec<f32>, usize, usize)> {
    let delta = |s: [f32; 3]| against_background(s, bg);
    if dl >= 0.0 || dab > SHADOW_CHROMA * -dl {
        return None;
    }
    // Contrast of the samples lighter than the background, sought within the shadow's
    // width on either side of it.
    let lit: Vec<f32> = profile
        .iter()
        .zip(fg)
        .map(|(&s, &f)| if delta(s).0 > 0.0 { f } else { 0.0 })
        .collect();
    let reach = hi - lo + 1;
    let top = (lo.saturating_sub(reach)..lo)
        .chain(hi + 1..(hi + 1 + reach).min(lit.len()))
        .max_by(|&a, &b| lit[a].total_cmp(&lit[b]))?;
    if lit[top] < LIT_SHARE * min_de {
        return None;
    }
    let half = 0.5 * lit[top];
    let m: Vec<f32> = lit.iter().map(|f| f - half).collect();
    let (lo, hi) = run_around(&m, top)?;
    Some((m, lo, hi))
}

/// How well the shadows read along one cable must agree in direction (the length of
/// their mean unit direction in the image) for the lit runs beside them to be trusted:
/// one light casts every shadow of a cable to the same side, wood grain or a cable
/// alongside falls to either side.
const SHADOW_AGREEMENT: f32 = 0.8;

/// Whether the shadows found across `line` (the profiles with a lit run) fall the same
/// way in the image (see [`SHADOW_AGREEMENT`]).
fn shadows_agree(readings: &[(usize, Reading)], normal: &[[f32; 2]]) -> bool {
    let (mut sum, mut n) = ([0.0f32; 2], 0.0f32);
    for (i, r) in readings {
        if let Some(lit) = r.lit {
            // From the cable (the lit run) to its shadow (the plain run).
            let side = (r.plain.0 - lit.0).signum();
            sum = [sum[0] + side * normal[*i][0], sum[1] + side * normal[*i][1]];
            n += 1.0;
        }
    }
    n > 0.0 && sum[0].hypot(sum[1]) >= SHADOW_AGREEMENT * n
}

/// Offsets at every point: read ones median-filtered (5) and mean-filtered (5), the
/// gaps filled by linear interpolation, all clamped to ±`limit`.
pub(super) fn smooth_offsets(read: &[(usize, f32)], n: usize, limit: f32) -> Vec<f32> {
    let vals: Vec<f32> = read.iter().map(|r| r.1).collect();
    let med: Vec<f32> = (0..vals.len())
        .map(|i| {
            let mut w: Vec<f32> = vals[i.saturating_sub(2)..(i + 3).min(vals.len())].to_vec();
            median(&mut w, f32::total_cmp).unwrap_or(0.0)
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
        let params = Params {
            refine_radius_px: 10.0,
            ..Params::default()
        };
        let r = refine(&line, &lab, &params);
        for p in &r.points {
            assert!((p[1] - 20.5).abs() < 0.3, "{p:?}");
        }
        let w = r.width_px.unwrap();
        assert!((w - 8.0).abs() < 1.0, "width {w}");
    }

    #[test]
    fn a_cable_reads_as_a_ridge_and_the_edge_of_a_board_as_a_step() {
        let params = Params {
            refine_radius_px: 10.0,
            ..Params::default()
        };
        let along = |y: f32| (10..50).map(|x| [x as f32, y]).collect::<Vec<_>>();
        let cable = refine(&along(20.5), &band(), &params);
        assert_eq!(cable.ridge_share, Some(1.0));
        // The table's lower half is a dark floor: the line runs along the step.
        let board = table_with(|_, y| (y >= 20).then_some([70, 62, 55]));
        let edge = refine(&along(19.5), &board, &params);
        assert_eq!(edge.ridge_share, Some(0.0));
        // A plain table shows nothing to read.
        assert_eq!(refine(&along(19.5), &table(&[]), &params).ridge_share, None);
    }

    /// A pale table (rows 0..40) with horizontal bands: `(first row, last row, colour)`.
    fn table(bands: &[(usize, usize, [u8; 3])]) -> LabImage {
        table_with(|_, y| bands.iter().find(|b| (b.0..=b.1).contains(&y)).map(|b| b.2))
    }

    /// A 60x40 pale table with `paint(x, y)`'s colour where it gives one.
    fn table_with(paint: impl Fn(usize, usize) -> Option<[u8; 3]>) -> LabImage {
        let (w, h) = (60, 40);
        let rgb: Vec<u8> = (0..w * h)
            .flat_map(|i| paint(i % w, i / w).unwrap_or([190, 214, 208]))
            .collect();
        LabImage::from_rgb(&rgb, w, h)
    }

    /// Asserts that `refine` moves a line started at row `y` wholly into the rows
    /// strictly between `above` and `below`.
    #[track_caller]
    fn assert_refined_between(lab: &LabImage, y: f32, above: f32, below: f32) {
        let line: Vec<[f32; 2]> = (10..50).map(|x| [x as f32, y]).collect();
        let params = Params {
            refine_radius_px: 10.0,
            ..Params::default()
        };
        let r = refine(&line, lab, &params);
        let (lo, hi) = r.points.iter().fold((f32::MAX, f32::MIN), |(lo, hi), p| {
            (lo.min(p[1]), hi.max(p[1]))
        });
        assert!(lo > above && hi < below, "rows {lo}..{hi}");
    }

    #[test]
    fn a_dark_glossy_cable_is_not_split_by_its_highlight() {
        // A dark cable (rows 16-26, centre 21) with a dark rim and a lighter highlight
        // along its middle (rows 20-22), still darker than the table: the highlight
        // falls below the half maximum, and a line started on the upper half moves to
        // the middle of the whole cable, which is read whole.
        let lab = table(&[
            (16, 16, [10, 10, 12]),
            (17, 19, [40, 40, 45]),
            (20, 22, [150, 150, 155]),
            (23, 25, [40, 40, 45]),
            (26, 26, [10, 10, 12]),
        ]);
        assert_refined_between(&lab, 18.0, 20.5, 21.5);
        let line: Vec<[f32; 2]> = (10..50).map(|x| [x as f32, 18.0]).collect();
        let width = refine(&line, &lab, &Params::default()).width_px.unwrap();
        assert!((10.0..12.0).contains(&width), "{width}");
    }

    #[test]
    fn a_pale_cable_is_told_from_its_darker_shadow() {
        // A white cable (rows 17-20, centre 18.5) and its grey shadow below it (rows
        // 22-28), wider and of more contrast than the cable: a line started on the
        // shadow moves onto the cable.
        let lab = table(&[(17, 20, [240, 248, 240]), (22, 28, [120, 130, 122])]);
        assert_refined_between(&lab, 23.0, 18.0, 19.0);
        // A grey cable alone stays a grey cable, and a blue one stays itself beside a
        // white one: a shadow has the table's colour, and the blue one does not.
        assert_refined_between(&table(&[(22, 28, [120, 130, 122])]), 24.0, 24.5, 25.5);
        let lab = table(&[(17, 20, [240, 248, 240]), (22, 28, [40, 60, 160])]);
        assert_refined_between(&lab, 24.0, 24.5, 25.5);
    }

    #[test]
    fn a_pale_cable_whose_shadow_is_tinted_in_places_is_read_off_it_throughout() {
        // The cable and shadow of the test above, but along half the cable the shadow
        // takes a brown tint (a blend with the cable, reflected light): too coloured
        // to read as a cast shadow there, it has no lit run beside it. The lit runs
        // elsewhere say the cable is the pale one: the tinted stretches are its shadow
        // too, and the whole line moves off it.
        let lab = table_with(|x, y| match y {
            17..=20 => Some([240, 248, 240]),
            22..=28 if x % 8 >= 4 => Some([150, 130, 100]),
            22..=28 => Some([120, 130, 122]),
            _ => None,
        });
        assert_refined_between(&lab, 23.0, 17.5, 19.5);
    }

    #[test]
    fn a_shadow_read_with_a_pale_cable_is_cut_off_and_a_cables_own_shade_is_not() {
        // A pale yellow cable (rows 18-23, centre 20.5) and its grey shadow below it
        // (rows 24-29), read as one run: the shadow is cut off.
        let lab = table(&[(18, 23, [245, 225, 150]), (24, 29, [125, 136, 130])]);
        assert_refined_between(&lab, 22.0, 20.0, 21.0);
        // A red cable (rows 16-25, centre 20.5) whose lower half is in its own shade.
        let lab = table(&[(16, 20, [200, 40, 40]), (21, 25, [110, 20, 20])]);
        assert_refined_between(&lab, 21.0, 20.0, 21.0);
    }

    #[test]
    fn a_pale_cable_s_highlight_is_read_as_part_of_it() {
        // A dark yellow cable body (rows 20-23) lit from above: a highlight lighter than
        // the table along its upper flank (rows 17-19), of less than half the body's
        // contrast. The cable is rows 17-23 (centre 20), not the body alone (21.5).
        let lab = table(&[(17, 19, [252, 252, 240]), (20, 23, [170, 150, 60])]);
        assert_refined_between(&lab, 21.5, 19.5, 20.5);
        // Light that is no highlight stays out: a white cable (rows 18-23) on a dark
        // table, its soft edges grey (rows 16-17 and 24-25), lighter than the table but
        // darker than the cable, keeps its own width.
        let dark = table_with(|_, y| {
            Some(match y {
                18..=23 => [235, 235, 230],
                16..=17 | 24..=25 => [110, 110, 108],
                _ => [30, 30, 32],
            })
        });
        let line: Vec<[f32; 2]> = (10..50).map(|x| [x as f32, 20.5]).collect();
        let width = refine(&line, &dark, &Params::default()).width_px.unwrap();
        assert!((5.0..7.0).contains(&width), "{width}");
    }

    #[test]
    fn a_cable_of_the_table_s_colour_is_read_between_its_rims() {
        // A cable of the table's own colour (rows 16-26, centre 21) shows only its grey
        // rims (rows 16-17 and 25-26). Started on the upper rim, the line moves to the
        // middle, and the width read is the cable's, not a rim's.
        let rim = [110, 120, 116];
        let lab = table(&[(16, 17, rim), (25, 26, rim)]);
        assert_refined_between(&lab, 17.0, 20.5, 21.5);
        let line: Vec<[f32; 2]> = (10..50).map(|x| [x as f32, 17.0]).collect();
        let width = refine(&line, &lab, &Params::default()).width_px.unwrap();
        assert!((9.0..12.0).contains(&width), "{width}");
        // Two grey cables 4 px wide, 2 px apart, are no outline: each stays itself.
        let pair = table(&[(15, 18, rim), (21, 24, rim)]);
        assert_refined_between(&pair, 17.0, 16.0, 17.5);
    }

    #[test]
    fn light_stripes_on_either_side_of_a_grey_cable_are_not_taken_for_it() {
        // A grey cable (rows 22-28) with a white stripe above it on the left half and
        // below it on the right: no one light casts that shadow, so it stays the cable.
        let lab = table_with(|x, y| match y {
            22..=28 => Some([120, 130, 122]),
            17..=20 if x < 30 => Some([240, 248, 240]),
            30..=33 if x >= 30 => Some([240, 248, 240]),
            _ => None,
        });
        assert_refined_between(&lab, 24.0, 24.5, 25.5);
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
