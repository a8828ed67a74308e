//! End to end with the real parts: the bundled model through ONNX Runtime behind the
//! real server, on a photo of the development split (needs `make setup` and the
//! dataset).

#![allow(clippy::unwrap_used)] // test code: a failure should panic

mod common;

use std::sync::Arc;

use ariadne_dlo::detect::{DetectorConfig, OnnxDetector};
use ariadne_dlo::eval;
use common::app::TestApp;

/// No ends in the request: the bundled detector finds the terminals of a real photo,
/// and the cables are found from them.
#[tokio::test(flavor = "multi_thread")]
async fn a_photo_alone_is_segmented_with_detected_ends() {
    let detector = OnnxDetector::load(&DetectorConfig::default(), 2)
        .expect("bundled model (run `make setup`)");
    let app = TestApp::spawn(Arc::new(detector), |_| {}, true).await;
    let samples = eval::load_dataset(&eval::default_dataset_dir()).expect("dataset");
    let sample = samples
        .iter()
        .find(|s| s.set == "simple" && s.name == "00000")
        .unwrap();
    let body = app
        .segment_photo(std::fs::read(&sample.image).unwrap())
        .await;
    let ends = body["endpoints"].as_array().unwrap();
    let truth = eval::terminal_ends(&sample.cables, 640, 480);
    let found: Vec<[f64; 2]> = ends
        .iter()
        .map(|e| serde_json::from_value(e["point"].clone()).unwrap())
        .collect();
    let matched = eval::match_points(&found, &truth, eval::TERMINAL_MATCH_PX);
    assert!(
        matched * 10 >= truth.len() * 7,
        "{matched} of {} terminals detected: {found:?}",
        truth.len()
    );
    for e in ends {
        let c = e["confidence"].as_f64().unwrap();
        assert!(c > 0.0 && c <= 1.0, "confidence {c}");
    }
    let cables = body["cables"].as_array().unwrap();
    assert!(cables.len() >= 4, "{} cables", cables.len());
    assert!(ends.iter().filter(|e| e["cable"].is_u64()).count() >= 4);
    assert!(body["timings_ms"]["endpoints"].as_f64().unwrap() > 0.0);
    assert!(
        app.endpoint_inferences().await >= 1.0,
        "endpoint inference time is recorded"
    );
}
