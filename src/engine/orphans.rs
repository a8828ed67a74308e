//! Cables whose ends the network missed. On a background it never saw, the terminal
//! head misses more than the cable probability does: a cable can lie in the field with
//! neither end detected. Superpixels the field calls cable that no cable found so far
//! explains form connected pieces; the two ends of each elongated piece (the two
//! superpixels farthest apart along it) become extra seeds, walked with the border
//! seeds of [`super::border`]: a walk from one counts when it reaches another seed or
//! the border. An end at the border is left to the border seeds (a cable crossing the
//! frame is theirs whole).

use std::collections::VecDeque;

use super::Params;
use super::field::VertexField;
use super::graph::Graph;
use super::walk::Seed;

/// Seeds at the ends of every piece of unexplained cable (connected superpixels with a
/// mean cable probability of at least `field_orphan_level`, none of them `covered`)
/// whose two ends lie at least `field_orphan_min_steps` superpixel steps apart; ends
/// within one step of the border of the `size` (width, height) image are left out.
pub fn orphan_seeds(
    graph: &Graph,
    field: &[VertexField],
    covered: &[bool],
    (step_px, size): (f32, [usize; 2]),
    params: &Params,
) -> Vec<Seed> {
    let n = graph.len();
    let cable =
        |v: u32| field[v as usize].cable >= params.field_orphan_level && !covered[v as usize];
    let min_length = params.field_orphan_min_steps * step_px;
    let [w, h] = size.map(|v| v as f32);
    let inside = |[x, y]: [f32; 2]| x.min(y).min(w - x).min(h - y) > step_px;
    let mut seen = vec![false; n];
    let mut hops = vec![u32::MAX; n];
    let mut seeds = Vec::new();
    for start in 0..n as u32 {
        if seen[start as usize] || !cable(start) {
            continue;
        }
        // The piece and its two ends: the farthest superpixel (in hops) from any of
        // its superpixels, and the farthest from that one.
        let (a, piece) = farthest(graph, start, &cable, &mut hops);
        for &v in &piece {
            seen[v as usize] = true;
        }
        let (b, _) = farthest(graph, a, &cable, &mut hops);
        let [ca, cb] = [a, b].map(|v| graph.vertices[v as usize].centroid);
        if (ca[0] - cb[0]).hypot(ca[1] - cb[1]) >= min_length {
            seeds.extend(
                [(a, ca), (b, cb)]
                    .into_iter()
                    .filter(|&(_, c)| inside(c))
                    .map(|(vertex, point)| Seed { point, vertex }),
            );
        }
    }
    seeds
}

/// Breadth-first search from `start` over the superpixels `inside` marks: the last one
/// reached (the farthest in hops) and every one reached, in order. `hops` is scratch
/// space, all `u32::MAX` before and after.
fn farthest(
    graph: &Graph,
    start: u32,
    inside: &impl Fn(u32) -> bool,
    hops: &mut [u32],
) -> (u32, Vec<u32>) {
    let mut order = vec![start];
    let mut queue = VecDeque::from([start]);
    hops[start as usize] = 0;
    while let Some(v) = queue.pop_front() {
        for &u in graph.neighbours(v) {
            if hops[u as usize] == u32::MAX && inside(u) {
                hops[u as usize] = hops[v as usize] + 1;
                order.push(u);
                queue.push_back(u);
            }
        }
    }
    for &v in &order {
        hops[v as usize] = u32::MAX;
    }
    (*order.last().unwrap_or(&start), order)
}
