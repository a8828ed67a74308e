//! The JSON document describing one segmentation, shared by `ariadne segment --json`
//! and `POST /segment`, plus PNG encoding of masks.

use base64::Engine as _;
use image::{ImageEncoder, codecs::png::PngEncoder};
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use crate::engine::{Cable, Mask, Segmentation};

/// Result of segmenting one image.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SegmentResponse {
    /// Identifier of the request (echo of `x-request-id`, or generated).
    pub request_id: String,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Cables found, by decreasing score.
    pub cables: Vec<CableReport>,
    /// Every end used (given or detected), with the cable it was assigned to.
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
    /// Confidence in 0..=1.
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
    /// Detector confidence in 0..=1 (1 for ends given by the caller).
    pub confidence: f32,
    /// Id of the cable it ends, or null when no cable was found from it.
    pub cable: Option<usize>,
}

/// Stage timings, milliseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct Timings {
    /// Waiting for a worker.
    pub queue: f64,
    /// Image decoding.
    pub decode: f64,
    /// Endpoint detection (0 when ends were given).
    pub endpoints: f64,
    /// Colour conversion, blur and SLIC.
    pub superpixels: f64,
    /// Region adjacency graph.
    pub graph: f64,
    /// Walks and pairing.
    pub walks: f64,
    /// Spline fits and refinement.
    pub splines: f64,
    /// Mask (and overlay) drawing.
    pub mask: f64,
    /// PNG and JSON encoding.
    pub encode: f64,
    /// Whole request, from arrival to response.
    pub total: f64,
}

impl Timings {
    /// Copies the engine's stage times in.
    pub fn with_engine(mut self, seg: &Segmentation) -> Self {
        self.superpixels = seg.timings.superpixels;
        self.graph = seg.timings.graph;
        self.walks = seg.timings.walks;
        self.splines = seg.timings.splines;
        self
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
pub fn endpoint_reports(
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

/// Encodes a mask as PNG bytes.
pub fn mask_png(mask: &Mask) -> Vec<u8> {
    match mask {
        Mask::Gray(img) => png(
            img.as_raw(),
            img.width(),
            img.height(),
            image::ExtendedColorType::L8,
        ),
        Mask::Rgb(img) => png(
            img.as_raw(),
            img.width(),
            img.height(),
            image::ExtendedColorType::Rgb8,
        ),
    }
}

/// Encodes raw 8-bit pixels as PNG (fast compression: masks compress well anyway).
pub fn png(raw: &[u8], width: u32, height: u32, kind: image::ExtendedColorType) -> Vec<u8> {
    let mut out = Vec::new();
    let encoder = PngEncoder::new_with_quality(
        &mut out,
        image::codecs::png::CompressionType::Fast,
        image::codecs::png::FilterType::Sub,
    );
    // Writing to a Vec with matching dimensions cannot fail.
    if encoder.write_image(raw, width, height, kind).is_err() {
        out.clear();
    }
    out
}

/// Base64 (standard alphabet, padded) of `bytes`.
pub fn base64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}
