//! `ariadne segment` and `ariadne eval`.

use crate::detect::{DetectorConfig, OnnxDetector};
use crate::eval::{self, EndsFrom, ImageResult};
use crate::pipeline;
use crate::report::{self, SegmentResponse};

use super::args::{EndsArg, EvalArgs, SegmentArgs};
use super::{CliError, params_from, write};

/// Segments one photo and writes what was asked for.
pub fn segment(args: SegmentArgs) -> Result<(), CliError> {
    let params = params_from(&args.preset, args.options.as_deref())?;
    let given = match &args.endpoints {
        Some(text) => Some(report::parse_endpoints(text).map_err(CliError::BadEndpoints)?),
        None => None,
    };
    let bytes = std::fs::read(&args.image).map_err(|e| CliError::Io(args.image.clone(), e))?;
    // The network runs even with given ends: its cable field guides the walks.
    let network = OnnxDetector::load(&DetectorConfig::from(args.detector), 1)?;
    let out = pipeline::run(&pipeline::Job {
        bytes: &bytes,
        ends: given.as_deref(),
        network: Some(&network),
        params: &params,
        max_pixels: u64::MAX,
        mask: args.mask_kind.into(),
        overlay: args.overlay.is_some(),
        encode: true,
        deadline: crate::engine::Deadline::NONE,
        overlap: true,
    })
    .map_err(|e| CliError::Image(args.image.clone(), e))?;
    if let (Some(path), Some(png)) = (&args.mask, &out.mask_png) {
        write(path, png)?;
    }
    if let (Some(path), Some(png)) = (&args.overlay, &out.overlay_png) {
        write(path, png)?;
    }
    if let Some(path) = &args.json {
        let mut response = SegmentResponse::new(&out, format!("cli-{}", uuid::Uuid::new_v4()));
        // What went to a file is not embedded a second time.
        if args.mask.is_some() {
            response.mask_png.clear();
        }
        if args.overlay.is_some() {
            response.overlay_png = None;
        }
        let mut text = serde_json::to_vec_pretty(&response)
            .map_err(|e| CliError::BadOptions(e.to_string()))?;
        text.push(b'\n');
        write(path, &text)?;
    }
    eprintln!(
        "{} cable(s) from {} end(s) in {:.1} ms",
        out.segmentation.cables.len(),
        out.ends.points.len(),
        out.timings.total
    );
    Ok(())
}

/// Scores the engine on a dataset folder and prints per-image lines and set tables.
pub fn evaluate(args: EvalArgs) -> Result<(), CliError> {
    let dir = args
        .dataset
        .clone()
        .unwrap_or_else(eval::default_dataset_dir);
    let samples = eval::load_dataset(&dir)?;
    let simple = params_from(&args.preset, args.options.as_deref())?;
    let hard = params_from(&args.hard_preset, args.options.as_deref())?;
    // The network runs with true ends too: its cable field guides the walks.
    let network = OnnxDetector::load(&DetectorConfig::from(args.detector.clone()), 1)?;
    let ends = match args.endpoints {
        EndsArg::Gt => EndsFrom::Truth,
        EndsArg::Detect => EndsFrom::Network,
    };
    let print = |r: &ImageResult| {
        if !args.json {
            let t = &r.timings_ms;
            println!(
                "{:<7} {} x{}  IoU {:.3}  cables {}/{} found {}  ends {} ({}/{} terminals)  ms: ends {:.1} sp {:.1} graph {:.1} walks {:.1} splines {:.1} mask {:.1} total {:.1}",
                r.set,
                r.name,
                r.scale,
                r.iou,
                r.matched_cables,
                r.gt_cables,
                r.found_cables,
                r.ends,
                r.terminals_matched,
                r.terminals,
                t.endpoints,
                t.superpixels,
                t.graph,
                t.walks,
                t.splines,
                t.mask,
                t.total
            );
        }
    };
    check(
        (1.0..=8.0).contains(&args.zoom),
        "--zoom",
        args.zoom,
        "a factor in [1, 8]",
    )?;
    check(
        args.exposure > 0.0 && args.exposure <= 1.0,
        "--exposure",
        args.exposure,
        "a factor in (0, 1]",
    )?;
    check(
        (0.0..=10.0).contains(&args.blur),
        "--blur",
        args.blur,
        "a σ in [0, 10] pixels",
    )?;
    check(
        (0.0..=50.0).contains(&args.noise),
        "--noise",
        args.noise,
        "a σ in [0, 50] levels",
    )?;
    let mut images = Vec::new();
    let mut scales = Vec::new();
    for &scale in &args.scale {
        check(
            scale > 0.0 && scale <= 8.0,
            "--scale",
            scale,
            "factors in (0, 8]",
        )?;
        let setup = eval::Setup {
            network: Some(&network),
            ends,
            camera: eval::Camera {
                scale,
                zoom: args.zoom,
                exposure: args.exposure,
                blur: args.blur,
                noise: args.noise,
            },
            save_views: args.save_views.as_deref(),
        };
        let results = eval::evaluate_all(&samples, &simple, &hard, setup, print)?;
        scales.push((scale, eval::summarise(&results)));
        images.extend(results);
    }
    if args.json {
        let scales: Vec<_> = scales
            .iter()
            .map(|(scale, sets)| serde_json::json!({ "scale": scale, "sets": sets }))
            .collect();
        let doc = serde_json::json!({ "dataset": dir, "images": images, "scales": scales });
        println!("{}", serde_json::to_string_pretty(&doc).unwrap_or_default());
    } else {
        println!();
        println!(
            "scale  set      images  weighted IoU  cable recall  cable precision  matched IoU  end recall  end precision  median ms"
        );
        for (scale, summaries) in &scales {
            for s in summaries {
                println!(
                    "{:<5}  {:<8} {:>6}  {:>12.3}  {:>12.3}  {:>15.3}  {:>11.3}  {:>10.3}  {:>13.3}  {:>9.1}",
                    scale,
                    s.set,
                    s.images,
                    s.weighted_iou,
                    s.cable_recall,
                    s.cable_precision,
                    s.matched_iou,
                    s.terminal_recall,
                    s.terminal_precision,
                    s.median_total_ms
                );
            }
        }
    }
    Ok(())
}

/// `Ok` when `ok`; else the error naming `flag`, its `value` and what it `expects`.
fn check(ok: bool, flag: &str, value: f64, expects: &str) -> Result<(), CliError> {
    if ok {
        Ok(())
    } else {
        Err(CliError::OutOfRange(format!(
            "{flag} {value}: expected {expects}"
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_argument_out_of_range_is_named_with_what_it_expects() {
        assert!(check(true, "--noise", 12.0, "a σ in [0, 50] levels").is_ok());
        let err = check(false, "--noise", 60.0, "a σ in [0, 50] levels").unwrap_err();
        assert_eq!(
            err.to_string(),
            "--noise 60: expected a σ in [0, 50] levels"
        );
    }
}
