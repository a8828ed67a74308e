//! Wall-clock time per stage of one segmentation: the one record the engine, the
//! pipeline, the service's JSON and the evaluator all fill and read.

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

/// Milliseconds per stage. The engine fills `superpixels` to `splines`; the pipeline
/// (`crate::pipeline`) the others but `queue` and `total`, which only the service
/// knows (the command line and the evaluator set `total` to the pipeline's time).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct Timings {
    /// Waiting for a worker.
    pub queue: f64,
    /// Image decoding, EXIF orientation and resampling to the working size.
    pub decode: f64,
    /// The network: endpoint detection and cable field (0 when none is loaded). When it
    /// runs on a second thread beside SLIC (`pipeline::Job::overlap`, the service's
    /// choice when a worker is idle), it and `superpixels` overlap in `total`.
    pub endpoints: f64,
    /// Colour conversion, blur and SLIC.
    pub superpixels: f64,
    /// Region adjacency graph.
    pub graph: f64,
    /// All walks (from the ends and, with `border_cables`, from the border) and the
    /// pairing.
    pub walks: f64,
    /// Spline fits and refinement.
    pub splines: f64,
    /// Mask (and overlay) drawing.
    pub mask: f64,
    /// PNG encoding of the mask and overlay.
    pub encode: f64,
    /// Whole request, from arrival to response.
    pub total: f64,
}

impl Timings {
    /// Adds every stage of `other` (both passes of a photo segmented twice).
    pub fn add(&mut self, other: &Timings) {
        self.queue += other.queue;
        self.decode += other.decode;
        self.endpoints += other.endpoints;
        self.superpixels += other.superpixels;
        self.graph += other.graph;
        self.walks += other.walks;
        self.splines += other.splines;
        self.mask += other.mask;
        self.encode += other.encode;
        self.total += other.total;
    }

    /// Every stage but `queue` and `total` with its metric name, in pipeline order.
    pub fn stages(&self) -> [(&'static str, f64); 8] {
        [
            ("decode", self.decode),
            ("endpoints", self.endpoints),
            ("superpixels", self.superpixels),
            ("graph", self.graph),
            ("walks", self.walks),
            ("splines", self.splines),
            ("mask", self.mask),
            ("encode", self.encode),
        ]
    }
}

/// Milliseconds since `t`.
pub fn ms_since(t: std::time::Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
