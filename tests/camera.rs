//! Any camera: photos with an EXIF orientation, portrait photos, a 12 MP photo and a
//! perspective scene are segmented in the pixels of the photo as displayed, at the
//! working resolution (docs/CAMERAS.md). Ends are given, so no model is needed.

#![allow(clippy::unwrap_used)] // test code: a failure should panic

mod common;

use ariadne_dlo::engine::{Mask, MaskKind, Params, Segmentation, render};
use ariadne_dlo::eval;
use ariadne_dlo::pipeline::{self, Job, Output};
use ariadne_dlo::synth::{Background, Scene, SceneSpec, scene};
use common::{mask, mask_iou};
use image::codecs::jpeg::JpegEncoder;
use image::{DynamicImage, GrayImage, Luma, Rgb, RgbImage, metadata::Orientation};

/// The photo as a JPEG of quality 95.
fn jpeg(image: &RgbImage) -> Vec<u8> {
    let mut out = Vec::new();
    JpegEncoder::new_with_quality(&mut out, 95)
        .encode_image(image)
        .unwrap();
    out
}

/// `jpeg` with an EXIF APP1 segment right after its start-of-image marker holding one
/// tag: orientation (0x0112) = `orientation`, little-endian TIFF.
fn with_exif_orientation(jpeg: &[u8], orientation: u16) -> Vec<u8> {
    let mut tiff = b"II*\0".to_vec();
    tiff.extend_from_slice(&8u32.to_le_bytes()); // first IFD right after the header
    tiff.extend_from_slice(&1u16.to_le_bytes()); // one entry
    tiff.extend_from_slice(&0x0112u16.to_le_bytes());
    tiff.extend_from_slice(&3u16.to_le_bytes()); // SHORT
    tiff.extend_from_slice(&1u32.to_le_bytes()); // count
    tiff.extend_from_slice(&orientation.to_le_bytes());
    tiff.extend_from_slice(&[0, 0]); // value padding
    tiff.extend_from_slice(&0u32.to_le_bytes()); // no next IFD
    let mut app1 = b"Exif\0\0".to_vec();
    app1.extend_from_slice(&tiff);
    let mut out = jpeg[..2].to_vec();
    out.extend_from_slice(&[0xFF, 0xE1]);
    out.extend_from_slice(&(app1.len() as u16 + 2).to_be_bytes());
    out.extend_from_slice(&app1);
    out.extend_from_slice(&jpeg[2..]);
    out
}

/// The pipeline on `bytes` with the given ends, no network and the default parameters.
fn run(bytes: &[u8], ends: &[[f64; 2]]) -> Output {
    run_with(bytes, ends, &Params::default())
}

/// [`run`] with `params`.
fn run_with(bytes: &[u8], ends: &[[f64; 2]], params: &Params) -> Output {
    pipeline::run(&Job {
        bytes,
        ends: Some(ends),
        network: None,
        params,
        max_pixels: u64::MAX,
        mask: MaskKind::Binary,
        overlay: false,
        encode: false,
        deadline: ariadne_dlo::engine::Deadline::NONE,
        overlap: true,
    })
    .unwrap()
}

/// Asserts that every true end lies within `tol` pixels of an end of a found cable,
/// and that as many cables as true ones were found.
fn assert_found(out: &Output, truth: &Scene, tol: f32) {
    let found: Vec<[f32; 2]> = out
        .segmentation
        .cables
        .iter()
        .flat_map(|c| c.ends)
        .collect();
    assert_eq!(out.segmentation.cables.len(), truth.cables.len());
    for p in truth.ends() {
        let d = found
            .iter()
            .map(|q| (q[0] - p[0] as f32).hypot(q[1] - p[1] as f32))
            .fold(f32::MAX, f32::min);
        assert!(d <= tol, "true end {p:?} is {d:.1} px from every found end");
    }
}

/// Two random cables on a plain background (of the synthetic scenes, pairs are seldom
/// ambiguous: ends touching the other cable).
fn spec(width: u32, height: u32, cable_width: f32, seed: u64) -> SceneSpec {
    SceneSpec {
        width,
        height,
        cables: 2,
        cable_width,
        background: Background::Plain,
        seed,
    }
}

#[test]
fn every_exif_orientation_is_applied_before_anything_else() {
    let truth = scene(&spec(640, 480, 9.0, 1));
    let upright = DynamicImage::ImageRgb8(truth.image.clone());
    for tag in 1..=8u8 {
        let shown = Orientation::from_exif(tag).unwrap();
        // The sensor's pixels: the displayed photo turned back. Turns by a quarter are
        // undone by the opposite quarter; flips and the two transposes undo themselves.
        let undo = match shown {
            Orientation::Rotate90 => Orientation::Rotate270,
            Orientation::Rotate270 => Orientation::Rotate90,
            other => other,
        };
        let mut stored = upright.clone();
        stored.apply_orientation(undo);
        let bytes = with_exif_orientation(&jpeg(&stored.into_rgb8()), tag.into());
        assert_eq!(
            ariadne_dlo::decode::dimensions(&bytes).unwrap(),
            (640, 480),
            "orientation {tag}"
        );
        let out = run(&bytes, &truth.ends());
        let seg = &out.segmentation;
        assert_eq!((seg.width, seg.height), (640, 480), "orientation {tag}");
        assert_found(&out, &truth, 6.0);
        assert!(mask_iou(&out, &truth.mask) > 0.6, "orientation {tag}");
    }
}

#[test]
fn a_portrait_phone_photo_is_segmented_upright_at_the_working_size() {
    // 1080x1920: cables about 3x as wide as at 640x480.
    let truth = scene(&spec(1080, 1920, 26.0, 1));
    let out = run(&jpeg(&truth.image), &truth.ends());
    let seg = &out.segmentation;
    assert_eq!((seg.width, seg.height), (1080, 1920));
    assert!(
        (seg.working_scale - 0.385).abs() < 0.01,
        "{}",
        seg.working_scale
    );
    assert_found(&out, &truth, 15.0);
    for cable in &seg.cables {
        assert!(
            (18.0..36.0).contains(&cable.width_px),
            "width {} in photo pixels",
            cable.width_px
        );
    }
    assert!(mask_iou(&out, &truth.mask) > 0.6);
}

#[test]
fn a_12_mp_photo_is_segmented_in_its_own_pixels() {
    let truth = scene(&spec(4000, 3000, 56.0, 1));
    let out = run(&jpeg(&truth.image), &truth.ends());
    assert_eq!(mask(&out).dimensions(), (4000, 3000));
    assert!((out.segmentation.working_scale - 0.16).abs() < 1e-6);
    assert_found(&out, &truth, 40.0);
    assert!(mask_iou(&out, &truth.mask) > 0.6);
    // Segmented at 640x480, the centreline is still placed to a small part of the
    // cable's width in the photo's own pixels (measured: 3.5 px mean for 56 px cables).
    let error = centreline_error(&out, &truth);
    assert!(error < 0.1 * 56.0, "mean centreline error {error:.2} px");
}

/// Mean distance, pixels, from the found centrelines' points to the nearest point of a
/// true centreline.
fn centreline_error(out: &Output, truth: &Scene) -> f32 {
    let true_points: Vec<[f32; 2]> = truth
        .cables
        .iter()
        .flat_map(|c| c.centreline.iter().copied())
        .collect();
    let distances = common::distances_to_truth(out, &true_points);
    distances.iter().sum::<f32>() / distances.len().max(1) as f32
}

#[test]
fn a_small_photo_is_enlarged_and_mapped_back() {
    let truth = scene(&spec(320, 240, 4.5, 2));
    let out = run(&jpeg(&truth.image), &truth.ends());
    assert_eq!(out.segmentation.working_scale, 2.0);
    assert_eq!(mask(&out).dimensions(), (320, 240));
    assert_found(&out, &truth, 4.0);
}

#[test]
fn far_cables_half_as_wide_as_near_ones_are_all_found() {
    // A table seen at an angle: the far (top) cable 6 px wide, the near (bottom) one
    // 12 px, and one running from far to near whose width grows along it.
    let (w, h) = (640u32, 480u32);
    let mut image = RgbImage::from_pixel(w, h, Rgb([226, 222, 214]));
    let mut mask = GrayImage::new(w, h);
    let arc = |y0: f32, y1: f32, bend: f32| -> Vec<[f32; 2]> {
        (0..=400)
            .map(|i| {
                let t = i as f32 / 400.0;
                [
                    80.0 + 480.0 * t,
                    y0 + (y1 - y0) * t + bend * 4.0 * t * (1.0 - t),
                ]
            })
            .collect()
    };
    let diagonal: Vec<[f32; 2]> = (0..=400)
        .map(|i| {
            let t = i as f32 / 400.0;
            [200.0 + 60.0 * (t * 3.0).sin(), 60.0 + 360.0 * t]
        })
        .collect();
    // Centreline, colour, width at its start and at its end.
    let cables = [
        (arc(90.0, 70.0, 20.0), [190, 35, 30], 6.0, 6.0),
        (arc(400.0, 380.0, -30.0), [30, 60, 180], 12.0, 12.0),
        (diagonal, [35, 140, 50], 6.0, 12.0),
    ];
    let mut truth_cables = Vec::new();
    for (line, colour, start, end) in &cables {
        for (k, piece) in line.windows(2).enumerate() {
            let t = k as f32 / line.len() as f32;
            render::stroke(piece, start + (end - start) * t, w, h, |x, y| {
                image.put_pixel(x, y, Rgb(*colour));
                mask.put_pixel(x, y, Luma([255]));
            });
        }
        truth_cables.push(ariadne_dlo::synth::SynthCable {
            centreline: line.clone(),
            color: *colour,
        });
    }
    let truth = Scene {
        image,
        cables: truth_cables,
        mask,
    };
    let out = run(&jpeg(&truth.image), &truth.ends());
    assert_found(&out, &truth, 6.0);
    assert!(mask_iou(&out, &truth.mask) > 0.6);
}

/// One scene of [`spec`] at 640x480 run with the true ends twice: with the default
/// parameters and with `other`.
struct Compared {
    /// The output with the default parameters, and its mask IoU.
    out: Output,
    iou: f64,
    /// The output with `other`, and its mask IoU.
    other: Output,
    other_iou: f64,
}

/// [`Compared`] for the scene of `cable_width` px cables drawn from `seed`.
fn compare(cable_width: f32, seed: u64, other: &Params) -> Compared {
    let truth = scene(&spec(640, 480, cable_width, seed));
    let bytes = jpeg(&truth.image);
    let out = run(&bytes, &truth.ends());
    let other = run_with(&bytes, &truth.ends(), other);
    Compared {
        iou: mask_iou(&out, &truth.mask),
        other_iou: mask_iou(&other, &truth.mask),
        out,
        other,
    }
}

/// Scenes of two `cable_width` px cables at 640x480, seeds 1-4: each one's seed,
/// working scale and mask IoU with the width correction and without it (no second
/// pass, masks as wide as `mask_width_px`).
fn with_and_without_correction(cable_width: f32) -> Vec<(u64, f32, f64, f64)> {
    let no_correction = Params {
        width_tolerance: 100.0,
        mask_width_tolerance: 100.0,
        ..Params::default()
    };
    let mut rows = Vec::new();
    for seed in 1..=4 {
        let Compared {
            out,
            iou: corrected,
            other: fixed,
            other_iou: uncorrected,
        } = compare(cable_width, seed, &no_correction);
        assert_eq!(fixed.segmentation.working_scale, 1.0);
        eprintln!(
            "width {cable_width}, seed {seed}: mask IoU {corrected:.3} corrected, \
             {uncorrected:.3} at the default scale"
        );
        rows.push((seed, out.segmentation.working_scale, corrected, uncorrected));
    }
    rows
}

#[test]
fn a_closer_camera_is_segmented_at_the_scale_its_cables_ask_for() {
    // Cables 24 px wide at 640x480: a camera about 2.5 times closer than the one the
    // engine's lengths suit. The first pass measures them and the photo is segmented
    // again smaller; without the correction the masks are far too thin. Pooled over
    // the four scenes: in seed 3's the blue cable crosses the red one at a shallow
    // angle next to its end, and at the working scale (0.32) its spline is fitted as a
    // chord across its S-bend, mask IoU 0.28 corrected against 0.28 at the default
    // scale (0.29 against 0.19 before session 67, whose walks also pass an end met
    // across its own cable: its default-scale walks improved, the chord did not).
    let rows = with_and_without_correction(24.0);
    for &(seed, scale, _, _) in &rows {
        assert!(
            (0.3..0.75).contains(&scale),
            "seed {seed}: working scale {scale}"
        );
    }
    let corrected: f64 = rows.iter().map(|r| r.2).sum();
    let uncorrected: f64 = rows.iter().map(|r| r.3).sum();
    assert!(corrected > 1.5 * uncorrected, "{rows:?}");
}

#[test]
fn cables_a_little_wider_than_nominal_get_wider_masks_without_a_second_pass() {
    // Cables 10.5 px wide at 640x480 (a camera a little closer than the development
    // photos'): within the width tolerance, so segmented once, but drawn as wide as
    // they read rather than `mask_width_px`.
    let fixed_masks = Params {
        mask_width_tolerance: 100.0,
        ..Params::default()
    };
    for seed in 1..=4 {
        let Compared {
            out,
            iou: wider,
            other: fixed,
            other_iou: narrow,
        } = compare(10.5, seed, &fixed_masks);
        let seg = &out.segmentation;
        eprintln!(
            "seed {seed}: working scale {}, mask scale {}, mask IoU {wider:.3} against {narrow:.3}",
            seg.working_scale, seg.mask_scale
        );
        assert_eq!(seg.working_scale, 1.0, "seed {seed}");
        assert!(seg.mask_scale > 1.3, "seed {seed}: {}", seg.mask_scale);
        assert_eq!(fixed.segmentation.mask_scale, 1.0);
        assert!(wider > narrow + 0.05, "seed {seed}");
    }
}

#[test]
fn a_farther_camera_is_segmented_at_the_scale_its_thin_cables_ask_for() {
    // Cables 3 px wide at 640x480 (thin rods, or a camera far from the table): the
    // first pass measures them and the photo is segmented again enlarged, at most twice.
    for (seed, scale, corrected, uncorrected) in with_and_without_correction(3.0) {
        assert_eq!(scale, 2.0, "seed {seed}");
        assert!(corrected > 0.6, "seed {seed}: {corrected:.3}");
        assert!(corrected > 1.5 * uncorrected, "seed {seed}");
    }
}

#[test]
fn after_a_second_pass_masks_follow_the_width_and_only_widen() {
    // Cables 32 px wide at 640x480 (a camera about four times closer) are segmented
    // again smaller, where they still read wider than nominal (the reading is
    // sub-linear), so their masks are drawn as much wider than `mask_width_px`,
    // whatever `mask_width_tolerance` says; thin rods enlarged for a second pass are
    // never drawn narrower.
    let params = Params::default();
    let no_tolerance = Params {
        mask_width_tolerance: 100.0,
        ..Params::default()
    };
    for (width, seed) in (1..=4).flat_map(|seed| [(32.0, seed), (3.0, seed)]) {
        let truth = scene(&spec(640, 480, width, seed));
        let bytes = jpeg(&truth.image);
        let out = run(&bytes, &truth.ends());
        let seg = &out.segmentation;
        let tolerant = run_with(&bytes, &truth.ends(), &no_tolerance);
        assert_eq!(
            tolerant.segmentation.mask_scale, seg.mask_scale,
            "seed {seed}"
        );
        let scaled = mask_iou(&out, &truth.mask);
        let plain_seg = Segmentation {
            mask_scale: 1.0,
            ..seg.clone()
        };
        let plain_width = plain_seg.mask_width(params.mask_width_px);
        let Mask::Gray(plain_mask) = render::render_mask(&plain_seg, MaskKind::Binary, plain_width)
        else {
            unreachable!("binary masks are single-channel")
        };
        let plain = eval::iou(&plain_mask, &truth.mask);
        eprintln!(
            "width {width}, seed {seed}: working scale {}, mask scale {}, mask IoU {scaled:.3} \
             against {plain:.3} with masks as wide as mask_width_px",
            seg.working_scale, seg.mask_scale
        );
        if width > 8.0 {
            assert!(seg.working_scale < 1.0, "seed {seed}");
            assert!(seg.mask_scale > 1.0, "seed {seed}: {}", seg.mask_scale);
            assert!(scaled > plain, "seed {seed}");
        } else {
            assert!(seg.working_scale > 1.0, "seed {seed}");
            assert_eq!(seg.mask_scale, 1.0, "seed {seed}");
        }
    }
}
