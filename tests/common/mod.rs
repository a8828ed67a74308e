//! Shared by the integration tests: scoring the development split, and a real server.
// Each test binary uses a different part of this module.
#![allow(dead_code)]

pub mod app;

use ariadne_dlo::detect::EndpointDetector;
use ariadne_dlo::engine::Params;
use ariadne_dlo::eval;

/// Weighted IoU of `simple` (preset `default`) and `hard` (preset `clutter`) on the
/// development split as `camera` sees it, with ends from `ends` and the cable field of
/// `network` when given.
pub fn split_iou(
    network: Option<&dyn EndpointDetector>,
    ends: eval::EndsFrom,
    camera: eval::Camera,
) -> (f64, f64) {
    let samples = eval::load_dataset(&eval::default_dataset_dir())
        .unwrap_or_else(|e| panic!("dataset missing ({e}); set ARIADNE_DATASET"));
    let simple = Params::preset("default").unwrap();
    let hard = Params::preset("clutter").unwrap();
    let setup = eval::Setup {
        network,
        ends,
        camera,
    };
    let results = eval::evaluate_all(&samples, &simple, &hard, setup, |_| {}).unwrap();
    (
        eval::weighted_iou(&results, "simple"),
        eval::weighted_iou(&results, "hard"),
    )
}
