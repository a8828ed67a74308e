//! The bundled endpoint model through ONNX Runtime on dataset images, and the start-up
//! errors a bad model or runtime gives.

#![allow(clippy::unwrap_used)] // test code: a failure should panic

mod common;

use std::process::Command;

use ariadne_dlo::detect::{DetectorConfig, EndpointDetector, Ends, OnnxDetector};
use ariadne_dlo::engine::{self, Deadline, Params, geometry, spline};
use ariadne_dlo::eval::{self, TERMINAL_MATCH_PX};
use image::imageops::FilterType;

/// Weighted IoU floors (simple, hard) with a photo alone: measured 0.716 and 0.751
/// (README, Accuracy). These photos are in the network's training set, but its training
/// (2000 steps on a frozen ImageNet stem) does not learn the three textured `hard`
/// photos by heart (terminal recall 0.792 there), so `hard`'s floor is loose.
const PHOTO_ALONE: (f64, f64) = (0.65, 0.55);
/// Weighted IoU floors (simple, hard) with the true ends and the field: measured 0.739
/// and 0.780.
const TRUE_ENDS: (f64, f64) = (0.70, 0.70);

/// Terminal recall and precision at 15 px over a whole set. The floors sit below the
/// measured figures (README) so that they guard against regressions, not noise.
#[test]
fn bundled_model_finds_the_terminals() {
    let detector = OnnxDetector::load(&DetectorConfig::default(), 1)
        .expect("bundled model (run `make setup`)");
    let samples = eval::load_dataset(&eval::default_dataset_dir()).expect("dataset");
    // Threshold 0.25 trades precision for recall (measured 0.891 / 0.784 on simple,
    // 0.792 / 0.655 on hard, ends with no cable beside them dropped: the textured
    // photos are hard for the network even in-sample; see PHOTO_ALONE).
    for (set, min_recall, min_precision) in [("simple", 0.85, 0.70), ("hard", 0.50, 0.35)] {
        let (mut hits, mut truth, mut found) = (0, 0, 0);
        for s in samples.iter().filter(|s| s.set == set) {
            let bytes = std::fs::read(&s.image).unwrap();
            let image = ariadne_dlo::decode::decode_rgb(&bytes, u64::MAX).unwrap();
            let terminals = eval::terminal_ends(&s.cables, image.width(), image.height());
            let ends = Ends::detected(&detector.detect(&image).unwrap().ends).points;
            hits += eval::match_points(&ends, &terminals, TERMINAL_MATCH_PX);
            truth += terminals.len();
            found += ends.len();
        }
        let recall = hits as f64 / truth.max(1) as f64;
        let precision = hits as f64 / found.max(1) as f64;
        eprintln!("{set}: recall {recall:.3} precision {precision:.3}");
        assert!(recall >= min_recall, "{set}: recall {recall:.3}");
        assert!(
            precision >= min_precision,
            "{set}: precision {precision:.3}"
        );
    }
}

/// A portrait camera: the development photos turned a quarter (480x640) are fed to
/// the network at the same scale as landscape ones (their own shape, padded), so it
/// finds their terminals as well as in the landscape photos.
#[test]
fn portrait_photos_are_seen_at_the_landscape_scale() {
    let detector = OnnxDetector::load(&DetectorConfig::default(), 1)
        .expect("bundled model (run `make setup`)");
    let samples = eval::load_dataset(&eval::default_dataset_dir()).expect("dataset");
    let (mut upright, mut turned, mut truth) = (0, 0, 0);
    for s in samples.iter().filter(|s| s.set == "simple").step_by(3) {
        let bytes = std::fs::read(&s.image).unwrap();
        let image = ariadne_dlo::decode::decode_rgb(&bytes, u64::MAX).unwrap();
        let terminals = eval::terminal_ends(&s.cables, image.width(), image.height());
        let ends = Ends::detected(&detector.detect(&image).unwrap().ends).points;
        upright += eval::match_points(&ends, &terminals, TERMINAL_MATCH_PX);
        // A quarter turn clockwise: (x, y) goes to (H - 1 - y, x).
        let portrait = image::imageops::rotate90(&image);
        let h = image.height() as f64;
        let turned_terminals: Vec<[f64; 2]> =
            terminals.iter().map(|&[x, y]| [h - 1.0 - y, x]).collect();
        let ends = Ends::detected(&detector.detect(&portrait).unwrap().ends).points;
        turned += eval::match_points(&ends, &turned_terminals, TERMINAL_MATCH_PX);
        truth += terminals.len();
    }
    let (upright, turned) = (upright as f64 / truth as f64, turned as f64 / truth as f64);
    eprintln!("terminal recall: landscape {upright:.3}, portrait {turned:.3}");
    assert!(
        turned >= upright - 0.08,
        "portrait {turned:.3} vs {upright:.3}"
    );
}

/// A photo segmented enlarged (a small camera's) reaches the network from its own
/// pixels: a development photo taken at half size and shown as a 640x480 frame gives the
/// ends the full-size photo gives, in the frame's pixels, and a field over the frame.
#[test]
fn a_small_photo_shown_as_a_larger_frame_is_seen_from_its_own_pixels() {
    let detector = OnnxDetector::load(&DetectorConfig::default(), 1)
        .expect("bundled model (run `make setup`)");
    let samples = eval::load_dataset(&eval::default_dataset_dir()).expect("dataset");
    let (mut same, mut total) = (0, 0);
    for s in samples.iter().filter(|s| s.set == "simple").step_by(4) {
        let bytes = std::fs::read(&s.image).unwrap();
        let photo = ariadne_dlo::decode::decode_rgb(&bytes, u64::MAX).unwrap();
        let small = image::imageops::resize(&photo, 320, 240, FilterType::Triangle);
        let full = Ends::detected(&detector.detect(&photo).unwrap().ends).points;
        let framed = detector.detect_as(&small, [640, 480]).unwrap();
        let ends = Ends::detected(&framed.ends).points;
        same += eval::match_points(&ends, &full, 3.0);
        total += full.len().max(ends.len());
        let field = framed.field.unwrap();
        let covered = [
            field.width as f32 * field.cell_px[0],
            field.height as f32 * field.cell_px[1],
        ];
        assert_eq!(covered, [640.0, 480.0]);
    }
    let share = same as f64 / total as f64;
    eprintln!("{same} of {total} ends within 3 px of the full-size photo's");
    assert!(share >= 0.9, "{share:.3}");
}

/// End to end on the development split with the bundled network: a photo alone (its
/// ends and field), and the true ends guided by its field. Floors a little under the
/// measured values (README, Accuracy; in-sample for this model), which are themselves
/// under the cable-field issue's targets (0.72 / 0.60 and 0.75 / 0.70) but for `hard`
/// with true ends.
#[test]
fn the_network_segments_the_development_split() {
    let network = OnnxDetector::load(&DetectorConfig::default(), 1)
        .expect("bundled model (run `make setup`)");
    common::assert_split_iou(
        "photo alone",
        Some(&network),
        eval::EndsFrom::Network,
        eval::Camera::default(),
        PHOTO_ALONE,
    );
    common::assert_split_iou(
        "true ends and field",
        Some(&network),
        eval::EndsFrom::Truth,
        eval::Camera::default(),
        TRUE_ENDS,
    );
}

/// An underexposed photo (every value multiplied by 0.3: a dim cell, a short exposure)
/// is brightened before the network and the engine see it, so it is segmented about as
/// well as the photo itself: measured 0.714 / 0.745 from a photo alone, against 0.716 /
/// 0.751 for the photos as they are and 0.636 / 0.468 with the correction off
/// (`exposure_max_gain` 1). The floors are those of the photos as they are.
#[test]
fn an_underexposed_photo_is_segmented_like_a_well_exposed_one() {
    let dim = eval::Camera {
        exposure: 0.3,
        ..eval::Camera::default()
    };
    assert_photo_alone_holds_its_floors("exposure 0.3, photo alone", dim);
}

/// A soft photo (a Gaussian blur of 1.5 px over every photo: a lens out of focus) is
/// sharpened before the network and the engine see it, so it is segmented about as
/// well as the sharp photo: with the true ends and the field, measured 0.739 / 0.790
/// (simple / hard), against 0.739 / 0.780 for the photos as they are and 0.735 / 0.762
/// with the sharpening off (`sharpen_amount` 0). The floors are those of the photos as
/// they are.
#[test]
fn a_soft_photo_is_segmented_like_a_sharp_one() {
    let network = OnnxDetector::load(&DetectorConfig::default(), 1)
        .expect("bundled model (run `make setup`)");
    let soft = eval::Camera {
        blur: 1.5,
        ..eval::Camera::default()
    };
    common::assert_split_iou(
        "blur 1.5 px, true ends",
        Some(&network),
        eval::EndsFrom::Truth,
        soft,
        TRUE_ENDS,
    );
}

/// A noisy photo (Gaussian noise of σ 12 levels on every channel: a small sensor at
/// high gain) from a photo alone is segmented about as well as the clean one: measured
/// 0.710 / 0.719 (simple / hard) against 0.716 / 0.751 (`ariadne eval --endpoints
/// detect --noise 12`; the three `hard` photos move by single cables). The floors are
/// those of the photos as they are.
#[test]
fn a_noisy_photo_alone_is_segmented_like_a_clean_one() {
    let noisy = eval::Camera {
        noise: 12.0,
        ..eval::Camera::default()
    };
    assert_photo_alone_holds_its_floors("noise σ 12, photo alone", noisy);
}

/// The development split from a photo alone as `camera` sees it, held to the floors of
/// the photos as they are ([`PHOTO_ALONE`]).
fn assert_photo_alone_holds_its_floors(label: &str, camera: eval::Camera) {
    let network = OnnxDetector::load(&DetectorConfig::default(), 1)
        .expect("bundled model (run `make setup`)");
    common::assert_split_iou(
        label,
        Some(&network),
        eval::EndsFrom::Network,
        camera,
        PHOTO_ALONE,
    );
}

/// With `overlap` the pipeline runs the network on a second thread while SLIC runs:
/// its cables are exactly those it finds with the two in turn, and those of the engine
/// run after the network, on the network's ends and field (a 640x480 development photo
/// is its own working image, and bright enough to need no exposure gain).
#[test]
fn the_network_beside_slic_gives_the_sequential_result() {
    let network = OnnxDetector::load(&DetectorConfig::default(), 1)
        .expect("bundled model (run `make setup`)");
    let bytes = std::fs::read(dataset_photo()).unwrap();
    let params = Params::default();
    let image = ariadne_dlo::decode::decode_rgb(&bytes, u64::MAX).unwrap();
    let seen = network
        .detect_as(&image, [image.width(), image.height()])
        .unwrap();
    let ends = Ends::detected(&seen.ends);
    let direct = engine::segment_with_confidence(
        &image,
        &ends.points,
        &ends.confidences,
        seen.field.as_ref(),
        &params,
        Deadline::NONE,
    )
    .unwrap();
    assert!(!direct.cables.is_empty());
    for overlap in [true, false] {
        let out = common::photo_alone(&bytes, &network, &params, overlap);
        assert_eq!(out.ends.points, ends.points, "overlap {overlap}");
        assert_eq!(out.segmentation.cables, direct.cables, "overlap {overlap}");
    }
}

/// Cables 32 px wide at 640x480 (a camera about four times closer than the development
/// photos'), far wider than any the network learnt: at the working size its field
/// shows none of them and the engine found nothing, not even from the true ends. Its
/// field at half the size shows them, so the photo is worked smaller (docs/CAMERAS.md).
/// Measured over the four scenes (2026-11-29, session 67): mask IoU 0.43 / 0.77 / 0.61 /
/// 0.42 with the true ends and 0.23 / 0.76 / 0.31 / 0.32 from a photo alone, against
/// 0.00 with the field's probe and the look at half size when nothing is found both off
/// (`wide_field_ratio` 100, `empty_rescale` 1). The look alone reaches the same scale
/// and figures in all eight runs. (Earlier figures here, 0.59 / 0.20 / 0.60 / 0.67 and
/// 0.38 / 0.75 / 0.27 / 0.38, had gone stale before session 67, whose closing rule moved
/// only seed 2 with the true ends, 0.42 → 0.77.)
#[test]
fn cables_too_wide_for_the_network_are_found_at_a_smaller_scale() {
    use ariadne_dlo::synth::{Background, SceneSpec, scene};
    let network = OnnxDetector::load(&DetectorConfig::default(), 1)
        .expect("bundled model (run `make setup`)");
    let look_only = Params {
        wide_field_ratio: 100.0,
        ..Params::default()
    };
    let never = Params {
        empty_rescale: 1.0,
        ..look_only
    };
    let (mut probed, mut looked, mut unprobed) = (Vec::new(), Vec::new(), Vec::new());
    for seed in 1..=4 {
        let truth = scene(&SceneSpec {
            width: 640,
            height: 480,
            cables: 2,
            cable_width: 32.0,
            background: Background::Plain,
            seed,
        });
        let mut bytes = Vec::new();
        truth
            .image
            .write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::Png,
            )
            .unwrap();
        let ends = truth.ends();
        for given in [Some(ends.as_slice()), None] {
            let run = |params: &Params| {
                ariadne_dlo::pipeline::run(&ariadne_dlo::pipeline::Job {
                    ends: given,
                    ..common::job(&bytes, &network, params)
                })
                .unwrap()
            };
            let (out, look, off) = (run(&Params::default()), run(&look_only), run(&never));
            let iou = |o: &ariadne_dlo::pipeline::Output| common::mask_iou(o, &truth.mask);
            let scale = out.segmentation.working_scale;
            eprintln!(
                "seed {seed}, given ends {}: working scale {scale}, mask IoU {:.3}, {:.3} with the look alone, {:.3} with neither",
                given.is_some(),
                iou(&out),
                iou(&look),
                iou(&off)
            );
            assert!(scale <= 0.5, "seed {seed}: working scale {scale}");
            assert!(!out.segmentation.cables.is_empty(), "seed {seed}");
            probed.push(iou(&out));
            looked.push(iou(&look));
            unprobed.push(iou(&off));
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(mean(&unprobed) < 0.05, "{unprobed:?}");
    assert!(mean(&probed) > 0.4, "{probed:?}");
    assert!(mean(&looked) > 0.4, "{looked:?}");
}

/// A development photo seen 3 times closer (simple/00038: a white and a yellow cable,
/// each about 25 px wide, crossing the frame with no end in view). At the working scale
/// their walks read little lateral contrast, as every superpixel beside them is cable
/// too, and score under the floor for cables with no end in view: nothing is found,
/// so no width is read to correct the scale by. Looked at once more at half the size
/// (`empty_rescale`), the yellow cable is found, and the photo is then segmented at the
/// scale its width asks for (docs/CAMERAS.md). The white one stays lost. Both runs
/// leave the traces in the field out (`field_trace_level` 1): traces from where the
/// cables meet the frame's edge find two cables in the first pass, so that the photo
/// is never empty (docs/ENGINE.md, "A wire no superpixel follows").
#[test]
fn a_photo_in_which_nothing_is_found_is_looked_at_smaller() {
    let network = OnnxDetector::load(&DetectorConfig::default(), 1)
        .expect("bundled model (run `make setup`)");
    let sample = &dev_sample("simple", "00038");
    let closer = eval::Camera {
        zoom: 3.0,
        ..eval::Camera::default()
    };
    let view = eval::View::of(sample, closer).unwrap();
    let untraced = Params {
        field_trace_level: 1.0,
        ..Params::default()
    };
    let never = Params {
        empty_rescale: 1.0,
        ..untraced.clone()
    };
    let run = |params: &Params| common::photo_alone(&view.bytes, &network, params, true);
    let (out, off) = (run(&untraced), run(&never));
    // Median distance of the found centrelines' points to the nearest annotated
    // centreline (resampled every pixel).
    let truth: Vec<[f32; 2]> = view
        .centrelines
        .iter()
        .flat_map(|line| spline::resample(line, 1.0))
        .collect();
    let mut off_truth = common::distances_to_truth(&out, &truth);
    let median = geometry::median(&mut off_truth, f32::total_cmp).unwrap_or(f32::MAX);
    let scale = out.segmentation.working_scale;
    eprintln!(
        "found {} cable(s) at working scale {scale:.2}, mask IoU {:.3}, centreline {median:.1} px from the truth's (median)",
        out.segmentation.cables.len(),
        common::mask_iou(&out, &view.mask_all),
    );
    assert!(off.segmentation.cables.is_empty(), "found without the rule");
    assert!(!out.segmentation.cables.is_empty());
    assert!(scale < 0.5, "working scale {scale}");
    // Along the yellow cable, within its width: measured 14.6 px off the annotated
    // middle, on the cable's shaded lower edge (the masks' IoU is 0.176).
    assert!(median < 25.0, "centreline {median:.1} px from the truth's");
}

/// A weak end's cable gives way to the whole cable it lies on (`field_weak_cable_score`;
/// docs/ENGINE.md, "A weak end's cable that a whole one runs along"). On hard/00002 from
/// a photo alone, the cable annotated from (109, 374) to (400, 54) has two weak ends
/// on it (0.26 in mid-cable, 0.30 at its upper terminal): the walk from the first ran
/// down to the frame's bottom edge, the one from the second went the wrong way, and
/// the two cables they made (scoring 0.027 and 0.020) covered the field's pieces along
/// it, so it was never found whole (its centreline 8.1 px from the found ones, mean).
/// Looked for again as if those two were not there, it is found whole from the field's
/// pieces (scoring 0.17; 1.0 px), and they give way to it.
#[test]
fn a_weak_end_s_cable_gives_way_to_the_whole_cable_it_lies_on() {
    let network = OnnxDetector::load(&DetectorConfig::default(), 1)
        .expect("bundled model (run `make setup`)");
    let sample = dev_sample("hard", "00002");
    let bytes = std::fs::read(&sample.image).unwrap();
    let truth = spline::resample(&sample.cables[0], 1.0);
    // Mean distance from the annotated cable's points to the nearest found centreline.
    let error = |weak: f32| {
        let params = Params {
            field_weak_cable_score: weak,
            ..Params::preset("clutter").unwrap()
        };
        let out = common::photo_alone(&bytes, &network, &params, true);
        common::centreline_error(&truth, &common::found_points(&out))
    };
    let (with, without) = (error(Params::default().field_weak_cable_score), error(0.0));
    eprintln!(
        "the cable's centreline {with:.1} px from the found ones, {without:.1} without the rule"
    );
    assert!(with < 4.0, "{with:.1} px");
    assert!(without > 5.0, "{without:.1} px without the rule");
}

/// The development split's photo `set`/`name`, with its annotation.
fn dev_sample(set: &str, name: &str) -> eval::Sample {
    eval::load_dataset(&eval::default_dataset_dir())
        .expect("dataset")
        .into_iter()
        .find(|s| s.set == set && s.name == name)
        .unwrap_or_else(|| panic!("{set}/{name} in the dataset"))
}

/// A development photo, as an absolute path.
fn dataset_photo() -> std::path::PathBuf {
    let dir = eval::default_dataset_dir().join("simple/00000.jpg");
    std::fs::canonicalize(&dir).unwrap_or(dir)
}

/// `ariadne serve` with a bad model or runtime stops at once with a message saying what
/// is wrong, before it listens; the bundled model is found from any working directory,
/// and `segment --json` embeds only what it did not write to files.
#[test]
fn bad_model_or_runtime_stops_the_service_at_start_up() {
    let dir = std::env::temp_dir().join(format!("ariadne-detector-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let corrupt = dir.join("corrupt.onnx");
    std::fs::write(&corrupt, b"this is not a protobuf").unwrap();
    let missing = dir.join("missing.onnx");
    // Inputs the service cannot feed (scripts/make-test-models.py).
    let one_side = std::fs::canonicalize("tests/models/one_side_fixed.onnx").unwrap();
    let gray = std::fs::canonicalize("tests/models/one_channel.onnx").unwrap();
    let cases: [(&[&str], &str); 5] = [
        (
            &["--model", missing.to_str().unwrap()],
            "not found (looked at",
        ),
        (&["--model", corrupt.to_str().unwrap()], "corrupt.onnx"),
        (
            &["--model", one_side.to_str().unwrap()],
            "both sides fixed or both free",
        ),
        (&["--model", gray.to_str().unwrap()], "has 1 channels"),
        (
            &["--ort-library", "/nonexistent/libonnxruntime.so.1.31.1"],
            "make setup",
        ),
    ];
    let elsewhere = Command::new(env!("CARGO_BIN_EXE_ariadne"))
        .args([
            "segment",
            "--json",
            "-",
            "--mask",
            "m.png",
            "--overlay",
            "o.png",
        ])
        .arg(dataset_photo())
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(
        elsewhere.status.success(),
        "{}",
        String::from_utf8_lossy(&elsewhere.stderr)
    );
    // What went to files is not embedded in the JSON again.
    let doc: serde_json::Value = serde_json::from_slice(&elsewhere.stdout).unwrap();
    assert_eq!(doc["mask_png"], "");
    assert!(doc.get("overlay_png").is_none());
    assert!(dir.join("m.png").is_file() && dir.join("o.png").is_file());
    for (flags, expected) in cases {
        let out = Command::new(env!("CARGO_BIN_EXE_ariadne"))
            .args(["serve", "--bind", "127.0.0.1:0"])
            .args(flags)
            .env_remove("ORT_DYLIB_PATH")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{flags:?} started");
        assert!(
            stderr.contains("endpoint detector") && stderr.contains(expected),
            "{flags:?}: {stderr}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
