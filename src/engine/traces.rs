//! Cables the field shows where no walk could follow them. A thin dark wire on a dark
//! card is plain to the network, yet SLIC's colour term is too weak there to cut
//! superpixels along it: every superpixel next to its ends is mostly card, and the
//! walks from them are lost at their first step. Once the walks, the border and the
//! field's pieces have been tried, the field itself is followed from every end that
//! still has no cable, then from where the field's cables meet the frame's edge with
//! no cable found there: half-cell steps along the field's direction where the network
//! is sure of one, each moved across the heading to the top of the ridge of cable
//! probability, straight on over cables already found (where the field's direction
//! mixes both cables'), until the trace fades, arrives at an end with no cable or
//! leaves the frame. A trace that arrives or leaves is fitted and refined on the photo
//! like a walked cable, and kept when it reads as a cable there and does not repeat one
//! already found. Before them, a cable whose walk was lost short of an end and of the
//! frame runs on the same way from where it was lost ([`run_on_lost`]).

use image::RgbImage;

use super::Params;
use super::border::{marked_runs, perimeter};
use super::cable::{Cable, fit_refined, median_rgb};
use super::color::LabImage;
use super::field::CableField;
use super::geometry::{
    along_one_side, border_exit, border_inset, dist, heading, points_near_any, polyline_length,
    unit_or,
};

/// A trace's step, in field cells: fine enough to follow a bend of a cable a few cells
/// across.
const STEP_CELLS: f32 = 0.5;

/// How far beside a cable already found, in field cells past its half width, a trace
/// stops turning with the field (whose direction there mixes both cables').
const CROSSING_CELLS: f32 = 1.5;

/// Largest angle between a trace and a cable found near it, degrees, at which the
/// trace runs alongside that cable (repeats it there) rather than crossing it.
const ALONGSIDE_DEG: f32 = 30.0;

/// Length of the trace behind it, in field cells, whose direction a trace keeps
/// across a cable already found.
const CHORD_CELLS: f32 = 3.0;

/// Least confidence of the field's direction (the length of its (cos 2θ, sin 2θ)) that
/// turns a trace's heading, and the largest turn it makes per step, degrees.
const SURE_DIRECTION: f32 = 0.5;
const MAX_TURN_DEG: f32 = 30.0;

/// Least cosine between a start on the frame's edge and the edge's inward normal for
/// the start to take the field's direction (a cable crossing the edge within about 75°
/// of square); square to the edge otherwise.
const INTO_FRAME_COS: f32 = 0.25;

/// How far across its heading a trace looks for the top of the field's ridge after
/// each step, in field cells either way.
const RECENTRE_CELLS: f32 = 0.5;

/// Cable probability a point across the heading loses per pixel from the straight
/// course: at a crossing, the cable ahead and the one across are both cable, and the
/// one ahead wins.
const RECENTRE_COST: f32 = 0.01;

/// Steps in a row a trace may run under the level before it is taken to have faded
/// (a cell or two where the network's probability dips along a cable).
const MAX_WEAK_STEPS: usize = 3;

/// Radius, in field cells, of the ring around an end where a trace looks for the way
/// its cable leaves: past the end's metal tip, which the network need not call cable.
const OPENING_CELLS: f32 = 2.0;

/// Directions tried on that ring.
const OPENING_DIRECTIONS: usize = 48;

/// Share of a trace's centreline alongside cables already found ([`points_alongside`])
/// from which it repeats one.
const MAX_SHARED: f32 = 0.3;

/// Everything a trace reads.
#[derive(Clone, Copy)]
pub(super) struct Ground<'a> {
    /// The network's cable field.
    pub field: &'a CableField,
    /// The working image in CIELAB, blurred as the superpixels saw it.
    pub lab: &'a LabImage,
    /// The working image.
    pub image: &'a RgbImage,
    /// The engine's parameters.
    pub params: &'a Params,
    /// The superpixels' nominal step, pixels.
    pub step_px: f32,
    /// The working image's width and height, pixels.
    pub size: [usize; 2],
}

/// Appends to `cables` the cables traced in the field from ends that have none
/// (`end_cables[i]` is `None`), and then from where the field's cables meet the
/// frame's edge with no cable found there ([`border_starts`]), each to another such end
/// or out of the frame at least `field_orphan_min_steps` superpixel steps from where it
/// starts, and records them in `end_cables`. `confidence` holds the ends'
/// confidences. A traced cable scores the mean cable probability along its centreline
/// times the geometric mean of its two ends' confidences, its one end's when it has one
/// in view, or `border_seed_confidence` when it has none; it is kept from the floor of
/// every cable with a field (`field_min_cable_score`; `field_border_min_score` with no
/// end in view) when no more than [`MAX_SHARED`] of it lies within a field cell past
/// their half widths of a cable already found and runs its way, and, with no end in
/// view, when it does not run all along one side of the frame.
pub(super) fn trace_free_ends(
    cables: &mut Vec<Cable>,
    end_cables: &mut [Option<usize>],
    ends: &[[f32; 2]],
    confidence: &[f32],
    ground: Ground<'_>,
) {
    let params = ground.params;
    if params.field_trace_level >= 1.0 {
        return;
    }
    let cell = cell_side(ground.field);
    let free: Vec<usize> = (0..ends.len())
        .filter(|&i| end_cables[i].is_none())
        .collect();
    let mut starts: Vec<Start> = free
        .iter()
        .filter_map(|&a| {
            let dir = opening(
                ground.field,
                ends[a],
                OPENING_CELLS * cell,
                params.field_trace_level,
            )?;
            Some(Start {
                point: ends[a],
                dir,
                end: Some(a),
            })
        })
        .collect();
    if params.border_cables {
        starts.extend(border_starts(ground.field, ground.size, params));
    }
    run_on_lost(cables, end_cables, &free, ends, ground);
    for start in starts {
        if start.end.is_some_and(|a| end_cables[a].is_some()) {
            continue;
        }
        let targets: Vec<(usize, [f32; 2])> = free
            .iter()
            .filter(|&&b| Some(b) != start.end && end_cables[b].is_none())
            .map(|&b| (b, ends[b]))
            .collect();
        let Some(cable) = follow(&start, &targets, cables, confidence, ground) else {
            continue;
        };
        let id = cables.len();
        for i in cable.end_indices.into_iter().flatten() {
            end_cables[i] = Some(id);
        }
        cables.push(Cable { id, ..cable });
    }
}

/// Runs on along the field the cables whose walk was lost short of an end and of the
/// frame (an end of `cables` that is no given end and lies more than
/// `border_margin_px` inside the frame): from there, a trace the way the cable was
/// heading over its last [`CHORD_CELLS`] cells, to one of the `free` ends (indices into
/// `ends`) with no cable yet or out of the frame, at least `min_cable_length_px` on,
/// repeating no other cable, and for a cable with no given end, along which the field
/// is sure of a cable (a mean cable probability of at least `field_border_sure_level`:
/// the grout of a tiled floor can read as an unsure cable); the cable is then modelled
/// again over both, its score kept.
fn run_on_lost(
    cables: &mut [Cable],
    end_cables: &mut [Option<usize>],
    free: &[usize],
    ends: &[[f32; 2]],
    ground: Ground<'_>,
) {
    let (field, params) = (ground.field, ground.params);
    let cell = cell_side(field);
    let [width, height] = ground.size;
    let margin = params.border_margin_px;
    for k in 0..cables.len() {
        for side in 0..2 {
            let cable = &cables[k];
            let mut line = cable.polyline.clone();
            if side == 0 {
                line.reverse();
            }
            let end = line[line.len() - 1];
            if cable.end_indices[side].is_some() || border_inset(end, width, height) < margin {
                continue;
            }
            if line.len() < 2 {
                continue;
            }
            let dir = heading(&line, CHORD_CELLS * cell);
            let targets: Vec<(usize, [f32; 2])> = free
                .iter()
                .filter(|&&b| end_cables[b].is_none())
                .map(|&b| (b, ends[b]))
                .collect();
            let others = crossing_zones(cables, Some(cable.id), cell);
            let start = Start {
                point: end,
                dir,
                end: None,
            };
            let Some((far, points)) = trace(field, &start, &targets, &others, params) else {
                continue;
            };
            let sure = || {
                let sum: f32 = points.iter().map(|p| field.cable_at(p[0], p[1])).sum();
                sum / points.len() as f32 >= params.field_border_sure_level
            };
            if polyline_length(&points) < params.min_cable_length_px
                || (cable.end_indices[1 - side].is_none() && !sure())
            {
                continue;
            }
            if repeats(&points, cable.width_px, cables, Some(cable.id), cell) {
                continue;
            }
            line.extend_from_slice(&points[1..]);
            let mut ids = [cable.end_indices[1 - side], far];
            if side == 0 {
                line.reverse();
                ids.reverse();
            }
            let Some(longer) = model(&line, ids, ground) else {
                continue;
            };
            if let Some(b) = far {
                end_cables[b] = Some(cable.id);
            }
            cables[k] = Cable {
                id: cable.id,
                score: cable.score,
                twin_ends: cable.twin_ends,
                ..longer
            };
        }
    }
}

/// The lines of `cables` (but the one of id `except`), each with the reach within
/// which a trace near it crosses it: its half width and [`CROSSING_CELLS`] cells of
/// `cell` pixels.
fn crossing_zones(cables: &[Cable], except: Option<usize>, cell: f32) -> Vec<(&[[f32; 2]], f32)> {
    cables
        .iter()
        .filter(|c| Some(c.id) != except)
        .map(|c| (&c.polyline[..], 0.5 * c.width_px + CROSSING_CELLS * cell))
        .collect()
}

/// Whether `line`, a cable `width` pixels wide, repeats one of `cables` (but the one
/// of id `except`): more than [`MAX_SHARED`] of its points lie within a cell (`cell`
/// pixels) past their half widths of one of them and run its way ([`points_alongside`]).
fn repeats(
    line: &[[f32; 2]],
    width: f32,
    cables: &[Cable],
    except: Option<usize>,
    cell: f32,
) -> bool {
    let found: Vec<(&[[f32; 2]], f32)> = cables
        .iter()
        .filter(|c| Some(c.id) != except)
        .map(|c| (&c.polyline[..], 0.5 * (c.width_px + width) + cell))
        .collect();
    points_alongside(line, &found) as f32 > MAX_SHARED * line.len() as f32
}

/// The mean side of one of `field`'s cells, pixels.
fn cell_side(field: &CableField) -> f32 {
    0.5 * (field.cell_px[0] + field.cell_px[1])
}

/// Where a trace starts: a point, the way it sets off, and the given end it is, if any
/// (otherwise a point on the frame's edge).
struct Start {
    point: [f32; 2],
    dir: [f32; 2],
    end: Option<usize>,
}

/// The cable traced from `start` to one of `targets` (free ends, an index and its
/// point) or out of the frame, as [`trace_free_ends`] keeps it; `None` when the trace
/// fades or its cable is not kept.
fn follow(
    start: &Start,
    targets: &[(usize, [f32; 2])],
    cables: &[Cable],
    confidence: &[f32],
    ground: Ground<'_>,
) -> Option<Cable> {
    let (field, params) = (ground.field, ground.params);
    let cell = cell_side(field);
    let min_apart = params.field_orphan_min_steps * ground.step_px;
    let targets: Vec<(usize, [f32; 2])> = targets
        .iter()
        .copied()
        .filter(|&(_, t)| dist(start.point, t) >= min_apart)
        .collect();
    let crossed = crossing_zones(cables, None, cell);
    // Where a cable found meets the edge, the field's run is that cable's.
    if start.end.is_none() && points_near_any(&[start.point], &crossed) > 0 {
        return None;
    }
    let (far, points) = trace(field, start, &targets, &crossed, params)?;
    if dist(points[0], points[points.len() - 1]) < min_apart {
        return None;
    }
    let ids = [start.end, far];
    let mut cable = model(&points, ids, ground)?;
    let repeated = repeats(&cable.polyline, cable.width_px, cables, None, cell);
    let given: Vec<f32> = ids.into_iter().flatten().map(|i| confidence[i]).collect();
    cable.score *= match given[..] {
        [a, b] => (a * b).sqrt(),
        [a] => a,
        _ => params.border_seed_confidence,
    };
    let (floor, [w, h]) = (
        if given.is_empty() {
            params.field_border_min_score
        } else {
            params.field_min_cable_score
        },
        ground.size,
    );
    let kept = !repeated
        && cable.score >= floor
        && !(given.is_empty() && along_one_side(&cable.polyline, w, h, params.border_margin_px));
    kept.then_some(cable)
}

/// Where the field's cables meet the frame's edge: one start in the middle of every run
/// of edge pixels whose cable probability reaches `field_trace_level`, as long as a
/// cable crossing (`border_min_crossing_px` ..= `border_max_crossing_px`), heading
/// into the frame along the field's direction there where it is sure of one and that
/// points into the frame ([`INTO_FRAME_COS`]), square to the edge otherwise. `size` is
/// the image's width and height.
fn border_starts(field: &CableField, size: [usize; 2], params: &Params) -> Vec<Start> {
    let [w, h] = size;
    // The edge pixels' centres, clockwise from the top left corner, with the inward
    // normal of their side (a corner counts to the side the ring reaches it along).
    let ring: Vec<([f32; 2], [f32; 2])> = perimeter(w, h)
        .into_iter()
        .map(|[x, y]| {
            let inward = if y == 0 {
                [0.0, 1.0]
            } else if x == w - 1 {
                [-1.0, 0.0]
            } else if y == h - 1 {
                [0.0, -1.0]
            } else {
                [1.0, 0.0]
            };
            ([x as f32 + 0.5, y as f32 + 0.5], inward)
        })
        .collect();
    let on: Vec<bool> = ring
        .iter()
        .map(|(p, _)| field.cable_at(p[0], p[1]) >= params.field_trace_level)
        .collect();
    let crossing = params.border_min_crossing_px as usize..=params.border_max_crossing_px as usize;
    marked_runs(&on)
        .into_iter()
        .filter(|(_, run)| crossing.contains(run))
        .map(|(mid, _)| {
            let (point, inward) = ring[mid];
            let dir = field_direction(field, point, inward, INTO_FRAME_COS).unwrap_or(inward);
            Start {
                point,
                dir,
                end: None,
            }
        })
        .collect()
}

/// The cable along `points` (a trace from end `ids[0]` to end `ids[1]`, a point on the
/// frame's edge where one is `None`: its first and last point), fitted and refined
/// with both held; `None` when it cannot be fitted, is shorter than
/// `min_cable_length_px`, reads a ridge (a cable on its background, not a step between
/// two backgrounds) on fewer than `ended_min_ridge_share` of its profiles
/// (`min_ridge_share`, as a cable with no end, when an end lies on the edge) or lies on
/// cable pixels for less than `field_min_share` of its length. Its score is the mean
/// cable probability along it.
fn model(points: &[[f32; 2]], ids: [Option<usize>; 2], ground: Ground<'_>) -> Option<Cable> {
    let Ground {
        field,
        lab,
        image,
        params,
        ..
    } = ground;
    let mut weights = vec![1.0; points.len()];
    let last = points.len() - 1;
    weights[0] = params.end_weight;
    weights[last] = params.end_weight;
    let anchors = [points[0], points[last]].map(|p| Some((p, params.end_weight)));
    let fitted = fit_refined(points, &weights, anchors, lab, params)?;
    let polyline = fitted.polyline;
    let length_px = polyline_length(&polyline);
    let ridge_share = fitted.ridge_share.unwrap_or(1.0);
    if length_px < params.min_cable_length_px
        || ridge_share
            < if ids.iter().all(Option::is_some) {
                params.ended_min_ridge_share
            } else {
                params.min_ridge_share
            }
        || field.share_on_cable(&polyline, params.field_level) < params.field_min_share
    {
        return None;
    }
    let mean_cable = polyline
        .iter()
        .map(|p| field.cable_at(p[0], p[1]))
        .sum::<f32>()
        / polyline.len() as f32;
    Some(Cable {
        id: 0,
        ends: [polyline[0], polyline[polyline.len() - 1]],
        end_indices: ids,
        twin_ends: [None, None],
        color: median_rgb(image, &polyline),
        spline: fitted.spline,
        width_px: fitted.width.unwrap_or(params.nominal_width_px),
        length_px,
        polyline,
        ridge_share,
        score: mean_cable.clamp(0.0, 1.0),
    })
}

/// Follows the field from `start` up its ridge of cable probability at least
/// `field_trace_level`: returns the first of `targets` (an index and its point) that
/// the trace comes within `close_radius_px` of once it has run `min_cable_length_px`,
/// with the trace's points from `start` to that target's point, or `None` for the
/// target and the points to where it leaves the frame; `None` when it fades or runs
/// longer than the frame's perimeter first.
fn trace(
    field: &CableField,
    start: &Start,
    targets: &[(usize, [f32; 2])],
    found: &[(&[[f32; 2]], f32)],
    params: &Params,
) -> Option<(Option<usize>, Vec<[f32; 2]>)> {
    let level = params.field_trace_level;
    let cell = cell_side(field);
    let step = STEP_CELLS * cell;
    let size = [
        field.width as f32 * field.cell_px[0],
        field.height as f32 * field.cell_px[1],
    ];
    let cable = |p: [f32; 2]| field.cable_at(p[0], p[1]);
    let ahead = |p: [f32; 2], d: [f32; 2], k: f32| [p[0] + k * step * d[0], p[1] + k * step * d[1]];
    let inside = |p: [f32; 2]| p[0] >= 0.0 && p[1] >= 0.0 && p[0] < size[0] && p[1] < size[1];

    let mut dir = start.dir;
    let mut points = vec![start.point];
    let mut p = start.point;
    let (mut run, mut weak, mut crossed) = (0.0, 0, false);
    let max_run = 2.0 * (size[0] + size[1]);
    while run < max_run {
        // Over a cable already found (a crossing), the trace runs straight on, along
        // the way it came rather than the heading the field bent near the other
        // cable. Elsewhere its heading turns to the field's direction where the
        // network is sure of one, and each step goes along it, then across it to the
        // ridge's top.
        let near_found = [p, ahead(p, dir, 1.0), ahead(p, dir, 2.0)]
            .iter()
            .any(|&x| points_near_any(&[x], found) > 0);
        if near_found {
            if !crossed {
                if points.len() > 1 {
                    dir = heading(&points, CHORD_CELLS * cell);
                }
                crossed = true;
            }
            p = ahead(p, dir, 1.0);
        } else {
            crossed = false;
            if let Some(along) = field_direction(field, p, dir, MAX_TURN_DEG.to_radians().cos()) {
                dir = along;
            }
            let q = ahead(p, dir, 1.0);
            let normal = [-dir[1], dir[0]];
            let reach = (RECENTRE_CELLS * cell).round() as i32;
            let offset = (-reach..=reach)
                .map(|o| o as f32)
                .map(|o| {
                    let across = [q[0] + o * normal[0], q[1] + o * normal[1]];
                    (cable(across) - RECENTRE_COST * o.abs(), o)
                })
                .max_by(|x, y| x.0.total_cmp(&y.0))
                .map_or(0.0, |(_, o)| o);
            p = [q[0] + offset * normal[0], q[1] + offset * normal[1]];
        }
        run += step;
        if !inside(p) {
            let last = points[points.len() - 1];
            let exit = border_exit(last, dir, size[0] as usize, size[1] as usize, 2.0 * step)?;
            points.push(exit);
            return Some((None, points));
        }
        // Over a crossing the field may dip between the two cables' ridges: only a
        // trace away from the cables found fades.
        if cable(p) < level && !near_found {
            weak += 1;
            if weak > MAX_WEAK_STEPS {
                return None;
            }
        } else {
            weak = 0;
        }
        points.push(p);
        if run >= params.min_cable_length_px
            && let Some(&(id, target)) = targets
                .iter()
                .filter(|(_, t)| dist(*t, p) < params.close_radius_px)
                .min_by(|x, y| dist(x.1, p).total_cmp(&dist(y.1, p)))
        {
            points.push(target);
            return Some((Some(id), points));
        }
    }
    None
}

/// The way the cable leaves an end at `start`: the direction towards the point of
/// highest cable probability on the circle of `radius` around it, when that
/// probability reaches `level`.
fn opening(field: &CableField, start: [f32; 2], radius: f32, level: f32) -> Option<[f32; 2]> {
    (0..OPENING_DIRECTIONS)
        .map(|i| {
            let a = i as f32 * std::f32::consts::TAU / OPENING_DIRECTIONS as f32;
            let d = [a.cos(), a.sin()];
            (
                field.cable_at(start[0] + radius * d[0], start[1] + radius * d[1]),
                d,
            )
        })
        .max_by(|x, y| x.0.total_cmp(&y.0))
        .filter(|&(p, _)| p >= level)
        .map(|(_, d)| d)
}

/// The field's direction at `p` as a unit vector the way of `heading`, when the field
/// is at least [`SURE_DIRECTION`] sure of it and the cosine of its angle to `heading`
/// is at least `min_cos`.
fn field_direction(
    field: &CableField,
    p: [f32; 2],
    heading: [f32; 2],
    min_cos: f32,
) -> Option<[f32; 2]> {
    let [c2, s2] = field.orientation_at(p[0], p[1]);
    if c2.hypot(s2) < SURE_DIRECTION {
        return None;
    }
    let theta = 0.5 * s2.atan2(c2);
    let mut d = [theta.cos(), theta.sin()];
    if d[0] * heading[0] + d[1] * heading[1] < 0.0 {
        d = [-d[0], -d[1]];
    }
    (d[0] * heading[0] + d[1] * heading[1] >= min_cos).then_some(d)
}

/// How many points of `line` lie within its tolerance of a point of one of `found`
/// (each with its tolerance) where that line runs within [`ALONGSIDE_DEG`] of `line`'s
/// direction: a crossing, however shallow, shares only the points where the two run
/// the same way.
fn points_alongside(line: &[[f32; 2]], found: &[(&[[f32; 2]], f32)]) -> usize {
    let alongside = ALONGSIDE_DEG.to_radians().cos();
    let direction = |l: &[[f32; 2]], i: usize| {
        let (a, b) = (l[i.saturating_sub(1)], l[(i + 1).min(l.len() - 1)]);
        unit_or([b[0] - a[0], b[1] - a[1]], [0.0, 0.0])
    };
    (0..line.len())
        .filter(|&i| {
            let d = direction(line, i);
            found.iter().any(|&(other, tolerance)| {
                (0..other.len()).any(|j| {
                    let e = direction(other, j);
                    dist(line[i], other[j]) <= tolerance
                        && (d[0] * e[0] + d[1] * e[1]).abs() >= alongside
                })
            })
        })
        .count()
}

#[cfg(test)]
mod tests {
    use image::Rgb;

    use super::super::cable::straight;
    use super::*;

    const CELL: f32 = 8.0;

    /// Unit direction of the bright cable: 35° down from the wire's, so that near
    /// their crossing the field's direction, their mean, still looks sure.
    fn across() -> [f32; 2] {
        let a = 35f32.to_radians();
        [a.cos(), a.sin()]
    }

    /// Distances of photo point `p` from the wire (along y = 60 from x = `wire[0]` to
    /// `wire[1]`) and from the bright cable (through (120, 60) along [`across`]).
    fn distances(p: [f32; 2], wire: [f32; 2]) -> (f32, f32) {
        let wire = if (wire[0]..=wire[1]).contains(&p[0]) {
            (p[1] - 60.0).abs()
        } else {
            f32::MAX
        };
        let d = across();
        let cable = ((p[0] - 120.0) * d[1] - (p[1] - 60.0) * d[0]).abs();
        (wire, cable)
    }

    /// A 240x120 dark grey photo with a lighter wire 4 px wide and a bright cable 8 px
    /// wide crossing it ([`distances`]), and a field that shows both (the wire at 0.8,
    /// the cable at 0.95; where both lie near a cell, its direction is their mean).
    fn scene(wire: [f32; 2]) -> (RgbImage, CableField) {
        let image = RgbImage::from_fn(240, 120, |x, y| {
            match distances([x as f32, y as f32], wire) {
                (_, c) if c <= 4.0 => Rgb([200, 200, 255]),
                (w, _) if w <= 2.0 => Rgb([95, 95, 95]),
                _ => Rgb([40, 40, 40]),
            }
        });
        let (w, h) = (30, 15);
        let d = across();
        let cells: Vec<(f32, [f32; 2])> = (0..w * h)
            .map(|i| {
                let centre = [((i % w) as f32 + 0.5) * CELL, ((i / w) as f32 + 0.5) * CELL];
                let (wire, cable) = distances(centre, wire);
                let mut p = 0.0f32;
                let mut o = [0.0f32, 0.0];
                let mut n = 0.0;
                if wire <= 0.6 * CELL {
                    p = 0.8;
                    o = [1.0, 0.0];
                    n += 1.0;
                }
                if cable <= 0.6 * CELL {
                    p = 0.95;
                    o = [o[0] + d[0] * d[0] - d[1] * d[1], o[1] + 2.0 * d[0] * d[1]];
                    n += 1.0;
                }
                (p, if n > 0.0 { [o[0] / n, o[1] / n] } else { o })
            })
            .collect();
        let field = CableField {
            width: w,
            height: h,
            cell_px: [CELL, CELL],
            cable: cells.iter().map(|c| c.0).collect(),
            orientation: cells.iter().map(|c| c.1).collect(),
        };
        (image, field)
    }

    /// How far the centreline of `cable` strays from the wire's line y = 60, pixels.
    fn off_the_wire(cable: &Cable) -> f32 {
        cable
            .polyline
            .iter()
            .map(|p| (p[1] - 60.0).abs())
            .fold(0.0, f32::max)
    }

    /// The cables after tracing from `ends` (none of them on a cable yet) with the
    /// bright cable already found, the wire from x = 20 to 220.
    fn traced(ends: &[[f32; 2]], params: &Params) -> (Vec<Cable>, Vec<Option<usize>>) {
        traced_along(ends, params, [20.0, 220.0])
    }

    /// [`traced`] with the wire from x = `wire[0]` to `wire[1]`.
    fn traced_along(
        ends: &[[f32; 2]],
        params: &Params,
        wire: [f32; 2],
    ) -> (Vec<Cable>, Vec<Option<usize>>) {
        let (image, field) = scene(wire);
        let mut lab = LabImage::from_rgb(image.as_raw(), 240, 120);
        lab.gaussian_blur(params.sigma);
        let d = across();
        let through = [-1.0, 1.0].map(|t: f32| [120.0 + 80.0 * t * d[0], 60.0 + 80.0 * t * d[1]]);
        let mut cables = vec![straight(0, through, [None, None])];
        let mut end_cables = vec![None; ends.len()];
        let ground = Ground {
            field: &field,
            lab: &lab,
            image: &image,
            params,
            step_px: 12.0,
            size: [240, 120],
        };
        let confidence = vec![1.0; ends.len()];
        trace_free_ends(&mut cables, &mut end_cables, ends, &confidence, ground);
        (cables, end_cables)
    }

    #[test]
    fn a_wire_the_field_shows_between_two_free_ends_is_traced_straight_across_a_cable() {
        let ends = [[20.0, 60.0], [220.0, 60.0]];
        let (cables, end_cables) = traced(&ends, &Params::default());
        assert_eq!(cables.len(), 2, "one cable traced");
        let wire = &cables[1];
        assert_eq!(wire.end_indices, [Some(0), Some(1)]);
        assert_eq!(end_cables, vec![Some(1), Some(1)]);
        let off = off_the_wire(wire);
        assert!(
            off < 2.0,
            "the trace keeps to the wire across the cable: {off} px off"
        );
        assert!(wire.score > 0.5, "score {}", wire.score);

        let off = Params {
            field_trace_level: 1.0,
            ..Params::default()
        };
        assert_eq!(traced(&ends, &off).0.len(), 1, "no traces at level 1");
    }

    #[test]
    fn a_trace_along_a_cable_already_found_is_no_cable_of_its_own() {
        let d = across();
        let ends = [-1.0, 1.0].map(|t: f32| [120.0 + 50.0 * t * d[0], 60.0 + 50.0 * t * d[1]]);
        let (cables, end_cables) = traced(&ends, &Params::default());
        assert_eq!(cables.len(), 1);
        assert_eq!(end_cables, vec![None, None]);
    }

    #[test]
    fn ends_with_no_cable_between_them_in_the_field_stay_free() {
        let (cables, end_cables) = traced(&[[20.0, 15.0], [220.0, 105.0]], &Params::default());
        assert_eq!(cables.len(), 1);
        assert_eq!(end_cables, vec![None, None]);
    }

    #[test]
    fn a_wire_the_field_shows_from_a_free_end_out_of_the_frame_is_traced_to_its_edge() {
        let (cables, end_cables) = traced_along(&[[20.0, 60.0]], &Params::default(), [20.0, 240.0]);
        assert_eq!(cables.len(), 2, "one cable traced");
        let wire = &cables[1];
        assert_eq!(wire.end_indices, [Some(0), None]);
        assert_eq!(end_cables, vec![Some(1)]);
        let exit = wire.ends[1];
        assert!(
            exit[0] > 237.0 && (exit[1] - 60.0).abs() < 2.0,
            "it leaves at the frame's edge: {exit:?}"
        );
        // The same end with the wire stopping short of the edge: no cable.
        let (cables, _) = traced_along(&[[20.0, 60.0]], &Params::default(), [20.0, 220.0]);
        assert_eq!(cables.len(), 1);
    }

    #[test]
    fn a_wire_the_field_shows_across_the_frame_with_no_end_in_view_is_traced_edge_to_edge() {
        let (cables, _) = traced_along(&[], &Params::default(), [0.0, 240.0]);
        assert_eq!(cables.len(), 2, "one cable traced");
        let wire = &cables[1];
        assert_eq!(wire.end_indices, [None, None]);
        let xs = wire.ends.map(|p| p[0]);
        assert!(
            xs.iter().any(|&x| x < 2.0) && xs.iter().any(|&x| x > 237.0),
            "from edge to edge: {:?}",
            wire.ends
        );
        let off = off_the_wire(wire);
        assert!(off < 2.0, "along the wire: {off} px off");
        let no_border = Params {
            border_cables: false,
            ..Params::default()
        };
        let (cables, _) = traced_along(&[], &no_border, [0.0, 240.0]);
        assert_eq!(
            cables.len(),
            1,
            "no starts on the edge without border cables"
        );
    }

    #[test]
    fn a_trace_from_the_frame_s_edge_sets_off_along_the_cable_crossing_it() {
        // No wire: the bright cable alone crosses the top and bottom edges at 55° to
        // their normals.
        let (_, field) = scene([0.0, 0.0]);
        let starts = border_starts(&field, [240, 120], &Params::default());
        assert_eq!(starts.len(), 2, "one start where it crosses each edge");
        let d = across();
        for start in &starts {
            let inward = if start.point[1] < 60.0 { 1.0 } else { -1.0 };
            assert!(
                start.dir[1] * inward > 0.0,
                "into the frame: {:?}",
                start.dir
            );
            let along = (start.dir[0] * d[0] + start.dir[1] * d[1]).abs();
            assert!(
                along > 0.95,
                "along the cable, not square to the edge: {:?}",
                start.dir
            );
        }
    }

    #[test]
    fn a_cable_whose_walk_was_lost_runs_on_along_the_field_out_of_the_frame() {
        let params = Params::default();
        let (image, field) = scene([20.0, 240.0]);
        let mut lab = LabImage::from_rgb(image.as_raw(), 240, 120);
        lab.gaussian_blur(params.sigma);
        let d = across();
        let through = [-1.0, 1.0].map(|t: f32| [120.0 + 80.0 * t * d[0], 60.0 + 80.0 * t * d[1]]);
        // The wire found from its end at x = 20, its walk lost at x = 40.
        let mut cables = vec![
            straight(0, through, [None, None]),
            straight(1, [[20.0, 60.0], [40.0, 60.0]], [Some(0), None]),
        ];
        let mut end_cables = vec![Some(1)];
        let ground = Ground {
            field: &field,
            lab: &lab,
            image: &image,
            params: &params,
            step_px: 12.0,
            size: [240, 120],
        };
        trace_free_ends(
            &mut cables,
            &mut end_cables,
            &[[20.0, 60.0]],
            &[1.0],
            ground,
        );
        assert_eq!(cables.len(), 2, "no cable of its own");
        let wire = &cables[1];
        assert_eq!(wire.end_indices, [Some(0), None]);
        assert!(
            wire.ends[1][0] > 237.0,
            "run on to the frame's edge: {:?}",
            wire.ends
        );
        assert_eq!(wire.score, 0.5, "its score kept");
        let off = off_the_wire(wire);
        assert!(off < 2.0, "along the wire, across the cable: {off} px off");
    }

    #[test]
    fn a_line_shares_with_a_cable_found_only_where_it_runs_its_way() {
        let line: Vec<[f32; 2]> = (0..=100).map(|x| [x as f32 * 2.0, 60.0]).collect();
        let d = across();
        let crossing: Vec<[f32; 2]> = (-50..=50)
            .map(|t| [100.0 + 2.0 * t as f32 * d[0], 60.0 + 2.0 * t as f32 * d[1]])
            .collect();
        let parallel: Vec<[f32; 2]> = (0..=50).map(|x| [x as f32 * 2.0, 66.0]).collect();
        assert_eq!(points_alongside(&line, &[(&crossing, 16.0)]), 0);
        // The 51 points up to x = 100, 6 px beside it, and the 7 next within 16 px of
        // its end.
        assert_eq!(points_alongside(&line, &[(&parallel, 16.0)]), 58);
    }
}
