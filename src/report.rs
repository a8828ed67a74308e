//! The JSON document describing one segmentation, shared by `ariadne segment --json`
//! and `POST /segment`.

use base64::Engine as _;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use crate::engine::{Cable, Segmentation};
use crate::pipeline::Output;
pub use crate::timings::Timings;

/// Result of segmenting one image.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SegmentResponse {
    /// Identifier of the request (echo of `x-request-id`, or generated).
    pub request_id: String,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Working pixels per photo pixel: the photo was segmented resampled by this factor
    /// (1 at 640x480; docs/CAMERAS.md). `width`, `height` and every coordinate
    /// are in pixels of the photo as displayed (its EXIF orientation applied).
    pub working_scale: f32,
    /// Cables found, by decreasing score.
    pub cables: Vec<CableReport>,
    /// Every end: given, or found (the network's terminal peaks the walks started from,
    /// then the second terminal beside one of them where a cable walked from it lay over
    /// two cables side by side, then weaker peaks where a found cable stops), with the
    /// cable it was assigned to.
    pub endpoints: Vec<EndpointReport>,
    /// The mask as a base64-encoded PNG of the image's size.
    pub mask_png: String,
    /// The photo with the curves drawn on it, base64 PNG; only when asked for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub overlay_png: Option<String>,
    /// Time spent per stage, milliseconds.
    pub timings_ms: Timings,
}

/// One cable.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct CableReport {
    /// Index of the cable; label masks use `id + 1`.
    pub id: usize,
    /// The two ends of the centreline, `[[x, y], [x, y]]`, pixels.
    pub endpoints: [[f32; 2]; 2],
    /// The centreline as a B-spline.
    pub spline: SplineReport,
    /// Points sampled along the spline from the first end to the second, pixels.
    pub polyline: Vec<[f32; 2]>,
    /// Length of the centreline, pixels.
    pub length_px: f32,
    /// Width measured across the cable, pixels.
    pub width_px: f32,
    /// Median colour along the centreline, `#rrggbb`.
    pub color: String,
    /// Confidence in 0..=1: how well the walk that found the cable kept to one thin
    /// structure of one colour (colour agreement, smoothness, lateral contrast, mean
    /// cable probability), discounted when no walk from the other end confirmed it and
    /// by the confidence of an unconfirmed start end, and multiplied by the share of
    /// the centreline that the cable field calls cable.
    pub score: f32,
}

/// A clamped B-spline with parameter domain [0, 1].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SplineReport {
    /// Polynomial degree.
    pub degree: usize,
    /// Knot vector (`control_points + degree + 1` values).
    pub knots: Vec<f64>,
    /// Control points `[[x, y], ...]`, pixels.
    pub control_points: Vec<[f64; 2]>,
}

/// One cable end.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct EndpointReport {
    /// Position `[x, y]`, pixels.
    pub point: [f64; 2],
    /// The network's terminal confidence in 0..=1 (the cable field's terminal heatmap
    /// at its peak; 1 for ends given by the caller). Ends under the detection threshold
    /// started no walk: a cable found from the others stops on them.
    pub confidence: f32,
    /// Id of the cable it ends, or null when no cable was found from it.
    pub cable: Option<usize>,
}

impl SegmentResponse {
    /// The document of a pipeline's output (its mask and overlay PNGs base64-encoded;
    /// an output made without encoding gets an empty `mask_png`).
    pub fn new(output: &Output, request_id: String) -> Self {
        let seg = &output.segmentation;
        Self {
            request_id,
            width: seg.width,
            height: seg.height,
            working_scale: seg.working_scale,
            cables: seg.cables.iter().map(CableReport::from).collect(),
            endpoints: endpoint_reports(seg, &output.ends.points, &output.ends.confidences),
            mask_png: output.mask_png.as_deref().map(base64).unwrap_or_default(),
            overlay_png: output.overlay_png.as_deref().map(base64),
            timings_ms: output.timings,
        }
    }
}

impl From<&Cable> for CableReport {
    fn from(c: &Cable) -> Self {
        Self {
            id: c.id,
            endpoints: c.ends,
            spline: SplineReport {
                degree: c.spline.degree,
                knots: c.spline.knots.clone(),
                control_points: c.spline.control_points.clone(),
            },
            polyline: c.polyline.clone(),
            length_px: c.length_px,
            width_px: c.width_px,
            color: format!("#{:02x}{:02x}{:02x}", c.color[0], c.color[1], c.color[2]),
            score: c.score,
        }
    }
}

/// Parses cable ends given as JSON `[[x, y], ...]` (integer or fractional numbers).
pub fn parse_endpoints(text: &str) -> Result<Vec<[f64; 2]>, String> {
    serde_json::from_str::<Vec<[f64; 2]>>(text).map_err(|e| e.to_string())
}

/// Reports every end of `ends` with its confidence and the cable `seg` assigned it to.
fn endpoint_reports(
    seg: &Segmentation,
    ends: &[[f64; 2]],
    confidences: &[f32],
) -> Vec<EndpointReport> {
    ends.iter()
        .enumerate()
        .map(|(i, &point)| EndpointReport {
            point,
            confidence: confidences.get(i).copied().unwrap_or(1.0),
            cable: seg.end_cables.get(i).copied().flatten(),
        })
        .collect()
}

/// Base64 (standard alphabet, padded) of `bytes`.
fn base64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}
