//! The pure Ariadne engine: image + cable ends + parameters → cables (B-splines,
//! polylines, widths, colours) from which masks are drawn. No I/O, no async.
//!
//! Stages, each in its own module:
//! [`superpixels`] (SLIC) → [`graph`] (region adjacency graph) → [`walk`] (walks from
//! every end) → [`pairing`] (global choice of walks) → [`spline`] (B-spline fit) →
//! [`refine`] (sub-pixel centreline, width) → [`render`] (masks, overlay).

mod border;
pub mod color;
mod error;
pub mod graph;
pub mod pairing;
mod params;
pub mod refine;
pub mod render;
pub mod spline;
pub mod superpixels;
pub mod walk;

use std::time::Instant;

use image::RgbImage;

pub use error::EngineError;
pub use params::{PRESET_NAMES, Params};
pub use render::{Mask, MaskKind};

use color::LabImage;
use graph::Graph;
use pairing::{FarEnd, Pairing};
use spline::BSpline;
use superpixels::{SlicSettings, Superpixels};
use walk::{Seed, Walk, WalkEnd, dist, heading};

/// Smallest image side the engine accepts, pixels.
pub const MIN_SIDE: u32 = 16;
/// Fit weight of a given end relative to a superpixel centroid: ends are exact.
const END_WEIGHT: f32 = 25.0;
/// Refinement passes (each re-reads the image around the previous curve).
const REFINE_PASSES: usize = 2;

/// One cable found in the image.
#[derive(Debug, Clone, PartialEq)]
pub struct Cable {
    /// Index in [`Segmentation::cables`]; label masks use `id + 1`.
    pub id: usize,
    /// First and last point of the centreline, pixels.
    pub ends: [[f32; 2]; 2],
    /// For each of `ends`, the index of the given end it is, or `None` where the cable
    /// leaves the frame or was lost.
    pub end_indices: [Option<usize>; 2],
    /// The centreline model.
    pub spline: BSpline,
    /// Dense samples of the spline from `ends[0]` to `ends[1]`.
    pub polyline: Vec<[f32; 2]>,
    /// Length of the polyline, pixels.
    pub length_px: f32,
    /// Width measured across the curve on the image, pixels.
    pub width_px: f32,
    /// Median sRGB colour along the centreline.
    pub color: [u8; 3],
    /// Confidence in 0..=1.
    pub score: f32,
}

/// Wall-clock time of the engine's stages, milliseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimings {
    /// Colour conversion, blur and SLIC.
    pub superpixels: f64,
    /// Region adjacency graph.
    pub graph: f64,
    /// All walks and the pairing.
    pub walks: f64,
    /// Spline fits and refinement.
    pub splines: f64,
}

/// Output of [`segment`].
#[derive(Debug, Clone, PartialEq)]
pub struct Segmentation {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Cables, by decreasing score.
    pub cables: Vec<Cable>,
    /// For each given end, the cable it was assigned to.
    pub end_cables: Vec<Option<usize>>,
    /// Number of superpixels used.
    pub superpixels: usize,
    /// Stage timings.
    pub timings: StageTimings,
}

/// Checks that every end is finite and inside a `width` x `height` image.
pub fn validate_ends(ends: &[[f64; 2]], width: u32, height: u32) -> Result<(), EngineError> {
    for (index, &[x, y]) in ends.iter().enumerate() {
        if !x.is_finite() || !y.is_finite() {
            return Err(EngineError::EndpointNotFinite { index });
        }
        if x < 0.0 || y < 0.0 || x > (width - 1) as f64 || y > (height - 1) as f64 {
            return Err(EngineError::EndpointOutside {
                index,
                x,
                y,
                width,
                height,
            });
        }
    }
    Ok(())
}

/// Finds the cables of `image` that start or end at the given `ends` (pixel
/// coordinates, unpaired; the engine pairs them), all trusted fully; with
/// `border_cables`, also those crossing the frame with no end in view.
///
/// Errors: invalid parameters, an image smaller than [`MIN_SIDE`], an end outside the
/// image or not finite.
pub fn segment(
    image: &RgbImage,
    ends: &[[f64; 2]],
    params: &Params,
) -> Result<Segmentation, EngineError> {
    segment_with_confidence(image, ends, &vec![1.0; ends.len()], params)
}

/// [`segment`] with a confidence in 0..=1 per end (a detector's scores): a cable that
/// reaches no second end is only as credible as the end it starts from.
pub fn segment_with_confidence(
    image: &RgbImage,
    ends: &[[f64; 2]],
    confidence: &[f32],
    params: &Params,
) -> Result<Segmentation, EngineError> {
    params.validate()?;
    if confidence.len() != ends.len() {
        return Err(EngineError::BadConfidences {
            ends: ends.len(),
            confidences: confidence.len(),
        });
    }
    let (width, height) = image.dimensions();
    if width < MIN_SIDE || height < MIN_SIDE {
        return Err(EngineError::ImageTooSmall {
            width,
            height,
            min: MIN_SIDE,
        });
    }
    validate_ends(ends, width, height)?;
    let mut timings = StageTimings::default();

    let t = Instant::now();
    let rgb = image.as_raw();
    let mut lab = LabImage::from_rgb(rgb, width as usize, height as usize);
    lab.gaussian_blur(params.sigma);
    let settings = SlicSettings {
        n_segments: params.n_segments,
        compactness: params.compactness,
        iterations: params.slic_iterations,
        min_size_factor: params.min_size_factor,
    };
    let sp = superpixels::slic(&lab, &settings);
    timings.superpixels = ms(t);

    let t = Instant::now();
    let graph = Graph::build(&sp, rgb, &lab, params.hist_bins);
    timings.graph = ms(t);

    let t = Instant::now();
    let seeds: Vec<Seed> = ends
        .iter()
        .map(|&[x, y]| {
            let (px, py) = (x.round() as usize, y.round() as usize);
            Seed {
                point: [x as f32, y as f32],
                vertex: sp.labels[py * sp.width + px],
            }
        })
        .collect();
    let walks = walk::walk_all(&graph, &lab, &seeds, sp.step, params);
    let chosen = pairing::pair(&walks, confidence, params);
    timings.walks = ms(t);

    let t = Instant::now();
    let mut cables = Vec::with_capacity(chosen.len());
    let mut end_cables = vec![None; ends.len()];
    let scene = Scene {
        walks: &walks,
        seeds: &seeds,
        graph: &graph,
        sp: &sp,
        lab: &lab,
        image,
        params,
    };
    for choice in &chosen {
        let Some(mut cable) = model_cable(&scene, choice) else {
            continue;
        };
        cable.id = cables.len();
        for i in cable.end_indices.into_iter().flatten() {
            end_cables[i] = Some(cable.id);
        }
        cables.push(cable);
    }
    timings.splines = ms(t);

    if params.border_cables {
        let t = Instant::now();
        let found = border_crossing_cables(&scene, &chosen);
        for mut cable in found {
            cable.id = cables.len();
            cables.push(cable);
        }
        timings.walks += ms(t);
    }

    Ok(Segmentation {
        width,
        height,
        cables,
        end_cables,
        superpixels: sp.count,
        timings,
    })
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Seeds on the border count as this sure as a given end.
const BORDER_SEED_CONFIDENCE: f32 = 0.5;
/// Lowest score of a cable found from border seeds alone.
const MIN_BORDER_CABLE_SCORE: f32 = 0.35;
/// Shortest cable found from border seeds alone, in superpixel steps.
const MIN_BORDER_CABLE_STEPS: f32 = 5.0;
/// Largest fraction of a border walk's superpixels that may belong to cables already
/// found (a walk that runs along one of them explains nothing new).
const MAX_COVERED_FRACTION: f32 = 0.25;

/// Cables crossing the whole frame, with no end in view: walks from border seeds where
/// the border shows a colour the cables in `chosen` do not explain, kept when they reach
/// another border point (see [`border`]). Their ends belong to no given end.
fn border_crossing_cables(scene: &Scene<'_>, chosen: &[Pairing]) -> Vec<Cable> {
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
    let seeds = border::border_seeds(graph, sp, &covered);
    if seeds.is_empty() {
        return Vec::new();
    }
    let min_length = MIN_BORDER_CABLE_STEPS * sp.step;
    let crossing: Vec<Walk> = walk::walk_all(graph, scene.lab, &seeds, sp.step, scene.params)
        .into_iter()
        .filter(|w| {
            let on_found = w.vertices.iter().filter(|&&v| covered[v as usize]).count();
            matches!(w.end, WalkEnd::Border | WalkEnd::Seed(_))
                && w.length_px >= min_length
                && (on_found as f32) <= MAX_COVERED_FRACTION * w.vertices.len() as f32
        })
        .collect();
    let confidence = vec![BORDER_SEED_CONFIDENCE; seeds.len()];
    let border_scene = Scene {
        walks: &crossing,
        seeds: &seeds,
        ..*scene
    };
    pairing::pair(&crossing, &confidence, scene.params)
        .iter()
        // Only crossing walks were kept, so every pairing ends on the border or a seed.
        .filter(|c| c.score >= MIN_BORDER_CABLE_SCORE)
        .filter_map(|c| model_cable(&border_scene, c))
        .map(|mut cable| {
            cable.end_indices = [None, None];
            cable
        })
        .collect()
}

/// Everything the modelling of one cable reads: the earlier stages' results.
#[derive(Clone, Copy)]
struct Scene<'a> {
    walks: &'a [Walk],
    seeds: &'a [Seed],
    graph: &'a Graph,
    sp: &'a Superpixels,
    lab: &'a LabImage,
    image: &'a RgbImage,
    params: &'a Params,
}

/// Builds the spline model of one chosen walk: data points from the walk, fit,
/// refinement on the image, final fit and measurements.
fn model_cable(scene: &Scene<'_>, choice: &Pairing) -> Option<Cable> {
    let Scene {
        walks,
        seeds,
        graph,
        sp,
        lab,
        image,
        params,
    } = *scene;
    let walk = &walks[choice.walk];
    let start = seeds[choice.start].point;
    let mut points = vec![start];
    let mut weights = vec![END_WEIGHT];
    points.extend(
        walk.vertices[1..]
            .iter()
            .map(|&v| graph.vertices[v as usize].centroid),
    );
    if let Some(j) = choice.joined {
        let other = &walks[j];
        points.extend(
            other.vertices[1..]
                .iter()
                .rev()
                .map(|&v| graph.vertices[v as usize].centroid),
        );
    }
    weights.resize(points.len(), 1.0);
    let far_index = match choice.far {
        FarEnd::Seed(t) => {
            let target = seeds[t].point;
            // Centroids next to the far end may lie beside or beyond it: the end is exact.
            while points.len() > 2
                && dist(points[points.len() - 1], target) < params.close_radius_px * 0.5
            {
                points.pop();
                weights.pop();
            }
            points.push(target);
            weights.push(END_WEIGHT);
            Some(t)
        }
        FarEnd::Border => {
            let dir = heading(&points, params.heading_span_px);
            if let Some(exit) = border_exit(points[points.len() - 1], dir, sp, 3.0 * sp.step) {
                points.push(exit);
                weights.push(1.0);
            }
            None
        }
        FarEnd::Open => None,
    };
    let mut spline = BSpline::fit(&points, &weights, params.knot_spacing_px, params.smoothing)?;
    let mut polyline = spline.sample(params.polyline_step_px);
    let mut width = None;
    if params.refine {
        for _ in 0..REFINE_PASSES {
            let refined = refine::refine(&polyline, lab, params.refine_radius_px);
            width = refined.width_px.or(width);
            let mut pts = refined.points;
            let mut w = vec![1.0; pts.len()];
            // The given ends stay where they were given.
            pts[0] = start;
            w[0] = END_WEIGHT;
            if let Some(t) = far_index {
                let last = pts.len() - 1;
                pts[last] = seeds[t].point;
                w[last] = END_WEIGHT;
            }
            spline = BSpline::fit(&pts, &w, params.knot_spacing_px, params.smoothing)?;
            polyline = spline.sample(params.polyline_step_px);
        }
    }
    let width_px = width.unwrap_or_else(|| fallback_width(walk, graph, sp));
    let length_px = spline::polyline_length(&polyline);
    Some(Cable {
        id: 0,
        ends: [polyline[0], polyline[polyline.len() - 1]],
        end_indices: [Some(choice.start), far_index],
        color: median_rgb(image, &polyline),
        spline,
        polyline,
        length_px,
        width_px,
        score: choice.score.clamp(0.0, 1.0),
    })
}

/// Where a ray from `from` along `dir` leaves the image, if within `max_px`.
fn border_exit(from: [f32; 2], dir: [f32; 2], sp: &Superpixels, max_px: f32) -> Option<[f32; 2]> {
    let (w, h) = ((sp.width - 1) as f32, (sp.height - 1) as f32);
    let mut t = f32::INFINITY;
    if dir[0] > 1e-6 {
        t = t.min((w - from[0]) / dir[0]);
    } else if dir[0] < -1e-6 {
        t = t.min(-from[0] / dir[0]);
    }
    if dir[1] > 1e-6 {
        t = t.min((h - from[1]) / dir[1]);
    } else if dir[1] < -1e-6 {
        t = t.min(-from[1] / dir[1]);
    }
    (t.is_finite() && t > 0.5 && t <= max_px).then(|| [from[0] + t * dir[0], from[1] + t * dir[1]])
}

/// Width from the walk's superpixels when the image could not be read: a superpixel on
/// a cable spans about its width, so the side of the mean superpixel's square.
fn fallback_width(walk: &Walk, graph: &Graph, sp: &Superpixels) -> f32 {
    let n = walk.vertices.len().max(1) as f32;
    let area: f32 = walk
        .vertices
        .iter()
        .map(|&v| graph.vertices[v as usize].pixels as f32)
        .sum::<f32>()
        / n;
    area.sqrt().min(sp.step * 2.0)
}

/// Per-channel median sRGB colour of `image` along `line`.
fn median_rgb(image: &RgbImage, line: &[[f32; 2]]) -> [u8; 3] {
    let (w, h) = image.dimensions();
    let mut channels: [Vec<u8>; 3] = Default::default();
    for p in line {
        let (x, y) = (p[0].round(), p[1].round());
        if x >= 0.0 && y >= 0.0 && (x as u32) < w && (y as u32) < h {
            let px = image.get_pixel(x as u32, y as u32).0;
            for c in 0..3 {
                channels[c].push(px[c]);
            }
        }
    }
    let mut out = [0u8; 3];
    for (o, ch) in out.iter_mut().zip(channels.iter_mut()) {
        ch.sort_unstable();
        *o = ch.get(ch.len() / 2).copied().unwrap_or(0);
    }
    out
}
