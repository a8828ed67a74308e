//! Cables with no end in view: both of their ends lie outside the frame, so no walk from
//! an end can find them. Where such a cable crosses the border, the border has a short
//! run of pixels that are cable: where the cable field says so when there is one, else
//! where the superpixels' colour stands out from the rest of the border (mostly
//! background). Each such run not explained by a cable already found becomes an extra
//! seed on the border, and only walks that cross the image to another border point
//! count from it. With a field, the two ends of every piece of cable inside the frame
//! that no cable explains are seeds too ([`super::orphans`]): cables whose ends the
//! network missed; a walk from one counts when it reaches another seed or the border.
//! With a field, a walk from either kind of seed also counts where it loses the cable
//! along a field sure of all it followed (`field_border_sure_level`): a cable with one
//! end out of view and a terminal the network missed, or missed at both ends.

use super::cable::{Cable, Scene, model_cable, model_course};
use super::chains::{chain, extend};
use super::field::CableField;
use super::geometry::{along_one_side, dist3, median, points_near_any, runs_along};
use super::graph::Graph;
use super::orphans::orphan_seeds;
use super::pairing::{self, Floor, Pairing};
use super::superpixels::Superpixels;
use super::twins::lies_over_twins;
use super::walk::{self, Seed, Walk, WalkEnd};
use super::{EngineError, Params};

/// The perimeter pixels in clockwise order from the top-left corner, once each.
pub(super) fn perimeter(w: usize, h: usize) -> Vec<[usize; 2]> {
    let mut out = Vec::with_capacity(2 * (w + h));
    out.extend((0..w).map(|x| [x, 0]));
    out.extend((1..h).map(|y| [w - 1, y]));
    out.extend((0..w - 1).rev().map(|x| [x, h - 1]));
    out.extend((1..h - 1).rev().map(|y| [0, y]));
    out
}

/// Cables crossing the whole frame, with no end in view, and (with a field) cables
/// whose ends were missed: walks from border seeds where the border shows a colour the
/// cables in `chosen` do not explain, kept when they reach another border point (see
/// [`border`]); then walks from the ends of the pieces of the field that still no
/// cable explains, kept when they reach the border or another such seed and do not
/// repeat a cable found before them (one of `ended`, the cables of `chosen`, or one
/// from the border). Their ends belong to no given end.
pub(super) fn border_crossing_cables(
    scene: &Scene<'_>,
    chosen: &[Pairing],
    ended: &[Cable],
) -> Result<Vec<Cable>, EngineError> {
    let Scene {
        walks,
        terrain,
        field,
        sp,
        ..
    } = *scene;
    let (graph, p) = (terrain.graph, terrain.params);
    let mut covered = vec![false; graph.len()];
    cover(&mut covered, graph, walks, chosen);
    let (evidence, min_score) = match field {
        Some(f) => (Evidence::Field(f), p.field_border_min_score),
        None => (Evidence::Colour(graph), p.border_min_score),
    };
    let (seeds, targets) = border_seeds(evidence, sp, &covered, p);
    let mut found = cables_from(scene, (&seeds, targets), &covered, min_score, false)?;
    if let Some(vertex_field) = terrain.field {
        cover(&mut covered, graph, &found.walks, &found.picked);
        let frame = (sp.step, [sp.width, sp.height]);
        let seeds = orphan_seeds(graph, vertex_field, &covered, frame, p);
        let orphans = cables_from(scene, (&seeds, seeds.len()), &covered, min_score, true)?;
        // A pale cable can be walked a superpixel beside it, leaving pieces of field
        // along it that its walk does not cover: a cable over them repeats it. So can
        // a cable between two ends (the synthetic `Loop`: the walk ran along the outer
        // side of its wide bends); as a piece of field there may lead on to a cable
        // of its own, such a repeat must lie all but wholly on those cables.
        let half_width = |f: &Cable| half_width(f, p);
        let ended_lines: Vec<(&[[f32; 2]], f32)> = ended
            .iter()
            .map(|f| (&f.polyline[..], half_width(f)))
            .collect();
        let repeats = |c: &Cable| {
            found
                .cables
                .iter()
                .any(|f| runs_along(&c.polyline, &f.polyline, half_width(f)))
                || points_near_any(&c.polyline, &ended_lines) as f32
                    >= ENDED_REPEAT_SHARE * c.polyline.len() as f32
        };
        let new: Vec<Cable> = orphans.cables.into_iter().filter(|c| !repeats(c)).collect();
        found.cables.extend(new);
    }
    Ok(found.cables)
}

/// Least share of a cable walked from the field's pieces that must lie on cables
/// between ends for it to repeat them.
const ENDED_REPEAT_SHARE: f32 = 0.9;

/// How far from a cable's centreline another runs along it: half its width, or half
/// the nominal width for a thinner one.
fn half_width(cable: &Cable, p: &Params) -> f32 {
    0.5 * cable.width_px.max(p.nominal_width_px)
}

/// How many times a weak cable's score the cable that takes its place must score
/// ([`yield_weak_cables`]).
const YIELD_SCORE_RATIO: f32 = 2.0;

/// How many times a weak cable's length the cable that takes its place must be: it
/// must run on well past the weak cable.
const YIELD_LENGTH_RATIO: f32 = 1.3;

/// Whether a cable from the ends is weak enough to give way to a whole cable it lies
/// on ([`yield_weak_cables`]): from one end only (the other at the border or lost), and
/// scoring under `field_weak_cable_score`. A cable between two ends is confirmed by
/// both.
pub(super) fn is_weak(cable: &Cable, p: &Params) -> bool {
    cable.score < p.field_weak_cable_score && cable.end_indices.iter().any(Option::is_none)
}

/// With a field, which cables of `cables` give way to a whole cable they lie on: the
/// weak ones ([`is_weak`]), made from the pairings of `chosen` that `weak_choice`
/// flags. [`border_crossing_cables`] is run again as if they were not there; a cable
/// it finds that is not weak itself and that `found` (what the first run found) does
/// not already hold takes the place of every weak cable lying along it, where it
/// scores [`YIELD_SCORE_RATIO`] times as well and is [`YIELD_LENGTH_RATIO`] times as
/// long. It joins `found`, and the pieces of it there are dropped. The walk from a
/// weak false end (a knot in wood) that ran onto a cable crossing the frame covers
/// that cable's border seed, and weak ends walked the wrong way cover the field's
/// pieces along a cable whose ends were missed, so the first run finds only the rest
/// of such a cable, or nothing. One flag per cable: true where it gave way.
pub(super) fn yield_weak_cables(
    scene: &Scene<'_>,
    (chosen, weak_choice): (&[Pairing], &[bool]),
    cables: &[Cable],
    found: &mut Vec<Cable>,
) -> Result<Vec<bool>, EngineError> {
    let p = scene.terrain.params;
    let weak = |c: &Cable| is_weak(c, p);
    let mut gone = vec![false; cables.len()];
    if scene.field.is_none() || !cables.iter().any(weak) {
        return Ok(gone);
    }
    let strong_choices: Vec<Pairing> = chosen
        .iter()
        .zip(weak_choice)
        .filter(|&(_, &w)| !w)
        .map(|(c, _)| *c)
        .collect();
    let strong: Vec<Cable> = cables.iter().filter(|c| !weak(c)).cloned().collect();
    for crossing in border_crossing_cables(scene, &strong_choices, &strong)? {
        let half = half_width(&crossing, p);
        if crossing.score < p.field_weak_cable_score
            || found
                .iter()
                .any(|f| runs_along(&crossing.polyline, &f.polyline, half_width(f, p)))
        {
            continue;
        }
        let mut took = false;
        for (cable, gone) in cables.iter().zip(gone.iter_mut()) {
            if !*gone
                && weak(cable)
                && crossing.score >= YIELD_SCORE_RATIO * cable.score
                && crossing.length_px >= YIELD_LENGTH_RATIO * cable.length_px
                && runs_along(&cable.polyline, &crossing.polyline, half)
            {
                *gone = true;
                took = true;
            }
        }
        if took {
            found.retain(|f| !runs_along(&f.polyline, &crossing.polyline, half));
            found.push(crossing);
        }
    }
    Ok(gone)
}

/// Marks the superpixels of the `chosen` walks, and their neighbours, as `covered`.
fn cover(covered: &mut [bool], graph: &Graph, walks: &[Walk], chosen: &[Pairing]) {
    for choice in chosen {
        let joined = choice.joined.map(|j| &walks[j].vertices[..]).unwrap_or(&[]);
        for &v in walks[choice.walk].vertices.iter().chain(joined) {
            covered[v as usize] = true;
            for &n in graph.neighbours(v) {
                covered[n as usize] = true;
            }
        }
    }
}

/// What walks from extra seeds found.
#[derive(Default)]
struct SeedCables {
    /// The cables.
    cables: Vec<Cable>,
    /// The walks kept.
    walks: Vec<Walk>,
    /// The pairings of `walks` the cables come from.
    picked: Vec<Pairing>,
}

/// The cables walked from `seeds` that reach the border or another seed (one of the
/// first `targets`), or, with a field, lose the cable along a field as sure of them as
/// `field_border_sure_level` (the cable ends there, at a terminal the network missed),
/// over mostly uncovered superpixels, score at least `min_score` (with a field, a walk
/// along which it is sure, `field_border_sure_level`, only the floor of any cable),
/// read as a ridge rather than a step between two backgrounds across at least
/// `min_ridge_share` of their profiles, and do not lie all along one side of the
/// frame, within `border_margin_px` of it: the frame cuts whatever runs there (a
/// board's edge, a tray's rim, a strip of table), so its profiles cannot be read, and
/// a cable that close along a whole side would be mostly out of view.
/// With `chained`, the seeds are no cable's ends (the ends of the field's pieces): the
/// cables found are chained through them into whole ones ([`chain`]) and, with
/// `field_orphan_run_on`, run on past them where a walk lost the cable further on or
/// left the frame ([`extend`]).
fn cables_from(
    scene: &Scene<'_>,
    (seeds, targets): (&[Seed], usize),
    covered: &[bool],
    min_score: f32,
    chained: bool,
) -> Result<SeedCables, EngineError> {
    let (terrain, sp) = (scene.terrain, scene.sp);
    let p = terrain.params;
    if seeds.is_empty() {
        return Ok(Default::default());
    }
    let min_length = p.border_min_steps * sp.step;
    let unexplained = |w: &Walk| {
        let on_found = w.vertices.iter().filter(|&&v| covered[v as usize]).count();
        (on_found as f32) <= p.border_max_covered * w.vertices.len() as f32
    };
    // A walk that loses the cable where the field is sure of all it followed counts
    // too: the cable ends there, at a terminal the network missed.
    let field = terrain.field.is_some();
    let ends_sure = |w: &Walk| field && w.cable >= p.field_border_sure_level;
    let crosses = |w: &Walk| {
        (matches!(w.end, WalkEnd::Border | WalkEnd::Seed(_))
            || (w.end == WalkEnd::Lost && ends_sure(w)))
            && w.length_px >= min_length
            && unexplained(w)
    };
    // Border and piece seeds are no cable's ends, so a cable running on behind one
    // tells nothing (`pair` below gets a through factor of 1): not read.
    let walks = walk::walk_all(terrain, seeds, targets, false)?;
    // Chaining links pieces with any walk, so only then are all of them kept.
    let (crossing, links): (Vec<Walk>, Vec<Walk>) = if chained {
        (
            walks.iter().filter(|w| crosses(w)).cloned().collect(),
            walks,
        )
    } else {
        (
            walks.into_iter().filter(|w| crosses(w)).collect(),
            Vec::new(),
        )
    };
    let confidence = vec![p.border_seed_confidence; seeds.len()];
    // Only such walks were kept, so every pairing ends on the border, a seed or where
    // a sure field's cable ends. These seeds' floor rises above any cable's, but a walk
    // the field is sure of needs only what an end's cable needs; a hypothesis below its
    // floor could only have claimed ends from others below it, so dropping it in the
    // pairing keeps the rest.
    let floor = min_score.max(p.cable_score_floor(field));
    let sure = field.then_some((p.field_border_sure_level, p.cable_score_floor(field)));
    // Walks from the border are not joined where they leave it again (no field given),
    // and these seeds are no cable's ends, so a cable may run on behind them.
    let picked = pairing::pair(
        &crossing,
        &confidence,
        p,
        Floor {
            sure,
            ..Floor::new(floor)
        },
        1.0,
        None,
    );
    let seed_scene = Scene {
        walks: &crossing,
        seeds,
        ..*scene
    };
    let modelled: Vec<Cable> = if chained {
        let centroid = |v: u32| terrain.graph.vertices[v as usize].centroid;
        let mut courses = chain(&crossing, &picked, &links, centroid, (p, floor));
        if p.field_orphan_run_on {
            // The ways on ([`extend`] takes those that lost the cable or left the
            // frame): as long as a crossing walk and as little over cables already found.
            let ways_on: Vec<Walk> = links
                .into_iter()
                .filter(|w| w.length_px >= min_length && unexplained(w))
                .collect();
            extend(&mut courses, &ways_on, centroid, (p, floor));
        }
        courses
            .iter()
            .filter_map(|course| model_course(&seed_scene, course))
            .collect()
    } else {
        picked
            .iter()
            .filter_map(|c| model_cable(&seed_scene, c))
            .collect()
    };
    let cables = modelled
        .into_iter()
        .filter(|c| {
            c.ridge_share >= p.min_ridge_share || lies_over_twins(c, terrain.lab, scene.image, p)
        })
        .filter(|c| !along_one_side(&c.polyline, sp.width, sp.height, p.border_margin_px))
        .map(|mut cable| {
            cable.end_indices = [None, None];
            cable
        })
        .collect();
    Ok(SeedCables {
        cables,
        walks: crossing,
        picked,
    })
}

/// What tells a cable crossing the border from background.
#[derive(Clone, Copy)]
pub enum Evidence<'a> {
    /// Colour: a border superpixel whose mean colour differs from the border's median
    /// by `border_min_contrast` (Lab ΔE).
    Colour(&'a Graph),
    /// The cable field: probability at least `field_level`.
    Field(&'a CableField),
}

/// Seeds on the border where an unexplained cable may cross it, by `evidence`, and how
/// many of them (the first) a walk may end at ([`seeds_where`]); `covered[v]` marks
/// the superpixels already explained by a cable.
pub fn border_seeds(
    evidence: Evidence<'_>,
    sp: &Superpixels,
    covered: &[bool],
    params: &Params,
) -> (Vec<Seed>, usize) {
    seeds_where(sp, params, |ring, labels| {
        let cable: Vec<bool> = match evidence {
            Evidence::Colour(graph) => {
                let colours: Vec<[f32; 3]> = labels
                    .iter()
                    .map(|&v| graph.vertices[v as usize].mean_lab)
                    .collect();
                let mut background = [0.0; 3];
                for (c, b) in background.iter_mut().enumerate() {
                    let mut channel: Vec<f32> = colours.iter().map(|l| l[c]).collect();
                    *b = median(&mut channel, f32::total_cmp).unwrap_or(0.0);
                }
                colours
                    .iter()
                    .map(|&lab| dist3(lab, background) >= params.border_min_contrast)
                    .collect()
            }
            Evidence::Field(field) => ring
                .iter()
                .map(|&[x, y]| field.cable_at(x as f32, y as f32) >= params.field_level)
                .collect(),
        };
        cable
            .iter()
            .zip(labels)
            .map(|(&c, &v)| c && !covered[v as usize])
            .collect()
    })
}

/// One seed in the middle of every run of perimeter pixels that `stands_out` marks
/// (given the ring and each ring pixel's superpixel), when the run is as long as a
/// cable crossing (`border_min_crossing_px` ..= `border_max_crossing_px`), and after
/// those, one in each run up to `border_max_start_px` long; returns the seeds and how
/// many are crossings. A run may wrap past the ring's start. A cable crossing at a
/// grazing angle, or through a corner, stands out along more of the border than one
/// crossing it squarely, and its crossing lies somewhere along the run rather than in
/// its middle: walks start there, but a walk reaching the run ends on the border
/// itself, not at its middle (docs/ENGINE.md, "A grazing crossing of the border").
fn seeds_where(
    sp: &Superpixels,
    params: &Params,
    stands_out: impl FnOnce(&[[usize; 2]], &[u32]) -> Vec<bool>,
) -> (Vec<Seed>, usize) {
    let (w, h) = (sp.width, sp.height);
    if w < 3 || h < 3 {
        return (Vec::new(), 0);
    }
    let ring = perimeter(w, h);
    let labels: Vec<u32> = ring.iter().map(|&[x, y]| sp.labels[y * w + x]).collect();
    let stands_out = stands_out(&ring, &labels);
    let (shortest, longest) = (
        params.border_min_crossing_px as usize,
        params.border_max_crossing_px as usize,
    );
    let longest_start = (params.border_max_start_px as usize).max(longest);
    let mut seeds = Vec::new();
    let mut starts = Vec::new();
    for (mid, run) in marked_runs(&stands_out) {
        if (shortest..=longest_start).contains(&run) {
            let [x, y] = ring[mid];
            let seed = Seed {
                point: [x as f32, y as f32],
                vertex: labels[mid],
            };
            if run <= longest {
                seeds.push(seed);
            } else {
                starts.push(seed);
            }
        }
    }
    let crossings = seeds.len();
    seeds.extend(starts);
    (seeds, crossings)
}

/// The runs of marked positions around a ring (`marked[i]` for its i-th position; a
/// run may wrap past the ring's start), in ring order from its first unmarked
/// position, each as the index of its middle and its length; none when every position
/// is marked.
pub(super) fn marked_runs(marked: &[bool]) -> Vec<(usize, usize)> {
    let n = marked.len();
    let Some(start) = (0..n).find(|&i| !marked[i]) else {
        return Vec::new();
    };
    let mut runs = Vec::new();
    let mut i = 0;
    while i < n {
        if !marked[(start + i) % n] {
            i += 1;
            continue;
        }
        let run = (i..n).take_while(|&j| marked[(start + j) % n]).count();
        runs.push(((start + i + run / 2) % n, run));
        i += run;
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::color::LabImage;
    use crate::engine::superpixels::{SlicSettings, slic};

    #[test]
    fn perimeter_visits_every_border_pixel_once() {
        let p = perimeter(5, 4);
        assert_eq!(p.len(), 2 * 5 + 2 * 4 - 4);
        let mut sorted = p.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), p.len());
    }

    #[test]
    fn a_stripe_crossing_the_frame_gives_two_border_seeds() {
        // A dark 8 px stripe from the top edge to the bottom edge on a light background.
        let (w, h) = (96, 72);
        let mut rgb = vec![230u8; w * h * 3];
        for y in 0..h {
            for x in 44..52 {
                rgb[(y * w + x) * 3..(y * w + x) * 3 + 3].copy_from_slice(&[30, 30, 160]);
            }
        }
        let mut lab = LabImage::from_rgb(&rgb, w, h);
        lab.gaussian_blur(1.0);
        let sp = slic(
            &lab,
            &SlicSettings {
                n_segments: 150,
                compactness: 10.0,
                iterations: 10,
                min_size_factor: 0.25,
            },
        );
        let graph = Graph::build(&sp, &rgb, &lab, 4);
        let p = Params::default();
        let (seeds, crossings) =
            border_seeds(Evidence::Colour(&graph), &sp, &vec![false; graph.len()], &p);
        assert_eq!((seeds.len(), crossings), (2, 2), "{seeds:?}");
        assert!(seeds.iter().all(|s| (44.0..52.0).contains(&s.point[0])));
        // Once the stripe is explained, nothing is left to seed.
        let (none, _) = border_seeds(Evidence::Colour(&graph), &sp, &vec![true; graph.len()], &p);
        assert!(none.is_empty());
    }

    /// A plain grey `w` x `h` image in Lab and its superpixels (about `n` of them).
    fn plain(w: usize, h: usize, n: u32) -> (LabImage, Superpixels) {
        let lab = LabImage::from_rgb(&vec![200u8; w * h * 3], w, h);
        let settings = SlicSettings {
            n_segments: n,
            compactness: 10.0,
            iterations: 5,
            min_size_factor: 0.25,
        };
        let sp = slic(&lab, &settings);
        (lab, sp)
    }

    #[test]
    fn a_field_cable_crossing_the_frame_gives_two_border_seeds() {
        // The field sees a vertical cable in grid column 5 (x 40..48) from top to bottom;
        // the image itself is plain, so colour alone would see nothing.
        let (w, h) = (96usize, 72usize);
        let (lab, sp) = plain(w, h, 150);
        let (gw, gh) = (w / 8, h / 8);
        let field = CableField {
            width: gw,
            height: gh,
            cell_px: [8.0, 8.0],
            cable: (0..gw * gh)
                .map(|i| if i % gw == 5 { 0.9 } else { 0.0 })
                .collect(),
            orientation: vec![[-1.0, 0.0]; gw * gh],
        };
        let p = Params::default();
        let uncovered = vec![false; sp.count];
        let (seeds, crossings) = border_seeds(Evidence::Field(&field), &sp, &uncovered, &p);
        assert_eq!((seeds.len(), crossings), (2, 2), "{seeds:?}");
        assert!(seeds.iter().all(|s| (36.0..52.0).contains(&s.point[0])));
        let graph = Graph::build(&sp, &vec![200u8; w * h * 3], &lab, 4);
        let (none, _) = border_seeds(Evidence::Colour(&graph), &sp, &uncovered, &p);
        assert!(none.is_empty());
    }

    #[test]
    fn a_longer_run_starts_walks_but_ends_none() {
        // Runs along the top edge of 20 px (a cable crossing it), 50 px (one crossing at
        // a grazing angle) and 100 px (something lying along the edge).
        let (_, sp) = plain(320, 60, 100);
        let p = Params::default();
        let runs = [(10, 30), (60, 110), (150, 250)];
        let (seeds, crossings) = seeds_where(&sp, &p, |ring, _| {
            ring.iter()
                .map(|&[x, y]| y == 0 && runs.iter().any(|&(a, b)| (a..b).contains(&x)))
                .collect()
        });
        assert_eq!(crossings, 1, "{seeds:?}");
        let xs: Vec<f32> = seeds.iter().map(|s| s.point[0]).collect();
        assert_eq!(xs, [20.0, 85.0], "{seeds:?}");
    }
}
