//! ONNX Runtime back end: the shared library is loaded at run time (`load-dynamic`),
//! and each worker gets a session of its own, since `Session::run` needs `&mut`.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

use image::RgbImage;
use ort::session::Session;
use ort::session::builder::GraphOptimizationLevel;
use ort::value::TensorRef;

use crate::engine::resample::{Kernel, weights};

use super::output::{self, Decoding, Letterbox, YoloLayout};
use super::{DetectError, DetectorConfig, EndpointDetector, ModelKind, Perception, field, locate};

/// The size a photo is fed to the network at.
#[derive(Debug, Clone, Copy, PartialEq)]
enum InputSize {
    /// The model declares its width and height: the photo is letterboxed into them.
    Fixed([usize; 2]),
    /// The model takes any multiple of `stride`: the photo is scaled by `scale`
    /// whatever its size and aspect ratio (portrait or landscape alike), then padded.
    Dynamic {
        /// Input pixels per photo pixel: the configured input's for a 640x480 photo.
        scale: f64,
        /// Both sides are padded to a multiple of this.
        stride: usize,
    },
}

impl InputSize {
    /// The size declared by `session`'s first input (`[1, 3, H, W]`, a dimension < 1
    /// being free), else the configured size's scale at the model kind's stride. An
    /// input of another rank or channel count, or with one side fixed and the other
    /// free, cannot be fed: a one-line error naming the shape.
    fn of(session: &Session, config: &DetectorConfig) -> Result<Self, String> {
        let declared = session
            .inputs()
            .first()
            .and_then(|input| input.dtype().tensor_shape())
            .map(|shape| shape.to_vec())
            .unwrap_or_default();
        let free = |d: i64| d < 1;
        match declared[..] {
            [_, c, _, _] if c > 0 && c != 3 => Err(format!(
                "the model's input {declared:?} has {c} channels; it must take RGB ([1, 3, H, W])"
            )),
            [_, _, h, w] if h > 0 && w > 0 => Ok(Self::Fixed([w as usize, h as usize])),
            // The configured input size is meant for a 640x480 photo; working images
            // of other sizes are scaled alike.
            [_, _, h, w] if free(h) && free(w) => Ok(Self::Dynamic {
                scale: ((config.model_input_width * config.model_input_height) as f64
                    / crate::engine::REFERENCE_PIXELS)
                    .sqrt(),
                stride: config.model_kind.stride(),
            }),
            _ => Err(format!(
                "the model's input {declared:?} is not [1, 3, H, W] with both sides fixed or both free; export it so"
            )),
        }
    }

    /// How a `width` x `height` photo fits.
    fn fit(self, width: u32, height: u32) -> Letterbox {
        match self {
            Self::Fixed(input) => Letterbox::fit(width, height, input),
            Self::Dynamic { scale, stride } => Letterbox::fit_scaled(width, height, scale, stride),
        }
    }
}

/// A model run by ONNX Runtime on the CPU.
pub struct OnnxDetector {
    sessions: Vec<Mutex<Session>>,
    next: AtomicUsize,
    kind: ModelKind,
    input: InputSize,
    /// Decoded down to the lower of the two thresholds.
    decoding: Decoding,
    /// Lowest confidence of an end (the rest are candidates).
    threshold: f32,
    /// How a YOLO model lays out its boxes (from its metadata).
    layout: YoloLayout,
}

impl std::fmt::Debug for OnnxDetector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OnnxDetector")
            .field("sessions", &self.sessions.len())
            .field("kind", &self.kind)
            .field("input", &self.input)
            .field("layout", &self.layout)
            .finish()
    }
}

impl OnnxDetector {
    /// Loads ONNX Runtime (once per process) and `sessions` copies of the model, each
    /// using `config.ort_threads` threads, and runs each once on a grey image.
    pub fn load(config: &DetectorConfig, sessions: usize) -> Result<Self, DetectError> {
        config.validate().map_err(DetectError::Settings)?;
        let environment = runtime(config.ort_library.as_deref())?;
        let model = locate::first_file(&locate::candidates(&config.model))
            .map_err(|e| DetectError::Model {
                path: config.model.clone(),
                message: format!("{e}; set --model / ARIADNE_MODEL"),
            })?
            .clone();
        let config = &DetectorConfig {
            model,
            ..config.clone()
        };
        let sessions = (0..sessions.max(1))
            .map(|_| build_session(environment, config).map(Mutex::new))
            .collect::<Result<Vec<_>, _>>()?;
        let input = InputSize::of(
            &sessions[0].lock().unwrap_or_else(PoisonError::into_inner),
            config,
        )
        .map_err(|message| DetectError::Model {
            path: config.model.clone(),
            message,
        })?;
        let layout = {
            let session = sessions[0].lock().unwrap_or_else(PoisonError::into_inner);
            let metadata = session.metadata().ok();
            let entry = |key: &str| metadata.as_ref().and_then(|m| m.custom(key));
            YoloLayout::from_metadata(entry("end2end").as_deref(), entry("args").as_deref())
        };
        let detector = Self {
            sessions,
            layout,
            next: AtomicUsize::new(0),
            kind: config.model_kind,
            input,
            decoding: Decoding {
                threshold: config.detect_threshold.min(config.detect_confirm_threshold),
                nms_radius_px: config.detect_nms_px,
                min_cable: config.detect_min_cable,
            },
            threshold: config.detect_threshold,
        };
        // Every session runs once now: a bad model fails here, and no worker's first
        // request pays for ONNX Runtime's lazy set-up.
        let grey = RgbImage::from_pixel(
            config.model_input_width as u32,
            config.model_input_height as u32,
            image::Rgb([128, 128, 128]),
        );
        for session in &detector.sessions {
            let mut session = session.lock().unwrap_or_else(PoisonError::into_inner);
            detector
                .run(&mut session, &grey, [grey.width(), grey.height()])
                .map_err(|e| DetectError::Model {
                    path: config.model.clone(),
                    message: format!("warm-up inference: {e}"),
                })?;
        }
        Ok(detector)
    }

    /// Resizes `image` into the input of a `size` photo, runs `session` and decodes its
    /// output in the pixels of `size`.
    fn run(
        &self,
        session: &mut Session,
        image: &RgbImage,
        size: [u32; 2],
    ) -> Result<Perception, DetectError> {
        let fit = self.input.fit(size[0], size[1]);
        let fit = match self.kind {
            ModelKind::Yolo => fit.centred(),
            ModelKind::Field | ModelKind::Heatmap => fit,
        };
        let tensor = input_tensor(image, fit, self.kind.padding_grey());
        let [w, h] = fit.input;
        let input = TensorRef::from_array_view(([1usize, 3, h, w], tensor.as_slice()))
            .map_err(|e| DetectError::Inference(e.to_string()))?;
        let outputs = session
            .run(ort::inputs![input])
            .map_err(|e| DetectError::Inference(e.to_string()))?;
        let (shape, data) = outputs[0]
            .try_extract_tensor::<f32>()
            .map_err(|e| DetectError::Output(e.to_string()))?;
        let ends_only = |ends| Perception {
            ends,
            ..Perception::default()
        };
        let seen = match self.kind {
            ModelKind::Field => field::decode(shape, data, fit, self.decoding),
            ModelKind::Heatmap => output::heatmap(shape, data, fit, self.decoding).map(ends_only),
            ModelKind::Yolo => {
                output::yolo(shape, data, fit, self.decoding, self.layout).map(ends_only)
            }
        };
        seen.map(|s| s.split_candidates(self.threshold))
    }

    /// A free session if there is one, else a wait for the next in turn.
    fn session(&self) -> MutexGuard<'_, Session> {
        for s in &self.sessions {
            if let Ok(guard) = s.try_lock() {
                return guard;
            }
        }
        let i = self.next.fetch_add(1, Ordering::Relaxed) % self.sessions.len();
        // A panic during a run leaves the session itself usable.
        self.sessions[i]
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
    }
}

impl EndpointDetector for OnnxDetector {
    fn detect_as(&self, image: &RgbImage, size: [u32; 2]) -> Result<Perception, DetectError> {
        self.run(&mut self.session(), image, size)
    }
}

/// One session of the model with the configured threads (no spinning: the workers
/// share the CPUs with the rest of the pipeline).
fn build_session(
    environment: &ort::environment::Environment,
    config: &DetectorConfig,
) -> Result<Session, DetectError> {
    let model_error = |message: String| DetectError::Model {
        path: config.model.clone(),
        message,
    };
    let mut builder = Session::builder(environment).map_err(|e| model_error(e.to_string()))?;
    builder = builder
        .with_optimization_level(GraphOptimizationLevel::Level3)
        .map_err(|e| model_error(e.to_string()))?;
    builder = builder
        .with_intra_threads(config.ort_threads)
        .map_err(|e| model_error(e.to_string()))?;
    builder = builder
        .with_inter_threads(1)
        .map_err(|e| model_error(e.to_string()))?;
    builder = builder
        .with_intra_op_spinning(false)
        .map_err(|e| model_error(e.to_string()))?;
    builder
        .commit_from_file(&config.model)
        .map_err(|e| model_error(e.to_string()))
}

/// The photo resized into the network input as planar RGB in [0, 1], padding grey.
///
/// Separable triangle filter stretched by the reduction factor (antialiased bilinear,
/// as PIL, which made the training inputs, and `image` do), computed in f32 straight
/// into the planar tensor: no intermediate 8-bit image.
fn input_tensor(image: &RgbImage, fit: Letterbox, pad: f32) -> Vec<f32> {
    let [w, h] = fit.input;
    let [left, top] = fit.offset;
    let [rw, rh] = fit.resized().map(|v| v as usize);
    let (sw, sh) = (image.width() as usize, image.height() as usize);
    let columns = weights(sw, rw, Kernel::Triangle);
    let rows = weights(sh, rh, Kernel::Triangle);
    // Horizontal pass: every source row, resized columns, one plane per channel.
    let mut narrow = vec![0.0f32; 3 * sh * rw];
    for (y, src) in image.as_raw().chunks_exact(sw * 3).enumerate() {
        for (x, (first, weights)) in columns.iter().enumerate() {
            let mut acc = [0.0f32; 3];
            for (k, &wk) in weights.iter().enumerate() {
                let px = &src[(first + k) * 3..(first + k) * 3 + 3];
                for c in 0..3 {
                    acc[c] += wk * px[c] as f32;
                }
            }
            for (c, v) in acc.iter().enumerate() {
                narrow[c * sh * rw + y * rw + x] = v / 255.0;
            }
        }
    }
    // Vertical pass into the padded input, a whole row at a time.
    let mut tensor = vec![pad; 3 * w * h];
    for c in 0..3 {
        let plane = &narrow[c * sh * rw..(c + 1) * sh * rw];
        for (y, (first, weights)) in rows.iter().enumerate() {
            let row = c * w * h + (top + y) * w + left;
            let out = &mut tensor[row..row + rw];
            out.fill(0.0);
            for (k, &wk) in weights.iter().enumerate() {
                let src = &plane[(first + k) * rw..(first + k + 1) * rw];
                for (o, &v) in out.iter_mut().zip(src) {
                    *o += wk * v;
                }
            }
        }
    }
    tensor
}

/// Loads the ONNX Runtime library once per process and builds its environment.
fn runtime(
    configured: Option<&Path>,
) -> Result<&'static ort::environment::Environment, DetectError> {
    static ENVIRONMENT: std::sync::OnceLock<ort::environment::Environment> =
        std::sync::OnceLock::new();
    if let Some(env) = ENVIRONMENT.get() {
        return Ok(env);
    }
    let candidates = match configured {
        Some(path) => vec![path.to_owned()],
        None => locate::default_runtime_candidates(),
    };
    let library = locate::first_file(&candidates).map_err(|e| {
        DetectError::Runtime(format!(
            "{} {e}: run `make setup`, or point ORT_DYLIB_PATH / --ort-library at it",
            locate::RUNTIME_FILE
        ))
    })?;
    let environment = ort::init_from(library)
        .map_err(|e| DetectError::Runtime(e.to_string()))?
        .with_name("ariadne")
        .build()
        .map_err(|e| DetectError::Runtime(e.to_string()))?;
    Ok(ENVIRONMENT.get_or_init(|| environment))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resizing_matches_an_antialiased_bilinear_resize() {
        let image = RgbImage::from_fn(64, 48, |x, y| {
            image::Rgb([(x * 4) as u8, (y * 5) as u8, ((x * y) % 256) as u8])
        });
        let fit = Letterbox::fit(64, 48, [32, 24]);
        let ours = input_tensor(&image, fit, 0.5);
        let reference =
            image::imageops::resize(&image, 32, 24, image::imageops::FilterType::Triangle);
        for (i, px) in reference.pixels().enumerate() {
            for c in 0..3 {
                let got = ours[c * 32 * 24 + i] * 255.0;
                assert!(
                    (got - px[c] as f32).abs() <= 1.0,
                    "pixel {i} channel {c}: {got} vs {}",
                    px[c]
                );
            }
        }
    }

    #[test]
    fn input_tensor_is_planar_and_padded() {
        let mut image = RgbImage::from_pixel(4, 2, image::Rgb([255, 0, 51]));
        image.put_pixel(3, 1, image::Rgb([0, 255, 0]));
        let fit = Letterbox::fit(4, 2, [4, 4]);
        let t = input_tensor(&image, fit, 0.5);
        assert_eq!(t.len(), 3 * 16);
        assert_eq!([t[0], t[16], t[32]], [1.0, 0.0, 0.2]);
        assert_eq!(
            [t[7], t[16 + 7], t[32 + 7]],
            [0.0, 1.0, 0.0],
            "pixel (3, 1)"
        );
        assert!(
            t[8..16].iter().all(|&v| v == 0.5),
            "rows 2 and 3 are padding"
        );
    }

    #[test]
    fn a_centred_fit_pads_both_sides_with_the_given_grey() {
        let image = RgbImage::from_pixel(4, 2, image::Rgb([255, 255, 255]));
        let fit = Letterbox::fit(4, 2, [4, 4]).centred();
        assert_eq!(fit.offset, [0, 1]);
        let grey = ModelKind::Yolo.padding_grey();
        let t = input_tensor(&image, fit, grey);
        let rows: Vec<f32> = (0..4).map(|y| t[y * 4]).collect();
        assert_eq!(
            rows,
            [grey, 1.0, 1.0, grey],
            "row 0 and row 3 pad, 1 and 2 hold the photo"
        );
    }
}
