//! Cables with no end in view: both of their ends lie outside the frame, so no walk from
//! an end can find them. Where such a cable crosses the border, the border has a short
//! run of superpixels whose colour stands out from the rest of the border (mostly
//! background); each such run not explained by a cable already found becomes an extra
//! seed on the border, and only walks that cross the image to another border point
//! count from it.

use super::graph::Graph;
use super::superpixels::Superpixels;
use super::walk::Seed;

/// Lab ΔE from the border's median colour at which a border superpixel stands out.
const MIN_BORDER_CONTRAST: f32 = 20.0;
/// Longest run of standing-out border pixels taken for one cable crossing (longer runs
/// are objects lying along the border, not cables crossing it).
const MAX_CROSSING_PX: usize = 40;
/// Shortest run, pixels (JPEG noise and specks).
const MIN_CROSSING_PX: usize = 3;

/// The perimeter pixels in clockwise order from the top-left corner, once each.
fn perimeter(w: usize, h: usize) -> Vec<[usize; 2]> {
    let mut out = Vec::with_capacity(2 * (w + h));
    out.extend((0..w).map(|x| [x, 0]));
    out.extend((1..h).map(|y| [w - 1, y]));
    out.extend((0..w - 1).rev().map(|x| [x, h - 1]));
    out.extend((1..h - 1).rev().map(|y| [0, y]));
    out
}

/// Seeds on the border where an unexplained cable may cross it; `covered[v]` marks the
/// superpixels already explained by a cable.
pub fn border_seeds(graph: &Graph, sp: &Superpixels, covered: &[bool]) -> Vec<Seed> {
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
        channel.sort_by(f32::total_cmp);
        *b = channel[channel.len() / 2];
    }
    let stands_out: Vec<bool> = labels
        .iter()
        .zip(&colours)
        .map(|(&v, lab)| {
            let de = (0..3)
                .map(|c| (lab[c] - background[c]).powi(2))
                .sum::<f32>()
                .sqrt();
            de >= MIN_BORDER_CONTRAST && !covered[v as usize]
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
        if (MIN_CROSSING_PX..=MAX_CROSSING_PX).contains(&run) {
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
        let seeds = border_seeds(&graph, &sp, &vec![false; graph.len()]);
        assert_eq!(seeds.len(), 2, "{seeds:?}");
        assert!(seeds.iter().all(|s| (44.0..52.0).contains(&s.point[0])));
        // Once the stripe is explained, nothing is left to seed.
        assert!(border_seeds(&graph, &sp, &vec![true; graph.len()]).is_empty());
    }
}
