//! One segmentation request from bytes to masks, the same for the service, the command
//! line, the evaluator and the benchmarks: decode (upright, EXIF orientation applied) →
//! resample to the working size, a dim photo brightened and a soft one sharpened →
//! network (ends and cable field) beside the engine's superpixels → the rest of the
//! engine → cables back in the photo's pixels → masks at the photo's size → PNG, timed
//! stage by stage in one [`Timings`].
//!
//! The network runs whenever there is one, also when the caller gives the ends: then
//! its ends are ignored but its cable field still guides the walks. It needs no
//! superpixels and SLIC needs no network, so with [`Job::overlap`] it runs on a second
//! (scoped) thread while SLIC runs on the caller's: a request uses at most two
//! threads, and a lone request on an idle machine is answered sooner (docs/PERFORMANCE.md).
//! The results are the same either way.

use std::time::Instant;

use image::{ExtendedColorType, ImageEncoder, RgbImage, codecs::png};
use thiserror::Error;

use crate::decode::{self, DecodeError};
use crate::detect::{DetectError, EndpointDetector, Ends};
use crate::engine::{
    self, Deadline, EngineError, MAX_CORRECTION, MIN_CORRECTION, Mask, MaskKind, Params,
    Segmentation, WorkingFrame, exposure, render, sharpness,
};
use crate::timings::{Timings, ms_since as ms};

/// What to do with one photo.
#[derive(Clone, Copy)]
pub struct Job<'a> {
    /// The JPEG or PNG file.
    pub bytes: &'a [u8],
    /// The caller's cable ends (confidence 1); `None` takes the network's.
    pub ends: Option<&'a [[f64; 2]]>,
    /// The network: cable ends and, for a cable-field model, the field.
    pub network: Option<&'a dyn EndpointDetector>,
    /// Engine parameters.
    pub params: &'a Params,
    /// Largest accepted pixel count, checked from the header before decoding.
    pub max_pixels: u64,
    /// Which mask to draw.
    pub mask: MaskKind,
    /// Also draw the photo with the cables on it.
    pub overlay: bool,
    /// Encode the mask (and overlay) as PNG; the evaluator reads the mask directly.
    pub encode: bool,
    /// When to give up (the engine checks it between its steps).
    pub deadline: Deadline,
    /// Run the network on a second thread while SLIC runs on this one (module docs);
    /// the service asks for it only when a CPU would otherwise idle.
    pub overlap: bool,
}

/// A job without ends needs a network.
const NO_ENDS: &str = "no cable ends were given and no network is loaded to find them";

/// What one photo gave.
#[derive(Debug, Clone)]
pub struct Output {
    /// The cables.
    pub segmentation: Segmentation,
    /// The ends used, with their confidences.
    pub ends: Ends,
    /// Whether the network ran.
    pub network_ran: bool,
    /// The mask of the asked kind.
    pub mask: Mask,
    /// The mask as PNG, when encoding was asked for.
    pub mask_png: Option<Vec<u8>>,
    /// The overlay as PNG, when asked for and encoding was asked for.
    pub overlay_png: Option<Vec<u8>>,
    /// Every stage; `total` is the pipeline's own time, `queue` is 0.
    pub timings: Timings,
}

/// Why a photo could not be segmented.
#[derive(Debug, Error)]
pub enum PipelineError {
    /// The bytes are not a usable image.
    #[error(transparent)]
    Decode(#[from] DecodeError),
    /// The detector failed.
    #[error("endpoint detector: {0}")]
    Detect(#[from] DetectError),
    /// The engine refused the input.
    #[error(transparent)]
    Engine(#[from] EngineError),
    /// PNG encoding failed.
    #[error("PNG encoding failed: {0}")]
    Encode(String),
    /// Neither ends nor a network to find them.
    #[error("{0}")]
    NoEnds(&'static str),
}

/// Runs `job` (see the module docs).
pub fn run(job: &Job<'_>) -> Result<Output, PipelineError> {
    let started = Instant::now();
    let t = Instant::now();
    let photo = decode::decode_rgb(job.bytes, job.max_pixels)?;
    let (width, height) = photo.dimensions();
    if let Some(points) = job.ends {
        engine::validate_ends(points, width, height)?;
    }
    let decode_ms = ms(t);
    let frame = WorkingFrame::choose(width, height, job.params);
    let [working_width, working_height] = frame.working;
    if working_width.min(working_height) < engine::MIN_SIDE {
        return Err(EngineError::PhotoTooSmall {
            width,
            height,
            working_width,
            working_height,
            max_upscale: job.params.max_upscale,
            min: engine::MIN_SIDE,
        }
        .into());
    }
    let (mut frame, mut k) = (frame, 1.0);
    let mut pass = Pass::run(job, &photo, frame, true)?;
    // The photo once more with the working scale times `k`, the passes' times added up.
    let again = |earlier: &Pass, k: f64, probe: bool| {
        let frame = WorkingFrame::corrected(width, height, job.params, k);
        let mut pass = Pass::run(job, &photo, frame, probe)?;
        pass.timings.add(&earlier.timings);
        Ok::<_, PipelineError>((pass, frame))
    };
    // Cables too wide for the network to see (a camera much closer): at half the size,
    // and at a quarter if the field asks again (docs/CAMERAS.md).
    while pass.too_wide {
        k *= 0.5;
        (pass, frame) = again(&pass, k, k > MIN_CORRECTION)?;
    }
    // Nothing found at the working scale: once more smaller, kept if it finds any
    // (cables too wide to score at this one leave no width to correct by).
    if k == 1.0 && pass.segmentation.cables.is_empty() && job.params.rescales_empty() {
        let smaller = f64::from(job.params.empty_rescale);
        let (second, at) = again(&pass, smaller, false)?;
        if second.segmentation.cables.is_empty() {
            pass.timings = second.timings;
        } else {
            (pass, frame, k) = (second, at, smaller);
        }
    }
    // Cables far wider or thinner than the engine's lengths suit (a closer or farther
    // camera): once more at the scale that makes them nominal (docs/CAMERAS.md).
    let corrected = pass
        .segmentation
        .width_correction(&frame, job.params)
        .map(|c| (k * c).clamp(MIN_CORRECTION, MAX_CORRECTION))
        .filter(|&next| next != k);
    // At the scale one kind of cable asks for, another may be lost (a power cable
    // among signal wires): the first pass's cables that this scale does not suit, that
    // start at an end this pass left without a cable, or that have no end (enlarged:
    // two thin wires side by side whose gap widens; shrunk: a pale cable across the
    // frame, blurred into its board), are taken in, and a wire this scale made too
    // thin to follow gives way to the first pass's. Where a shrunk pass lost cables
    // (not merely walked one astray), the masks keep the first pass's width: the thin
    // cables set the scene's scale, the wide ones are wide cables.
    let mut mixed_mask_scale = None;
    if let Some(next) = corrected {
        let shrinks = next < k;
        k = next;
        let (second, at) = again(&pass, k, false)?;
        let earlier = std::mem::replace(&mut pass, second);
        frame = at;
        let scale = earlier.segmentation.working_scale;
        let Ends {
            points,
            confidences,
        } = &mut pass.ends;
        let taken = pass.segmentation.adopt_lost(
            points,
            confidences,
            earlier.segmentation,
            (&earlier.ends.points, &earlier.ends.confidences),
            job.params,
        );
        if taken > 0 && shrinks {
            mixed_mask_scale = Some(pass.segmentation.working_scale / scale);
        }
    }
    // Masks as wide as the cables read. Wide cables read sub-linearly, so shrunk
    // photos' cables still read wider than nominal: their masks follow whatever is left,
    // never narrower; thin ones enlarged keep `mask_width_px`; at the first pass's
    // scale masks follow only a width off by more than `mask_width_tolerance`
    // (docs/CAMERAS.md).
    let (params, found) = (job.params, &pass.segmentation);
    let mask_scale = if let Some(scale) = mixed_mask_scale {
        scale
    } else if k < 1.0 {
        found.mask_correction(&frame, params, 1.0).max(1.0)
    } else if k > 1.0 {
        1.0
    } else {
        found.mask_correction(&frame, params, params.mask_width_tolerance)
    };
    pass.segmentation.mask_scale = mask_scale;
    let Pass {
        segmentation,
        ends,
        network_ran,
        timings: pass_timings,
        ..
    } = pass;
    let t = Instant::now();
    let mask_width = segmentation.mask_width(job.params.mask_width_px);
    let mask = render::render_mask(&segmentation, job.mask, mask_width);
    let overlay = job.overlay.then(|| render::overlay(&photo, &segmentation));
    let mask_ms = ms(t);
    let t = Instant::now();
    let (mask_png, overlay_png) = if job.encode {
        (
            Some(mask_png(&mask)?),
            overlay.as_ref().map(rgb_png).transpose()?,
        )
    } else {
        (None, None)
    };
    let encode_ms = ms(t);
    let timings = Timings {
        decode: decode_ms + pass_timings.decode,
        mask: mask_ms,
        encode: encode_ms,
        total: ms(started),
        ..pass_timings
    };
    Ok(Output {
        network_ran,
        segmentation,
        ends,
        mask,
        mask_png,
        overlay_png,
        timings,
    })
}

/// The network and the engine on the photo at one working size, the cables and ends
/// mapped back to the photo's pixels.
struct Pass {
    segmentation: Segmentation,
    ends: Ends,
    network_ran: bool,
    /// The network's field at half the working size says the cables are too wide for
    /// it at this one ([`engine::too_wide_for_the_field`]); only when asked to probe.
    too_wide: bool,
    /// The engine's stages, `endpoints`, and `decode` = the resampling.
    timings: Timings,
}

impl Pass {
    /// The pass at `frame`; with `probe` (and a cable-field network whose field sees
    /// little cable) the network also looks at half that size, to tell cables too wide
    /// for it.
    fn run(
        job: &Job<'_>,
        photo: &RgbImage,
        frame: WorkingFrame,
        probe: bool,
    ) -> Result<Self, PipelineError> {
        let t = Instant::now();
        let resampled = frame.resample(photo);
        // A dim photo is brightened, by one gain for the network's source and the
        // engine's image, and a soft one sharpened (docs/CAMERAS.md).
        let params = frame.params(job.params);
        let gain = exposure::gain(&resampled, params.exposure_level, params.exposure_max_gain);
        let lit = exposure::apply(&resampled, gain);
        let image = sharpness::apply(&lit, &params);
        let resample_ms = ms(t);
        // An enlarged photo reaches the network from its own pixels: enlarging it and
        // shrinking it again into the network's input blurs what the network sees.
        let (lit_photo, own);
        let source: &RgbImage = if frame.enlarges() {
            lit_photo = exposure::apply(photo, gain);
            own = sharpness::apply(&lit_photo, &params);
            &own
        } else {
            &image
        };
        let probe = probe && params.probes_wide_cables();
        let detect = |network: &dyn EndpointDetector| {
            let t = Instant::now();
            let seen = network.detect_as(source, frame.working)?;
            let too_wide = match &seen.field {
                Some(full) if probe && engine::field_may_miss_wide_cables(full) => {
                    let half = frame.working.map(|v| (v / 2).max(1));
                    let coarse = network.detect_as(source, half)?;
                    coarse.field.is_some_and(|half| {
                        engine::too_wide_for_the_field(full, &half, params.wide_field_ratio)
                    })
                }
                _ => false,
            };
            Ok::<_, DetectError>((seen, too_wide, ms(t)))
        };
        let (seen, over) = match job.network {
            // The network on a second thread while SLIC runs here (module docs).
            Some(network) if job.overlap => std::thread::scope(|scope| {
                let thread = scope.spawn(move || detect(network));
                let over = engine::oversegment(&image, &params, job.deadline);
                match thread.join() {
                    Ok(seen) => (Some(seen), over),
                    Err(panic) => std::panic::resume_unwind(panic),
                }
            }),
            network => (
                network.map(detect),
                engine::oversegment(&image, &params, job.deadline),
            ),
        };
        let (seen, too_wide, network_ms) = match seen.transpose()? {
            Some((seen, too_wide, network_ms)) => (Some(seen), too_wide, network_ms),
            None => (None, false, 0.0),
        };
        let over = over?;
        let network_ran = seen.is_some();
        let ends = match (job.ends, &seen) {
            (Some(points), _) => Ends::given(
                &points
                    .iter()
                    .map(|&p| frame.working_point(p))
                    .collect::<Vec<_>>(),
            ),
            (None, Some(seen)) => Ends::detected(&seen.ends),
            (None, None) => return Err(PipelineError::NoEnds(NO_ENDS)),
        };
        let field = seen.as_ref().and_then(|s| s.field.as_ref());
        let mut segmentation = engine::segment_oversegmented(
            &image,
            over,
            &ends.points,
            &ends.confidences,
            field,
            &params,
            job.deadline,
        )?;
        let ends = match (job.ends, seen) {
            (Some(points), _) => Ends::given(points),
            (None, seen) => {
                let mut ends = ends;
                // One terminal peak for two twins' terminals: the second is an end too.
                for (point, beside) in segmentation.twin_ends() {
                    ends.points.push(point);
                    ends.confidences.push(ends.confidences[beside]);
                }
                // Weaker terminal peaks where a cable stops are its ends too.
                let candidates = seen.map(|s| s.candidates).unwrap_or_default();
                let points: Vec<[f64; 2]> = candidates.iter().map(|d| d.point).collect();
                for i in segmentation.confirm_ends(
                    &points,
                    params.end_confirm_px,
                    params.border_margin_px,
                ) {
                    ends.points.push(points[i]);
                    ends.confidences.push(candidates[i].confidence);
                }
                Ends {
                    points: ends.points.iter().map(|&p| frame.photo_point(p)).collect(),
                    ..ends
                }
            }
        };
        let segmentation = segmentation.into_photo(&frame);
        Ok(Self {
            timings: Timings {
                decode: resample_ms,
                endpoints: network_ms,
                ..segmentation.timings
            },
            segmentation,
            ends,
            network_ran,
            too_wide,
        })
    }
}

/// Encodes a mask as PNG.
pub fn mask_png(mask: &Mask) -> Result<Vec<u8>, PipelineError> {
    match mask {
        Mask::Gray(img) => png_bytes(
            img.as_raw(),
            img.width(),
            img.height(),
            ExtendedColorType::L8,
        ),
        Mask::Rgb(img) => rgb_png(img),
    }
}

/// Encodes an RGB picture as PNG.
pub fn rgb_png(img: &RgbImage) -> Result<Vec<u8>, PipelineError> {
    png_bytes(
        img.as_raw(),
        img.width(),
        img.height(),
        ExtendedColorType::Rgb8,
    )
}

/// Raw 8-bit pixels as PNG, with fast compression (masks compress well anyway).
fn png_bytes(
    raw: &[u8],
    width: u32,
    height: u32,
    kind: ExtendedColorType,
) -> Result<Vec<u8>, PipelineError> {
    let mut out = Vec::new();
    png::PngEncoder::new_with_quality(&mut out, png::CompressionType::Fast, png::FilterType::Sub)
        .write_image(raw, width, height, kind)
        .map_err(|e| PipelineError::Encode(e.to_string()))?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detect::Perception;

    #[test]
    fn a_png_that_cannot_be_written_is_an_error_not_an_empty_mask() {
        // A zero-sized picture: the PNG encoder refuses it.
        let err = png_bytes(&[], 0, 0, ExtendedColorType::L8).unwrap_err();
        assert!(matches!(err, PipelineError::Encode(_)), "{err}");
    }

    #[test]
    fn a_photo_too_small_to_enlarge_enough_is_refused_in_its_own_size() {
        let params = Params::default();
        let run_on = |bytes: &[u8]| {
            run(&Job {
                bytes,
                ends: Some(&[]),
                network: None,
                params: &params,
                max_pixels: u64::MAX,
                mask: MaskKind::Binary,
                overlay: false,
                encode: true,
                deadline: Deadline::NONE,
                overlap: false,
            })
        };
        let tiny = rgb_png(&RgbImage::from_pixel(3, 40, image::Rgb([200, 200, 200]))).unwrap();
        let err = run_on(&tiny).unwrap_err();
        let message = err.to_string();
        assert!(
            matches!(
                err,
                PipelineError::Engine(EngineError::PhotoTooSmall {
                    width: 3,
                    height: 40,
                    ..
                })
            ),
            "{message}"
        );
        assert!(message.starts_with("photo 3x40 is too small"), "{message}");
        // Four pixels a side reach the engine's sixteen.
        let small = rgb_png(&RgbImage::from_pixel(4, 4, image::Rgb([200, 200, 200]))).unwrap();
        let out = run_on(&small);
        assert!(out.is_ok(), "{:?}", out.err());
    }

    /// Two 8 px cables on a plain background, at the working size (640x480), so the
    /// engine sees the decoded photo itself.
    fn two_cables() -> crate::synth::Scene {
        crate::synth::scene(&crate::synth::SceneSpec {
            width: 640,
            height: 480,
            cables: 2,
            cable_width: 8.0,
            background: crate::synth::Background::Plain,
            seed: 3,
        })
    }

    #[test]
    fn given_ends_run_every_stage_but_detection() {
        let scene = two_cables();
        let bytes = rgb_png(&scene.image).unwrap();
        let ends = scene.ends();
        let params = Params::default();
        let out = run(&Job {
            bytes: &bytes,
            ends: Some(&ends),
            network: None,
            params: &params,
            max_pixels: u64::MAX,
            mask: MaskKind::Labels,
            overlay: true,
            encode: true,
            deadline: Deadline::NONE,
            overlap: false,
        })
        .unwrap();
        // The same cables as the engine on the decoded photo (PNG is lossless).
        let direct = engine::segment(&scene.image, &ends, &params).unwrap();
        assert_eq!(out.segmentation.cables, direct.cables);
        assert!(!direct.cables.is_empty());
        assert_eq!(out.ends.confidences, vec![1.0; ends.len()]);
        assert!(out.mask_png.is_some() && out.overlay_png.is_some());
        let t = out.timings;
        assert_eq!((t.endpoints, t.queue), (0.0, 0.0));
        assert!(t.decode > 0.0 && t.superpixels > 0.0 && t.encode > 0.0);
        assert!(t.total >= t.decode + t.superpixels + t.mask + t.encode);
    }

    /// Sees the given ends and, as weaker candidates, the given candidates.
    struct Sees(Vec<[f64; 2]>, Vec<[f64; 2]>);

    impl EndpointDetector for Sees {
        fn detect_as(&self, _: &RgbImage, _: [u32; 2]) -> Result<Perception, DetectError> {
            let found = |points: &[[f64; 2]], confidence| {
                points
                    .iter()
                    .map(|&point| crate::detect::Detection { point, confidence })
                    .collect()
            };
            Ok(Perception {
                ends: found(&self.0, 0.9),
                candidates: found(&self.1, 0.1),
                field: None,
            })
        }
    }

    #[test]
    fn a_weak_peak_where_a_cable_stops_is_reported_as_its_end() {
        let scene = two_cables();
        let bytes = rgb_png(&scene.image).unwrap();
        // The network saw one end of the first cable only weakly, and a weak peak on
        // the bare background.
        let mut ends = scene.terminals();
        let missed = ends.remove(1);
        let decoy = [20.0 + missed[0] / 4.0, 400.0];
        let params = Params::default();
        let run_with = |network: &Sees| {
            run(&Job {
                bytes: &bytes,
                ends: None,
                network: Some(network),
                params: &params,
                max_pixels: u64::MAX,
                mask: MaskKind::Binary,
                overlay: false,
                encode: false,
                deadline: Deadline::NONE,
                overlap: false,
            })
        };
        let out = run_with(&Sees(ends.clone(), vec![decoy, missed])).unwrap();
        assert_eq!(out.ends.points.len(), ends.len() + 1, "{:?}", out.ends);
        assert_eq!(out.ends.points.last(), Some(&missed));
        assert_eq!(out.ends.confidences.last(), Some(&0.1));
        let cable = out.segmentation.end_cables.last().copied().flatten();
        assert_eq!(
            cable, out.segmentation.end_cables[0],
            "the first cable's other end"
        );
        // The cables are those found without the candidates.
        let alone = run_with(&Sees(ends, Vec::new())).unwrap();
        assert_eq!(
            out.segmentation.cables.len(),
            alone.segmentation.cables.len()
        );
    }
}
