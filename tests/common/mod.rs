//! Shared by the integration tests: scoring the development split, and a real server.
// Each test binary uses a different part of this module.
#![allow(dead_code)]

pub mod app;

use ariadne_dlo::detect::EndpointDetector;
use ariadne_dlo::engine::{Deadline, Mask, MaskKind, Params};
use ariadne_dlo::{eval, pipeline};
use image::GrayImage;

/// The output's binary mask.
pub fn mask(out: &pipeline::Output) -> &GrayImage {
    let Mask::Gray(mask) = &out.mask else {
        unreachable!("binary masks are single-channel")
    };
    mask
}

/// IoU of the output's binary mask with the truth.
pub fn mask_iou(out: &pipeline::Output, truth: &GrayImage) -> f64 {
    eval::iou(mask(out), truth)
}

/// Mean distance from each true centreline point to the nearest found polyline point.
pub fn centreline_error(truth: &[[f32; 2]], found: &[[f32; 2]]) -> f32 {
    let total: f32 = truth
        .iter()
        .map(|p| {
            found
                .iter()
                .map(|q| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt())
                .fold(f32::MAX, f32::min)
        })
        .sum();
    total / truth.len() as f32
}

/// The points of every centreline the output found, in one list.
pub fn found_points(out: &pipeline::Output) -> Vec<[f32; 2]> {
    out.segmentation
        .cables
        .iter()
        .flat_map(|c| c.polyline.iter().copied())
        .collect()
}

/// Distance, pixels, from each point of the output's centrelines to the nearest of
/// `truth` (points of the true centrelines, as dense as the distances should be exact).
pub fn distances_to_truth(out: &pipeline::Output, truth: &[[f32; 2]]) -> Vec<f32> {
    found_points(out)
        .iter()
        .map(|p| {
            truth
                .iter()
                .map(|q| (q[0] - p[0]).hypot(q[1] - p[1]))
                .fold(f32::MAX, f32::min)
        })
        .collect()
}

/// A job on an image file with no given ends (the network finds them), its binary mask
/// drawn but not encoded, the network beside SLIC.
pub fn job<'a>(
    bytes: &'a [u8],
    network: &'a dyn EndpointDetector,
    params: &'a Params,
) -> pipeline::Job<'a> {
    pipeline::Job {
        bytes,
        ends: None,
        network: Some(network),
        params,
        max_pixels: u64::MAX,
        mask: MaskKind::Binary,
        overlay: false,
        encode: false,
        deadline: Deadline::NONE,
        overlap: true,
    }
}

/// The pipeline on [`job`]; `overlap` as in [`pipeline::Job::overlap`].
pub fn photo_alone(
    bytes: &[u8],
    network: &dyn EndpointDetector,
    params: &Params,
    overlap: bool,
) -> pipeline::Output {
    pipeline::run(&pipeline::Job {
        overlap,
        ..job(bytes, network, params)
    })
    .expect("the pipeline runs")
}

/// Asserts that the weighted IoU of `simple` (preset `default`) and `hard` (preset
/// `clutter`) on the development split as `camera` sees it, with ends from `ends` and
/// the cable field of `network` when given, reaches `floors` (simple, hard); prints
/// both under `label`.
pub fn assert_split_iou(
    label: &str,
    network: Option<&dyn EndpointDetector>,
    ends: eval::EndsFrom,
    camera: eval::Camera,
    floors: (f64, f64),
) {
    assert_split_iou_with(label, ["default", "clutter"], network, ends, camera, floors);
}

/// [`assert_split_iou`] with the named presets for `simple/` and `hard/`.
pub fn assert_split_iou_with(
    label: &str,
    presets: [&str; 2],
    network: Option<&dyn EndpointDetector>,
    ends: eval::EndsFrom,
    camera: eval::Camera,
    floors: (f64, f64),
) {
    let samples = eval::load_dataset(&eval::default_dataset_dir())
        .unwrap_or_else(|e| panic!("dataset missing ({e}); set ARIADNE_DATASET"));
    let [simple, hard] = presets.map(|name| Params::preset(name).unwrap());
    let setup = eval::Setup {
        network,
        ends,
        camera,
        save_views: None,
    };
    let results = eval::evaluate_all(&samples, &simple, &hard, setup, |_| {}).unwrap();
    let simple_iou = eval::weighted_iou(&results, "simple");
    let hard_iou = eval::weighted_iou(&results, "hard");
    eprintln!("{label}, weighted IoU: simple {simple_iou:.3}, hard {hard_iou:.3}");
    assert!(simple_iou >= floors.0, "{label}: simple {simple_iou:.3}");
    assert!(hard_iou >= floors.1, "{label}: hard {hard_iou:.3}");
}
