//! Choosing walks and pairing ends into cables, globally.
//!
//! Every walk is a hypothesis "the cable from end A goes there": to another end B, out
//! of the frame, or nowhere in particular (lost). Hypotheses are scored by walk quality
//! times a factor for how they ended (a closing walk confirmed by a walk from the other
//! end scores highest) and accepted greedily from the best down, so that each end
//! belongs to at most one cable and no cable is reported twice: not from its two ends,
//! nor from two ends on one cable (a terminal seen twice, at its metal tip and where the
//! insulation ends; a false end along a cable), whose walks run over the same
//! superpixels. A walk that links two ends over less than a few cable widths most often
//! joins such a terminal's two marks, or two cables' ends lying side by side: it is
//! weighed after every other hypothesis, a cable only where its ends have nothing else.
//!
//! Two lost walks from different ends whose heads face each other across a short gap
//! (a crossing or a glare spot they could not pass) are joined into one hypothesis
//! between their ends. So are two walks that leave the frame facing each other across
//! a short gap along which the cable field shows cable, each meeting it at a shallow
//! angle: a cable that grazes the border (as well supported as a confirmed pair: each
//! walk found the other's way out), not one that leaves the frame and comes back. Where
//! both walks were accepted as cables leaving the frame, their join replaces them.

use super::Params;
use super::field::{CableField, GAP_SAMPLE_PX};
use super::geometry::norm;
use super::spline::resample;
use super::walk::{Walk, WalkEnd};

/// Two walks that leave the frame are joined only where each meets the gap between
/// their exits within this many degrees (and `max_turn_deg`): a cable grazing the border
/// runs along it there (28° and 18° on simple/00039's orange cable), while two cables
/// leaving the frame a little apart, converging, meet it steeper (48-59° where they were
/// joined at `max_turn_deg`, 60°).
const GRAZE_MAX_TURN_DEG: f32 = 40.0;

/// How an accepted cable's far end was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FarEnd {
    /// Another given end.
    Seed(usize),
    /// The image border.
    Border,
    /// The walk lost the cable here.
    Open,
}

/// An accepted cable hypothesis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pairing {
    /// The seed the kept walk starts from.
    pub start: usize,
    /// Where it ends.
    pub far: FarEnd,
    /// Index of the kept walk.
    pub walk: usize,
    /// A second walk, from the far end, whose vertices continue this one in reverse
    /// (two lost walks joined across a gap).
    pub joined: Option<usize>,
    /// Score in 0..=1.
    pub score: f32,
}

/// The lowest score a hypothesis may have to be accepted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Floor {
    /// For every hypothesis ([`Params::cable_score_floor`]).
    pub score: f32,
    /// For one walk alone (none joined) along which the cable field's mean is at least
    /// `.0`: `.1` instead.
    pub sure: Option<(f32, f32)>,
    /// Times the floor for a hypothesis that arrives at another seed of confidence 1, by
    /// one walk or two joined ([`Params::reached_floor`] for ends; 1 for the same floor
    /// as every hypothesis).
    pub reached: f32,
}

impl Floor {
    /// `score` for every hypothesis.
    pub fn new(score: f32) -> Self {
        Self {
            score,
            sure: None,
            reached: 1.0,
        }
    }

    /// The lowest score for `h`, a hypothesis over `walks` between ends of the given
    /// `confidence`. The lower floor of a hypothesis arriving at another end counts as
    /// far as that end is credible: fully for a caller's end, less for a weak detection.
    fn of(&self, h: &Pairing, walks: &[Walk], confidence: &[f32]) -> f32 {
        let floor = match self.sure {
            Some((level, score)) if h.joined.is_none() && walks[h.walk].cable >= level => {
                score.min(self.score)
            }
            _ => self.score,
        };
        match h.far {
            FarEnd::Seed(t) => floor * (1.0 - (1.0 - self.reached) * confidence[t]),
            _ => floor,
        }
    }
}

/// Pairs the ends using `walks` (see module docs); `confidence` holds one value in
/// 0..=1 per end (1 for ends given by a caller, the detector's score otherwise). A cable
/// that no second end confirms rests on its start end alone, so its score is scaled by
/// that end's confidence. Hypotheses scoring below `floor` are dropped. Walks that
/// leave the frame are joined only where `field` shows the cable between them. A walk
/// along a cable that runs on behind its end ([`Walk::through`]) follows a cable
/// passing the end, not the end's own, and its score is multiplied by
/// `through_factor` (1 where the seeds are no cable's ends).
/// A hypothesis whose walks run more than `pair_max_shared` of their superpixels over
/// those of hypotheses accepted before it repeats a cable already found and is
/// dropped. A walk that closes on an end after fewer than `close_min_steps` steps
/// ([`Walk::steps`]) is no hypothesis; one that closes over less than
/// `closed_min_length_px` is weighed after all the others. Two cables accepted as
/// leaving the frame where the border walks they rest on join ([`merge_grazes`]) are
/// one. The result is ordered by decreasing score.
pub fn pair(
    walks: &[Walk],
    confidence: &[f32],
    params: &Params,
    floor: Floor,
    through_factor: f32,
    field: Option<&CableField>,
) -> Vec<Pairing> {
    let passing = |w: &Walk| if w.through { through_factor } else { 1.0 };
    let n_seeds = confidence.len();
    // Which ordered (from, to) closures exist, to find confirmed pairs.
    let closes = |from: usize, to: usize| {
        walks
            .iter()
            .any(|w| w.seed == from && w.end == WalkEnd::Seed(to))
    };
    let mut hypotheses: Vec<Pairing> = walks
        .iter()
        .enumerate()
        .filter(|(_, w)| w.length_px >= params.min_cable_length_px)
        .filter(|(_, w)| {
            !matches!(w.end, WalkEnd::Seed(_)) || w.steps() >= params.close_min_steps as usize
        })
        .map(|(i, w)| {
            let alone = confidence[w.seed];
            let (far, factor) = match w.end {
                WalkEnd::Seed(t) if closes(t, w.seed) => (FarEnd::Seed(t), 1.0),
                WalkEnd::Seed(t) => (FarEnd::Seed(t), params.unconfirmed_factor * alone),
                WalkEnd::Border => (FarEnd::Border, params.border_factor * alone),
                WalkEnd::Lost => (FarEnd::Open, params.lost_factor * alone),
            };
            Pairing {
                start: w.seed,
                far,
                walk: i,
                joined: None,
                score: w.quality(params) * factor * passing(w),
            }
        })
        .collect();
    hypotheses.extend(joins(walks, confidence, params, field, &passing));
    hypotheses.retain(|h| h.score >= floor.of(h, walks, confidence));
    // A short link between two ends: taken only by ends nothing else claims.
    let short = |h: &Pairing| {
        matches!(h.far, FarEnd::Seed(_))
            && h.joined.is_none()
            && walks[h.walk].length_px < params.closed_min_length_px
    };
    hypotheses.sort_by(|a, b| short(a).cmp(&short(b)).then(b.score.total_cmp(&a.score)));
    let grazing: Vec<Pairing> = hypotheses
        .iter()
        .filter(|h| h.joined.is_some() && walks[h.walk].end == WalkEnd::Border)
        .copied()
        .collect();
    let mut used = vec![false; n_seeds];
    let mut taken = vec![false; vertex_count(walks)];
    let mut accepted = Vec::new();
    for h in hypotheses {
        if used[h.start] {
            continue;
        }
        let vertices = || {
            let joined = h.joined.map_or(&[][..], |j| &walks[j].vertices[..]);
            walks[h.walk].vertices.iter().chain(joined)
        };
        let (shared, all) =
            vertices().fold((0, 0), |(s, n), &v| (s + taken[v as usize] as usize, n + 1));
        if shared as f32 > params.pair_max_shared * all as f32 {
            continue;
        }
        if let FarEnd::Seed(t) = h.far {
            if used[t] {
                continue;
            }
            used[t] = true;
        }
        used[h.start] = true;
        for &v in vertices() {
            taken[v as usize] = true;
        }
        accepted.push(h);
    }
    merge_grazes(&mut accepted, &grazing);
    accepted.sort_by(|a, b| b.score.total_cmp(&a.score));
    accepted
}

/// Replaces two accepted cables that each leave the frame, by walks that a grazing
/// join of `grazing` links, with that join: one cable that runs along the border
/// between their exits (the field shows it there), not two that leave it. The join
/// scores the geometric mean of its walks, so the better walk leaving the frame alone
/// can outscore it (with `border_factor` 0.9, once one walk's quality is under 0.81 of
/// the other's); both being accepted shows neither end found a better cable.
fn merge_grazes(accepted: &mut Vec<Pairing>, grazing: &[Pairing]) {
    for join in grazing {
        let Some(j) = join.joined else { continue };
        let leaving = |walk: usize| {
            accepted
                .iter()
                .position(|a| a.walk == walk && a.far == FarEnd::Border && a.joined.is_none())
        };
        let (Some(a), Some(b)) = (leaving(join.walk), leaving(j)) else {
            continue;
        };
        accepted[a] = *join;
        accepted.remove(b);
    }
}

/// One more than the largest superpixel index any of `walks` visits.
fn vertex_count(walks: &[Walk]) -> usize {
    walks
        .iter()
        .flat_map(|w| w.vertices.iter())
        .max()
        .map_or(0, |&v| v as usize + 1)
}

/// Hypotheses joining two lost walks, or two walks that leave the frame with the
/// cable between their exits ([`grazes`]), whose heads face each other within
/// `join_radius_px`, each turning at most `max_turn_deg` to meet the other; scored by
/// the geometric means of the two walks' qualities and of their ends' confidences,
/// times `unconfirmed_factor` for lost walks and by `passing` of each walk.
fn joins(
    walks: &[Walk],
    confidence: &[f32],
    params: &Params,
    field: Option<&CableField>,
    passing: &dyn Fn(&Walk) -> f32,
) -> Vec<Pairing> {
    let cos_max = params.max_turn_deg.to_radians().cos();
    let open: Vec<(usize, &Walk)> = walks
        .iter()
        .enumerate()
        .filter(|(_, w)| {
            let joinable = match w.end {
                WalkEnd::Lost => true,
                WalkEnd::Border => field.is_some(),
                WalkEnd::Seed(_) => false,
            };
            joinable && w.length_px >= params.min_cable_length_px * params.join_min_length
        })
        .collect();
    let mut out = Vec::new();
    for (n, &(i, a)) in open.iter().enumerate() {
        for &(j, b) in &open[n + 1..] {
            if a.seed == b.seed || a.end != b.end {
                continue;
            }
            let gap = [
                b.end_point[0] - a.end_point[0],
                b.end_point[1] - a.end_point[1],
            ];
            let d = norm(gap);
            if d > params.join_radius_px {
                continue;
            }
            let cos_max = if a.end == WalkEnd::Border {
                cos_max.max(GRAZE_MAX_TURN_DEG.to_radians().cos())
            } else {
                cos_max
            };
            let facing = if d < 1e-3 {
                -(a.end_heading[0] * b.end_heading[0] + a.end_heading[1] * b.end_heading[1])
                    >= cos_max
            } else {
                let (ux, uy) = (gap[0] / d, gap[1] / d);
                a.end_heading[0] * ux + a.end_heading[1] * uy >= cos_max
                    && -(b.end_heading[0] * ux + b.end_heading[1] * uy) >= cos_max
            };
            if !facing {
                continue;
            }
            let factor = match (a.end, field) {
                (WalkEnd::Border, Some(f)) if grazes(f, a.end_point, b.end_point, params) => 1.0,
                (WalkEnd::Border, _) => continue,
                _ => params.unconfirmed_factor,
            };
            out.push(Pairing {
                start: a.seed,
                far: FarEnd::Seed(b.seed),
                walk: i,
                joined: Some(j),
                score: (a.quality(params)
                    * b.quality(params)
                    * confidence[a.seed]
                    * confidence[b.seed])
                    .sqrt()
                    * factor
                    * passing(a)
                    * passing(b),
            });
        }
    }
    out
}

/// True when the field shows cable (at least `field_level`) along most of the
/// straight gap between two border walks' exits `a` and `b` (just inside the frame).
fn grazes(field: &CableField, a: [f32; 2], b: [f32; 2], params: &Params) -> bool {
    field.share_on_cable(&resample(&[a, b], GAP_SAMPLE_PX), params.field_level) >= 0.5
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A walk from `seed` over superpixels of its own: its seed's, its first and one
    /// step.
    fn walk(seed: usize, end: WalkEnd, q: f32) -> Walk {
        let first = 3 * seed as u32;
        Walk {
            seed,
            vertices: vec![first, first + 1, first + 2],
            end,
            visual: q,
            smoothness: 1.0,
            contrast: 1.0,
            cable: 1.0,
            length_px: 100.0,
            end_heading: [1.0, 0.0],
            end_point: [0.0, 0.0],
            through: false,
            opening: 1.0,
        }
    }

    /// The walks of ends 0 and 1 closing on each other, each of quality `q`.
    fn closing_on_each_other(q: f32) -> [Walk; 2] {
        [walk(0, WalkEnd::Seed(1), q), walk(1, WalkEnd::Seed(0), q)]
    }

    /// [`pair`] with every end fully trusted (confidence 1), the default floor, no
    /// penalty for walks along a passing cable and no field.
    fn pair_sure(walks: &[Walk], p: &Params) -> Vec<Pairing> {
        let seeds = walks
            .iter()
            .flat_map(|w| match w.end {
                WalkEnd::Seed(t) => vec![w.seed, t],
                _ => vec![w.seed],
            })
            .max()
            .map_or(0, |s| s + 1);
        pair(
            walks,
            &vec![1.0; seeds],
            p,
            Floor::new(p.min_cable_score),
            1.0,
            None,
        )
    }

    #[test]
    fn each_end_used_once_and_confirmed_pairs_win() {
        let p = Params::default();
        let walks = vec![
            walk(0, WalkEnd::Seed(1), 0.9),
            walk(1, WalkEnd::Seed(0), 0.8),
            walk(2, WalkEnd::Seed(1), 0.95), // unconfirmed: 0.95 * 0.8 < 0.9
            walk(2, WalkEnd::Border, 0.7),
            walk(3, WalkEnd::Lost, 0.9),
        ];
        let got = pair_sure(&walks, &p);
        assert_eq!(got.len(), 3);
        assert_eq!((got[0].start, got[0].far), (0, FarEnd::Seed(1)));
        assert_eq!((got[1].start, got[1].far), (2, FarEnd::Border));
        assert_eq!((got[2].start, got[2].far), (3, FarEnd::Open));
        let mut ends: Vec<usize> = got.iter().map(|h| h.start).collect();
        ends.extend(got.iter().filter_map(|h| match h.far {
            FarEnd::Seed(t) => Some(t),
            _ => None,
        }));
        ends.sort_unstable();
        assert_eq!(ends, vec![0, 1, 2, 3]);
    }

    #[test]
    fn an_end_met_before_the_first_step_is_no_cable() {
        let p = Params::default();
        // Ends 0 and 1 face each other across a gap: their walks close on each other
        // as soon as they leave their own superpixels; each also runs out of the frame.
        let mut meet = closing_on_each_other(0.9);
        for w in &mut meet {
            w.vertices.truncate(2);
        }
        let mut walks = meet.to_vec();
        walks.extend([walk(0, WalkEnd::Border, 0.6), walk(1, WalkEnd::Border, 0.6)]);
        let got = pair_sure(&walks, &p);
        assert_eq!(got.len(), 2);
        assert!(got.iter().all(|h| h.far == FarEnd::Border), "{got:?}");
        // The paper closes on any end within r.
        let paper = Params::preset("paper").expect("a preset");
        let got = pair_sure(&walks, &paper);
        assert_eq!((got[0].start, got[0].far), (0, FarEnd::Seed(1)));
    }

    #[test]
    fn a_terminal_seen_twice_yields_to_its_cable() {
        let p = Params::default();
        // Ends 0 and 1 mark one terminal twice (a ferrule's tip and its base): their
        // walks close on each other after a step, confirmed both ways, over less than
        // `closed_min_length_px`, and score above end 1's walk along its cable.
        let mut short = closing_on_each_other(0.9);
        for w in &mut short {
            w.length_px = 0.8 * p.closed_min_length_px;
        }
        let mut along = walk(1, WalkEnd::Border, 0.6);
        along.vertices = (10..20).collect();
        let mut walks = short.to_vec();
        walks.push(along);
        let got = pair_sure(&walks, &p);
        assert_eq!(got.len(), 1);
        assert_eq!((got[0].start, got[0].far), (1, FarEnd::Border));
        // With nothing else for its ends, a short cable is one.
        let got = pair_sure(&short, &p);
        assert_eq!((got[0].start, got[0].far), (0, FarEnd::Seed(1)));
        // As long as the limit, the link wins on its score.
        for w in &mut walks[..2] {
            w.length_px = p.closed_min_length_px;
        }
        let got = pair_sure(&walks, &p);
        assert_eq!((got[0].start, got[0].far), (0, FarEnd::Seed(1)));
    }

    #[test]
    fn a_second_end_on_a_cable_found_adds_no_cable() {
        let p = Params::default();
        let mut a = walk(0, WalkEnd::Border, 0.9);
        a.vertices = (0..10).collect();
        // A metal tip seen as its own end just beyond end 0: its walk runs over the
        // cable's superpixels, one of them its own.
        let mut tip = walk(1, WalkEnd::Border, 0.8);
        tip.vertices = [20].into_iter().chain(0..10).collect();
        let got = pair_sure(&[a.clone(), tip.clone()], &p);
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].start, 0);
        // A cable alongside, crossing the first once, is a cable of its own.
        tip.vertices = (20..30).chain([5]).collect();
        assert_eq!(pair_sure(&[a, tip], &p).len(), 2);
    }

    #[test]
    fn facing_lost_walks_are_joined() {
        let p = Params::default();
        let mut a = walk(0, WalkEnd::Lost, 0.8);
        a.end_point = [100.0, 100.0];
        let mut b = walk(1, WalkEnd::Lost, 0.8);
        b.end_point = [140.0, 100.0];
        b.end_heading = [-1.0, 0.0];
        let got = pair_sure(&[a.clone(), b.clone()], &p);
        assert_eq!(got.len(), 1);
        assert_eq!((got[0].far, got[0].joined), (FarEnd::Seed(1), Some(1)));
        // Heads pointing the same way do not meet.
        b.end_heading = [1.0, 0.0];
        assert!(pair_sure(&[a, b], &p).iter().all(|h| h.joined.is_none()));
    }

    #[test]
    fn walks_leaving_the_frame_face_to_face_join_where_the_field_shows_the_cable() {
        let p = Params::default();
        // Two walks leave the bottom of a 160x80 frame 40 px apart, heading towards
        // each other: a cable grazing the border, or one leaving and coming back.
        let leaving = |seed, x: f32, dx: f32| {
            let mut w = walk(seed, WalkEnd::Border, 0.8);
            w.end_point = [x, 76.0];
            let n = (dx * dx + 0.09).sqrt();
            w.end_heading = [dx / n, 0.3 / n];
            w
        };
        let walks = [leaving(0, 60.0, 1.0), leaving(1, 100.0, -1.0)];
        let field = |bottom: f32| CableField {
            width: 20,
            height: 10,
            cell_px: [8.0, 8.0],
            cable: (0..200)
                .map(|i| if i >= 180 { bottom } else { 0.0 })
                .collect(),
            orientation: vec![[1.0, 0.0]; 200],
        };
        let pair_over = |walks: &[Walk], field| {
            pair(
                walks,
                &[1.0; 2],
                &p,
                Floor::new(p.min_cable_score),
                1.0,
                field,
            )
        };
        let grazing = field(0.9);
        let got = pair_over(&walks, Some(&grazing));
        assert_eq!(got.len(), 1);
        assert_eq!((got[0].far, got[0].joined), (FarEnd::Seed(1), Some(1)));
        assert_eq!(got[0].score, walks[0].quality(&p));
        // One walk much better than the other: leaving the frame, it alone would
        // outscore the join (0.9 · 0.89 against √(0.89 · 0.4)), but the two are one cable.
        let mut uneven = walks.clone();
        uneven[1].visual = 0.16;
        let got = pair_over(&uneven, Some(&grazing));
        assert_eq!(got.len(), 1, "{got:?}");
        assert_eq!((got[0].start, got[0].joined), (0, Some(1)));
        // Two cables leaving the frame close together, converging (each meeting the
        // border at 55°), are two, though the field shows cable between their exits.
        let mut steep = walks.clone();
        for w in &mut steep {
            w.end_heading = [0.57 * w.end_heading[0].signum(), 0.82];
        }
        let got = pair_over(&steep, Some(&grazing));
        assert_eq!(got.len(), 2, "{got:?}");
        assert!(got.iter().all(|h| h.far == FarEnd::Border));
        // Background between the exits (the cable left the frame), or no field: two
        // cables, each through the border.
        let left = field(0.0);
        for field in [Some(&left), None] {
            let got = pair_over(&walks, field);
            assert_eq!(got.len(), 2);
            assert!(got.iter().all(|h| h.far == FarEnd::Border));
        }
    }

    #[test]
    fn walks_along_a_cable_passing_the_end_yield_to_the_end_s_own() {
        let p = Params::default();
        // From an end pushed against another cable: the walk along that cable (it runs
        // on behind the end) scores a little better than the one along the end's own.
        let mut passing = walk(0, WalkEnd::Border, 0.8);
        passing.through = true;
        let own = walk(0, WalkEnd::Border, 0.7);
        let walks = [passing, own];
        let kept = |factor| {
            pair(
                &walks,
                &[1.0],
                &p,
                Floor::new(p.min_cable_score),
                factor,
                None,
            )[0]
            .walk
        };
        assert_eq!(kept(p.field_through_factor), 1);
        assert_eq!(kept(1.0), 0);
    }

    #[test]
    fn short_or_weak_walks_are_dropped() {
        let p = Params::default();
        let mut short = walk(0, WalkEnd::Border, 1.0);
        short.length_px = 5.0;
        // Visual likelihood v scores v^0.5 · lost_factor: half the minimum score.
        let v = (0.5 * p.min_cable_score / p.lost_factor).powi(2);
        let weak = walk(1, WalkEnd::Lost, v);
        assert!(pair_sure(&[short, weak], &p).is_empty());
    }

    #[test]
    fn the_field_lowers_the_floor_a_cable_must_reach() {
        let p = Params::default();
        // A lost walk scoring midway between the two floors.
        let score = 0.5 * (p.field_min_cable_score + p.min_cable_score);
        let weak = [walk(0, WalkEnd::Lost, (score / p.lost_factor).powi(2))];
        let kept = |field| {
            pair(
                &weak,
                &[1.0],
                &p,
                Floor::new(p.cable_score_floor(field)),
                1.0,
                None,
            )
            .len()
        };
        assert!(p.field_min_cable_score < p.min_cable_score);
        assert_eq!(kept(true), 1);
        assert_eq!(kept(false), 0);
    }

    #[test]
    fn a_walk_the_field_is_sure_of_needs_only_the_sure_floor() {
        let p = Params::default();
        let (level, low) = (p.field_border_sure_level, p.field_min_cable_score);
        let floor = Floor {
            sure: Some((level, low)),
            ..Floor::new(p.field_border_min_score)
        };
        // A walk leaving the frame with the field's mean `cable` along it, its lateral
        // contrast set so that it scores midway between the two floors.
        let score = 0.5 * (low + p.field_border_min_score);
        let kept = |cable: f32| {
            let mut w = walk(0, WalkEnd::Border, 1.0);
            w.cable = cable;
            let rest = p.border_factor * cable.powf(p.quality_field_exponent);
            w.contrast = (score / rest).powf(1.0 / p.quality_contrast_exponent);
            pair(&[w], &[1.0], &p, floor, 1.0, None).len()
        };
        assert_eq!(kept(level), 1);
        assert_eq!(kept(0.95 * level), 0);
        // With no such rule, the walk the field is sure of is dropped too.
        let mut w = walk(0, WalkEnd::Border, 1.0);
        w.contrast = (score / p.border_factor).powf(1.0 / p.quality_contrast_exponent);
        assert!(pair(&[w], &[1.0], &p, Floor::new(floor.score), 1.0, None).is_empty());
    }

    #[test]
    fn a_cable_arriving_at_another_end_needs_only_its_share_of_the_floor() {
        let p = Params::default();
        let floor = p.field_min_cable_score;
        // An unconfirmed walk to another end and a lost walk, both from an end of
        // confidence 1 and scoring midway between the lowered floor and the floor.
        let score = 0.5 * (1.0 + p.field_reached_floor) * floor;
        let arriving = walk(0, WalkEnd::Seed(1), (score / p.unconfirmed_factor).powi(2));
        let lost = walk(0, WalkEnd::Lost, (score / p.lost_factor).powi(2));
        let kept = |w: &Walk, reached: f32, far_confidence: f32| {
            let floor = Floor {
                reached,
                ..Floor::new(floor)
            };
            pair(
                std::slice::from_ref(w),
                &[1.0, far_confidence],
                &p,
                floor,
                1.0,
                None,
            )
            .len()
        };
        assert!(p.field_reached_floor < 1.0);
        assert_eq!(kept(&arriving, p.field_reached_floor, 1.0), 1);
        assert_eq!(kept(&arriving, 1.0, 1.0), 0);
        assert_eq!(kept(&lost, p.field_reached_floor, 1.0), 0);
        // Arriving at an end nothing vouches for earns nothing.
        assert_eq!(kept(&arriving, p.field_reached_floor, 0.0), 0);
    }

    #[test]
    fn unconfirmed_cables_rest_on_their_end_confidence() {
        let p = Params::default();
        let walks = vec![
            walk(0, WalkEnd::Border, 0.8),
            walk(1, WalkEnd::Border, 0.8),
            walk(2, WalkEnd::Seed(3), 0.8),
            walk(3, WalkEnd::Seed(2), 0.8),
        ];
        // A weak detection leaving through the frame (scoring half the minimum) is
        // dropped; a confirmed pair of weak detections is kept at full score.
        let weak = 0.5 * p.min_cable_score / (p.border_factor * walks[1].quality(&p));
        let got = pair(
            &walks,
            &[1.0, weak, 0.4, 0.4],
            &p,
            Floor::new(p.min_cable_score),
            1.0,
            None,
        );
        assert_eq!(got.len(), 2);
        assert_eq!((got[0].start, got[0].score), (2, walks[2].quality(&p)));
        assert_eq!(got[1].start, 0);
    }
}
