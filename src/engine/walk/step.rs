//! Scoring one step of a walk: the likelihoods of every candidate, the field's term,
//! and the rule that refuses the best one (module docs of [`super`]).

use super::{Candidate, Walker, visual_likelihood};
use crate::engine::field::{GAP_SAMPLE_PX, VertexField, alignment};
use crate::engine::geometry::{dist3, norm};
use crate::engine::graph::intersection;
use crate::engine::spline::resample;

impl Walker<'_> {
    /// The best acceptable next vertex among those within `order` hops of `head`;
    /// `colour_blind`: among those the field is sure of (`field_trust`), whatever their
    /// colour (a step by the field alone, module docs).
    pub(super) fn best_candidate(
        &mut self,
        id: u32,
        head: u32,
        here: [f32; 2],
        dir: [f32; 2],
        order: u32,
        colour_blind: bool,
    ) -> Option<Candidate> {
        let p = self.params;
        self.hood
            .collect(self.graph, head, order, &mut self.candidates);
        let mut best: Option<(f32, Candidate)> = None;
        for &(c, _) in &self.candidates {
            if self.in_walk[c as usize] == id {
                continue;
            }
            let q = self.pos(c);
            let step = [q[0] - here[0], q[1] - here[1]];
            let d = norm(step);
            if d < 1e-3 || d > p.max_step_px {
                continue;
            }
            let cos = (step[0] * dir[0] + step[1] * dir[1]) / d;
            if cos < self.cos_max_turn {
                continue;
            }
            let similarity = intersection(&self.model, self.graph.histogram(c));
            let pv = if colour_blind {
                1.0
            } else {
                visual_likelihood(similarity, p)
            };
            let curvature = (p.kappa * (cos - 1.0)).exp();
            let pd = 1.0 / (1.0 + p.c_distance * d / p.max_step_px);
            let unit = [step[0] / d, step[1] / d];
            let contrast = self.contrast(c, unit);
            let (cable, field_term) = match self.vertex_field(c) {
                Some(f) => {
                    let presence = p.field_floor + (1.0 - p.field_floor) * f.cable;
                    let w = p.field_alignment_weight;
                    let agreement = 1.0 - w + w * alignment(unit, f.orientation);
                    (f.cable, presence * agreement)
                }
                None => (1.0, 1.0),
            };
            if colour_blind && cable < p.field_trust {
                continue;
            }
            let score = pv * curvature * pd * contrast * field_term;
            if best.as_ref().is_none_or(|b| score > b.0) {
                best = Some((
                    score,
                    Candidate {
                        vertex: c,
                        similarity,
                        curvature,
                        contrast,
                        cable,
                    },
                ));
            }
        }
        let field = self.field.is_some();
        best.map(|b| b.1).filter(|b| {
            let sure = field && b.cable >= p.field_trust;
            (b.similarity >= p.min_similarity || colour_blind)
                && (!field || b.cable >= p.field_min_cable)
                && (b.contrast >= p.min_contrast || sure)
                && !self.crosses_background(here, self.pos(b.vertex))
        })
    }

    /// True when the straight line from `a` to `b` runs longer than one superpixel step
    /// where the field's cable probability is below `field_gap_min_cable` (never
    /// without a field).
    fn crosses_background(&self, a: [f32; 2], b: [f32; 2]) -> bool {
        let Some(field) = self.field_map else {
            return false;
        };
        let level = self.params.field_gap_min_cable;
        let line = resample(&[a, b], GAP_SAMPLE_PX);
        let mut run = 0.0f32;
        for q in &line {
            run = if field.cable_at(q[0], q[1]) < level {
                run + GAP_SAMPLE_PX
            } else {
                0.0
            };
            if run > self.side_px {
                return true;
            }
        }
        false
    }

    /// The field's mean over vertex `v`, when a field is used.
    pub(super) fn vertex_field(&self, v: u32) -> Option<VertexField> {
        self.field.map(|f| f[v as usize])
    }

    /// How much vertex `v` differs in colour from the image one step to either side of
    /// the heading `dir`: the smaller of the two Lab distances (a cable differs from the
    /// background on both sides; a walk on the background beside a cable only on one),
    /// capped at `far_contrast_factor` times the larger distance two steps to either side
    /// (the background between two cables side by side matches what lies beyond them),
    /// saturating at 1; 1 when lateral contrast is off.
    pub(super) fn contrast(&self, v: u32, dir: [f32; 2]) -> f32 {
        if !self.params.lateral_contrast {
            return 1.0;
        }
        let vert = &self.graph.vertices[v as usize];
        let c = vert.centroid;
        let normal = [-dir[1], dir[0]];
        let differs = |reach: f32, sign: f32| {
            let x = (c[0] + sign * normal[0] * reach).round();
            let y = (c[1] + sign * normal[1] * reach).round();
            if x < 0.0 || y < 0.0 || x >= self.lab.width as f32 || y >= self.lab.height as f32 {
                return None;
            }
            Some(dist3(
                self.lab.at(y as usize * self.lab.width + x as usize),
                vert.mean_lab,
            ))
        };
        let mut least = [-1.0, 1.0]
            .into_iter()
            .filter_map(|sign| differs(self.side_px, sign))
            .fold(f32::INFINITY, f32::min);
        // The cap binds only when both far sides are within `least / factor`: the second
        // is read only when the first is.
        let factor = self.params.far_contrast_factor;
        if factor > 0.0
            && let Some(a) = differs(2.0 * self.side_px, -1.0)
            && factor * a < least
            && let Some(b) = differs(2.0 * self.side_px, 1.0)
        {
            least = least.min(factor * a.max(b));
        }
        if least.is_finite() {
            (least / self.params.contrast_saturation).min(1.0)
        } else {
            0.0
        }
    }
}
