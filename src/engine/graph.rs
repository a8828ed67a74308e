//! The region adjacency graph (RAG) of a superpixel segmentation.
//!
//! One vertex per superpixel with its centroid, pixel count, mean Lab colour
//! and a normalised joint HSV histogram in OpenCV's ranges; an edge between two
//! superpixels that share a 4-connected boundary; and order-d neighbourhoods by BFS.

use super::color::{LabImage, rgb_to_hsv};
use super::superpixels::Superpixels;

/// Attributes of one superpixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vertex {
    /// Centroid (x, y), pixels.
    pub centroid: [f32; 2],
    /// Number of pixels.
    pub pixels: u32,
    /// Mean CIELAB colour.
    pub mean_lab: [f32; 3],
}

/// The region adjacency graph: vertices, symmetric adjacency in compressed rows, and
/// histograms.
#[derive(Debug, Clone, PartialEq)]
pub struct Graph {
    /// One entry per superpixel id.
    pub vertices: Vec<Vertex>,
    offsets: Vec<u32>,
    adjacency: Vec<u32>,
    histograms: Vec<f32>,
    cells: usize,
}

/// One superpixel's running sums.
#[derive(Debug, Clone, Copy, Default)]
struct Totals {
    x: u64,
    y: u64,
    lab: [f64; 3],
    pixels: u64,
}

/// The sums over a row's run of pixels of one superpixel.
#[derive(Debug, Clone, Copy, Default)]
struct Run {
    x: u64,
    lab: [f64; 3],
    pixels: u64,
}

impl Totals {
    /// Adds the run `run` of row `y`.
    fn add(&mut self, run: &Run, y: usize) {
        self.x += run.x;
        self.y += y as u64 * run.pixels;
        for (t, r) in self.lab.iter_mut().zip(run.lab) {
            *t += r;
        }
        self.pixels += run.pixels;
    }
}

impl Graph {
    /// Builds the graph of `sp` over the original colours `rgb` (interleaved RGB8) and
    /// the Lab planes `lab`, with `bins` histogram bins per HSV channel (joint, bins³ cells).
    pub fn build(sp: &Superpixels, rgb: &[u8], lab: &LabImage, bins: u32) -> Self {
        let (w, h, n) = (sp.width, sp.height, sp.count);
        let bins = bins.max(1) as usize;
        let cells = bins * bins * bins;
        // A row's run of one label is summed in registers and added to its superpixel
        // once; the histograms count in integers (no float add waits on the previous
        // one through memory).
        let mut sums = vec![Totals::default(); n];
        let mut counts = vec![0u32; n * cells];
        // Neighbour lists are short (about 6 per superpixel): a linear scan beats hashing.
        let mut lists: Vec<Vec<u32>> = vec![Vec::with_capacity(8); n];
        let mut link = |a: u32, b: u32| {
            if a != b && !lists[a as usize].contains(&b) {
                lists[a as usize].push(b);
                lists[b as usize].push(a);
            }
        };
        for y in 0..h {
            let row = y * w;
            let mut run = Run::default();
            let mut run_label = sp.labels[row];
            for x in 0..w {
                let p = row + x;
                let k = sp.labels[p];
                if x + 1 < w {
                    link(k, sp.labels[p + 1]);
                }
                if y + 1 < h {
                    link(k, sp.labels[p + w]);
                }
                if k != run_label {
                    sums[run_label as usize].add(&run, y);
                    run = Run::default();
                    run_label = k;
                }
                run.x += x as u64;
                run.lab[0] += lab.l[p] as f64;
                run.lab[1] += lab.a[p] as f64;
                run.lab[2] += lab.b[p] as f64;
                run.pixels += 1;
                let [hh, ss, vv] = rgb_to_hsv([rgb[3 * p], rgb[3 * p + 1], rgb[3 * p + 2]]);
                let cell = (hh as usize * bins / 180) * bins * bins
                    + (ss as usize * bins / 256) * bins
                    + vv as usize * bins / 256;
                counts[k as usize * cells + cell] += 1;
            }
            sums[run_label as usize].add(&run, y);
        }
        let vertices: Vec<Vertex> = sums
            .iter()
            .map(|s| {
                let inv = 1.0 / s.pixels.max(1) as f64;
                Vertex {
                    centroid: [(s.x as f64 * inv) as f32, (s.y as f64 * inv) as f32],
                    pixels: s.pixels as u32,
                    mean_lab: s.lab.map(|c| (c * inv) as f32),
                }
            })
            .collect();
        let histograms: Vec<f32> = counts
            .chunks_exact(cells)
            .zip(&vertices)
            .flat_map(|(c, v)| {
                let inv = 1.0 / v.pixels.max(1) as f32;
                c.iter().map(move |&k| k as f32 * inv)
            })
            .collect();
        let mut offsets = Vec::with_capacity(n + 1);
        let mut adjacency = Vec::new();
        offsets.push(0);
        for mut list in lists {
            list.sort_unstable();
            adjacency.extend_from_slice(&list);
            offsets.push(adjacency.len() as u32);
        }
        Self {
            vertices,
            offsets,
            adjacency,
            histograms,
            cells,
        }
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// True when the graph has no vertices.
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// Ring-1 neighbours of `v`, sorted by id.
    pub fn neighbours(&self, v: u32) -> &[u32] {
        let (a, b) = (self.offsets[v as usize], self.offsets[v as usize + 1]);
        &self.adjacency[a as usize..b as usize]
    }

    /// Normalised HSV histogram of `v` (sums to 1).
    pub fn histogram(&self, v: u32) -> &[f32] {
        &self.histograms[v as usize * self.cells..(v as usize + 1) * self.cells]
    }

    /// Number of cells of each histogram.
    pub fn histogram_cells(&self) -> usize {
        self.cells
    }
}

/// Histogram intersection Σ min(a_b, b_b), in 0..=1 for normalised histograms.
#[inline]
pub fn intersection(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| x.min(*y)).sum()
}

/// Reusable breadth-first search for order-d neighbourhoods, without per-call allocation.
#[derive(Debug, Default, Clone)]
pub struct Neighbourhood {
    stamp: Vec<u32>,
    generation: u32,
    frontier: Vec<u32>,
    next: Vec<u32>,
}

impl Neighbourhood {
    /// Writes into `out` every vertex within `order` hops of `v` (excluding `v`), each
    /// with its hop count, ring by ring.
    pub fn collect(&mut self, graph: &Graph, v: u32, order: u32, out: &mut Vec<(u32, u32)>) {
        out.clear();
        if self.stamp.len() != graph.len() {
            self.stamp = vec![0; graph.len()];
            self.generation = 0;
        }
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.fill(0);
            self.generation = 1;
        }
        let g = self.generation;
        self.stamp[v as usize] = g;
        self.frontier.clear();
        self.frontier.push(v);
        for hop in 1..=order {
            self.next.clear();
            for &u in &self.frontier {
                for &n in graph.neighbours(u) {
                    if self.stamp[n as usize] != g {
                        self.stamp[n as usize] = g;
                        self.next.push(n);
                        out.push((n, hop));
                    }
                }
            }
            std::mem::swap(&mut self.frontier, &mut self.next);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::superpixels::{SlicSettings, slic};
    use proptest::prelude::*;

    fn graph_of(rgb: &[u8], w: usize, h: usize, n: u32) -> (Superpixels, Graph) {
        let lab = LabImage::from_rgb(rgb, w, h);
        let sp = slic(
            &lab,
            &SlicSettings {
                n_segments: n,
                compactness: 10.0,
                iterations: 5,
                min_size_factor: 0.25,
            },
        );
        let g = Graph::build(&sp, rgb, &lab, 4);
        (sp, g)
    }

    #[test]
    fn grid_labels_give_grid_adjacency() {
        // Hand-made 2x2 blocks of 3x3 pixels.
        let (w, h) = (6, 6);
        let labels: Vec<u32> = (0..36)
            .map(|p| ((p / 6) / 3 * 2 + (p % 6) / 3) as u32)
            .collect();
        let sp = Superpixels {
            width: w,
            height: h,
            labels,
            count: 4,
            step: 3.0,
        };
        let rgb = vec![100u8; 36 * 3];
        let lab = LabImage::from_rgb(&rgb, w, h);
        let g = Graph::build(&sp, &rgb, &lab, 3);
        assert_eq!(g.neighbours(0), &[1, 2]);
        assert_eq!(g.neighbours(3), &[1, 2]);
        assert_eq!(g.vertices[0].centroid, [1.0, 1.0]);
        assert_eq!(g.vertices[3].pixels, 9);
        let sum: f32 = g.histogram(2).iter().sum();
        assert!((sum - 1.0).abs() < 1e-5);
        assert!((intersection(g.histogram(0), g.histogram(3)) - 1.0).abs() < 1e-5);
        let mut nb = Neighbourhood::default();
        let mut out = Vec::new();
        nb.collect(&g, 0, 2, &mut out);
        assert_eq!(out, vec![(1, 1), (2, 1), (3, 2)]);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        #[test]
        fn adjacency_is_symmetric_and_histograms_normalised(w in 8usize..40, h in 8usize..40, seed in any::<u64>()) {
            let mut state = seed | 1;
            let rgb: Vec<u8> = (0..w * h * 3).map(|_| {
                state ^= state << 13; state ^= state >> 7; state ^= state << 17;
                (state >> 56) as u8
            }).collect();
            let (sp, g) = graph_of(&rgb, w, h, 20);
            prop_assert_eq!(g.len(), sp.count);
            for v in 0..g.len() as u32 {
                for &u in g.neighbours(v) {
                    prop_assert!(u != v);
                    prop_assert!(g.neighbours(u).contains(&v));
                }
                let s: f32 = g.histogram(v).iter().sum();
                prop_assert!((s - 1.0).abs() < 1e-4);
            }
        }
    }
}
