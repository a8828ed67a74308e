//! A cable that loops over itself. Where a cable turns a full circle it crosses itself,
//! and there its way on and the way into the loop both continue it smoothly: the walk
//! takes the straighter, across the crossing, and leaves the loop out (found as a
//! cable of its own from the ends of its unexplained piece of field, or not at all).
//! The field still shows the loop: a piece of cable that leaves the cable and comes
//! back to it where it left, with no end on it. Such a piece is walked round (the
//! cheapest course over its superpixels from where it leaves the cable to where it
//! comes back, a superpixel costing more the further its colour is from the cable's,
//! so that the course keeps to the loop where other cables cross it rather than
//! taking a short cut along one of them) and spliced into the cable: the cable runs
//! to where the loop leaves it, round the loop, and on from where the loop comes
//! back, crossing itself there, and is fitted and refined again. A loop of another
//! colour is another cable's. A cable found along the loop alone is that loop, and is
//! dropped. Where no loop shows, the field is searched again at a fainter level, for
//! a loop of the cable's colour more closely: a pale or thin loop. Once every cable's
//! loop that leaves and comes back close together is taken, the cables with none take
//! a rounder loop that leaves and comes back farther apart, if the same search found
//! one: a wide loop met tangentially, whose arc nearest the cable the walk follows.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::Cable;
use super::Params;
use super::cable::{Fitted, LOOP_MIN_WIDTHS, drop_cables, fit_refined, median_rgb};
use super::color::LabImage;
use super::field::VertexField;
use super::geometry::{
    arc_lengths, dist, dist3, median_colour_of, points_near, points_near_any, polyline_length,
};
use super::graph::Graph;
use super::spline::resample;
use super::superpixels::Superpixels;
use super::walk::Seed;

/// How far along its cable a loop may leave and come back, and how round it must be.
#[derive(Clone, Copy)]
struct Span {
    /// Where the loop leaves its cable and where it comes back lie at most this many
    /// nominal widths apart along the cable.
    along: f32,
    /// Least roundness of the loop (4π times the area its course encloses, closed at
    /// the crossing, over its perimeter squared: 1 for a circle, 0 for a course that
    /// runs out along something and back).
    roundness: f32,
}

/// The first search: the crossing, and the stretch either side of it where the two
/// branches still touch at a shallow crossing.
const CLOSE: Span = Span {
    along: 12.0,
    roundness: 0.4,
};

/// The second, for the cables with no loop that closes: a wide loop that meets its
/// cable tangentially, whose arc nearest the cable the walk follows, leaves and comes
/// back farther apart along it. It must be rounder: within such a span a course also
/// runs out along a cable of the same colour beside this one (a twin, a neighbour) and
/// back, a lens between two cables, and a cable that only touches another's loop could
/// claim it.
/// On the stress scenes (seeds 11-22) the wide loops taken read 0.68-0.93 round, the
/// false courses 0.40-0.41. Found in the same search as the close loop, but taken
/// only after every cable's close loop is, and only for cables with none: the longest
/// course within a wide span can start on the cable's straight run before its loop.
const WIDE: Span = Span {
    along: 16.0,
    roundness: 0.6,
};

/// Where a loop leaves and comes back lie at least this many nominal widths from the
/// cable's ends: a cable ending there is no cable crossing itself.
const END_MARGIN: f32 = 2.0;
/// The loop reaches at least this many nominal widths from the crossing.
const MIN_REACH: f32 = 3.0;
/// Spacing of the data points fitted along a loop, pixels: far denser than the
/// superpixels along the rest of the cable, so that the fit's smoothing, made for
/// bends no tighter than a cable's usual ones, does not shrink the loop.
const LOOP_SPACING_PX: f32 = 2.0;
/// Most of the loop's course that may lie along other cables (those crossing it).
const ALONG_SHARE: f32 = 0.4;
/// A cable with at most this share of its length away from the loop is the loop
/// found on its own.
const OWN_SHARE: f32 = 0.3;
/// CIELAB distance from the cable's colour at which a superpixel costs a loop's
/// course twice as much as one of the cable's colour (the cost grows with its square):
/// the course goes round the loop rather than along another cable across it.
const COURSE_DE: f32 = 15.0;
/// How sure of a loop's course the search must be: the share of `field_orphan_level` a
/// superpixel's cable probability needs to lie on the course (where the loop leaves its
/// cable and comes back to it included), and the largest CIELAB distance between the
/// median colours of the course's superpixels and of its cable's.
struct Strictness {
    /// Least cable probability on the course, as a share of `field_orphan_level`.
    field_share: f32,
    /// Largest CIELAB distance of the course's colour from its cable's.
    max_colour_de: f32,
}

/// The first search. A loop's tight bend, the places where other cables cross it and
/// those where it touches its cable read fainter than a straight cable in the open (a
/// thin loop leaving its cable at a shallow angle read 0.46 and 0.32 there). A cable's
/// loop is its own colour, while a course of another colour is another cable's loop or
/// a ring closed by several cables (synthetic `LoopCrossedByAnother` from a photo
/// alone: 8-17 for the blue cable's own loop, about 100 for the same loop read from the
/// orange cable).
const USUAL: Strictness = Strictness {
    field_share: 0.6,
    max_colour_de: 30.0,
};

/// The second search, where the first finds none: a pale or thin loop that the field
/// reads fainter still (a white loop on orange card, 0.2-0.3 over its superpixels; a
/// course with one such gap), taken only where its colour is its cable's more closely.
/// On the stress scenes (seeds 11-21) the faint loops taken lay ΔE 1-8 from their
/// cables' colour; the false courses a bar of 30 let in (across a same-colour twin,
/// between another cable's loop and the cable) ΔE 21-27.
const FAINT: Strictness = Strictness {
    field_share: 0.4,
    max_colour_de: 15.0,
};

/// A cable found along a loop is the loop found on its own where it lies within this
/// many of its widths (beyond the half width and half superpixel of the other checks)
/// of the loop's course: walked along the loop's inner side, a superpixel in.
const OWN_REACH_WIDTHS: f32 = 0.5;

/// What finding loops reads: the image, its superpixels and graph, the field on
/// them, the given ends and the parameters.
#[derive(Clone, Copy)]
pub(super) struct Ground<'a> {
    pub graph: &'a Graph,
    pub sp: &'a Superpixels,
    pub field: &'a [VertexField],
    pub seeds: &'a [Seed],
    pub lab: &'a LabImage,
    pub image: &'a image::RgbImage,
    pub params: &'a Params,
}

/// Splices into every cable of `cables` the loop it was walked across (module docs),
/// drops the cables found along those loops alone and renumbers the rest;
/// `end_cables` (given end to cable) follows.
pub(super) fn close_loops(
    cables: &mut Vec<Cable>,
    end_cables: &mut [Option<usize>],
    ground: Ground<'_>,
) {
    let mut dropped = vec![false; cables.len()];
    // Each cable's wide loop is found with its close one, and taken, where it still
    // may be, once every close one is.
    let mut wide = Vec::with_capacity(cables.len());
    for i in 0..cables.len() {
        let [close, far] = if dropped[i] {
            [None, None]
        } else {
            find_loops(&cables[i], ground)
        };
        let looped = close.is_some_and(|c| close_loop(cables, i, c, &mut dropped, ground));
        wide.push(far.filter(|_| !looped));
    }
    for (i, course) in wide.into_iter().enumerate() {
        if let Some(course) = course.filter(|_| !dropped[i]) {
            close_loop(cables, i, course, &mut dropped, ground);
        }
    }
    drop_cables(cables, end_cables, &dropped);
}

/// Splices `course`, a loop cable `i` was walked across, into it, unless the loop runs
/// along other cables (theirs); marks in `dropped` the cables found along that loop
/// alone. Whether it did.
fn close_loop(
    cables: &mut [Cable],
    i: usize,
    course: LoopCourse,
    dropped: &mut [bool],
    ground: Ground<'_>,
) -> bool {
    // The loop's own: cables along it with little of themselves elsewhere. The rest
    // may cross it, but a piece that runs along them is theirs.
    let tolerance =
        |c: &Cable| 0.5 * c.width_px.max(ground.params.nominal_width_px) + 0.5 * ground.sp.step;
    let dense = resample(&course.points, 2.0);
    let others: Vec<usize> = (0..cables.len())
        .filter(|&j| j != i && !dropped[j])
        .collect();
    let (alone, crossing): (Vec<usize>, Vec<usize>) = others.into_iter().partition(|&j| {
        let other = &cables[j];
        let reach = tolerance(other) + OWN_REACH_WIDTHS * other.width_px;
        share_near(&other.polyline, &dense, reach) >= 1.0 - OWN_SHARE
    });
    let crossing: Vec<(&[[f32; 2]], f32)> = crossing
        .iter()
        .map(|&j| (&cables[j].polyline[..], tolerance(&cables[j])))
        .collect();
    let on_others = points_near_any(&dense, &crossing);
    let owned = on_others as f32 > ALONG_SHARE * dense.len() as f32;
    if owned {
        return false;
    }
    let Some(spliced) = splice(&cables[i], &course, ground) else {
        return false;
    };
    cables[i] = spliced;
    for j in alone {
        dropped[j] = true;
    }
    true
}

/// A loop found beside a cable: its course from where it leaves the cable (at arc
/// length `leaves` along the cable's polyline) round to where it comes back (`returns`).
#[derive(Clone)]
struct LoopCourse {
    /// Superpixel centroids along the loop.
    points: Vec<[f32; 2]>,
    /// Arc length along the cable where the loop leaves it.
    leaves: f32,
    /// Arc length along the cable where the loop comes back to it.
    returns: f32,
}

/// The loops `cable` was walked across, if the field shows them (module docs), within
/// [`CLOSE`] and within [`WIDE`]: for each, the longest of the cheapest courses
/// ([`cheapest`], [`COURSE_DE`]) over superpixels the field calls cable and the cable
/// does not cover, between two that touch the cable at most the span's `along` nominal
/// widths apart along it and [`END_MARGIN`] from its ends, at least
/// [`LOOP_MIN_WIDTHS`] long, reaching [`MIN_REACH`] from the crossing, at least the
/// span's `roundness` round, all in view, with no given end on it and of the cable's
/// colour: searched as sure as [`USUAL`], then, where that finds none, as [`FAINT`].
fn find_loops(cable: &Cable, ground: Ground<'_>) -> [Option<LoopCourse>; 2] {
    let Ground {
        graph, sp, field, ..
    } = ground;
    let p = ground.params;
    let nominal = p.nominal_width_px;
    let line = &cable.polyline;
    if line.len() < 2 {
        return [None, None];
    }
    let on = covered_by(
        line,
        0.5 * cable.width_px.max(nominal) + 0.5 * sp.step,
        ground,
    );
    let arc = arc_lengths(line);
    let centroid = |v: u32| graph.vertices[v as usize].centroid;
    let along = |q: [f32; 2]| {
        let nearest = (0..line.len())
            .min_by(|&a, &b| dist(line[a], q).total_cmp(&dist(line[b], q)))
            .unwrap_or(0);
        arc[nearest]
    };
    let [w, h] = [sp.width as f32, sp.height as f32];
    let in_view = |[x, y]: [f32; 2]| x.min(y).min(w - x).min(h - y) > sp.step;
    let no_end = |q: [f32; 2]| {
        ground
            .seeds
            .iter()
            .all(|s| dist(s.point, q) > p.close_radius_px)
    };
    // The cable's colour as its superpixels read it (mixed with the background's
    // where it is thin, as the loop's are).
    let under: Vec<u32> = line.iter().filter_map(|&q| label_under(sp, q)).collect();
    let Some(colour) = median_lab(graph, &under) else {
        return [None, None];
    };
    let unlike = |v: u32| dist3(graph.vertices[v as usize].mean_lab, colour) / COURSE_DE;
    let step_cost = |v: u32| 1.0 + unlike(v).powi(2);
    let mut cost = vec![f32::INFINITY; graph.len()];
    let mut parent = vec![0; graph.len()];
    let total = arc[arc.len() - 1];
    let margin = END_MARGIN * nominal;
    let spans = [CLOSE, WIDE];
    let widest = spans.iter().map(|s| s.along).fold(0.0, f32::max);
    let mut found = [None, None];
    for strictness in [&USUAL, &FAINT] {
        // Fainter field than an orphan's: colour keeps the course on its cable.
        let free = |v: u32| {
            field[v as usize].cable >= strictness.field_share * p.field_orphan_level
                && !on[v as usize]
        };
        // Free superpixels next to the cable, with where along it they touch it.
        let touching: Vec<(u32, f32)> = (0..graph.len() as u32)
            .filter(|&v| free(v) && graph.neighbours(v).iter().any(|&u| on[u as usize]))
            .map(|v| (v, along(centroid(v))))
            .filter(|&(_, s)| s >= margin && s <= total - margin)
            .collect();
        let of_its_colour = |course: &[u32]| {
            median_lab(graph, course).is_some_and(|c| dist3(c, colour) <= strictness.max_colour_de)
        };
        let mut best: [Option<(f32, LoopCourse)>; 2] = [None, None];
        for &(a, sa) in &touching {
            let order = cheapest(graph, a, &free, &step_cost, &mut cost, &mut parent);
            for &(b, sb) in &touching {
                if b == a || cost[b as usize].is_infinite() || (sa - sb).abs() > widest * nominal {
                    continue;
                }
                let mut course = vec![b];
                while let Some(&v) = course.last().filter(|&&v| v != a) {
                    course.push(parent[v as usize]);
                }
                course.reverse();
                let points: Vec<[f32; 2]> = course.iter().map(|&v| centroid(v)).collect();
                let length = polyline_length(&points);
                let crossing = line[arc
                    .partition_point(|&s| s < 0.5 * (sa + sb))
                    .min(line.len() - 1)];
                let reach = points
                    .iter()
                    .map(|&q| dist(q, crossing))
                    .fold(0.0, f32::max);
                if length < LOOP_MIN_WIDTHS * nominal || reach < MIN_REACH * nominal {
                    continue;
                }
                let round = roundness(&points);
                // The spans this course may be the best of so far.
                let open: [bool; 2] = std::array::from_fn(|k| {
                    found[k].is_none()
                        && (sa - sb).abs() <= spans[k].along * nominal
                        && round >= spans[k].roundness
                        && best[k].as_ref().is_none_or(|(l, _)| *l < length)
                });
                if !open.contains(&true)
                    || !points.iter().all(|&q| in_view(q) && no_end(q))
                    || !of_its_colour(&course)
                {
                    continue;
                }
                let course = LoopCourse {
                    points,
                    leaves: sa,
                    returns: sb,
                };
                for (slot, _) in best.iter_mut().zip(open).filter(|&(_, o)| o) {
                    *slot = Some((length, course.clone()));
                }
            }
            for &v in &order {
                cost[v as usize] = f32::INFINITY;
            }
        }
        for (slot, best) in found.iter_mut().zip(best) {
            if slot.is_none() {
                *slot = best.map(|(_, course)| course);
            }
        }
        if found.iter().all(Option::is_some) {
            break;
        }
    }
    found
}

/// The superpixel under the point `q`, if it lies in the image.
fn label_under(sp: &Superpixels, q: [f32; 2]) -> Option<u32> {
    let (x, y) = (q[0].round(), q[1].round());
    let inside = x >= 0.0 && y >= 0.0 && (x as usize) < sp.width && (y as usize) < sp.height;
    inside.then(|| sp.labels[y as usize * sp.width + x as usize])
}

/// Per-channel median of the mean colours of `vertices`.
fn median_lab(graph: &Graph, vertices: &[u32]) -> Option<[f32; 3]> {
    let colours: Vec<[f32; 3]> = vertices
        .iter()
        .map(|&u| graph.vertices[u as usize].mean_lab)
        .collect();
    median_colour_of(&colours)
}

/// Cheapest courses from `source` over the superpixels `inside` marks, entering each
/// at `step_cost` (Dijkstra): every one reached, in order, with its cost in `cost`
/// and the superpixel it was reached from (the source: itself) in `parent`. `cost`
/// must be infinite wherever this reaches.
fn cheapest(
    graph: &Graph,
    source: u32,
    inside: &impl Fn(u32) -> bool,
    step_cost: &impl Fn(u32) -> f32,
    cost: &mut [f32],
    parent: &mut [u32],
) -> Vec<u32> {
    let mut order = vec![source];
    cost[source as usize] = 0.0;
    parent[source as usize] = source;
    // Costs are never negative, so their bit patterns order as they do.
    let mut queue = BinaryHeap::from([Reverse((0.0f32.to_bits(), source))]);
    while let Some(Reverse((bits, v))) = queue.pop() {
        if bits != cost[v as usize].to_bits() {
            continue;
        }
        for &u in graph.neighbours(v) {
            let through = f32::from_bits(bits) + step_cost(u);
            if inside(u) && through < cost[u as usize] {
                if cost[u as usize].is_infinite() {
                    order.push(u);
                }
                cost[u as usize] = through;
                parent[u as usize] = v;
                queue.push(Reverse((through.to_bits(), u)));
            }
        }
    }
    order
}

/// For every superpixel, whether its centroid lies within `reach` of `line` (those
/// under the line and their neighbours are the only ones that can).
fn covered_by(line: &[[f32; 2]], reach: f32, ground: Ground<'_>) -> Vec<bool> {
    let Ground { graph, sp, .. } = ground;
    let mut on = vec![false; graph.len()];
    for &q in line {
        let Some(under) = label_under(sp, q) else {
            continue;
        };
        for &v in std::iter::once(&under).chain(graph.neighbours(under)) {
            if !on[v as usize] && dist(graph.vertices[v as usize].centroid, q) <= reach {
                on[v as usize] = true;
            }
        }
    }
    on
}

/// 4π times the area `points` enclose (closed from the last back to the first) over
/// their perimeter squared.
fn roundness(points: &[[f32; 2]]) -> f32 {
    let n = points.len();
    let twice_area: f32 = (0..n)
        .map(|k| {
            let (a, b) = (points[k], points[(k + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum();
    let perimeter = polyline_length(points) + dist(points[n - 1], points[0]);
    2.0 * std::f32::consts::PI * twice_area.abs() / (perimeter * perimeter).max(f32::EPSILON)
}

/// Share of the points of `line` within `tolerance` of a point of `other`.
fn share_near(line: &[[f32; 2]], other: &[[f32; 2]], tolerance: f32) -> f32 {
    points_near(line, other, tolerance) as f32 / line.len().max(1) as f32
}

/// `cable` run round `course`: its polyline to the later of where the loop leaves and
/// comes back (the way into the loop continues the cable ahead), round the loop, and
/// on from the earlier, crossing itself between them; fitted and refined again with
/// its ends held (and the denser knots of a cable that crosses itself,
/// [`fit_refined`]). `None` when the fit fails.
fn splice(cable: &Cable, course: &LoopCourse, ground: Ground<'_>) -> Option<Cable> {
    let p = ground.params;
    let line = &cable.polyline;
    let (into, back, round) = if course.leaves >= course.returns {
        (course.leaves, course.returns, course.points.clone())
    } else {
        let mut reversed = course.points.clone();
        reversed.reverse();
        (course.returns, course.leaves, reversed)
    };
    let arc = arc_lengths(line);
    // The last point at or before an arc length.
    let cut = |s: f32| arc.partition_point(|&a| a <= s).saturating_sub(1);
    let step = ground.sp.step;
    let mut points = resample(&line[..=cut(into)], step);
    points.extend(resample(&round, LOOP_SPACING_PX));
    points.extend(resample(&line[cut(back)..], step));
    let mut weights = vec![1.0; points.len()];
    let last = points.len() - 1;
    let ends = [line[0], line[line.len() - 1]];
    for (k, end) in [0, last].into_iter().zip(ends) {
        points[k] = end;
        weights[k] = p.end_weight;
    }
    let anchors = ends.map(|e| Some((e, p.end_weight)));
    let Fitted {
        spline,
        polyline,
        width,
        ridge_share,
    } = fit_refined(&points, &weights, anchors, ground.lab, p)?;
    Some(Cable {
        ends: [polyline[0], polyline[polyline.len() - 1]],
        length_px: polyline_length(&polyline),
        width_px: width.unwrap_or(cable.width_px),
        color: median_rgb(ground.image, &polyline),
        ridge_share: ridge_share.unwrap_or(cable.ridge_share),
        spline,
        polyline,
        ..cable.clone()
    })
}
