//! Walks on the region adjacency graph: likelihoods, extension and termination.
//!
//! From every end ("seed") a walk starts towards each ring-1 neighbour of the seed's
//! superpixel (of its region, when neighbours' centres lie within
//! `seed_region_steps` superpixel steps of the seed); the first step fixes the initial
//! heading. Each iteration scores every
//! vertex of the order-d neighbourhood of the head that lies ahead,
//! p = p_V · p_C · p_D · c · f, and appends the argmax:
//!
//! - p_V = 1 / (1 + c_V (1 − I)), the Bradford density at 1 − I normalised to 1 at
//!   I = 1, where I is the histogram intersection between the candidate and the walk's
//!   running colour model (not only the last vertex: the model stops slow drift);
//! - p_C = exp(κ (cos φ − 1)), a von Mises density in the turn φ between the walk's
//!   heading (measured over `heading_span_px`, which smooths centroid jitter) and the
//!   step, normalised to 1 at φ = 0; turns above `max_turn_deg` are refused;
//! - p_D = 1 / (1 + c_D d / D_max), the Bradford density in the step length;
//! - c, the candidate's lateral contrast in 0..=1: the smaller of its Lab distances to
//!   the image one superpixel step to either side of the step's direction, divided by
//!   `contrast_saturation` and capped at 1 (a cable differs from the background on both
//!   sides; a vertex of the background beside a cable on one side only), and at most
//!   `far_contrast_factor` times the larger distance two steps to either side (the
//!   strip of background between two same-colour cables side by side differs from both
//!   cables but matches the background beyond them). Not in the paper: it keeps walks
//!   off plain background. 1 with `lateral_contrast` off;
//! - f, the cable field's term (when a field is given and `use_field` is on):
//!   (ε + (1 − ε) p) · (1 − w + w a), where p is the candidate's mean cable
//!   probability, a the agreement of the step with the field's direction
//!   ([`alignment`]), ε = `field_floor`, w = `field_alignment_weight`; 1 otherwise.
//!
//! The argmax is refused (the walk stops) when its colour similarity is below
//! `min_similarity`, when its cable probability is below `field_min_cable`, when the
//! straight line from the head to it runs more than one superpixel step where the
//! field's cable probability is below `field_gap_min_cable` (a step may skip
//! superpixels — a crossing, a terminal's metal — but not cross the background from one
//! cable to another), or when its contrast is below `min_contrast` unless the field is
//! sure (p ≥ `field_trust`) that it is a cable. Within `field_recolour_steps` of its
//! seed, a walk refused on colour alone where the field calls where it stands cable
//! (p ≥ `field_collar_head`: a ferrule's collar or a sleeve between the end and the
//! cable's insulation) steps once by the field alone: onto the best vertex the field
//! is sure of, the step along the field's direction at both, whose colour becomes the
//! walk's model.
//!
//! A walk ends on reaching another seed (within r, and within
//! `close_max_lateral_steps` superpixel steps of the walk's line, so a walk passing the
//! terminal of a cable laid alongside goes on; with a field, only when the walk's
//! heading agrees with the field's direction at that seed by at least
//! `field_close_min_alignment`, so a walk passing the tip of another cable that ends
//! against its side goes on, and not where the seed lies more than a cable width beside
//! the walk's line while the field shows the walk's cable running on past it, so a
//! walk passing a terminal that lies beside its cable goes on; and, once every walk has
//! run, only when its heading agrees with the way that seed's own best walk opens by at
//! least `close_own_min_alignment`, so a walk along a cable that another cable's
//! terminal touches passes that terminal, and is run again if it closed there), on
//! leaving the frame,
//! when the best candidate's colour no longer matches the model (it left the cable) or
//! at the iteration cap. Each walk records the evidence pairing needs: mean colour
//! agreement, smoothness, and how much its vertices stand out from their sides (a cable
//! is a thin structure; a walk over plain background is not).

mod step;

use super::color::LabImage;
use super::field::{CableField, GAP_SAMPLE_PX, VertexField, alignment, orientation_of};
use super::geometry::{border_exit, dist, dist3, heading, norm};
use super::graph::{Graph, Neighbourhood};
use super::{Deadline, EngineError, Params};

/// An end given to the walker: its point and the superpixel that contains it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seed {
    /// Pixel coordinates (x, y).
    pub point: [f32; 2],
    /// Superpixel id containing the point.
    pub vertex: u32,
}

/// Why a walk stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WalkEnd {
    /// It reached the seed with this index.
    Seed(usize),
    /// It left the image through the border.
    Border,
    /// It lost the cable (colour mismatch, no candidate ahead, or iteration cap).
    Lost,
}

/// One finished walk.
#[derive(Debug, Clone, PartialEq)]
pub struct Walk {
    /// Index of the seed it started from.
    pub seed: usize,
    /// Visited superpixels in order, the seed's own first.
    pub vertices: Vec<u32>,
    /// How it ended.
    pub end: WalkEnd,
    /// Geometric mean of the colour likelihoods of its steps, 0..=1.
    pub visual: f32,
    /// Geometric mean of the curvature likelihoods of its steps, 0..=1.
    pub smoothness: f32,
    /// Mean lateral contrast of its vertices, 0..=1 (1: clearly a thin structure; 1
    /// when lateral contrast is off).
    pub contrast: f32,
    /// Mean cable probability of its vertices, 0..=1 (1 without a field).
    pub cable: f32,
    /// Length along the centroids, pixels.
    pub length_px: f32,
    /// Unit heading at the walk's head.
    pub end_heading: [f32; 2],
    /// Position of the walk's head, pixels; for a walk that left through the border,
    /// where its final heading comes within `EXIT_INSET_PX` of the frame.
    pub end_point: [f32; 2],
    /// Whether the cable it follows runs on behind its seed (see
    /// [`Walker::runs_on_behind`]): the walk follows a cable that passes the end, not
    /// the end's own cable. Always false without a field, where the seeds are no
    /// cable's ends, and with `field_through_factor` 1 (nothing reads it).
    pub through: bool,
    /// How the walk opens along the field's direction at its end, as a factor of its
    /// quality: 1 − w + w·a, where a is the agreement ([`alignment`]) of the way from
    /// the seed to the walk's first point `OPENING_STEPS` superpixel steps out with
    /// the field's direction at the seed, and w is `field_opening_weight`. At a
    /// terminal the field runs along the end's own cable; a walk opening across it
    /// has stepped onto a cable the end lies against. 1 without a field and where the
    /// seeds are no cable's ends.
    pub opening: f32,
}

impl Walk {
    /// How many steps it took past its first superpixel (the step onto that one, from
    /// the seed, sets its direction; its colour agreement and turn are not scored).
    pub fn steps(&self) -> usize {
        self.vertices.len().saturating_sub(2)
    }

    /// Overall quality in 0..=1: `visual`^a · `smoothness` · `contrast`^b · `cable`^c ·
    /// `opening`, with a = `quality_visual_exponent` (0.5 by default), b =
    /// `quality_contrast_exponent` (2) and c = `quality_field_exponent` (1).
    pub fn quality(&self, params: &Params) -> f32 {
        self.visual.powf(params.quality_visual_exponent)
            * self.smoothness
            * self.contrast.powf(params.quality_contrast_exponent)
            * self.cable.powf(params.quality_field_exponent)
            * self.opening
    }
}

/// What walks read: the graph, the Lab image (lateral contrast), the cable field per
/// vertex when there is one, the superpixel step and the parameters.
#[derive(Clone, Copy)]
pub struct Terrain<'a> {
    /// The region adjacency graph.
    pub graph: &'a Graph,
    /// The blurred Lab image.
    pub lab: &'a LabImage,
    /// The cable field's mean over each vertex, when a field is used.
    pub field: Option<&'a [VertexField]>,
    /// The cable field itself, when a field is used: read along each step's line.
    pub field_map: Option<&'a CableField>,
    /// Nominal superpixel step, pixels.
    pub step_px: f32,
    /// Parameters.
    pub params: &'a Params,
    /// When to give up.
    pub deadline: Deadline,
}

/// Runs all walks from all seeds; a walk may end at any of the first `targets` seeds
/// but its own (the rest only start walks); `from_ends` says whether the seeds are
/// cable ends, for which [`Walk::through`] and [`Walk::opening`] are read (false
/// leaves them false and 1: border seeds and the ends of pieces of the field). For
/// cable ends, a walk that closed on an end it arrived at across that end's own cable
/// (`close_own_min_alignment`) is run again, going on past it.
pub fn walk_all(
    terrain: Terrain<'_>,
    seeds: &[Seed],
    targets: usize,
    from_ends: bool,
) -> Result<Vec<Walk>, EngineError> {
    let graph = terrain.graph;
    let deadline = terrain.deadline;
    let mut walker = Walker::new(terrain, seeds, targets);
    let mut walks = Vec::new();
    let near_px = terrain.params.seed_region_steps * terrain.step_px;
    let regions: Vec<(Vec<u32>, Vec<u32>)> = seeds
        .iter()
        .map(|seed| seed_region(graph, seed, near_px))
        .collect();
    for (s, (region, firsts)) in regions.iter().enumerate() {
        for &first in firsts {
            deadline.check()?;
            if let Some(w) = walker.run(s, region, first, from_ends) {
                walks.push(w);
            }
        }
    }
    if from_ends && terrain.params.close_own_min_alignment > 0.0 {
        walker.own = (0..targets)
            .map(|t| walker.own_heading(t, &walks))
            .collect();
        for w in &mut walks {
            let across = match w.end {
                WalkEnd::Seed(t) => !walker.arrives_along_own(t, w.end_heading),
                _ => false,
            };
            if across {
                deadline.check()?;
                let (s, first) = (w.seed, w.vertices[1]);
                if let Some(again) = walker.run(s, &regions[s].0, first, from_ends) {
                    *w = again;
                }
            }
        }
    }
    Ok(walks)
}

/// How many superpixel steps out from its seed a walk's opening direction is read
/// ([`Walker::runs_on_behind`]).
const OPENING_STEPS: f32 = 2.0;
/// How many of a walk's first superpixels give the colour of the cable it opens along.
const OPENING_VERTICES: usize = 3;
/// Least agreement of the field's direction behind a seed with a walk's opening
/// direction for the cable to run on there (0.8: within about 26°).
const THROUGH_MIN_ALIGNMENT: f32 = 0.8;
/// Least agreement of a step taken by the field alone (`field_recolour_steps`) with
/// the field's direction where it starts and where it lands (0.8: within about 26°): a
/// cable that changes colour runs on the same way; the tip of an end pushed against
/// another cable meets that cable at an angle.
const RECOLOUR_MIN_ALIGNMENT: f32 = 0.8;
/// How many superpixel steps behind a seed another seed marks the same terminal
/// ([`Walker::end_behind`]): as far as [`Walker::runs_on_behind`] looks.
const BEHIND_STEPS: f32 = 2.0;
/// Largest Lab distance from the walk's opening colour for the photo behind a seed to
/// be the same cable.
const THROUGH_MAX_LAB: f32 = 20.0;

/// The paper's colour likelihood p_V of a step onto a superpixel whose histogram
/// intersects the walk's colour model by `similarity` (`c_visual`).
fn visual_likelihood(similarity: f32, params: &Params) -> f32 {
    1.0 / (1.0 + params.c_visual * (1.0 - similarity))
}

/// How far a walk stopped against an edge may head into the frame and still have been
/// cut by it ([`Walker::cut_by_border`]), as the sine of the angle (0.2: about 12°).
/// Its heading is read from superpixel centroids, and those against the edge lie on
/// the frame's side of the cable (they hold no pixels beyond it), so a cable running
/// out along the edge reads as leaning into the frame by a few degrees (4° where a
/// thin wire, its photo enlarged 1.76-fold, was taken as lost 5.8 px from the edge it
/// leaves: docs/ENGINE.md, "A walk stopped against the edge it leaves").
const GRAZING_INWARD: f32 = 0.2;

/// How far inside the frame a border walk's exit is placed (`Walk::end_point`), so
/// that what is read there is the photo's last pixels.
const EXIT_INSET_PX: f32 = 1.0;

/// A seed's region and the first steps of its walks. The region is the seed's
/// superpixel plus, repeatedly, any neighbour whose centre lies within `near_px` of
/// the seed (`seed_region_steps`); the first steps are the region's other neighbours.
fn seed_region(graph: &Graph, seed: &Seed, near_px: f32) -> (Vec<u32>, Vec<u32>) {
    let near = |v: u32| dist(graph.vertices[v as usize].centroid, seed.point) < near_px;
    let mut region = vec![seed.vertex];
    let mut firsts = Vec::new();
    let mut i = 0;
    while let Some(&v) = region.get(i) {
        for &n in graph.neighbours(v) {
            if region.contains(&n) || firsts.contains(&n) {
                continue;
            }
            if near(n) {
                region.push(n);
            } else {
                firsts.push(n);
            }
        }
        i += 1;
    }
    (region, firsts)
}

/// A scored candidate for the next step.
struct Candidate {
    vertex: u32,
    similarity: f32,
    curvature: f32,
    contrast: f32,
    cable: f32,
}

struct Walker<'a> {
    graph: &'a Graph,
    lab: &'a LabImage,
    field: Option<&'a [VertexField]>,
    field_map: Option<&'a CableField>,
    seeds: &'a [Seed],
    /// How many of `seeds` (the first) a walk may end at.
    targets: usize,
    params: &'a Params,
    /// Lateral offset at which contrast is sampled: one superpixel step.
    side_px: f32,
    hood: Neighbourhood,
    candidates: Vec<(u32, u32)>,
    in_walk: Vec<u32>,
    walk_id: u32,
    model: Vec<f32>,
    cos_max_turn: f32,
    /// Per target seed, the unit direction its own cable leaves it along
    /// ([`Walker::own_heading`]), once every walk has run; empty before.
    own: Vec<Option<[f32; 2]>>,
}

impl<'a> Walker<'a> {
    fn new(terrain: Terrain<'a>, seeds: &'a [Seed], targets: usize) -> Self {
        let Terrain {
            graph,
            lab,
            field,
            field_map,
            step_px,
            params,
            deadline: _,
        } = terrain;
        Self {
            graph,
            lab,
            field,
            field_map,
            seeds,
            targets,
            params,
            side_px: step_px,
            hood: Neighbourhood::default(),
            candidates: Vec::new(),
            in_walk: vec![0; graph.len()],
            walk_id: 0,
            model: vec![0.0; graph.histogram_cells()],
            cos_max_turn: params.max_turn_deg.to_radians().cos(),
            own: Vec::new(),
        }
    }

    /// The unit direction in which seed `t`'s own cable leaves it: how its best walk
    /// among `walks` opens ([`Self::opening_direction`]), by quality, of those along a
    /// cable that stops at the seed (not [`Walk::through`]) that reach as far as the
    /// opening is read (`OPENING_STEPS` superpixel steps: a walk lost a step from its
    /// seed scored no step, and its quality of 1 says nothing); `None` when it has none.
    fn own_heading(&self, t: usize, walks: &[Walk]) -> Option<[f32; 2]> {
        let p = self.params;
        let reach = OPENING_STEPS * self.side_px;
        let best = walks
            .iter()
            .filter(|w| w.seed == t && !w.through && w.length_px >= reach)
            .max_by(|a, b| a.quality(p).total_cmp(&b.quality(p)))?;
        let points: Vec<[f32; 2]> = best.vertices[1..].iter().map(|&v| self.pos(v)).collect();
        self.opening_direction(self.seeds[t].point, &points)
    }

    /// Whether a walk heading along `dir` arrives at seed `t` along the cable that
    /// leaves `t` ([`Self::own`]; any heading before that is known, or where seed `t`
    /// has no walk).
    fn arrives_along_own(&self, t: usize, dir: [f32; 2]) -> bool {
        self.own.get(t).copied().flatten().is_none_or(|u| {
            alignment(dir, orientation_of(u)) >= self.params.close_own_min_alignment
        })
    }

    fn pos(&self, v: u32) -> [f32; 2] {
        self.graph.vertices[v as usize].centroid
    }

    /// One walk from seed `s` (whose region is `region`) whose first step goes to
    /// `first`; `from_ends` as for [`walk_all`].
    fn run(&mut self, s: usize, region: &[u32], first: u32, from_ends: bool) -> Option<Walk> {
        let p = self.params;
        let seed = self.seeds[s];
        self.walk_id += 1;
        let id = self.walk_id;
        for &v in region {
            self.in_walk[v as usize] = id;
        }
        self.in_walk[first as usize] = id;
        let mut vertices = vec![seed.vertex, first];
        let mut points = vec![seed.point, self.pos(first)];
        if dist(points[0], points[1]) < 1e-3 {
            return None;
        }
        self.model.copy_from_slice(self.graph.histogram(first));
        let mut length = dist(points[0], points[1]);
        let (mut log_visual, mut log_curve, mut steps) = (0.0f32, 0.0f32, 0u32);
        let mut contrast_sum = self.contrast(first, heading(&points, p.heading_span_px));
        let mut cable_sum = self.vertex_field(first).map_or(1.0, |f| f.cable);
        let mut end = self.classify(s, &points, &vertices, length);
        let mut recoloured = false;

        while end.is_none() && (steps as usize) < p.max_steps as usize {
            let head = *vertices.last().unwrap_or(&first);
            let dir = heading(&points, p.heading_span_px);
            let here = *points.last().unwrap_or(&seed.point);
            // A walk that finds nothing acceptable nearby looks further once before it
            // gives up: crossings and terminals can hide the cable for a few superpixels.
            let jump = p.jump_order.max(p.neighbourhood_order);
            let mut found = self
                .best_candidate(id, head, here, dir, p.neighbourhood_order, false)
                .or_else(|| self.best_candidate(id, head, here, dir, jump, false));
            // Near its end, on a cable the field is sure of, a change of colour (a
            // collar) is stepped over once by the field alone.
            let reseed = found.is_none()
                && !recoloured
                && dist(here, seed.point) <= p.field_recolour_steps * self.side_px
                && self
                    .vertex_field(head)
                    .is_some_and(|f| f.cable >= p.field_collar_head);
            if reseed {
                found = self
                    .best_candidate(id, head, here, dir, jump, true)
                    .filter(|c| self.continues_along(head, here, c.vertex));
            }
            let Some(Candidate {
                vertex: c,
                similarity: sim,
                curvature: pc,
                contrast,
                cable,
            }) = found
            else {
                end = Some(self.stopped(s, here, dir));
                break;
            };
            self.in_walk[c as usize] = id;
            let q = self.pos(c);
            length += dist(here, q);
            vertices.push(c);
            points.push(q);
            log_curve += pc.ln();
            steps += 1;
            let hist = self.graph.histogram(c);
            if reseed {
                // A new colour on the same cable: it is the cable's from here on, and
                // the change itself says nothing about the walk.
                recoloured = true;
                self.model.copy_from_slice(hist);
            } else {
                log_visual += visual_likelihood(sim, p).ln();
                let rate = p.model_rate;
                for (m, h) in self.model.iter_mut().zip(hist) {
                    *m = (1.0 - rate) * *m + rate * h;
                }
            }
            contrast_sum += contrast;
            cable_sum += cable;
            end = self.classify(s, &points, &vertices, length);
        }
        let n = steps.max(1) as f32;
        let end = end.unwrap_or(WalkEnd::Lost);
        let end_heading = heading(&points, p.heading_span_px);
        let head = *points.last().unwrap_or(&seed.point);
        let end_point = match end {
            WalkEnd::Border => self.exit(head, end_heading).unwrap_or(head),
            _ => head,
        };
        // Read once for both terms; only walks from ends have them.
        let way = from_ends
            .then(|| self.opening_direction(seed.point, &points))
            .flatten();
        let through = p.field_through_factor < 1.0
            && way.is_some_and(|u| self.runs_on_behind(seed.point, u, &vertices));
        let opening = way.map_or(1.0, |u| self.opening(seed.point, u));
        Some(Walk {
            end_heading,
            end_point,
            through,
            seed: s,
            end,
            visual: (log_visual / n).exp(),
            smoothness: (log_curve / n).exp(),
            contrast: contrast_sum / (vertices.len() - 1) as f32,
            cable: cable_sum / (vertices.len() - 1) as f32,
            length_px: length,
            vertices,
            opening,
        })
    }

    /// The unit direction a walk from `seed` through `points` opens along: from the
    /// seed to its first point `OPENING_STEPS` superpixel steps out (its last point if
    /// none is that far); `None` where that point is the seed.
    fn opening_direction(&self, seed: [f32; 2], points: &[[f32; 2]]) -> Option<[f32; 2]> {
        let reach = OPENING_STEPS * self.side_px;
        let &out = points
            .iter()
            .find(|q| dist(**q, seed) >= reach)
            .or(points.last())?;
        let d = dist(out, seed);
        (d >= 1e-3).then(|| [(out[0] - seed[0]) / d, (out[1] - seed[1]) / d])
    }

    /// [`Walk::opening`] of a walk from an end at `seed` that opens along `u`
    /// ([`Self::opening_direction`]).
    fn opening(&self, seed: [f32; 2], u: [f32; 2]) -> f32 {
        let Some(field) = self.field_map else {
            return 1.0;
        };
        let agreement = alignment(u, field.orientation_at(seed[0], seed[1]));
        let w = self.params.field_opening_weight;
        1.0 - w + w * agreement
    }

    /// Whether the cable a walk over `vertices` opens along runs on behind its seed:
    /// [`Self::runs_on`] back from `seed` against the walk's opening direction `u`
    /// ([`Self::opening_direction`]), in the colour of the walk's first superpixels.
    /// An end's own cable stops at the end: behind it lie its metal tip and the
    /// background. A cable that passes the end (one the end's tip is pushed against)
    /// runs on.
    fn runs_on_behind(&self, seed: [f32; 2], u: [f32; 2], vertices: &[u32]) -> bool {
        let first = &vertices[1..vertices.len().min(1 + OPENING_VERTICES)];
        self.runs_on(seed, u, self.mean_colour(first))
    }

    /// Whether a walk over `vertices`, its head at `here` heading along `dir`, runs on
    /// past the end at `end` rather than arriving at it: `end` lies more than a nominal
    /// cable width beside the walk's line, and [`Self::runs_on`] ahead along that line
    /// from where `end` lies across it, in the colour of the walk's last superpixels.
    /// A cable that runs in at a shallow angle to end beside another puts its terminal
    /// within reach of the walks along that other cable, heading nearly their way; they
    /// pass it. Where the walk's own cable ends, its metal tip and the background lie
    /// ahead. An end nearer the line lies on the walk's cable (its terminal, or a false
    /// end along it) and is arrived at as before.
    fn runs_on_past(&self, here: [f32; 2], dir: [f32; 2], end: [f32; 2], vertices: &[u32]) -> bool {
        let v = [end[0] - here[0], end[1] - here[1]];
        if (v[0] * dir[1] - v[1] * dir[0]).abs() < self.params.nominal_width_px {
            return false;
        }
        let along = v[0] * dir[0] + v[1] * dir[1];
        let level = [here[0] + dir[0] * along, here[1] + dir[1] * along];
        let last = &vertices[vertices.len().saturating_sub(OPENING_VERTICES).max(1)..];
        self.runs_on(level, [-dir[0], -dir[1]], self.mean_colour(last))
    }

    /// Mean Lab colour of `vertices` (black where there are none).
    fn mean_colour(&self, vertices: &[u32]) -> [f32; 3] {
        let mut colour = [0.0f32; 3];
        for &v in vertices {
            let lab = self.graph.vertices[v as usize].mean_lab;
            for (c, l) in colour.iter_mut().zip(lab) {
                *c += l / vertices.len() as f32;
            }
        }
        colour
    }

    /// Whether a cable of `colour` runs on behind `point` against the direction `u`:
    /// over most of the samples one to two superpixel steps back, the field calls cable
    /// (`field_level`), runs along `u` (`THROUGH_MIN_ALIGNMENT`) and the photo is within
    /// `THROUGH_MAX_LAB` ΔE of `colour`. Never where another seed lies just behind
    /// ([`Self::end_behind`]: one terminal marked twice), nor without a field.
    fn runs_on(&self, point: [f32; 2], u: [f32; 2], colour: [f32; 3]) -> bool {
        let Some(field) = self.field_map else {
            return false;
        };
        if self.end_behind(point, u) {
            return false;
        }
        let (w, h) = (self.lab.width, self.lab.height);
        let samples = ((self.side_px / GAP_SAMPLE_PX).ceil() as usize).max(1);
        let on = (0..=samples)
            .filter(|&k| {
                let r = self.side_px * (1.0 + k as f32 / samples as f32);
                let (x, y) = (point[0] - u[0] * r, point[1] - u[1] * r);
                if x < 0.0 || y < 0.0 || x > (w - 1) as f32 || y > (h - 1) as f32 {
                    return false;
                }
                let at = self.lab.at(y.round() as usize * w + x.round() as usize);
                field.cable_at(x, y) >= self.params.field_level
                    && alignment(u, field.orientation_at(x, y)) >= THROUGH_MIN_ALIGNMENT
                    && dist3(at, colour) <= THROUGH_MAX_LAB
            })
            .count();
        2 * on > samples + 1
    }

    /// Whether another seed lies just behind `seed` against the direction `u` a walk
    /// opens along: within [`BEHIND_STEPS`] superpixel steps back, and off the line
    /// through the seed along `u` by at most one step. The network often marks one
    /// terminal twice, where the insulation ends and at the metal tip beyond it; the
    /// tip, of a pale cable's colour and called cable by the field, then reads as the
    /// cable running on behind the insulation's end ([`Self::runs_on_behind`]).
    fn end_behind(&self, seed: [f32; 2], u: [f32; 2]) -> bool {
        self.seeds.iter().any(|other| {
            let d = [seed[0] - other.point[0], seed[1] - other.point[1]];
            let back = d[0] * u[0] + d[1] * u[1];
            let across = (d[0] * u[1] - d[1] * u[0]).abs();
            back > 0.0 && back <= BEHIND_STEPS * self.side_px && across <= self.side_px
        })
    }

    /// Whether the step from `here` (on vertex `head`) to vertex `to` runs along the
    /// field's direction at both.
    fn continues_along(&self, head: u32, here: [f32; 2], to: u32) -> bool {
        let q = self.pos(to);
        let d = dist(here, q);
        let u = [(q[0] - here[0]) / d, (q[1] - here[1]) / d];
        [head, to].iter().all(|&v| {
            self.vertex_field(v)
                .is_some_and(|f| alignment(u, f.orientation) >= RECOLOUR_MIN_ALIGNMENT)
        })
    }

    /// Where a ray from `from` along `dir` comes within `EXIT_INSET_PX` of the frame.
    fn exit(&self, from: [f32; 2], dir: [f32; 2]) -> Option<[f32; 2]> {
        let i = EXIT_INSET_PX;
        let inner = |n: usize| n.saturating_sub(2 * i as usize);
        let (w, h) = (inner(self.lab.width), inner(self.lab.height));
        let exit = border_exit([from[0] - i, from[1] - i], dir, w, h, f32::INFINITY)?;
        Some([exit[0] + i, exit[1] + i])
    }

    /// Termination after a step over `vertices` (at `points`): another seed reached,
    /// or the frame left.
    fn classify(
        &self,
        s: usize,
        points: &[[f32; 2]],
        vertices: &[u32],
        length: f32,
    ) -> Option<WalkEnd> {
        let p = self.params;
        let here = *points.last()?;
        let dir = heading(points, p.heading_span_px);
        if length > p.close_radius_px {
            let hit = self
                .seeds
                .iter()
                .enumerate()
                .take(self.targets)
                .filter(|&(t, _)| t != s)
                .map(|(t, seed)| (t, dist(seed.point, here)))
                .filter(|&(_, d)| d <= p.close_radius_px)
                .filter(|&(t, _)| self.arrives_at(t, here, dir))
                .filter(|&(t, _)| !self.runs_on_past(here, dir, self.seeds[t].point, vertices))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((t, _)) = hit {
                return Some(WalkEnd::Seed(t));
            }
        }
        self.near_border_heading_out(here, dir, 1.0)
            .then_some(WalkEnd::Border)
    }

    /// Whether a walk whose head is at `here`, heading along `dir`, arrives at seed `t`
    /// (within reach): the seed lies on the walk's line, not beside it (the terminal of
    /// a cable laid alongside), and the walk runs along the cable the field sees there
    /// (a terminal pushed against the walk's side belongs to a cable across it) and
    /// along the seed's own cable ([`Self::arrives_along_own`]).
    fn arrives_at(&self, t: usize, here: [f32; 2], dir: [f32; 2]) -> bool {
        let p = self.params;
        let at = self.seeds[t].point;
        let v = [at[0] - here[0], at[1] - here[1]];
        let beside = (v[0] * dir[1] - v[1] * dir[0]).abs();
        beside <= p.close_max_lateral_steps * self.side_px
            && self.field_map.is_none_or(|f| {
                alignment(dir, f.orientation_at(at[0], at[1])) >= p.field_close_min_alignment
            })
            && self.arrives_along_own(t, dir)
    }

    /// How a walk that found no acceptable next vertex ends: on a seed just ahead (the
    /// last superpixels before a terminal are often not the cable's colour), through the
    /// border, or lost.
    fn stopped(&self, s: usize, here: [f32; 2], dir: [f32; 2]) -> WalkEnd {
        let p = self.params;
        let reach = p.stopped_seed_reach * p.close_radius_px;
        let ahead = self
            .seeds
            .iter()
            .enumerate()
            .take(self.targets)
            .filter(|&(t, _)| t != s)
            .filter_map(|(t, seed)| {
                let v = [seed.point[0] - here[0], seed.point[1] - here[1]];
                let d = norm(v);
                let cos = (v[0] * dir[0] + v[1] * dir[1]) / d.max(1e-6);
                (d <= reach && cos >= self.cos_max_turn && self.arrives_along_own(t, dir))
                    .then_some((t, d))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((t, _)) = ahead {
            WalkEnd::Seed(t)
        } else if self.near_border_heading_out(here, dir, p.stopped_border_reach)
            || self.cut_by_border(here, dir)
        {
            WalkEnd::Border
        } else {
            WalkEnd::Lost
        }
    }

    /// True when `here` lies within a nominal cable width of an edge and `dir` runs
    /// along it or out of the frame, leaning into the frame by at most
    /// [`GRAZING_INWARD`]: a cable leaving the frame at a grazing angle, its last
    /// superpixels slivers along the edge, runs on out of view there.
    fn cut_by_border(&self, here: [f32; 2], dir: [f32; 2]) -> bool {
        self.at_edge_heading(here, dir, self.params.nominal_width_px, |out| {
            out >= -GRAZING_INWARD
        })
    }

    /// True when `here` lies within `factor · border_margin_px` of an edge that `dir`
    /// points towards.
    fn near_border_heading_out(&self, here: [f32; 2], dir: [f32; 2], factor: f32) -> bool {
        let out = self.params.border_outward_cos;
        self.at_edge_heading(here, dir, self.params.border_margin_px * factor, |o| {
            o > out
        })
    }

    /// True when `here` lies within `margin` of an edge along whose outward normal
    /// `dir`'s component passes `outward`.
    fn at_edge_heading(
        &self,
        here: [f32; 2],
        dir: [f32; 2],
        margin: f32,
        outward: impl Fn(f32) -> bool,
    ) -> bool {
        let (w, h) = (self.lab.width as f32, self.lab.height as f32);
        (here[0] < margin && outward(-dir[0]))
            || (here[0] > w - 1.0 - margin && outward(dir[0]))
            || (here[1] < margin && outward(-dir[1]))
            || (here[1] > h - 1.0 - margin && outward(dir[1]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::superpixels::Superpixels;

    /// The walks from `seeds` on a 200x60 grey photo (level 160) cut into 20 px
    /// superpixels (ids 0-9 the top row, 10-19 the middle row, 20-29 the bottom row)
    /// whose middle row has the grey level `line` gives for each column (pixels), where
    /// the field shows horizontal cable on the 10 px cells of the middle row for which
    /// `cable` holds (given the cell's column), under `params`.
    fn walks_on_a_line(
        line: impl Fn(usize) -> u8,
        cable: impl Fn(usize) -> bool,
        seeds: &[Seed],
        params: &Params,
    ) -> Vec<Walk> {
        walks_on_a_graded_line(line, |col| f32::from(cable(col)), seeds, params)
    }

    /// [`walks_on_a_line`] where the field's cable probability on the middle row's
    /// cells is `cable` of the cell's column (0 elsewhere).
    fn walks_on_a_graded_line(
        line: impl Fn(usize) -> u8,
        cable: impl Fn(usize) -> f32,
        seeds: &[Seed],
        params: &Params,
    ) -> Vec<Walk> {
        on_a_line(line, cable, params, |terrain| {
            walk_all(terrain, seeds, seeds.len(), true).unwrap()
        })
    }

    /// `then` on the terrain of [`walks_on_a_graded_line`].
    fn on_a_line<R>(
        line: impl Fn(usize) -> u8,
        cable: impl Fn(usize) -> f32,
        params: &Params,
        then: impl FnOnce(Terrain<'_>) -> R,
    ) -> R {
        let (w, h) = (200usize, 60usize);
        let labels: Vec<u32> = (0..w * h)
            .map(|p| ((p / w) / 20 * 10 + p % w / 20) as u32)
            .collect();
        let sp = Superpixels {
            width: w,
            height: h,
            labels,
            count: 30,
            step: 20.0,
        };
        let rgb: Vec<u8> = (0..w * h)
            .flat_map(|p| {
                let middle = (20..40).contains(&(p / w));
                [if middle { line(p % w) } else { 160 }; 3]
            })
            .collect();
        let lab = LabImage::from_rgb(&rgb, w, h);
        let graph = Graph::build(&sp, &rgb, &lab, 3);
        let field = CableField {
            width: 20,
            height: 6,
            cell_px: [10.0, 10.0],
            cable: (0..120)
                .map(|i| {
                    if (2..4).contains(&(i / 20)) {
                        cable(i % 20)
                    } else {
                        0.0
                    }
                })
                .collect(),
            orientation: vec![[1.0, 0.0]; 120],
        };
        let vertex_field = field.per_vertex(&sp);
        let terrain = Terrain {
            graph: &graph,
            lab: &lab,
            field: Some(&vertex_field),
            field_map: Some(&field),
            step_px: 20.0,
            params,
            deadline: Deadline::NONE,
        };
        then(terrain)
    }

    /// A dark line (level 40) from the left edge to column `end`.
    fn dark_to(end: usize) -> impl Fn(usize) -> u8 {
        move |x| if x < end { 40 } else { 160 }
    }

    /// The walks from the end of a cable on a dark line along the whole middle row,
    /// where the field shows cable on the line's first three and last three superpixels
    /// only (a painted line or a shadow joins two cables), under `params`: the vertices
    /// each visits.
    fn walks_along_a_line_the_field_breaks(params: &Params) -> Vec<Vec<u32>> {
        // The end of the left cable, at the right edge of superpixel 12.
        let seeds = [Seed {
            point: [58.0, 30.0],
            vertex: 12,
        }];
        walks_on_a_line(|_| 40, |col| !(6..14).contains(&col), &seeds, params)
            .into_iter()
            .map(|w| w.vertices)
            .collect()
    }

    /// `then` on the terrain of [`on_a_line`] with a walker from one seed, at (30, 30) in
    /// superpixel 11, and that seed.
    fn from_one_seed(
        line: impl Fn(usize) -> u8,
        cable: impl Fn(usize) -> f32,
        params: &Params,
        then: impl FnOnce(Terrain<'_>, &Walker<'_>, &[Seed]),
    ) {
        let seeds = [Seed {
            point: [30.0, 30.0],
            vertex: 11,
        }];
        on_a_line(line, cable, params, |terrain| {
            then(terrain, &Walker::new(terrain, &seeds, seeds.len()), &seeds)
        })
    }

    #[test]
    fn a_walk_stopped_against_an_edge_heading_along_it_has_left_the_frame() {
        let p = Params::default();
        from_one_seed(
            |_| 160,
            |_| 0.0,
            &p,
            |_, walker, _| {
                let w = p.nominal_width_px;
                // 0.8 of a cable width from the right edge (x = 199), heading up and 4° into
                // the frame: centroids against an edge read so where a cable runs out along
                // it (once lost: half a width and no lean into the frame were allowed).
                let up = [-0.06, -0.998];
                assert_eq!(
                    walker.stopped(0, [199.0 - 0.8 * w, 30.0], up),
                    WalkEnd::Border
                );
                // Farther from the edge, or clearly heading back into the frame: lost.
                assert_eq!(
                    walker.stopped(0, [199.0 - 1.5 * w, 30.0], up),
                    WalkEnd::Lost
                );
                let back = [-0.5, -0.866];
                assert_eq!(
                    walker.stopped(0, [199.0 - 0.8 * w, 30.0], back),
                    WalkEnd::Lost
                );
            },
        );
    }

    #[test]
    fn a_walk_opening_across_the_field_at_its_end_scores_less() {
        let p = Params::default();
        from_one_seed(
            dark_to(200),
            |_| 1.0,
            &p,
            |terrain, walker, seeds| {
                // The field runs along the row: a way out along it keeps the walk's quality;
                // one across it (onto a cable the end lies against) loses the weight.
                let seed = seeds[0].point;
                let opening = |points: &[[f32; 2]]| {
                    let u = walker.opening_direction(seed, points).expect("a way out");
                    walker.opening(seed, u)
                };
                let along = opening(&[seed, [50.0, 30.0], [72.0, 31.0]]);
                let across = opening(&[seed, [31.0, 50.0], [30.0, 72.0]]);
                assert!((along - 1.0).abs() < 1e-3, "{along}");
                let w = p.field_opening_weight;
                assert!(w > 0.0 && (across - (1.0 - w)).abs() < 1e-3, "{across}");
                // Seeds that are no cable's ends get no such factor.
                let walks = walk_all(terrain, seeds, seeds.len(), false).unwrap();
                assert!(!walks.is_empty() && walks.iter().all(|w| w.opening == 1.0));
            },
        );
    }

    #[test]
    fn a_walk_along_a_cable_that_runs_on_behind_its_seed_is_marked() {
        let p = Params::default();
        // A cable from the left edge to x = 120 (its end, in superpixel 15).
        let cable = |col: usize| col < 12;
        let end = Seed {
            point: [118.0, 30.0],
            vertex: 15,
        };
        let walks = walks_on_a_line(dark_to(120), cable, &[end], &p);
        let along = walks.iter().find(|w| w.end == WalkEnd::Border);
        assert!(along.is_some_and(|w| !w.through), "{walks:?}");
        // From a point in its middle the cable runs on behind every walk along it.
        let middle = Seed {
            point: [70.0, 30.0],
            vertex: 13,
        };
        let walks = walks_on_a_line(dark_to(120), cable, &[middle], &p);
        let on_it: Vec<&Walk> = walks
            .iter()
            .filter(|w| w.vertices.iter().all(|v| (10..20).contains(v)))
            .collect();
        assert_eq!(on_it.len(), 2, "{walks:?}");
        assert!(on_it.iter().all(|w| w.through), "{walks:?}");
    }

    #[test]
    fn a_terminal_marked_twice_is_no_cable_running_on() {
        let p = Params::default();
        // A cable from the left edge to x = 120, where its insulation ends, and its
        // metal tip on to x = 160, of the same colour and called cable by the field.
        let (line, cable) = (dark_to(160), |col: usize| col < 16);
        let insulation = Seed {
            point: [118.0, 30.0],
            vertex: 15,
        };
        let tip = Seed {
            point: [158.0, 30.0],
            vertex: 17,
        };
        let to_the_edge = |seeds: &[Seed]| {
            walks_on_a_line(&line, cable, seeds, &p)
                .into_iter()
                .find(|w| w.seed == 0 && w.end == WalkEnd::Border && w.vertices.contains(&10))
        };
        // Alone, the end's tip reads as the cable running on behind it...
        let alone = to_the_edge(&[insulation]);
        assert!(alone.as_ref().is_some_and(|w| w.through), "{alone:?}");
        // ... but the network marked the tip's end too: the walk follows the end's own
        // cable.
        let twice = to_the_edge(&[insulation, tip]);
        assert!(twice.as_ref().is_some_and(|w| !w.through), "{twice:?}");
    }

    /// Whether a walk from the end of a dark cable from the left edge to x = 80, then a
    /// white collar to its end at x = 120 (superpixels 14 and 15), where the field's
    /// cable probability is `cable` of the cell's column, follows the cable to the
    /// left edge under `params`.
    fn passes_the_collar(cable: impl Fn(usize) -> f32, params: &Params) -> bool {
        let collared = |x: usize| match x {
            0..80 => 40,
            80..120 => 230,
            _ => 160,
        };
        let end = Seed {
            point: [118.0, 30.0],
            vertex: 15,
        };
        walks_on_a_graded_line(collared, cable, &[end], params)
            .iter()
            .any(|w| w.end == WalkEnd::Border && w.vertices.contains(&10))
    }

    #[test]
    fn a_walk_passes_a_collar_of_another_colour_between_its_end_and_the_cable() {
        // The field sees cable all along.
        let along = |params: &Params| passes_the_collar(|col| f32::from(col < 12), params);
        assert!(along(&Params::default()));
        let never = Params {
            field_recolour_steps: 0.0,
            ..Params::default()
        };
        assert!(!along(&never), "the collar this rule passes");
    }

    #[test]
    fn a_collar_the_field_is_less_sure_of_than_the_cable_is_passed() {
        // The field calls the collar (x 80-120) cable at 0.55 only, as it does a
        // ferrule's sleeve filling whole superpixels of a wide cable.
        let cable = |col: usize| match col {
            0..8 => 0.95,
            8..12 => 0.55,
            _ => 0.0,
        };
        let along = |params: &Params| passes_the_collar(cable, params);
        assert!(along(&Params::default()));
        let sure_only = Params {
            field_collar_head: Params::default().field_trust,
            ..Params::default()
        };
        assert!(!along(&sure_only), "a head the field is sure of, as before");
    }

    #[test]
    fn a_walk_does_not_cross_a_stretch_the_field_calls_background() {
        let reaches_the_right_cable = |params: &Params| {
            walks_along_a_line_the_field_breaks(params)
                .iter()
                .any(|v| v.iter().any(|&u| (17..20).contains(&u)))
        };
        let mut p = Params {
            field_gap_min_cable: 0.0,
            ..Params::default()
        };
        assert!(reaches_the_right_cable(&p), "the crossing this rule stops");
        p.field_gap_min_cable = Params::default().field_gap_min_cable;
        assert!(!reaches_the_right_cable(&p));
        // The walk along its own cable is not affected.
        let walks = walks_along_a_line_the_field_breaks(&p);
        assert!(walks.iter().any(|v| v.contains(&10)), "{walks:?}");
    }

    #[test]
    fn a_wrapped_seed_superpixel_walks_from_the_wrapper_s_neighbours() {
        // A 3x3 grid of 20 px superpixels (ids 0-8); a 4x4 one (id 9) at the centre of
        // the middle one, which wraps it: the seed's only neighbour lies about a pixel
        // away, a step that would give no heading.
        let (w, h) = (60usize, 60usize);
        let labels: Vec<u32> = (0..w * h)
            .map(|p| {
                let (x, y) = (p % w, p / w);
                if (28..32).contains(&x) && (28..32).contains(&y) {
                    9
                } else {
                    (y / 20 * 3 + x / 20) as u32
                }
            })
            .collect();
        let sp = Superpixels {
            width: w,
            height: h,
            labels,
            count: 10,
            step: 20.0,
        };
        let rgb = vec![120u8; w * h * 3];
        let lab = LabImage::from_rgb(&rgb, w, h);
        let graph = Graph::build(&sp, &rgb, &lab, 3);
        assert_eq!(graph.neighbours(9), &[4]);
        let seed = Seed {
            point: [29.5, 29.5],
            vertex: 9,
        };
        let (region, mut firsts) = seed_region(&graph, &seed, 0.4 * 20.0);
        assert_eq!(region, vec![9, 4]);
        firsts.sort_unstable();
        assert_eq!(firsts, vec![1, 3, 5, 7]);
        // Away from any wrapper the region is the seed's superpixel alone.
        let corner = Seed {
            point: [2.0, 2.0],
            vertex: 0,
        };
        let (region, mut firsts) = seed_region(&graph, &corner, 0.4 * 20.0);
        firsts.sort_unstable();
        assert_eq!((region, firsts), (vec![0], vec![1, 3]));
    }
}
