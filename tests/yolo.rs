//! Real ultralytics YOLO exports plug in: a tiny detector of cable ends trained with
//! ultralytics and exported the three ways users do (`scripts/make-yolo-test-models.py`:
//! a fixed 320x256 input, `dynamic=True`, `nms=True`), run through ONNX Runtime on
//! development photos with `--model-kind yolo`.

#![allow(clippy::unwrap_used)] // test code: a failure should panic

use ariadne_dlo::detect::{DetectorConfig, EndpointDetector, Ends, ModelKind, OnnxDetector};
use ariadne_dlo::eval::{self, TERMINAL_MATCH_PX};

/// One export of the tiny model, loaded as a user would configure it.
fn load(name: &str) -> OnnxDetector {
    let config = DetectorConfig {
        model: format!("tests/models/{name}.onnx").into(),
        model_kind: ModelKind::Yolo,
        ..DetectorConfig::default()
    };
    OnnxDetector::load(&config, 1).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Ends found by each export on every third development photo, with the photos'
/// terminals.
type Found = Vec<(Vec<[f64; 2]>, Vec<[f64; 2]>)>;

fn ends_on_photos(detector: &OnnxDetector) -> Found {
    let samples = eval::load_dataset(&eval::default_dataset_dir()).expect("dataset");
    samples
        .iter()
        .step_by(3)
        .map(|s| {
            let bytes = std::fs::read(&s.image).unwrap();
            let image = ariadne_dlo::decode::decode_rgb(&bytes, u64::MAX).unwrap();
            let perception = detector.detect(&image).unwrap();
            for end in &perception.ends {
                let [x, y] = end.point;
                assert!((0.0..=1.0).contains(&end.confidence), "{end:?}");
                assert!(x >= 0.0 && y >= 0.0, "{end:?}");
                assert!(x < image.width() as f64 && y < image.height() as f64);
            }
            let terminals = eval::terminal_ends(&s.cables, image.width(), image.height());
            (Ends::detected(&perception.ends).points, terminals)
        })
        .collect()
}

fn recall(found: &Found) -> f64 {
    let hits: usize = found
        .iter()
        .map(|(ends, truth)| eval::match_points(ends, truth, TERMINAL_MATCH_PX))
        .sum();
    hits as f64 / found.iter().map(|(_, t)| t.len()).sum::<usize>() as f64
}

/// The raw head with a fixed input and with free input sides (padded to stride 32,
/// centred, grey 114) sees the same letterboxed image, so it finds the same ends; the
/// `nms=True` export (`[1, 300, 6]` boxes) finds them too, not ends at (0, 0). The
/// model trained on these photos for a few minutes: the floor only says it works.
#[test]
fn ultralytics_exports_find_the_same_ends() {
    let fixed = ends_on_photos(&load("yolo_fixed"));
    let dynamic = ends_on_photos(&load("yolo_dynamic"));
    let nms = ends_on_photos(&load("yolo_nms"));
    let (r_fixed, r_dynamic, r_nms) = (recall(&fixed), recall(&dynamic), recall(&nms));
    eprintln!("terminal recall: fixed {r_fixed:.3}, dynamic {r_dynamic:.3}, nms {r_nms:.3}");
    assert!(r_fixed >= 0.5, "fixed input: recall {r_fixed:.3}");
    for (photo, ((a, _), (b, _))) in fixed.iter().zip(&dynamic).enumerate() {
        assert_eq!(a.len(), b.len(), "photo {photo}: {a:?} vs {b:?}");
        assert_eq!(eval::match_points(a, b, 1.0), a.len(), "photo {photo}");
    }
    assert!(
        (r_nms - r_fixed).abs() <= 0.05,
        "nms {r_nms:.3} vs {r_fixed:.3}"
    );
    for (photo, ((raw, _), (suppressed, _))) in fixed.iter().zip(&nms).enumerate() {
        let shared = eval::match_points(suppressed, raw, 4.0);
        assert!(
            shared * 10 >= suppressed.len() * 9,
            "photo {photo}: {shared} of {} nms ends among the raw ones",
            suppressed.len()
        );
    }
}

/// The service letterboxes and decodes as ultralytics does: on one photo, its ends and
/// scores match ultralytics' own predictions with the same model
/// (`tests/models/yolo_expected.json`, written by the script), to within the
/// difference of the two resizing filters.
#[test]
fn ends_match_ultralytics_own_predictions() {
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("tests/models/yolo_expected.json").unwrap())
            .unwrap();
    let reference: Vec<[f64; 3]> = expected["ends"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| [0, 1, 2].map(|i| e[i].as_f64().unwrap()))
        .collect();
    let photo = eval::default_dataset_dir().join(expected["photo"].as_str().unwrap());
    let image = ariadne_dlo::decode::decode_rgb(&std::fs::read(photo).unwrap(), u64::MAX).unwrap();
    let ends = load("yolo_fixed").detect(&image).unwrap().ends;
    assert!(ends.len() >= 5, "{ends:?}");
    for end in &ends {
        let [x, y] = end.point;
        let nearest = reference
            .iter()
            .min_by(|a, b| {
                let d = |r: &[f64; 3]| (r[0] - x).hypot(r[1] - y);
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        let distance = (nearest[0] - x).hypot(nearest[1] - y);
        assert!(
            distance <= 3.0,
            "{end:?}: nearest ultralytics end {nearest:?}"
        );
        assert!(
            (nearest[2] - end.confidence as f64).abs() <= 0.06,
            "{end:?}: ultralytics scores {nearest:?}"
        );
    }
}
