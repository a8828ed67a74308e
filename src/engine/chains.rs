//! Cables found in pieces, made whole. The seeds at the ends of the field's
//! unexplained pieces ([`super::orphans`]) are not cable ends: a cable whose ends the
//! network missed, crossed by cables already found, is cut by them into several
//! pieces, each with a seed at either end, and the pairing makes one cable of each
//! piece. Where a walk from the end of one such cable reaches the end of another, and
//! the course runs on smoothly through both joints (each turning at most
//! `max_turn_deg`), the two are one cable: their courses are chained, best linking walk
//! first, as long as a chain keeps a seed at one end at least.
//!
//! A piece ends where the field's unexplained cable ends: at a crossing with a cable
//! already found (a link goes on there), or where the cable's probability fades before
//! the cable does, short of the end the network missed. There the walks from the
//! piece's seed that lost the cable or left the frame are the cable's way on, to where
//! the colour or the field gives out or to the frame's edge: a chained course that
//! still ends on a seed runs on along the best of them that continues it smoothly
//! ([`extend`]). A seed by a crossing whose piece runs to the frame's edge has walks
//! out of the frame either way, along its piece and across the crossing: the pairing
//! takes one, and the course runs on along the other.

use super::Params;
use super::geometry::heading;
use super::pairing::{FarEnd, Pairing};
use super::walk::{Walk, WalkEnd};

/// A cable's course being chained: its superpixels in order and what lies at either
/// end of them.
#[derive(Debug, Clone, PartialEq)]
pub struct Course {
    /// The superpixels, first to last.
    pub vertices: Vec<u32>,
    /// What lies before the first and after the last superpixel.
    pub ends: [FarEnd; 2],
    /// Score: the least of the pieces' and the links'.
    pub score: f32,
}

impl Course {
    /// The course of one pairing of `walks`: its walk, then the walk it is joined to,
    /// backwards.
    pub fn of(walks: &[Walk], choice: &Pairing) -> Self {
        let mut vertices = walks[choice.walk].vertices.clone();
        if let Some(j) = choice.joined {
            vertices.extend(walks[j].vertices[1..].iter().rev());
        }
        Self {
            vertices,
            ends: [FarEnd::Seed(choice.start), choice.far],
            score: choice.score,
        }
    }

    fn reversed(mut self) -> Self {
        self.vertices.reverse();
        self.ends.reverse();
        self
    }

    /// Which end (0, 1) is `seed`.
    fn end_at(&self, seed: usize) -> Option<usize> {
        self.ends.iter().position(|&e| e == FarEnd::Seed(seed))
    }
}

/// The courses of the `picked` pairings of `walks` (walks from seeds; `centroid` gives
/// a superpixel's centroid), chained through the seeds where a walk of `links` joins
/// two of them (see the module docs). `links` holds every walk from those seeds, however
/// short or much over cables found, since crossing a found cable is what a link does;
/// links scoring below `min_score` are not used. Each course starts at a seed.
pub fn chain(
    walks: &[Walk],
    picked: &[Pairing],
    links: &[Walk],
    centroid: impl Fn(u32) -> [f32; 2],
    (params, min_score): (&Params, f32),
) -> Vec<Course> {
    let mut courses: Vec<Option<Course>> =
        picked.iter().map(|p| Some(Course::of(walks, p))).collect();
    let mut links: Vec<(f32, &Walk)> = links
        .iter()
        .filter_map(|w| match w.end {
            WalkEnd::Seed(_) => Some((w.quality(params), w)),
            _ => None,
        })
        .filter(|&(q, _)| q >= min_score)
        .collect();
    links.sort_by(|a, b| b.0.total_cmp(&a.0));
    let cos_max = params.max_turn_deg.to_radians().cos();
    let centroids = |vs: &[u32]| -> Vec<[f32; 2]> { vs.iter().map(|&v| centroid(v)).collect() };
    let span = params.heading_span_px;
    for (quality, link) in links {
        let WalkEnd::Seed(to) = link.end else {
            continue;
        };
        let owner = |seed: usize| {
            courses
                .iter()
                .position(|c| c.as_ref().is_some_and(|c| c.end_at(seed).is_some()))
        };
        let (Some(a), Some(b)) = (owner(link.seed), owner(to)) else {
            continue;
        };
        if a == b {
            continue;
        }
        // The first course ends at the link's start, the second starts at its end.
        let first = courses[a].clone().expect("owned");
        let first = if first.end_at(link.seed) == Some(0) {
            first.reversed()
        } else {
            first
        };
        let second = courses[b].clone().expect("owned");
        let second = if second.end_at(to) == Some(1) {
            second.reversed()
        } else {
            second
        };
        if !matches!(first.ends[0], FarEnd::Seed(_)) && !matches!(second.ends[1], FarEnd::Seed(_)) {
            continue;
        }
        let path = centroids(&link.vertices);
        let smooth = |into: [f32; 2], out: [f32; 2]| into[0] * out[0] + into[1] * out[1] >= cos_max;
        let out_of = |points: &[[f32; 2]]| {
            let rev: Vec<[f32; 2]> = points.iter().rev().copied().collect();
            heading(&rev, span).map(|v| -v)
        };
        let joints_smooth = smooth(heading(&centroids(&first.vertices), span), out_of(&path))
            && smooth(heading(&path, span), out_of(&centroids(&second.vertices)));
        if !joints_smooth {
            continue;
        }
        let mut vertices = first.vertices;
        for &v in link.vertices.iter().chain(&second.vertices) {
            if vertices.last() != Some(&v) {
                vertices.push(v);
            }
        }
        courses[b] = None;
        courses[a] = Some(Course {
            vertices,
            ends: [first.ends[0], second.ends[1]],
            score: first.score.min(second.score).min(quality),
        });
    }
    courses
        .into_iter()
        .flatten()
        .map(|c| {
            if matches!(c.ends[0], FarEnd::Seed(_)) {
                c
            } else {
                c.reversed()
            }
        })
        .collect()
}

/// Runs every course of `courses` that ends on a seed on along the best walk of
/// `extensions` from that seed (walks that lost the cable or left the frame, over
/// superpixels no cable explains) that scores at least `min_score` and leaves the seed
/// turning at most `max_turn_deg` from the course's heading there; that end is then
/// open or at the border, and the course scores at most the walk's quality.
pub fn extend(
    courses: &mut [Course],
    extensions: &[Walk],
    centroid: impl Fn(u32) -> [f32; 2],
    (params, min_score): (&Params, f32),
) {
    let cos_max = params.max_turn_deg.to_radians().cos();
    let span = params.heading_span_px;
    let centroids = |vs: &[u32]| -> Vec<[f32; 2]> { vs.iter().map(|&v| centroid(v)).collect() };
    for course in courses.iter_mut() {
        for end in [1, 0] {
            let FarEnd::Seed(seed) = course.ends[end] else {
                continue;
            };
            let ways: Vec<(f32, &Walk)> = extensions
                .iter()
                .filter(|w| w.seed == seed && matches!(w.end, WalkEnd::Lost | WalkEnd::Border))
                .map(|w| (w.quality(params), w))
                .filter(|&(q, _)| q >= min_score)
                .collect();
            if ways.is_empty() {
                continue;
            }
            if end == 0 {
                course.vertices.reverse();
            }
            let into = heading(&centroids(&course.vertices), span);
            let best = ways
                .into_iter()
                .filter(|(_, w)| {
                    let back: Vec<[f32; 2]> = centroids(&w.vertices).into_iter().rev().collect();
                    let out = heading(&back, span).map(|v| -v);
                    into[0] * out[0] + into[1] * out[1] >= cos_max
                })
                .max_by(|a, b| a.0.total_cmp(&b.0));
            if let Some((quality, walk)) = best {
                for &v in &walk.vertices {
                    if course.vertices.last() != Some(&v) && !course.vertices.contains(&v) {
                        course.vertices.push(v);
                    }
                }
                course.ends[end] = match walk.end {
                    WalkEnd::Border => FarEnd::Border,
                    _ => FarEnd::Open,
                };
                course.score = course.score.min(quality);
            }
            if end == 0 {
                course.vertices.reverse();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A walk from `seed` over `vertices` to seed `to`.
    fn walk(seed: usize, vertices: &[u32], to: usize) -> Walk {
        Walk {
            seed,
            vertices: vertices.to_vec(),
            end: WalkEnd::Seed(to),
            visual: 1.0,
            smoothness: 1.0,
            contrast: 1.0,
            cable: 1.0,
            length_px: 10.0 * vertices.len() as f32,
            end_heading: [1.0, 0.0],
            end_point: [0.0, 0.0],
            through: false,
            opening: 1.0,
        }
    }

    fn picked(walk: usize, start: usize, to: usize) -> Pairing {
        Pairing {
            start,
            far: FarEnd::Seed(to),
            walk,
            joined: None,
            score: 0.5,
        }
    }

    /// Superpixel `v` lies at (10 v, 0): one straight cable.
    fn on_a_line(v: u32) -> [f32; 2] {
        [10.0 * v as f32, 0.0]
    }

    #[test]
    fn pieces_a_walk_links_smoothly_become_one_cable() {
        // Seeds 0-1 end the first piece (superpixels 0-3), 2-3 the second (6-9); a walk
        // from seed 1 crosses 4-5 to seed 2.
        let walks = [walk(0, &[0, 1, 2, 3], 1), walk(2, &[6, 7, 8, 9], 3)];
        let links = [walk(1, &[3, 4, 5, 6], 2)];
        let picked = [picked(0, 0, 1), picked(1, 2, 3)];
        let with_floor = |floor: f32| {
            chain(
                &walks,
                &picked,
                &links,
                on_a_line,
                (&Params::default(), floor),
            )
        };
        let courses = with_floor(0.1);
        assert_eq!(courses.len(), 1);
        let c = &courses[0];
        assert_eq!(c.ends, [FarEnd::Seed(0), FarEnd::Seed(3)]);
        assert_eq!(c.vertices, (0..10).collect::<Vec<u32>>());
        // A link below the floor joins nothing.
        let apart = with_floor(1.1);
        assert_eq!(apart.len(), 2);
    }

    #[test]
    fn a_piece_runs_on_along_a_walk_that_lost_the_cable_further_on() {
        // One piece (superpixels 0-3) between seeds 0 and 1; walks from seed 1 that
        // lost the cable: straight on over 3-7, back at a right angle over 3, 20, 21.
        let walks = [walk(0, &[0, 1, 2, 3], 1)];
        let lost = |vertices: &[u32], quality: f32| Walk {
            end: WalkEnd::Lost,
            visual: quality * quality,
            ..walk(1, vertices, 0)
        };
        let at = |v: u32| match v {
            20 | 21 => [30.0, 10.0 * (v - 19) as f32],
            _ => on_a_line(v),
        };
        let p = Params::default();
        let course = |extensions: &[Walk], floor: f32| {
            let mut courses = chain(&walks, &[picked(0, 0, 1)], &[], at, (&p, floor));
            extend(&mut courses, extensions, at, (&p, floor));
            courses.remove(0)
        };
        let on = [lost(&[3, 4, 5, 6, 7], 0.6), lost(&[3, 20, 21], 0.9)];
        let c = course(&on, 0.1);
        assert_eq!(c.vertices, (0..8).collect::<Vec<u32>>());
        assert_eq!(c.ends, [FarEnd::Seed(0), FarEnd::Open]);
        assert_eq!(c.score, 0.5_f32.min(on[0].quality(&p)));
        // Along one that left the frame instead, the course ends at the border.
        let out = Walk {
            end: WalkEnd::Border,
            ..on[0].clone()
        };
        let c = course(std::slice::from_ref(&out), 0.1);
        assert_eq!(c.vertices, (0..8).collect::<Vec<u32>>());
        assert_eq!(c.ends, [FarEnd::Seed(0), FarEnd::Border]);
        // Below the floor, or only the sharp turn: the piece stays as it was.
        for (extensions, floor) in [(&on[..], 0.7), (&on[1..], 0.1)] {
            let c = course(extensions, floor);
            assert_eq!(c.vertices, [0, 1, 2, 3]);
            assert_eq!(c.ends, [FarEnd::Seed(0), FarEnd::Seed(1)]);
        }
    }

    #[test]
    fn pieces_meeting_at_a_sharp_turn_stay_apart() {
        // The second piece leaves the link's end at a right angle.
        let at = |v: u32| match v {
            0..=6 => on_a_line(v),
            _ => [60.0, 10.0 * (v - 6) as f32],
        };
        let walks = [walk(0, &[0, 1, 2, 3], 1), walk(2, &[6, 7, 8, 9], 3)];
        let links = [walk(1, &[3, 4, 5, 6], 2)];
        let picked = [picked(0, 0, 1), picked(1, 2, 3)];
        let courses = chain(&walks, &picked, &links, at, (&Params::default(), 0.1));
        assert_eq!(courses.len(), 2);
        assert_eq!(courses[0].vertices, [0, 1, 2, 3]);
    }
}
