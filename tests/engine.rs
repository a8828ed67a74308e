//! End-to-end tests of the engine: synthetic scenes with known truth, and the
//! development split of the real dataset with its accuracy floors.

#![allow(clippy::unwrap_used)] // test and benchmark code: a failure should panic

mod common;

use ariadne_dlo::engine::{self, MaskKind, Params, render};
use ariadne_dlo::eval;
use ariadne_dlo::synth::{Background, SceneSpec, scene, turning};
use common::centreline_error;

fn mask_of(seg: &engine::Segmentation, width_px: f32) -> image::GrayImage {
    match render::render_mask(seg, MaskKind::Binary, width_px) {
        engine::Mask::Gray(m) => m,
        engine::Mask::Rgb(_) => unreachable!(),
    }
}

#[test]
fn synthetic_scenes_are_recovered() {
    let (mut ious, mut recovered, mut total) = (Vec::new(), 0, 0);
    for (seed, background) in [
        (1, Background::Plain),
        (2, Background::Plain),
        (3, Background::Textured),
        (4, Background::Textured),
    ] {
        let spec = SceneSpec {
            width: 320,
            height: 240,
            cables: 2,
            cable_width: 9.0,
            background,
            seed,
        };
        let s = scene(&spec);
        let params = Params {
            n_segments: 500,
            ..Params::default()
        };
        let seg = engine::segment(&s.image, &s.ends(), &params).unwrap();
        assert_eq!(seg.width, 320);
        // Masks drawn with the measured width against the true cable bodies.
        let found = mask_of(&seg, 0.0);
        assert_eq!(found.dimensions(), (320, 240));
        let iou = eval::iou(&found, &s.mask);
        ious.push(iou);
        // A true cable is recovered when a found centreline runs within 3.5 px of it on average.
        for cable in &s.cables {
            let best = seg
                .cables
                .iter()
                .map(|c| centreline_error(&cable.centreline, &c.polyline))
                .fold(f32::MAX, f32::min);
            eprintln!("seed {seed}: mean centreline distance {best:.2} px");
            total += 1;
            recovered += usize::from(best < 3.5);
        }
        for c in &seg.cables {
            assert!(
                (6.0..13.0).contains(&c.width_px),
                "seed {seed}: width {}",
                c.width_px
            );
        }
    }
    let mean = ious.iter().sum::<f64>() / ious.len() as f64;
    eprintln!("synthetic: {recovered}/{total} cables recovered, mean IoU {mean:.3} ({ious:?})");
    assert!(
        recovered * 4 >= total * 3,
        "only {recovered}/{total} cables recovered"
    );
    assert!(
        mean > 0.55,
        "mean IoU on synthetic scenes {mean:.3} ({ious:?})"
    );
}

/// A cable crossing the whole frame has no end in view: it is found from the border,
/// and only when border cables are enabled.
#[test]
fn a_cable_crossing_the_frame_is_found_without_ends() {
    let (w, h) = (320u32, 240u32);
    let image = image::RgbImage::from_fn(w, h, |x, y| {
        let centre = 120.0 + 40.0 * (x as f32 / 60.0).sin();
        if (y as f32 - centre).abs() <= 4.0 {
            image::Rgb([200, 30, 30])
        } else {
            image::Rgb([235, 235, 225])
        }
    });
    let p = Params::default();
    let seg = engine::segment(&image, &[], &p).unwrap();
    assert_eq!(seg.cables.len(), 1, "one cable");
    let line = &seg.cables[0].polyline;
    let xs: Vec<f32> = line.iter().map(|q| q[0]).collect();
    let (lo, hi) = xs
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(lo < 15.0 && hi > w as f32 - 16.0, "spans {lo}..{hi}");
    for q in line.iter().filter(|q| q[0] > 8.0 && q[0] < w as f32 - 8.0) {
        let centre = 120.0 + 40.0 * (q[0] / 60.0).sin();
        assert!((q[1] - centre).abs() < 3.0, "{q:?} is off the cable");
    }
    let off = Params {
        border_cables: false,
        ..p
    };
    assert!(
        engine::segment(&image, &[], &off)
            .unwrap()
            .cables
            .is_empty()
    );
}

#[test]
fn bad_parameters_and_ends_are_errors_not_panics() {
    let s = scene(&SceneSpec {
        width: 64,
        height: 48,
        cables: 1,
        cable_width: 6.0,
        background: Background::Plain,
        seed: 5,
    });
    let p = Params::default();
    assert!(matches!(
        engine::segment(&s.image, &[[64.0, 10.0]], &p),
        Err(engine::EngineError::EndpointOutside { index: 0, .. })
    ));
    assert!(matches!(
        engine::segment(&s.image, &[[f64::NAN, 10.0]], &p),
        Err(engine::EngineError::EndpointNotFinite { index: 0 })
    ));
    let bad = Params {
        compactness: 0.0,
        ..Params::default()
    };
    assert!(matches!(
        engine::segment(&s.image, &[], &bad),
        Err(engine::EngineError::InvalidParameter {
            name: "compactness",
            ..
        })
    ));
    let tiny = image::RgbImage::new(8, 8);
    assert!(matches!(
        engine::segment(&tiny, &[], &p),
        Err(engine::EngineError::ImageTooSmall { .. })
    ));
    // Superpixels of another image.
    let other = image::RgbImage::new(32, 48);
    let over = engine::oversegment(&other, &p, engine::Deadline::NONE).unwrap();
    assert!(matches!(
        engine::segment_oversegmented(&s.image, over, &[], &[], None, &p, engine::Deadline::NONE),
        Err(engine::EngineError::OtherImage {
            superpixels: [32, 48],
            image: [64, 48]
        })
    ));
    // No ends: a valid, empty answer.
    let seg = engine::segment(&s.image, &[], &p).unwrap();
    assert!(seg.cables.is_empty());
}

/// Weighted IoU on the development split with the true ends: the acceptance
/// floors (measured values in the README, Accuracy).
#[test]
fn development_split_accuracy_floors() {
    common::assert_split_iou(
        "true ends, no network",
        None,
        eval::EndsFrom::Truth,
        eval::Camera::default(),
        (0.70, 0.60),
    );
}

/// The `paper` preset (the method as published, no field) with the true ends: a floor
/// under its measured 0.266 / 0.432 (README, Accuracy), which once fell unnoticed to
/// 0.126 / 0.152 when a second pass at another scale reached it.
#[test]
fn the_paper_preset_keeps_its_accuracy() {
    common::assert_split_iou_with(
        "paper preset, true ends",
        ["paper", "paper"],
        None,
        eval::EndsFrom::Truth,
        eval::Camera::default(),
        (0.24, 0.38),
    );
}

/// The cable field a perfect network would give for scene `s`: cable probability =
/// mask coverage of each 8 px cell (doubled, capped at 1); direction = the mean
/// (cos 2θ, sin 2θ) of the true centrelines' segments in the cell and its eight
/// neighbours, on cells the mask covers (where two cables cross, their directions
/// average to a shorter vector, as the network's do).
fn exact_field(s: &ariadne_dlo::synth::Scene) -> engine::CableField {
    const CELL: usize = 8;
    let mask = &s.mask;
    let (w, h) = (mask.width() as usize / CELL, mask.height() as usize / CELL);
    let cable: Vec<f32> = (0..w * h)
        .map(|i| {
            let (cx, cy) = ((i % w) * CELL, (i / w) * CELL);
            let on = (0..CELL * CELL)
                .filter(|k| {
                    let (x, y) = (cx + k % CELL, cy + k / CELL);
                    mask.get_pixel(x as u32, y as u32).0[0] > 0
                })
                .count();
            (2.0 * on as f32 / (CELL * CELL) as f32).min(1.0)
        })
        .collect();
    let mut sums = vec![[0.0f32; 3]; w * h];
    for c in &s.cables {
        for seg in c.centreline.windows(2) {
            let (dx, dy) = (seg[1][0] - seg[0][0], seg[1][1] - seg[0][1]);
            let theta = dy.atan2(dx);
            let mid = [(seg[0][0] + seg[1][0]) / 2.0, (seg[0][1] + seg[1][1]) / 2.0];
            let (gx, gy) = (
                mid[0] as isize / CELL as isize,
                mid[1] as isize / CELL as isize,
            );
            for (nx, ny) in (gx - 1..=gx + 1).flat_map(|x| (gy - 1..=gy + 1).map(move |y| (x, y))) {
                if (0..w as isize).contains(&nx) && (0..h as isize).contains(&ny) {
                    let sum = &mut sums[ny as usize * w + nx as usize];
                    sum[0] += (2.0 * theta).cos();
                    sum[1] += (2.0 * theta).sin();
                    sum[2] += 1.0;
                }
            }
        }
    }
    let orientation = sums
        .iter()
        .zip(&cable)
        .map(|(&[c, s, n], &p)| {
            if n > 0.0 && p > 0.0 {
                [c / n, s / n]
            } else {
                [0.0, 0.0]
            }
        })
        .collect();
    engine::CableField {
        width: w,
        height: h,
        cell_px: [CELL as f32; 2],
        cable,
        orientation,
    }
}

/// The engine trusts a field: with an exact one, every hard case is recovered from its
/// terminals (and the border, for the cable with no end in view), with nothing extra.
/// In `TerminalAgainstCable` the walks along the first cable pass within reach of the
/// second cable's terminal, across the field's direction there, and go on
/// (`field_close_min_alignment`; with it at 0 they close on it and a cable is lost).
/// In `TerminalBesideCable` they pass, heading nearly the field's way, the terminal of
/// a cable that ends 15 px beside theirs, and go on because their cable runs on past
/// it (without that, a cable 49 px off the truth is found).
/// In `Curl` the walk crosses the place where the cable crosses itself at a shallow
/// angle, leaving the loop out; the loop is taken in from the field (`loops`; with it
/// off this test fails on `Curl`). `CrossingLoop`, left out here until 2026-11-23, is
/// found whole with or without that rule. In `PaleNoEndInView` the pale cable is found
/// from the border, and walked partly a superpixel beside it: the pieces of field along
/// it then give it a second time, dropped as repeating it (without that, 3 cables).
#[test]
fn an_exact_field_recovers_the_hard_cases() {
    use ariadne_dlo::synth::Case;
    for case in Case::ALL {
        let s = ariadne_dlo::synth::case(case);
        let (found, err) = with_exact_field(&s, &s.terminals());
        assert_eq!(found, s.cables.len(), "{case:?}");
        assert!(err.iter().all(|&e| e < 3.0), "{case:?}: {err:?}");
    }
}

/// A cable that leaves the frame ends on its edge: the refinement cannot read past the
/// frame, and once carried the last points of such cables 10-16 px out of it (cables
/// that leave the frame at a slant, as most of the development photos' do).
#[test]
fn cables_leaving_the_frame_end_on_its_edge() {
    let samples = eval::load_dataset(&eval::default_dataset_dir()).expect("dataset");
    for sample in samples.iter().filter(|s| s.set == "simple").step_by(4) {
        let photo = image::open(&sample.image).unwrap().into_rgb8();
        let (w, h) = photo.dimensions();
        let ends = eval::terminal_ends(&sample.cables, w, h);
        let seg = engine::segment(&photo, &ends, &Params::default()).unwrap();
        for p in seg.cables.iter().flat_map(|c| &c.polyline) {
            let out = (-p[0])
                .max(-p[1])
                .max(p[0] - (w - 1) as f32)
                .max(p[1] - (h - 1) as f32);
            assert!(
                out <= 2.0,
                "{}: {p:?} lies {out} px out of the frame",
                sample.name
            );
        }
    }
}

/// Segments the synthetic scene `s` from `ends` (trusted fully) and its exact field:
/// the number of cables found, and each true cable's centreline error to the nearest.
fn with_exact_field(s: &ariadne_dlo::synth::Scene, ends: &[[f64; 2]]) -> (usize, Vec<f32>) {
    with_field(s, ends, &exact_field(s))
}

/// [`with_exact_field`] with the given `field`.
fn with_field(
    s: &ariadne_dlo::synth::Scene,
    ends: &[[f64; 2]],
    field: &engine::CableField,
) -> (usize, Vec<f32>) {
    with_field_and(s, ends, field, &Params::default())
}

/// Segments the synthetic scene `s` from `ends` (trusted fully) and `field`.
fn segment_trusting(
    s: &ariadne_dlo::synth::Scene,
    ends: &[[f64; 2]],
    field: &engine::CableField,
    params: &Params,
) -> engine::Segmentation {
    let confidences = vec![1.0; ends.len()];
    engine::segment_with_confidence(
        &s.image,
        ends,
        &confidences,
        Some(field),
        params,
        engine::Deadline::NONE,
    )
    .unwrap()
}

/// A loop goes to its own cable, round its own course. In `LoopCrossedByAnother` the
/// orange cable crosses the blue cable's loop, so the loop leaves the orange cable and
/// comes back to it as it does to the blue one. Each cable is found as long as it is
/// (within 10 %): the orange one without the loop, the blue one with it. With the
/// course searched breadth-first (fewest superpixels), the blue loop's course ran
/// along the orange cable across it, was refused as not of the blue cable's colour,
/// and the blue cable was found without its loop (0.62 of its length).
#[test]
fn a_loop_goes_to_its_own_cable_not_to_one_across_it() {
    use ariadne_dlo::engine::geometry::polyline_length;
    use ariadne_dlo::synth::Case;
    let s = ariadne_dlo::synth::case(Case::LoopCrossedByAnother);
    let seg = segment_trusting(&s, &s.terminals(), &exact_field(&s), &Params::default());
    assert_eq!(seg.cables.len(), 2);
    for truth in &s.cables {
        let found = seg
            .cables
            .iter()
            .min_by(|a, b| {
                let error = |c: &engine::Cable| centreline_error(&truth.centreline, &c.polyline);
                error(a).total_cmp(&error(b))
            })
            .unwrap();
        let ratio = found.length_px / polyline_length(&truth.centreline);
        assert!(
            (0.9..=1.1).contains(&ratio),
            "found {ratio:.2} of a cable's length"
        );
    }
}

/// A loop the field reads faintly is still taken in. In `Curl` the cable runs along
/// y = 330 into a loop of radius 45 about (290, 285); here the field reads at most 0.4
/// on the loop wherever it is more than a cable width from that straight run (as on a
/// thin or pale loop leaving its cable at a shallow angle: a stress scene's read 0.32
/// and 0.46 where it left). The loop's course, where it leaves and comes back
/// included, needs 0.6 of `field_orphan_level` (0.3). Until 2026-11-24 its two ends
/// needed the whole level, and this cable was found without its loop (centreline
/// error 15.3 px, against 0.8 px now).
#[test]
fn a_loop_the_field_reads_faintly_is_taken_in() {
    let (found, err) = curl_with_loop_read_at_most(0.4);
    assert_eq!(found, 1);
    assert!(err[0] < 3.0, "centreline error {:.1} px", err[0]);
}

/// A loop the field reads fainter still (at most 0.25, under 0.6 of
/// `field_orphan_level`: a white loop on orange card read 0.2-0.3) is found by the
/// second, fainter search, its course being of its cable's colour. Without that search
/// (before 2026-11-27) this cable was found without its loop.
#[test]
fn a_pale_loop_is_taken_in_by_its_colour() {
    let (found, err) = curl_with_loop_read_at_most(0.25);
    assert_eq!(found, 1);
    assert!(err[0] < 3.0, "centreline error {:.1} px", err[0]);
}

/// `Curl` segmented from its true ends and its exact field, with the field capped at
/// `cap` on the loop wherever it is more than a cable width from the straight run into
/// it: the number of cables found and the centreline error.
fn curl_with_loop_read_at_most(cap: f32) -> (usize, Vec<f32>) {
    use ariadne_dlo::synth::Case;
    let s = ariadne_dlo::synth::case(Case::Curl);
    let mut field = exact_field(&s);
    let (centre, radius) = ([290.0f32, 285.0], 45.0f32);
    for (i, p) in field.cable.iter_mut().enumerate() {
        let [cx, cy] = [
            (i % field.width) as f32 + 0.5,
            (i / field.width) as f32 + 0.5,
        ];
        let q = [cx * field.cell_px[0], cy * field.cell_px[1]];
        let on_ring = ((q[0] - centre[0]).hypot(q[1] - centre[1]) - radius).abs() < 12.0;
        if on_ring && (q[1] - 330.0).abs() > 10.0 {
            *p = p.min(cap);
        }
    }
    with_field(&s, &s.terminals(), &field)
}

/// [`with_field`] with the given `params`.
fn with_field_and(
    s: &ariadne_dlo::synth::Scene,
    ends: &[[f64; 2]],
    field: &engine::CableField,
    params: &Params,
) -> (usize, Vec<f32>) {
    let seg = segment_trusting(s, ends, field, params);
    let err = errors_against(s, &seg);
    eprintln!("{} cables, centreline errors {err:?}", seg.cables.len());
    (seg.cables.len(), err)
}

/// Each true cable of `s`'s centreline error to the nearest cable `seg` found.
fn errors_against(s: &ariadne_dlo::synth::Scene, seg: &engine::Segmentation) -> Vec<f32> {
    s.cables
        .iter()
        .map(|c| {
            seg.cables
                .iter()
                .map(|f| centreline_error(&c.centreline, &f.polyline))
                .fold(f32::MAX, f32::min)
        })
        .collect()
}

/// Cables whose ends the network missed are found from the field alone: with an exact
/// field and no ends at all, every cable of the hard cases is found whole, seeded at
/// the ends of the field's pieces no cable explains (and at the border). In
/// `NoEndInView` the cable whose arc touches the one crossing the frame is cut by it
/// into two pieces, found one from each, and chained back into one cable through the
/// touching point. Not `SideBySideThin`: there the field's two cables, 16 px apart,
/// make one piece (joined at their right-hand ends), whose two farthest superpixels are
/// the two left-hand ends; the walk from each follows its cable to the right and stops
/// there, at no seed and not at the border, so nothing is found (docs/ENGINE.md). With
/// their ends in view both are found (the tests above). In `Crossing` the two cables make
/// one X-shaped piece; its two farthest superpixels are the ends of one branch each, and
/// the other two ends are seeded as the tips of its other branches. Nor `CrossingLoop` (its
/// piece of field is one loop with two tails; not found whole from it). Nor `Mixed`: with
/// no end at all, three cables are found, one of them 94 px off its truth (a 16 px power
/// cable crossed by two 5 px wires makes one piece; the engine alone, at one scale, serves
/// neither width; from their ends, as above, all three are found, and from a photo alone
/// the pipeline's two passes find them, `tests/e2e.rs`). In `TerminalAgainstCable` (the
/// field joins the two cables into one T-shaped piece, and the second's end, touching the
/// first, is the tip of no branch), `LoopCrossedByAnother` and `TerminalBesideCable`, one
/// cable of each pair was found alone until a walk that loses the cable along a field as
/// sure of it as `field_border_sure_level` counted as a cable (its end a terminal the
/// network missed), not only one reaching the border or a seed (session 57).
#[test]
fn cables_whose_ends_were_missed_are_found_from_the_field() {
    use ariadne_dlo::synth::Case;
    let left_out = [Case::SideBySideThin, Case::CrossingLoop, Case::Mixed];
    for case in Case::ALL.into_iter().filter(|c| !left_out.contains(c)) {
        let s = ariadne_dlo::synth::case(case);
        let (found, err) = with_exact_field(&s, &[]);
        assert_eq!(found, s.cables.len(), "{case:?}");
        assert!(err.iter().all(|&e| e < 3.0), "{case:?}: {err:?}");
    }
}

/// A strip of table below the board's bottom edge, dark and half the frame long, that
/// the field calls cable in patches (as a network does: it is long, thin and unlike the
/// board), is not reported: it lies all along one side of the frame, where its profiles
/// cannot be read. The scene's cables still are.
#[test]
fn a_strip_along_the_frame_edge_is_not_a_cable() {
    let mut s = ariadne_dlo::synth::case(ariadne_dlo::synth::Case::SideBySide);
    let h = s.image.height();
    let strip = 160..480;
    for y in h - 12..h {
        for x in strip.clone() {
            s.image.put_pixel(x, y, image::Rgb([70, 60, 55]));
        }
    }
    // The field along the strip: fair one cell row up from the edge; on the edge's
    // row, under `field_level` but for two short runs at the strip's ends, which the
    // border reads as two crossings.
    let mut field = exact_field(&s);
    let (last, gw) = ((field.height - 1) * field.width, field.width);
    for cx in (strip.start / 8..strip.end / 8).map(|c| c as usize) {
        let run = cx < strip.start as usize / 8 + 3 || cx >= strip.end as usize / 8 - 3;
        field.cable[last + cx] = if run { 0.4 } else { 0.2 };
        field.cable[last - gw + cx] = 0.5;
    }
    let (found, err) = with_field(&s, &s.terminals(), &field);
    assert_eq!(found, s.cables.len());
    assert!(err.iter().all(|&e| e < 3.0), "{err:?}");
}

/// A board's edge whose two corners were taken for terminals is not a cable: the walk
/// between the two false ends follows the edge, which the refinement reads as a step
/// between the board and the table below it, not a ridge (`ended_min_ridge_share`;
/// with it at 0 the edge is reported). The scene's cables, from their true ends, are.
#[test]
fn a_board_edge_between_two_false_ends_is_not_a_cable() {
    let mut s = ariadne_dlo::synth::case(ariadne_dlo::synth::Case::SideBySide);
    let (w, h) = s.image.dimensions();
    // The board's edge face, 4 px of mid-grey, then the dark table.
    let edge = 440;
    for y in edge..h {
        let colour = if y < edge + 4 {
            [150, 145, 140]
        } else {
            [70, 60, 55]
        };
        for x in 0..w {
            s.image.put_pixel(x, y, image::Rgb(colour));
        }
    }
    // The field calls the edge's cells fair cable, as a network might.
    let mut field = exact_field(&s);
    let row = edge as usize / 8 * field.width;
    for cell in &mut field.cable[row + 6..row + field.width - 6] {
        *cell = 0.6;
    }
    let mut ends = s.terminals();
    ends.extend([
        [60.0, f64::from(edge) + 2.0],
        [580.0, f64::from(edge) + 2.0],
    ]);
    let found = |params: &Params| with_field_and(&s, &ends, &field, params).0;
    assert_eq!(found(&Params::default()), s.cables.len());
    let keep_edges = Params {
        ended_min_ridge_share: 0.0,
        ..Params::default()
    };
    assert_eq!(found(&keep_edges), s.cables.len() + 1);
}

/// Two cables of one colour laid together (`Twins`: a pixel apart) are one band to the
/// field and to the superpixels, and the network reports one end at each end of the
/// pair. The walk between those ends runs down the band's middle; the profiles across
/// it show two cables, so it is reported as two, each on its own centreline and about
/// as wide as drawn. With `twins` off it is one cable between the two.
#[test]
fn twins_laid_together_are_split_in_two() {
    use ariadne_dlo::synth::Case;
    let s = ariadne_dlo::synth::case(Case::Twins);
    let [a, b] = [&s.cables[0].centreline, &s.cables[1].centreline];
    let mid =
        |p: [f32; 2], q: [f32; 2]| [f64::from(p[0] + q[0]) / 2.0, f64::from(p[1] + q[1]) / 2.0];
    let ends = [mid(a[0], b[0]), mid(a[a.len() - 1], b[b.len() - 1])];
    let field = exact_field(&s);
    let run = |params: &Params| {
        engine::segment_with_confidence(
            &s.image,
            &ends,
            &[1.0, 1.0],
            Some(&field),
            params,
            engine::Deadline::NONE,
        )
        .unwrap()
    };
    let seg = run(&Params::default());
    assert_eq!(seg.cables.len(), 2);
    for truth in [a, b] {
        let err = seg
            .cables
            .iter()
            .map(|c| centreline_error(truth, &c.polyline))
            .fold(f32::MAX, f32::min);
        assert!(err < 2.0, "centreline error {err}");
    }
    for cable in &seg.cables {
        assert!(
            (7.0..=11.0).contains(&cable.width_px),
            "width {}",
            cable.width_px
        );
    }
    assert_eq!(seg.end_cables, vec![Some(0), Some(0)]);
    let one = run(&Params {
        twins: false,
        ..Params::default()
    });
    assert_eq!(one.cables.len(), 1);
}

/// A scene of `cables` (centreline in 1 px steps, colour), 11 px wide, drawn in order
/// on a plain light 640x480 background; their truth is the part of each centreline in
/// the frame.
fn drawn(cables: Vec<(Vec<[f32; 2]>, [u8; 3])>) -> ariadne_dlo::synth::Scene {
    let (w, h) = (640, 480);
    let mut image = image::RgbImage::from_pixel(w, h, image::Rgb([225, 220, 210]));
    let mut mask = image::GrayImage::new(w, h);
    let in_frame =
        |p: &[f32; 2]| (0.0..w as f32).contains(&p[0]) && (0.0..h as f32).contains(&p[1]);
    let cables = cables
        .into_iter()
        .map(|(line, color)| {
            render::stroke(&line, 11.0, w, h, |x, y| {
                image.put_pixel(x, y, image::Rgb(color));
                mask.put_pixel(x, y, image::Luma([255]));
            });
            let centreline = line.into_iter().filter(in_frame).collect();
            ariadne_dlo::synth::SynthCable { centreline, color }
        })
        .collect();
    ariadne_dlo::synth::Scene {
        image,
        cables,
        mask,
    }
}

/// A cable with no end in view, crossed 100 px from the frame's right edge by a cable
/// whose ends are in view, is found from edge to edge where the field fades in the
/// cells against the frame's edges (as a network's often does). No border seed lies on
/// it, and of the field's pieces of it either side of the crossing only the longer
/// gives a seed, by the crossing (its other end, at the edge, is left to the border
/// seeds). The walks from that seed out of the frame, one either way, make the cable:
/// the one the pairing takes, run on along the other (once run on only along a walk
/// that lost the cable: the cable was found on one side of the crossing alone,
/// centreline error 10 px).
#[test]
fn a_cable_crossed_with_no_border_seed_is_run_on_to_the_edges() {
    let across = (0..=660)
        .map(|i| [i as f32 - 10.0, 240.0 + i as f32 / 33.0])
        .collect();
    let upright = (0..=280).map(|i| [540.0, 100.0 + i as f32]).collect();
    let s = drawn(vec![(across, [30, 60, 190]), (upright, [200, 30, 30])]);
    let mut field = exact_field(&s);
    for row in field.cable.chunks_mut(field.width) {
        let last = row.len() - 1;
        row[0] = row[0].min(0.2);
        row[last] = row[last].min(0.2);
    }
    let (found, err) = with_field(&s, &s.terminals(), &field);
    assert_eq!(found, 2);
    assert!(err.iter().all(|&e| e < 3.0), "{err:?}");
}

/// A cable that leaves the frame at a grazing angle (10° to the left edge: the cable
/// cut lengthwise by the edge for some 60 px, too long a run for a border crossing) is
/// found from where it crosses the bottom edge: the walk along it stops in slivers of
/// superpixels against the edge, heading along it, and has left the frame there (it
/// was once taken as lost, and the cable dropped).
#[test]
fn a_cable_leaving_the_frame_at_a_grazing_angle_is_found() {
    // Up from below the bottom edge, bending left and back to 10° off the vertical
    // (at (15, 180)), then straight on out of the left edge (at y ≈ 93).
    let (up, slant) = (-std::f32::consts::FRAC_PI_2, 0.17);
    let mut line = turning([299.0, 560.0], up, -1.2, 250);
    line.extend(turning(*line.last().unwrap(), up - 1.2, 1.2 - slant, 250).split_off(1));
    line.extend(turning(*line.last().unwrap(), up - slant, 0.0, 150).split_off(1));
    let s = drawn(vec![(line, [30, 60, 190])]);
    let (found, err) = with_exact_field(&s, &[]);
    assert_eq!(found, 1);
    assert!(err[0] < 3.0, "centreline error {:.1} px", err[0]);
}

/// A walk arrives at an end along that end's own cable. A red cable ends with its tip
/// against the side of a dark one, leaving it at 60° to it; segmented from the true
/// ends with no field (no direction to check against), the walks along the dark cable
/// pass within reach of the red terminal, across the way that terminal's own walk
/// opens, and go on to the dark cable's other end (`close_own_min_alignment`; with it
/// at 0 they close on the red terminal and the dark cable is lost, its centreline 90
/// px from the nearest found). The crowded stress scenes (`scripts/stress.py`,
/// `crowded`) have many ends so placed.
#[test]
fn a_walk_passes_an_end_it_meets_across_that_end_s_cable() {
    let upright = (0..=360).map(|i| [300.0, 60.0 + i as f32]).collect();
    let slant = (0..=240)
        .map(|i| [311.0 + 0.866 * i as f32, 200.0 + 0.5 * i as f32])
        .collect();
    let s = drawn(vec![(upright, [40, 40, 40]), (slant, [200, 30, 30])]);
    let found = |own: f32| {
        let params = Params {
            close_own_min_alignment: own,
            ..Params::default()
        };
        let seg = engine::segment(&s.image, &s.terminals(), &params).unwrap();
        (seg.cables.len(), errors_against(&s, &seg))
    };
    let (count, errors) = found(Params::default().close_own_min_alignment);
    assert_eq!(count, 2);
    assert!(errors.iter().all(|&e| e < 3.0), "{errors:?}");
    let (_, errors) = found(0.0);
    assert!(errors[0] > 20.0, "{errors:?}");
}
