//! Cables whose ends the network missed. On a background it never saw, the terminal
//! head misses more than the cable probability does: a cable can lie in the field with
//! neither end detected. Superpixels the field calls cable that no cable found so far
//! explains form connected pieces; the two ends of each elongated piece (the two
//! superpixels farthest apart along it) and the tips of its other branches (two cables
//! crossing make one X-shaped piece) become extra seeds, walked with the border
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
/// whose two ends lie at least `field_orphan_min_steps` superpixel steps apart, and at
/// the tips of its other branches as long ([`branch_tips`]); ends within one step of
/// the border of the `size` (width, height) image are left out.
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
    let mut parent = vec![0; n];
    let mut seeds = Vec::new();
    for start in 0..n as u32 {
        if seen[start as usize] || !cable(start) {
            continue;
        }
        // The piece and its two ends: the farthest superpixel (in hops) from any of
        // its superpixels, and the farthest from that one.
        let (a, piece) = farthest(graph, start, &cable, (&mut hops, &mut parent));
        for &v in &piece {
            seen[v as usize] = true;
        }
        let (b, _) = farthest(graph, a, &cable, (&mut hops, &mut parent));
        let [ca, cb] = [a, b].map(|v| graph.vertices[v as usize].centroid);
        if (ca[0] - cb[0]).hypot(ca[1] - cb[1]) >= min_length {
            let mut ends = vec![a, b];
            let scratch = (&mut hops[..], &mut parent[..]);
            ends.extend(branch_tips(graph, [a, b], &cable, min_length, scratch));
            seeds.extend(
                ends.into_iter()
                    .map(|v| (v, graph.vertices[v as usize].centroid))
                    .filter(|&(_, c)| inside(c))
                    .map(|(vertex, point)| Seed { point, vertex }),
            );
        }
    }
    seeds
}

/// The farthest superpixel (in hops) from `start` over the superpixels `inside`
/// marks, and every one reached, in order ([`search`]).
fn farthest(
    graph: &Graph,
    start: u32,
    inside: &impl Fn(u32) -> bool,
    (hops, parent): (&mut [u32], &mut [u32]),
) -> (u32, Vec<u32>) {
    let order = search(graph, &[start], inside, hops, parent);
    clear(&order, hops);
    (*order.last().unwrap_or(&start), order)
}

/// Most branches a piece of field is searched for beyond its two ends.
const MAX_BRANCHES: usize = 4;

/// The tips of a piece's branches other than its two ends `[a, b]` (the piece: the
/// superpixels `inside` marks, connected to them): repeatedly, the superpixel farthest
/// (in hops) from the course a..b and the branches found so far, while it lies at least
/// `min_length` pixels from where its branch leaves them. Two cables whose ends were
/// missed, crossing, make one X-shaped piece: its two farthest superpixels are the ends
/// of one branch each, and the other two ends are these tips. `hops` and `parent` are
/// scratch space, `hops` all `u32::MAX` before and after.
fn branch_tips(
    graph: &Graph,
    [a, b]: [u32; 2],
    inside: &impl Fn(u32) -> bool,
    min_length: f32,
    (hops, parent): (&mut [u32], &mut [u32]),
) -> Vec<u32> {
    let centroid = |v: u32| graph.vertices[v as usize].centroid;
    // The course from b back to a.
    let order = search(graph, &[a], inside, hops, parent);
    let mut skeleton = vec![b];
    while let Some(&v) = skeleton.last().filter(|&&v| v != a) {
        skeleton.push(parent[v as usize]);
    }
    clear(&order, hops);
    let mut tips = Vec::new();
    for _ in 0..MAX_BRANCHES {
        let order = search(graph, &skeleton, inside, hops, parent);
        let tip = *order.last().unwrap_or(&a);
        let mut branch = Vec::new();
        let mut v = tip;
        while hops[v as usize] > 0 {
            branch.push(v);
            v = parent[v as usize];
        }
        clear(&order, hops);
        let [t, root] = [tip, v].map(centroid);
        if (t[0] - root[0]).hypot(t[1] - root[1]) < min_length {
            break;
        }
        tips.push(tip);
        skeleton.extend(branch);
    }
    tips
}

/// Breadth-first search from `sources` over the superpixels `inside` marks: every one
/// reached, in order, with its hops from the nearest source and the superpixel it was
/// reached from (a source: itself) in `hops` and `parent`.
pub(super) fn search(
    graph: &Graph,
    sources: &[u32],
    inside: &impl Fn(u32) -> bool,
    hops: &mut [u32],
    parent: &mut [u32],
) -> Vec<u32> {
    let mut order = sources.to_vec();
    for &v in sources {
        hops[v as usize] = 0;
        parent[v as usize] = v;
    }
    let mut queue: VecDeque<u32> = sources.iter().copied().collect();
    while let Some(v) = queue.pop_front() {
        for &u in graph.neighbours(v) {
            if hops[u as usize] == u32::MAX && inside(u) {
                hops[u as usize] = hops[v as usize] + 1;
                parent[u as usize] = v;
                order.push(u);
                queue.push_back(u);
            }
        }
    }
    order
}

/// Puts `hops` back to `u32::MAX` where a search reached.
fn clear(order: &[u32], hops: &mut [u32]) {
    for &v in order {
        hops[v as usize] = u32::MAX;
    }
}
