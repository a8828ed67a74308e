//! Parameters of the engine and the named presets.
//!
//! Every constant of the method is a field here, documented with its unit and the value
//! the paper or the authors' code used where it differs from ours. A [`Params`] is built
//! from a named preset and optionally overridden field by field from JSON (the service's
//! `options`, a presets file); [`Params::validate`] rejects zero or absurd values.

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use super::EngineError;

mod ranges;

pub use ranges::RANGES;

/// All tunable parameters of the engine, flat so that a JSON override such as
/// `{"n_segments": 1500}` names a field directly.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    // --- superpixels (SLIC) ---
    /// Wanted number of superpixels (paper: 2000; 1500 for cluttered scenes).
    pub n_segments: u32,
    /// SLIC compactness m: weight of spatial against colour distance (paper: 20; 10 for clutter).
    pub compactness: f32,
    /// Standard deviation of the Gaussian pre-blur, pixels; 0 disables it (paper: 1).
    pub sigma: f32,
    /// Number of k-means iterations.
    pub slic_iterations: u32,
    /// Fragments smaller than this fraction of the nominal superpixel area are merged
    /// into a neighbour when connectivity is enforced.
    pub min_size_factor: f32,
    /// Brightness (0..=255) the photo's bright end (the brightest channel at the
    /// 99.5th percentile) is brought up to before anything reads its colours, so an
    /// underexposed photo is seen as a well-exposed one (`exposure`).
    pub exposure_level: f32,
    /// Largest gain applied for that; 1 leaves every photo as it is.
    pub exposure_max_gain: f32,
    /// Edge width (`sharpness::edge_width`, pixels) of the photos the engine was tuned
    /// on (the development photos read 1.02-1.09); a photo whose edges are much wider
    /// (a soft lens) is sharpened by the difference (`sharpness`).
    pub sharp_edge_px: f32,
    /// Strength of that unsharp mask; 0 leaves every photo as it is.
    pub sharpen_amount: f32,

    // --- working resolution (see `scale`) ---
    /// Pixels of the image the engine works on: photos of another size are resampled
    /// to about this many (640x480 = 307,200, the size the lengths below suit).
    pub working_pixels: u32,
    /// Largest enlargement of a small photo to reach `working_pixels` (4: a 160x120
    /// photo is worked on at 640x480; a thin cable's correction is capped by it too).
    pub max_upscale: f32,
    /// Cable width the lengths suit, working pixels: the middle (geometric centre) of
    /// the widths the engine reads on the development photos at 640x480, whose
    /// per-photo estimates span 6.4-9.4 px (a full-width-at-half-maximum reading, a
    /// little below the annotated strokes).
    pub nominal_width_px: f32,
    /// The photo is segmented again at a corrected scale when the median cable width
    /// is off nominal by more than this factor (a closer or farther camera).
    pub width_tolerance: f32,
    /// When it is off nominal by more than this factor but within `width_tolerance`
    /// (no second pass), the masks are drawn that much wider or thinner than
    /// `mask_width_px` (docs/CAMERAS.md).
    pub mask_width_tolerance: f32,
    /// Cables too wide for the network (a camera much closer than the development
    /// photos'): when the cable field seen at half the working size calls more than
    /// this many times the share of the photo cable that the field at the working size
    /// does, the photo is worked at half the size, and again at a quarter (`scale`,
    /// [`super::too_wide_for_the_field`]). 100: never.
    pub wide_field_ratio: f32,
    /// A photo in which the first pass (at the working scale) finds no cable is
    /// segmented once more at this times the working scale, and that pass is kept when
    /// it finds any: cables much wider than nominal read little lateral contrast and
    /// score under the floors at the working scale, so no width is read to correct the
    /// scale by (docs/CAMERAS.md). 1: never.
    pub empty_rescale: f32,

    // --- graph ---
    /// Histogram bins per HSV channel; the histogram is joint (bins³ cells)
    /// (paper: 8, authors' code: 3).
    pub hist_bins: u32,

    // --- walks ---
    /// Order d of the neighbourhood searched at every step, in graph hops (paper: 3).
    pub neighbourhood_order: u32,
    /// Order searched when nothing acceptable lies within `neighbourhood_order` hops
    /// (authors' code: the order grows up to 5).
    pub jump_order: u32,
    /// Sharpness c_V of the Bradford visual likelihood (authors' code: 0.5, which barely
    /// separates colours; we use a sharper value).
    pub c_visual: f32,
    /// Sharpness c_D of the Bradford distance likelihood (paper: 0.5).
    pub c_distance: f32,
    /// D_max: candidates further than this from the walk's head are ignored, pixels (paper: 100).
    pub max_step_px: f32,
    /// Concentration kappa of the von Mises curvature likelihood (authors' code: 1 to 4).
    pub kappa: f32,
    /// Largest turn accepted in one step, degrees (authors' code: 90).
    pub max_turn_deg: f32,
    /// How far back, in pixels, the walk's heading is measured (smooths superpixel jitter).
    pub heading_span_px: f32,
    /// r: a walk closes when its head is this close to another end, pixels (paper: 20).
    pub close_radius_px: f32,
    /// A walk closes on an end within `close_radius_px` only when that end lies at most
    /// this many superpixel steps to the side of the walk's line (its heading through
    /// the head): the terminal of a cable laid alongside, within r of the walk's side,
    /// is not where the walk's cable ends (paper: no such limit).
    pub close_max_lateral_steps: f32,
    /// A walk closes on another end only when its heading agrees at least this much
    /// ([`crate::engine::field::alignment`] of the two directions: 1 along, 0 across)
    /// with the way that end's own best walk opens, the end's cable as seen from the
    /// end: an end whose tip touches another cable's side lies within reach of the
    /// walks along that cable, which pass it across its own (0.75: within 30°; session
    /// 67, docs/ENGINE.md). Checked after all walks are run once (an end's own walk is
    /// needed); the walks it refuses are run again past that end. 0: no such check
    /// (paper).
    pub close_own_min_alignment: f32,
    /// A walk that closes on another end is a cable only when it took at least this many
    /// steps past its first superpixel: one that meets an end as soon as it leaves its
    /// own has read nothing of a cable between the two (the ends of two cables lying
    /// tip to side; paper: 0).
    pub close_min_steps: u32,
    /// A walk stops when the best candidate's colour similarity to the walk's colour
    /// model falls below this (histogram intersection, 0..1).
    pub min_similarity: f32,
    /// A walk stops when the best candidate's lateral contrast (0..1: how much it differs
    /// from the image on both sides) falls below this: it has left the thin structure.
    pub min_contrast: f32,
    /// Weight of the newest vertex in the walk's running colour model (0..1).
    pub model_rate: f32,
    /// A walk is treated as leaving the frame when its head is this close to the border
    /// and heading outwards, pixels.
    pub border_margin_px: f32,
    /// Iteration cap of one walk (authors' code: 100).
    pub max_steps: u32,

    // --- pairing ---
    /// Score factor of a walk that closed on another end but whose reverse walk did not
    /// confirm it (0..1; 1 ignores confirmation).
    pub unconfirmed_factor: f32,
    /// Score factor of a walk that left through the border (one-ended cable).
    pub border_factor: f32,
    /// Score factor of a walk that lost the cable before an end or the border.
    pub lost_factor: f32,
    /// Two lost walks whose heads face each other at most this far apart are joined
    /// into one cable, pixels.
    pub join_radius_px: f32,
    /// Cables scoring below this are not reported when no cable field guides the walks
    /// (0..1).
    pub min_cable_score: f32,
    /// Walks shorter than this are never reported as cables, pixels.
    pub min_cable_length_px: f32,
    /// A walk that closes on another end over less than this many pixels is weighed
    /// after every other walk, so its ends take it only when nothing else is left for
    /// them: two ends that near along one path are most often one terminal seen twice
    /// (a metal tip and where its sleeve or the insulation ends) or two cables' ends
    /// side by side, not a cable of their own (paper: no such rule).
    pub closed_min_length_px: f32,
    /// A weaker terminal peak (one the detector keeps as a candidate, under its
    /// threshold) within this many pixels of a cable's free end, not at the frame's
    /// border, is reported as that cable's end; 0 reports none (docs/ACCURACY.md, "Ends
    /// a cable confirms").
    pub end_confirm_px: f32,

    // --- model ---
    /// Smoothing weight of the penalised B-spline fit (second-difference penalty).
    pub smoothing: f32,
    /// Spacing of the interior knots along the curve, pixels.
    pub knot_spacing_px: f32,
    /// Spacing of the reported polyline's samples, pixels.
    pub polyline_step_px: f32,
    /// Refine the centreline on the image (sub-pixel) before the final fit.
    pub refine: bool,
    /// Also look for cables with no end in view, crossing the frame from border to
    /// border (seeded where the border shows an unexplained colour or field), and, with
    /// a field, for cables whose ends were missed (seeded at the ends of unexplained
    /// pieces of the field: `field_orphan_level`).
    pub border_cables: bool,
    /// Half-length of the profiles sampled across the curve during refinement, pixels.
    pub refine_radius_px: f32,
    /// Width of the stroke drawn for each cable in the masks, pixels; 0 means the
    /// measured width of each cable. The default, 7, is the stroke of the dataset's
    /// hand-drawn masks.
    pub mask_width_px: f32,

    // --- walk details ---
    /// Lab distance at which a vertex's lateral contrast saturates at 1 (a clearly
    /// visible edge).
    pub contrast_saturation: f32,
    /// A vertex's lateral contrast is at most this many times its larger Lab distance
    /// to the image two superpixel steps to either side (0: no such cap). The strip of
    /// background between two same-colour cables side by side differs from the cables
    /// on both sides, as a cable differs from the background, but it matches the
    /// background beyond them; a cable does not (docs/ENGINE.md).
    pub far_contrast_factor: f32,
    /// A head counts as heading out of the frame when the component of its unit heading
    /// towards the near edge is at least this.
    pub border_outward_cos: f32,
    /// A walk that finds no next vertex still closes on another end straight ahead
    /// within this many `close_radius_px` (the last superpixels before a terminal are
    /// often not the cable's colour).
    pub stopped_seed_reach: f32,
    /// A walk that finds no next vertex leaves through the border when within this many
    /// `border_margin_px` of an edge it heads to.
    pub stopped_border_reach: f32,
    /// Superpixels whose centre lies closer to a seed than this many superpixel steps
    /// join the seed's own, and its walks start from that region's other neighbours: a
    /// small superpixel at a terminal is often wrapped by one whose centre is a pixel
    /// or two away, a first step that gives no heading. 0: walks start from the seed
    /// superpixel's neighbours, as in the paper.
    pub seed_region_steps: f32,
    /// Exponent of the colour agreement in a walk's quality.
    pub quality_visual_exponent: f32,
    /// Exponent of the lateral contrast in a walk's quality (a walk over plain
    /// background has low contrast: this is what drops it).
    pub quality_contrast_exponent: f32,

    // --- pairing details ---
    /// Lost walks shorter than this many `min_cable_length_px` are not joined.
    pub join_min_length: f32,
    /// Largest fraction of an end's walk's superpixels that cables accepted before it
    /// may have taken: beyond it the walk repeats a cable already found, from a second
    /// end on it (a terminal seen twice, at its metal tip and where the insulation
    /// ends), and is no cable of its own (1 accepts every walk).
    pub pair_max_shared: f32,

    // --- loops (see `loops`) ---
    /// A cable walked straight across the place where it loops over itself takes the
    /// loop in, where the field shows it (with a field only).
    pub loops: bool,

    // --- twins (see `twins`) ---
    /// Cables found as one over two of one colour side by side are split in two.
    pub twins: bool,
    /// Least share of the profiles read across a cable that must show twins for it
    /// to be split.
    pub twin_min_share: f32,
    /// Largest mismatch of a profile's band with itself shifted by the twins'
    /// separation, as a share of the band's own variation (Lab ΔE), for the profile to
    /// show twins.
    pub twin_max_cost: f32,

    // --- model details ---
    /// Fit weight of a given end relative to one superpixel centroid (ends are exact).
    pub end_weight: f32,
    /// Centroids closer than this many `close_radius_px` to the far end are dropped
    /// before the fit (they may lie beside or beyond it).
    pub far_end_trim: f32,
    /// A cable leaving through the border is extended to the border when it lies
    /// within this many superpixel steps.
    pub border_exit_steps: f32,
    /// Refinement passes (each re-reads the image around the previous curve).
    pub refine_passes: u32,
    /// Distance between the samples of a refinement profile, pixels.
    pub refine_profile_step_px: f32,
    /// A refinement profile is read every this many polyline points.
    pub refine_profile_stride: u32,
    /// A profile end closer than this (Lab ΔE) to the cable colour is not background,
    /// and the profile is skipped.
    pub refine_min_background_de: f32,
    /// Narrowest width a profile may measure, pixels.
    pub refine_min_width_px: f32,

    // --- cables with no end in view ---
    /// Lab ΔE from the border's median colour at which a border superpixel stands out.
    pub border_min_contrast: f32,
    /// Shortest run of standing-out border pixels taken as a crossing (JPEG specks).
    pub border_min_crossing_px: u32,
    /// Longest run taken as a crossing (longer runs are objects along the border).
    pub border_max_crossing_px: u32,
    /// Longest run from which walks still start, though none ends there: a cable
    /// crossing the border at a grazing angle, or leaving through a corner, stands out
    /// along more of it (docs/ENGINE.md, "A grazing crossing of the border").
    pub border_max_start_px: u32,
    /// A border seed counts as this sure as a given end.
    pub border_seed_confidence: f32,
    /// Lowest score of a cable found from border seeds alone.
    pub border_min_score: f32,
    /// Shortest such cable, in superpixel steps.
    pub border_min_steps: f32,
    /// Largest fraction of such a walk's superpixels that may belong to cables already
    /// found, or border them (a walk along one of them explains nothing new). Half: a
    /// cable that crosses several found ones touches a few superpixels at each
    /// crossing, and a cable whose far part was already found from a stray end (an end
    /// read where it crosses another cable) runs over that part; a quarter refused
    /// both.
    pub border_max_covered: f32,
    /// Least share of the profiles across such a cable (one with no given end) that
    /// must read a ridge, a cable on its background, rather than a step between two
    /// backgrounds (`refine::Refined::ridge_share`): the edge of a board or tray is
    /// long, straight and unexplained, and a field may call it cable (0 keeps them).
    pub min_ridge_share: f32,
    /// The same for a cable walked from its ends, lower: the ends are evidence of their
    /// own, and a true cable beside another reads a step on more of its profiles. A
    /// board's or sheet's edge whose corners were taken for terminals reads a step
    /// nearly all along (simple/00012: a ridge on none of its profiles); cables lying
    /// over twins are kept (0 keeps them all; only with `refine`, which reads them).
    pub ended_min_ridge_share: f32,

    // --- the cable field (a network's cable probability and direction) ---
    /// Trust the cable field when one is given: it joins the step score, stops walks
    /// that leave the cables, seeds cables at the border and scores the cables.
    pub use_field: bool,
    /// Lateral contrast (not in the paper) in the step score, the stop rule and the
    /// walk quality.
    pub lateral_contrast: bool,
    /// Step score factor of a candidate with no cable: the field's term is
    /// `floor + (1 − floor) · p`, p the candidate's mean cable probability.
    pub field_floor: f32,
    /// Weight of the agreement between a step and the field's direction in the step
    /// score: the term is `1 − w + w · a`, a in 0..=1.
    pub field_alignment_weight: f32,
    /// A candidate whose mean cable probability is below this is refused (the walk has
    /// left the cables).
    pub field_min_cable: f32,
    /// A step whose straight line runs more than one superpixel step where the cable
    /// probability is below this is refused: a step may skip superpixels (a crossing, a
    /// terminal's metal) but not cross the background from one cable onto another.
    pub field_gap_min_cable: f32,
    /// A candidate whose mean cable probability is at least this is accepted even when
    /// its lateral contrast is low (a dark cable on a dark background).
    pub field_trust: f32,
    /// A walk that, within this many superpixel steps of its seed, finds nothing ahead
    /// of its colour while the field calls where it stands cable (`field_collar_head`;
    /// a ferrule's collar, a sleeve or a label between the end and the cable) steps
    /// once, by the field alone, onto a vertex the field is sure of (`field_trust`) and
    /// whose direction the step follows, and takes that vertex's colour as the cable's.
    /// 0: never.
    pub field_recolour_steps: f32,
    /// Least cable probability of the vertex a walk stands on for the step by the field
    /// alone (`field_recolour_steps`): more likely cable than not. A collar of another
    /// colour fills whole superpixels when cables are wide, and the field is less sure
    /// of it than of the insulation beyond.
    pub field_collar_head: f32,
    /// A walk that comes within `close_radius_px` of another end closes on it only when
    /// its heading agrees with the field's direction at that end at least this much
    /// ([`crate::engine::field::alignment`]: 1 along, 0 across, 1/2 where the field has
    /// no direction): a walk passing the tip of a cable that ends against its side (a
    /// T-junction) goes on. 0 closes on every end within reach.
    pub field_close_min_alignment: f32,
    /// A walk along a cable that runs on behind its seed, the way it opens (the field
    /// and the photo show the same cable there: a cable that passes the end, the end's
    /// tip pushed against it), has its hypothesis score multiplied by this
    /// (docs/ENGINE.md). 1: no such rule.
    pub field_through_factor: f32,
    /// Weight w of how a walk from an end opens along the field's direction at the end:
    /// its quality is multiplied by 1 − w + w·a, a the agreement of its opening way with
    /// that direction ([`crate::engine::walk::Walk::opening`]; docs/ENGINE.md). 0: no such
    /// term.
    pub field_opening_weight: f32,
    /// Exponent of the walk's mean cable probability in its quality.
    pub quality_field_exponent: f32,
    /// Cable probability from which a point counts as on a cable (centreline share,
    /// border seeds).
    pub field_level: f32,
    /// Cables with a smaller share of their centreline on cable pixels are dropped; a
    /// kept cable's score is multiplied by its share.
    pub field_min_share: f32,
    /// `border_min_score` when the field is used (its share already weeds out walks
    /// over the background, and lowers the scores it keeps).
    pub field_border_min_score: f32,
    /// Mean cable probability along a walk from a border or piece seed from which the
    /// field is taken to be sure of it: such a walk needs only the score an end's cable
    /// needs (`field_min_cable_score`), not `field_border_min_score`. A pale cable on a
    /// pale board crossing the frame has little colour likelihood and lateral contrast
    /// to score by, yet the field sees it whole (docs/ENGINE.md). Such a walk also counts
    /// where it loses the cable (a terminal the network missed), not only at the border or
    /// another seed. 1: only walks over a field certain everywhere (a network's never is).
    pub field_border_sure_level: f32,
    /// `min_cable_score` when the field is used: its share in every score keeps walks
    /// over the background out, so weaker cables (a pale cable on a pale card, whose
    /// lateral contrast is low) can be kept.
    pub field_min_cable_score: f32,
    /// With a field, a cable from one end (the other at the border or lost) scoring
    /// under this gives way to a cable found from the border or the field's pieces as
    /// if it were not there, where that cable runs along it, scores at least this and
    /// twice as well, and is a third longer. The walk from a weak false end (a knot in
    /// wood, a fleck of a print) or a weak end walked the wrong way can run onto a
    /// cable, cover its border seed or the field's pieces along it, and leave only the
    /// rest of it to be found, or nothing (docs/ENGINE.md, "A weak end's cable that a
    /// whole one runs along"). 0: never.
    pub field_weak_cable_score: f32,
    /// Share of `field_min_cable_score` that a cable from an end needs when it arrives
    /// at another end of confidence 1, walked there or joined across a gap to a walk
    /// from it; at an end of confidence c the floor is multiplied by 1 - c (1 - this).
    /// Reaching a second end is evidence of a cable in itself, as far as that end is
    /// credible: a walk over the background rarely arrives at a true end, but may link
    /// two false ones. A dark cable on a dark board keeps little colour likelihood and
    /// contrast to score by, and when no walk comes back from the far end to confirm
    /// it, `unconfirmed_factor` sinks it under the floor (docs/ENGINE.md). Cables seeded at
    /// the border or on pieces of the field keep their floor: a piece's two ends are seeds
    /// because they bound one piece, so a walk from one reaching the other adds nothing. 1:
    /// the same floor as every cable.
    pub field_reached_floor: f32,
    /// With a field, the least score of a cable shorter than `field_short_widths`
    /// nominal widths, however it was found. Walks that wander over photographed
    /// clutter (brick, print, a cluttered room) end soon and score low; a real cable
    /// that short and that weak is rare, and losing one costs few pixels (docs/ENGINE.md,
    /// "Short, weak cables"). 0: no such floor.
    pub field_short_min_score: f32,
    /// Length below which [`Params::field_short_min_score`] applies, nominal widths.
    pub field_short_widths: f32,
    /// With a field, the least score of a cable between two ends (both of its ends on
    /// seeds, neither at the border) shorter than `field_pair_short_widths` nominal
    /// widths. On a textured surface the network sees terminals at both tips of a short
    /// stroke, and a walk joins them with a weak score; a true cable that short between
    /// two terminals stands out from its background and scores high (docs/ENGINE.md,
    /// "Short, weak cables"). 0: no such floor.
    pub field_pair_short_min_score: f32,
    /// Length below which [`Params::field_pair_short_min_score`] applies, nominal widths.
    pub field_pair_short_widths: f32,
    /// Mean cable probability from which a superpixel no cable explains counts as part
    /// of a piece of cable whose ends were missed; the ends of such pieces are seeds
    /// (docs/ENGINE.md). 1 or more: no such seeds.
    pub field_orphan_level: f32,
    /// Such a piece seeds walks when its two ends lie this many superpixel steps apart.
    pub field_orphan_min_steps: f32,
    /// A cable found from such a piece runs on past the piece's ends, along the walks
    /// from them that lost the cable further on (where the field fades before the
    /// cable does, short of the end the network missed) or left the frame (across a
    /// cable found at the piece's end; docs/ENGINE.md).
    pub field_orphan_run_on: bool,
    /// Cable probability a trace in the field follows from an end that no walk found a
    /// cable from, or from where the field's cables meet the frame's edge with no cable
    /// found there, to another such end or out of the frame (a thin dark wire on a dark
    /// card, along which no superpixel runs), and from where a cable's walk was lost
    /// (docs/ENGINE.md). 1 or more: no traces.
    pub field_trace_level: f32,
}

/// Names of the built-in presets, in the order `--help` lists them.
pub const PRESET_NAMES: [&str; 3] = ["default", "clutter", "paper"];

impl Default for Params {
    fn default() -> Self {
        Self {
            n_segments: 2000,
            compactness: 20.0,
            sigma: 1.0,
            slic_iterations: 10,
            min_size_factor: 0.25,
            exposure_level: 230.0,
            exposure_max_gain: 4.0,
            sharp_edge_px: 1.05,
            sharpen_amount: 1.5,
            working_pixels: 307_200,
            max_upscale: 4.0,
            nominal_width_px: 7.8,
            width_tolerance: 1.4,
            mask_width_tolerance: 1.3,
            wide_field_ratio: 2.5,
            empty_rescale: 0.5,
            hist_bins: 4,
            neighbourhood_order: 3,
            jump_order: 5,
            c_visual: 5.0,
            c_distance: 4.0,
            max_step_px: 100.0,
            kappa: 2.0,
            max_turn_deg: 60.0,
            heading_span_px: 25.0,
            close_radius_px: 20.0,
            close_max_lateral_steps: 1.3,
            close_own_min_alignment: 0.75,
            close_min_steps: 1,
            min_similarity: 0.1,
            min_contrast: 0.15,
            model_rate: 0.3,
            border_margin_px: 12.0,
            max_steps: 150,
            unconfirmed_factor: 0.8,
            border_factor: 0.9,
            lost_factor: 0.4,
            join_radius_px: 80.0,
            min_cable_score: 0.05,
            min_cable_length_px: 30.0,
            closed_min_length_px: 60.0,
            end_confirm_px: 20.0,
            smoothing: 1.0,
            knot_spacing_px: 45.0,
            polyline_step_px: 2.0,
            refine: true,
            border_cables: true,
            refine_radius_px: 16.0,
            mask_width_px: 7.0,
            contrast_saturation: 25.0,
            far_contrast_factor: 1.5,
            border_outward_cos: 0.3,
            stopped_seed_reach: 2.0,
            stopped_border_reach: 2.0,
            seed_region_steps: 0.4,
            quality_visual_exponent: 0.5,
            quality_contrast_exponent: 2.0,
            join_min_length: 0.5,
            pair_max_shared: 0.45,
            loops: true,
            twins: true,
            twin_min_share: 0.6,
            twin_max_cost: 0.95,
            end_weight: 25.0,
            far_end_trim: 0.5,
            border_exit_steps: 3.0,
            refine_passes: 2,
            refine_profile_step_px: 0.5,
            refine_profile_stride: 2,
            refine_min_background_de: 10.0,
            refine_min_width_px: 2.0,
            border_min_contrast: 20.0,
            border_min_crossing_px: 3,
            border_max_crossing_px: 40,
            border_max_start_px: 60,
            border_seed_confidence: 0.5,
            border_min_score: 0.35,
            border_min_steps: 5.0,
            border_max_covered: 0.5,
            min_ridge_share: 0.5,
            ended_min_ridge_share: 0.25,
            use_field: true,
            lateral_contrast: true,
            field_floor: 0.1,
            field_alignment_weight: 0.5,
            field_min_cable: 0.0,
            field_gap_min_cable: 0.02,
            field_trust: 0.6,
            field_recolour_steps: 2.0,
            field_collar_head: 0.5,
            field_close_min_alignment: 0.25,
            field_through_factor: 0.5,
            field_opening_weight: 0.15,
            quality_field_exponent: 1.0,
            field_level: 0.3,
            field_min_share: 0.15,
            field_border_min_score: 0.12,
            field_border_sure_level: 0.7,
            field_min_cable_score: 0.03,
            field_weak_cable_score: 0.1,
            field_short_min_score: 0.08,
            field_short_widths: 20.0,
            field_pair_short_min_score: 0.2,
            field_pair_short_widths: 25.0,
            field_reached_floor: 0.7,
            field_orphan_level: 0.5,
            field_orphan_min_steps: 6.0,
            field_orphan_run_on: true,
            field_trace_level: 0.5,
        }
    }
}

impl Params {
    /// The built-in preset of that name: `default` (2000 segments, compactness 20,
    /// sigma 1) or `clutter` (1500, 10, 1), the paper's two superpixel settings with
    /// everything this engine adds; or `paper`, the method as published.
    pub fn preset(name: &str) -> Result<Self, EngineError> {
        match name {
            "default" => Ok(Self::default()),
            "clutter" => Ok(Self {
                n_segments: 1500,
                compactness: 10.0,
                ..Self::default()
            }),
            "paper" => Ok(Self::paper()),
            other => Err(EngineError::UnknownPreset(
                other.to_string(),
                PRESET_NAMES.join(", "),
            )),
        }
    }

    /// The method as published (README, "The `paper` preset"): colour, curvature and
    /// distance only — no cable field, no lateral contrast, no border seeds, no
    /// refinement on the image, no seed regions, no limit on how far beside a walk an
    /// end it closes on may lie or on the way it arrives there, no brightening of a dim
    /// photo or sharpening of a soft one, no second pass at another scale for cables
    /// wider or thinner than nominal, masks as wide as the walk's superpixels, no weaker
    /// terminal peaks reported where a cable ends — with the paper's
    /// and its authors' code's constants (8 histogram bins, c_V = c_D = 0.5, κ = 1 on
    /// the newest turn, turns up to 90°, 100 steps). What the paper leaves open stays
    /// ours: the global pairing of ends and the penalised spline fit.
    fn paper() -> Self {
        Self {
            hist_bins: 8,
            c_visual: 0.5,
            c_distance: 0.5,
            kappa: 1.0,
            max_turn_deg: 90.0,
            max_steps: 100,
            use_field: false,
            lateral_contrast: false,
            border_cables: false,
            refine: false,
            mask_width_px: 0.0,
            seed_region_steps: 0.0,
            close_max_lateral_steps: 100.0,
            close_own_min_alignment: 0.0,
            close_min_steps: 0,
            closed_min_length_px: 0.0,
            exposure_max_gain: 1.0,
            sharpen_amount: 0.0,
            width_tolerance: 100.0,
            wide_field_ratio: 100.0,
            empty_rescale: 1.0,
            end_confirm_px: 0.0,
            loops: false,
            twins: false,
            ..Self::default()
        }
    }

    /// Whether the network is asked about cables too wide for it
    /// ([`Params::wide_field_ratio`] under 100).
    pub fn probes_wide_cables(&self) -> bool {
        self.wide_field_ratio < 100.0
    }

    /// Whether a photo whose first pass finds no cable is segmented again smaller
    /// ([`Params::empty_rescale`] under 1).
    pub fn rescales_empty(&self) -> bool {
        self.empty_rescale < 1.0
    }

    /// The least score of a reported cable: `field_min_cable_score` when a cable field
    /// guides the walks, `min_cable_score` otherwise.
    pub fn cable_score_floor(&self, field: bool) -> f32 {
        if field {
            self.field_min_cable_score
        } else {
            self.min_cable_score
        }
    }

    /// The share of the floor that a cable arriving at another end needs:
    /// `field_reached_floor` when a cable field guides the walks, 1 otherwise.
    pub fn reached_floor(&self, field: bool) -> f32 {
        if field { self.field_reached_floor } else { 1.0 }
    }

    /// These parameters with the fields named in `overrides` replaced, then validated.
    /// Unknown field names and values of the wrong type are rejected.
    pub fn with_overrides(&self, overrides: &Map<String, Value>) -> Result<Self, EngineError> {
        let mut merged = self.fields();
        for (key, value) in overrides {
            merged.insert(key.clone(), value.clone());
        }
        let params: Self = serde_json::from_value(Value::Object(merged))
            .map_err(|e| EngineError::BadOptions(e.to_string()))?;
        params.validate()?;
        Ok(params)
    }

    /// The parameters as a JSON object, field name to value.
    pub(super) fn fields(&self) -> Map<String, Value> {
        match serde_json::to_value(self) {
            Ok(Value::Object(map)) => map,
            _ => unreachable!("Params always serialises to an object"),
        }
    }
}

#[cfg(test)]
mod tests;
