//! The pure Ariadne engine: image + cable ends + parameters → cables (B-splines,
//! polylines, widths, colours) from which masks are drawn. No I/O, no async.
//!
//! Stages, each in its own module:
//! [`superpixels`] (SLIC) → [`graph`] (region adjacency graph) → [`walk`] (walks from
//! every end) → [`pairing`] (global choice of walks) → [`spline`] (B-spline fit) →
//! [`refine`] (sub-pixel centreline, width) → [`render`] (masks, overlay); [`connectivity`]
//! makes every superpixel one region, [`scale`] brings photos to the working size, [`cable`]
//! models one cable from its walk, [`border`] finds cables with no end in view,
//! [`loops`] takes in the loop a cable was walked across where it crosses itself,
//! [`traces`] follows the field from ends no walk found a cable from, from the
//! frame's edge and on from where a walk was lost,
//! [`twins`] splits a cable found over two of one colour laid together,
//! [`geometry`] holds the plane geometry they share, and [`exposure`] brightens a dim
//! photo and [`sharpness`] sharpens a soft one (the pipeline calls them); [`field`] reads a network's cable
//! field (cable probability and direction), which, when given, joins the step score,
//! stops walks that leave the cables, seeds cables at the border and scores each
//! cable. [`segment`] runs them in order.

mod border;
mod cable;
mod chains;
pub mod color;
mod confirm;
pub mod connectivity;
mod deadline;
mod error;
pub mod exposure;
pub mod field;
pub mod geometry;
pub mod graph;
mod loops;
mod orphans;
pub mod pairing;
mod params;
pub mod refine;
pub mod render;
pub mod resample;
mod scale;
pub mod sharpness;
pub mod spline;
pub mod superpixels;
mod traces;
mod twins;
pub mod walk;

use std::time::Instant;

use image::RgbImage;

pub use cable::Cable;
pub use deadline::Deadline;
pub use error::{EngineError, compact};
pub use field::CableField;
pub use params::{PRESET_NAMES, Params, RANGES};
pub use render::{Mask, MaskKind};
pub use scale::{
    MAX_CORRECTION, MIN_CORRECTION, WorkingFrame, field_may_miss_wide_cables,
    too_wide_for_the_field,
};

use crate::timings::{Timings, ms_since as ms};
use cable::Scene;
use color::LabImage;
use graph::Graph;
use superpixels::{SlicSettings, Superpixels};
use walk::{Seed, Terrain};

/// Smallest image side the engine accepts, pixels.
pub const MIN_SIDE: u32 = 16;

/// Pixels of the photos the development split is shot at (640x480): the size the
/// engine's defaults, the network's input size and the masks' pixel convention are
/// set for.
pub const REFERENCE_PIXELS: f64 = 640.0 * 480.0;

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
    /// Working pixels per photo pixel: the photo was segmented resampled by this
    /// factor (1: at its own size; see [`WorkingFrame`]).
    pub working_scale: f32,
    /// Factor the masks are drawn wider by than `Params::mask_width_px` says, for
    /// cables wider or thinner than nominal that were not segmented again, or still
    /// wider after a photo was shrunk for them ([`Segmentation::mask_correction`]; 1
    /// otherwise).
    pub mask_scale: f32,
    /// Time of the engine's stages (`superpixels` to `splines`; the rest are 0).
    pub timings: Timings,
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
/// `border_cables`, also those crossing the frame with no end in view and, with a
/// field, those whose ends are not among `ends`.
///
/// Errors: invalid parameters, an image smaller than [`MIN_SIDE`], an end outside the
/// image or not finite.
pub fn segment(
    image: &RgbImage,
    ends: &[[f64; 2]],
    params: &Params,
) -> Result<Segmentation, EngineError> {
    segment_with_confidence(
        image,
        ends,
        &vec![1.0; ends.len()],
        None,
        params,
        Deadline::NONE,
    )
}

/// [`segment`] with a confidence in 0..=1 per end (a detector's scores: a cable that
/// reaches no second end is only as credible as the end it starts from), when given
/// and `use_field` is on, the cable field of the photo, and a `deadline` past which it
/// gives up ([`EngineError::DeadlineExceeded`]).
pub fn segment_with_confidence(
    image: &RgbImage,
    ends: &[[f64; 2]],
    confidence: &[f32],
    field: Option<&CableField>,
    params: &Params,
    deadline: Deadline,
) -> Result<Segmentation, EngineError> {
    let over = oversegment(image, params, deadline)?;
    segment_oversegmented(image, over, ends, confidence, field, params, deadline)
}

/// The photo's blurred Lab image and its superpixels: the first stage of
/// [`segment_with_confidence`], which needs neither the ends nor the field (a caller
/// may run the network meanwhile).
#[derive(Debug)]
pub struct Oversegmented {
    lab: LabImage,
    sp: Superpixels,
    /// Time taken, milliseconds.
    ms: f64,
}

/// Converts `image` to Lab, blurs it and runs SLIC (after checking the parameters and
/// the image's size), giving up between SLIC iterations once `deadline` has passed.
pub fn oversegment(
    image: &RgbImage,
    params: &Params,
    deadline: Deadline,
) -> Result<Oversegmented, EngineError> {
    params.validate()?;
    let (width, height) = image.dimensions();
    if width < MIN_SIDE || height < MIN_SIDE {
        return Err(EngineError::ImageTooSmall {
            width,
            height,
            min: MIN_SIDE,
        });
    }
    let t = Instant::now();
    let mut lab = LabImage::from_rgb(image.as_raw(), width as usize, height as usize);
    lab.gaussian_blur(params.sigma);
    let settings = SlicSettings {
        n_segments: params.n_segments,
        compactness: params.compactness,
        iterations: params.slic_iterations,
        min_size_factor: params.min_size_factor,
    };
    let sp = superpixels::slic_until(&lab, &settings, deadline)?;
    Ok(Oversegmented { lab, sp, ms: ms(t) })
}

/// The rest of [`segment_with_confidence`]: graph, walks, pairing and cables on
/// `image` oversegmented by [`oversegment`] with the same `params`
/// ([`EngineError::OtherImage`] when `over` was made from an image of another size).
pub fn segment_oversegmented(
    image: &RgbImage,
    over: Oversegmented,
    ends: &[[f64; 2]],
    confidence: &[f32],
    field: Option<&CableField>,
    params: &Params,
    deadline: Deadline,
) -> Result<Segmentation, EngineError> {
    if confidence.len() != ends.len() {
        return Err(EngineError::BadConfidences {
            ends: ends.len(),
            confidences: confidence.len(),
        });
    }
    let (width, height) = image.dimensions();
    if [over.sp.width, over.sp.height] != [width as usize, height as usize] {
        return Err(EngineError::OtherImage {
            superpixels: [over.sp.width, over.sp.height],
            image: [width, height],
        });
    }
    validate_ends(ends, width, height)?;
    let Oversegmented {
        lab,
        sp,
        ms: oversegment_ms,
    } = over;
    let mut timings = Timings {
        superpixels: oversegment_ms,
        ..Timings::default()
    };
    let rgb = image.as_raw();
    deadline.check()?;

    let t = Instant::now();
    let graph = Graph::build(&sp, rgb, &lab, params.hist_bins);
    let field = field.filter(|_| params.use_field);
    let vertex_field = field.map(|f| f.per_vertex(&sp));
    timings.graph = ms(t);
    let terrain = Terrain {
        graph: &graph,
        lab: &lab,
        field: vertex_field.as_deref(),
        field_map: field,
        step_px: sp.step,
        params,
        deadline,
    };

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
    let walks = walk::walk_all(terrain, &seeds, seeds.len(), true)?;
    let chosen = pairing::pair(
        &walks,
        confidence,
        params,
        pairing::Floor {
            reached: params.reached_floor(field.is_some()),
            ..pairing::Floor::new(params.cable_score_floor(field.is_some()))
        },
        params.field_through_factor,
        field,
    );
    timings.walks = ms(t);

    let t = Instant::now();
    let mut cables = Vec::with_capacity(chosen.len());
    // Per pairing: whether it became a weak cable (`border::is_weak`).
    let mut weak_choice = vec![false; chosen.len()];
    let mut end_cables = vec![None; ends.len()];
    let scene = Scene {
        walks: &walks,
        seeds: &seeds,
        terrain,
        field,
        sp: &sp,
        image,
    };
    for (choice, weak) in chosen.iter().zip(weak_choice.iter_mut()) {
        deadline.check()?;
        let Some(mut cable) = cable::model_cable(&scene, choice) else {
            continue;
        };
        // An edge between two backgrounds, its corners taken for terminals.
        if cable.ridge_share < params.ended_min_ridge_share
            && !twins::lies_over_twins(&cable, &lab, image, params)
        {
            continue;
        }
        *weak = border::is_weak(&cable, params);
        cable.id = cables.len();
        for i in cable.end_indices.into_iter().flatten() {
            end_cables[i] = Some(cable.id);
        }
        cables.push(cable);
    }
    timings.splines = ms(t);

    if params.border_cables {
        let t = Instant::now();
        deadline.check()?;
        let mut found = border::border_crossing_cables(&scene, &chosen, &cables)?;
        let gone = border::yield_weak_cables(&scene, (&chosen, &weak_choice), &cables, &mut found)?;
        if gone.contains(&true) {
            cable::drop_cables(&mut cables, &mut end_cables, &gone);
        }
        for mut cable in found {
            cable.id = cables.len();
            cables.push(cable);
        }
        timings.walks += ms(t);
    }
    if let Some(field) = field {
        let t = Instant::now();
        let points: Vec<[f32; 2]> = seeds.iter().map(|s| s.point).collect();
        let ground = traces::Ground {
            field,
            lab: &lab,
            image,
            params,
            step_px: sp.step,
            size: [sp.width, sp.height],
        };
        traces::trace_free_ends(&mut cables, &mut end_cables, &points, confidence, ground);
        timings.walks += ms(t);
    }
    if let Some(field) = vertex_field.as_deref().filter(|_| params.loops) {
        let t = Instant::now();
        let ground = loops::Ground {
            graph: &graph,
            sp: &sp,
            field,
            seeds: &seeds,
            lab: &lab,
            image,
            params,
        };
        loops::close_loops(&mut cables, &mut end_cables, ground);
        timings.splines += ms(t);
    }
    if params.twins {
        let t = Instant::now();
        twins::split_twins(&mut cables, &mut end_cables, &lab, image, params);
        timings.splines += ms(t);
    }
    if field.is_some() {
        cable::drop_short_weak(&mut cables, &mut end_cables, params);
    }

    Ok(Segmentation {
        width,
        height,
        cables,
        end_cables,
        superpixels: sp.count,
        working_scale: 1.0,
        mask_scale: 1.0,
        timings,
    })
}
