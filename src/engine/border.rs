//! Cables with no end in view: both of their ends lie outside the frame, so no walk from
//! an end can find them. Where such a cable crosses the border, the border has a short
//! run of superpixels whose colour stands out from the rest of the border (mostly
//! background); each such run not explained by a cable already found becomes an extra
//! seed on the border, and only walks that cross the image to another border point
//! count from it.

use super::Params;
use super::cable::{Cable, Scene, model_cable};
use super::geometry::{dist3, median};
use super::graph::Graph;
use super::pairing::{self, Pairing};
use super::superpixels::Superpixels;
use super::walk::{self, Seed, Walk, WalkEnd};

/// The perimeter pixels in clockwise order from the top-left corner, once each.
fn perimeter(w: usize, h: usize) -> Vec<[usize; 2]> {
    let mut out = Vec::with_capacity(2 * (w + h));
    out.extend((0..w).map(|x| [x, 0]));
    out.extend((1..h).map(|y| [w - 1, y]));
    out.extend((0..w - 1).rev().map(|x| [x, h - 1]));
    out.extend((1..h - 1).rev().map(|y| [0, y]));
    out
}

/// Cables crossing the whole frame, with no end in view: walks from border seeds where
/// the border shows a colour the cables in `chosen` do not explain, kept when they reach
/// another border point (see [`border`]). Their ends belong to no given end.
pub(super) fn border_crossing_cables(scene: &Scene<'_>, chosen: &[Pairing]) -> Vec<Cable> {
    let Scene {
        walks, graph, sp, ..
    } = *scene;
    let mut covered = vec![false; graph.len()];
    for choice in chosen {
        let joined = choice.joined.map(|j| &walks[j].vertices[..]).unwrap_or(&[]);
        for &v in walks[choice.walk].vertices.iter().chain(joined) {
            covered[v as usize] = true;
            for &n in graph.neighbours(v) {
                covered[n as usize] = true;
            }
        }
    }
    let seeds = border_seeds(graph, sp, &covered, scene.params);
    if seeds.is_empty() {
        return Vec::new();
    }
    let p = scene.params;
    let min_length = p.border_min_steps * sp.step;
    let crossing: Vec<Walk> = walk::walk_all(graph, scene.lab, &seeds, sp.step, p)
        .into_iter()
        .filter(|w| {
            let on_found = w.vertices.iter().filter(|&&v| covered[v as usize]).count();
            matches!(w.end, WalkEnd::Border | WalkEnd::Seed(_))
                && w.length_px >= min_length
                && (on_found as f32) <= p.border_max_covered * w.vertices.len() as f32
        })
        .collect();
    let confidence = vec![p.border_seed_confidence; seeds.len()];
    let border_scene = Scene {
        walks: &crossing,
        seeds: &seeds,
        ..*scene
    };
    pairing::pair(&crossing, &confidence, scene.params)
        .iter()
        // Only crossing walks were kept, so every pairing ends on the border or a seed.
        .filter(|c| c.score >= p.border_min_score)
        .filter_map(|c| model_cable(&border_scene, c))
        .map(|mut cable| {
            cable.end_indices = [None, None];
            cable
        })
        .collect()
}

/// Seeds on the border where an unexplained cable may cross it; `covered[v]` marks the
/// superpixels already explained by a cable.
pub fn border_seeds(
    graph: &Graph,
    sp: &Superpixels,
    covered: &[bool],
    params: &Params,
) -> Vec<Seed> {
    let (w, h) = (sp.width, sp.height);
    if w < 3 || h < 3 {
        return Vec::new();
    }
    let ring = perimeter(w, h);
    let labels: Vec<u32> = ring.iter().map(|&[x, y]| sp.labels[y * w + x]).collect();
    let colours: Vec<[f32; 3]> = labels
        .iter()
        .map(|&v| graph.vertices[v as usize].mean_lab)
        .collect();
    let mut background = [0.0; 3];
    for (c, b) in background.iter_mut().enumerate() {
        let mut channel: Vec<f32> = colours.iter().map(|l| l[c]).collect();
        *b = median(&mut channel, f32::total_cmp).unwrap_or(0.0);
    }
    let stands_out: Vec<bool> = labels
        .iter()
        .zip(&colours)
        .map(|(&v, lab)| {
            dist3(*lab, background) >= params.border_min_contrast && !covered[v as usize]
        })
        .collect();
    // Runs of standing-out pixels along the ring (a run may wrap past the start).
    let n = ring.len();
    let Some(start) = (0..n).find(|&i| !stands_out[i]) else {
        return Vec::new();
    };
    let mut seeds = Vec::new();
    let mut i = 0;
    while i < n {
        let at = (start + i) % n;
        if !stands_out[at] {
            i += 1;
            continue;
        }
        let run = (i..n).take_while(|&j| stands_out[(start + j) % n]).count();
        let crossing =
            params.border_min_crossing_px as usize..=params.border_max_crossing_px as usize;
        if crossing.contains(&run) {
            let mid = (start + i + run / 2) % n;
            let [x, y] = ring[mid];
            seeds.push(Seed {
                point: [x as f32, y as f32],
                vertex: labels[mid],
            });
        }
        i += run;
    }
    seeds
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
        let seeds = border_seeds(&graph, &sp, &vec![false; graph.len()], &p);
        assert_eq!(seeds.len(), 2, "{seeds:?}");
        assert!(seeds.iter().all(|s| (44.0..52.0).contains(&s.point[0])));
        // Once the stripe is explained, nothing is left to seed.
        assert!(border_seeds(&graph, &sp, &vec![true; graph.len()], &p).is_empty());
    }
}
