//! Families of straight lines: the joints of a brick wall, the lines of a printed page,
//! the rulings of a cutting mat. The field calls such lines cable, and walks from the
//! frame's edge or from a false terminal follow them; each alone looks like a thin
//! straight rod. Together they give themselves away: several found cables, all straight,
//! all of one colour, all running one way, none between two terminals, each scoring
//! low. Real cables laid on a table bend and end in view; a drawn or printed texture
//! repeats (docs/ENGINE.md, "Families of straight lines").

use super::Params;
use super::cable::{Cable, drop_cables};
use super::color::rgb_to_lab;
use std::f32::consts::PI;

use super::geometry::{dist, dist3, unit_or};

/// A cable is straight when its ends lie at least this share of its length apart.
const MIN_STRAIGHTNESS: f32 = 0.95;
/// Two straight cables run one way when their chords differ by under this, degrees.
const MAX_ANGLE_DEG: f32 = 10.0;
/// Two cables are of one colour when their median colours lie under this apart, ΔE.
const MAX_COLOUR_DE: f32 = 20.0;
/// Kin lying closer across than this many widths run in one lane: twins laid side by
/// side (one width and a gap apart) are one member of a family, not two.
const LANE_WIDTHS: f32 = 3.0;

/// One cable as a family member is judged: straight or not, its chord's midpoint,
/// unit direction and direction (radians in [0, π)), its colour in Lab and width.
struct Line {
    straight: bool,
    middle: [f32; 2],
    along: [f32; 2],
    angle: f32,
    lab: [f32; 3],
    width: f32,
}

impl Line {
    fn of(cable: &Cable) -> Self {
        let [a, b] = cable.ends;
        let chord = dist(a, b);
        Self {
            straight: chord >= MIN_STRAIGHTNESS * cable.length_px,
            middle: [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0],
            along: unit_or([b[0] - a[0], b[1] - a[1]], [1.0, 0.0]),
            angle: (b[1] - a[1]).atan2(b[0] - a[0]).rem_euclid(PI),
            lab: rgb_to_lab(cable.color),
            width: cable.width_px,
        }
    }

    /// Both straight, of one colour, running one way.
    fn kin(&self, other: &Self) -> bool {
        let turn = (self.angle - other.angle).abs();
        let turn = turn.min(PI - turn);
        self.straight
            && other.straight
            && turn < MAX_ANGLE_DEG.to_radians()
            && dist3(self.lab, other.lab) < MAX_COLOUR_DE
    }

    /// Signed distance of `other`'s midpoint from this line's chord, across it.
    fn offset(&self, other: &Self) -> f32 {
        let d = [
            other.middle[0] - self.middle[0],
            other.middle[1] - self.middle[1],
        ];
        d[1] * self.along[0] - d[0] * self.along[1]
    }

    /// How many lanes the kin of this line among `lines` (itself included) run in:
    /// kin closer across than [`LANE_WIDTHS`] widths to the last lane counted lie in
    /// it (twins laid together, or one cable found twice, are one lane).
    fn lanes(&self, lines: &[Line]) -> usize {
        let mut offsets: Vec<f32> = lines
            .iter()
            .filter(|other| self.kin(other))
            .map(|other| self.offset(other))
            .collect();
        offsets.sort_by(f32::total_cmp);
        let apart = LANE_WIDTHS * self.width;
        let mut lanes = 0;
        let mut last = f32::NEG_INFINITY;
        for o in offsets {
            if o - last >= apart {
                lanes += 1;
                last = o;
            }
        }
        lanes
    }
}

/// Drops every cable whose kin among the found cables (straight, of its colour,
/// running its way, itself included) run in at least [`Params::field_line_family`]
/// lanes, that has at most one end on a given end and that scores under
/// [`Params::field_line_family_max_score`]; its ends are left free. 0 in
/// `field_line_family` keeps them all.
pub(super) fn drop_line_families(
    cables: &mut Vec<Cable>,
    end_cables: &mut [Option<usize>],
    params: &Params,
) {
    if params.field_line_family == 0 || cables.len() < params.field_line_family as usize {
        return;
    }
    let lines: Vec<Line> = cables.iter().map(Line::of).collect();
    let dropped: Vec<bool> = cables
        .iter()
        .zip(&lines)
        .map(|(cable, line)| {
            cable.score < params.field_line_family_max_score
                && cable.end_indices.iter().flatten().count() <= 1
                && line.lanes(&lines) >= params.field_line_family as usize
        })
        .collect();
    if dropped.contains(&true) {
        drop_cables(cables, end_cables, &dropped);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::cable::straight;

    /// A vertical line from the top edge to the bottom at `x`, grey, scoring 0.1.
    fn joint(id: usize, x: f32) -> Cable {
        Cable {
            color: [200, 150, 170],
            score: 0.1,
            ..straight(id, [[x, 0.0], [x + 8.0, 479.0]], [None, None])
        }
    }

    #[test]
    fn four_parallel_weak_lines_of_one_colour_are_dropped_and_a_cable_across_them_kept() {
        let mut cables: Vec<Cable> = (0..4).map(|k| joint(k, 60.0 + 90.0 * k as f32)).collect();
        cables.push(Cable {
            color: [200, 150, 170],
            score: 0.1,
            ..straight(4, [[20.0, 200.0], [600.0, 260.0]], [Some(0), Some(1)])
        });
        let mut end_cables = vec![Some(4), Some(4)];
        drop_line_families(&mut cables, &mut end_cables, &Params::default());
        assert_eq!(cables.len(), 1);
        assert_eq!(cables[0].id, 0);
        assert_eq!(end_cables, vec![Some(0), Some(0)]);
    }

    #[test]
    fn three_lines_a_strong_one_or_one_between_two_ends_are_kept() {
        let params = Params::default();
        let mut three: Vec<Cable> = (0..3).map(|k| joint(k, 60.0 + 90.0 * k as f32)).collect();
        drop_line_families(&mut three, &mut [], &params);
        assert_eq!(three.len(), 3);

        let mut four: Vec<Cable> = (0..4).map(|k| joint(k, 60.0 + 90.0 * k as f32)).collect();
        four[1].score = 0.6;
        four[2].end_indices = [Some(0), Some(1)];
        let mut end_cables = vec![Some(2), Some(2)];
        drop_line_families(&mut four, &mut end_cables, &params);
        assert_eq!(four.len(), 2);
        assert_eq!(four[0].score, 0.6);
        assert_eq!(end_cables, vec![Some(1), Some(1)]);
    }

    #[test]
    fn two_pairs_of_twins_of_one_colour_are_two_lanes_and_kept() {
        let mut twins: Vec<Cable> = [60.0, 70.0, 300.0, 310.0]
            .into_iter()
            .enumerate()
            .map(|(k, x)| joint(k, x))
            .collect();
        drop_line_families(&mut twins, &mut [], &Params::default());
        assert_eq!(twins.len(), 4);
    }

    #[test]
    fn bent_lines_or_lines_of_other_colours_make_no_family() {
        let params = Params::default();
        let mut colours: Vec<Cable> = (0..4)
            .map(|k| Cable {
                color: [[200, 150, 170], [40, 40, 40], [30, 90, 220], [240, 220, 40]][k],
                ..joint(k, 60.0 + 90.0 * k as f32)
            })
            .collect();
        drop_line_families(&mut colours, &mut [], &params);
        assert_eq!(colours.len(), 4);

        let mut bent: Vec<Cable> = (0..4).map(|k| joint(k, 60.0 + 90.0 * k as f32)).collect();
        for cable in &mut bent[..2] {
            cable.length_px *= 1.2;
        }
        drop_line_families(&mut bent, &mut [], &params);
        assert_eq!(bent.len(), 4);
    }
}
