//! Benchmarks on real dataset images (640x480): each stage alone, endpoint detection,
//! and the whole `segment` path from JPEG bytes to the mask PNG, single-threaded; the
//! whole path also on the same photos enlarged to 2, 5 and 12 MP.
//!
//! Run: `cargo bench --bench pipeline` (reads the dataset from `$ARIADNE_DATASET`,
//! default `../shared/datasets/cables`).

#![allow(clippy::unwrap_used)] // test and benchmark code: a failure should panic

use ariadne_dlo::detect::{DetectorConfig, EndpointDetector, OnnxDetector};
use ariadne_dlo::engine::color::LabImage;
use ariadne_dlo::engine::graph::Graph;
use ariadne_dlo::engine::resample;
use ariadne_dlo::engine::superpixels::{SlicSettings, slic};
use ariadne_dlo::engine::{self, MaskKind, Params, exposure, render, sharpness};
use ariadne_dlo::pipeline;
use ariadne_dlo::{decode, eval};

fn main() {
    divan::main();
}

struct Fixture {
    jpeg: Vec<u8>,
    image: image::RgbImage,
    ends: Vec<[f64; 2]>,
}

fn fixtures() -> Vec<Fixture> {
    let samples =
        eval::load_dataset(&eval::default_dataset_dir()).expect("dataset (set ARIADNE_DATASET)");
    samples
        .iter()
        .filter(|s| s.set == "simple")
        .step_by(8)
        .map(|s| {
            let jpeg = std::fs::read(&s.image).expect("readable image");
            let image = decode::decode_rgb(&jpeg, u64::MAX).expect("decodable image");
            let ends = eval::terminal_ends(&s.cables, image.width(), image.height());
            Fixture { jpeg, image, ends }
        })
        .collect()
}

/// The bundled cable-field network, ONNX Runtime on one thread: resize, inference,
/// decoding of the terminals and the field. Needs `make setup`.
#[divan::bench(sample_count = 50)]
fn cable_field_640x480(bencher: divan::Bencher) {
    let fx = fixtures();
    let detector = single_thread_detector();
    let mut i = 0;
    bencher.bench_local(|| {
        i += 1;
        detector.detect(&fx[i % fx.len()].image).unwrap()
    });
}

/// The service's path for a photo alone: decode → network (ends and field) → engine →
/// mask PNG.
#[divan::bench(sample_count = 30)]
fn segment_with_detection_640x480(bencher: divan::Bencher) {
    let detector = single_thread_detector();
    bench_segment(bencher, Some(&detector));
}

/// Photo sizes of the camera benchmark: 0.3, 2, 5 and 12 MP (4:3).
const CAMERA_SIZES: [(u32, u32); 4] = [(640, 480), (1632, 1224), (2592, 1944), (4000, 3000)];

/// A photo alone at each of [`CAMERA_SIZES`]: development photos enlarged (Catmull-Rom)
/// and saved as JPEG of quality 90, through the whole service path (decode, resampling
/// to the working size, network, engine, mask at the photo's size, PNG).
#[divan::bench(args = CAMERA_SIZES, sample_count = 10)]
fn segment_with_detection_by_size(bencher: divan::Bencher, size: (u32, u32)) {
    let photos: Vec<Vec<u8>> = fixtures()
        .iter()
        .take(3)
        .map(|f| {
            let big = image::imageops::resize(
                &f.image,
                size.0,
                size.1,
                image::imageops::FilterType::CatmullRom,
            );
            let mut jpeg = Vec::new();
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 90)
                .encode_image(&big)
                .unwrap();
            jpeg
        })
        .collect();
    let detector = single_thread_detector();
    let p = Params::default();
    let mut i = 0;
    bencher.bench_local(|| {
        i += 1;
        service_path(&photos[i % photos.len()], None, Some(&detector), &p)
    });
}

/// Decode → engine (true ends, no field) → binary mask → PNG.
#[divan::bench(sample_count = 30)]
fn segment_640x480(bencher: divan::Bencher) {
    bench_segment(bencher, None);
}

/// The pipeline (decode → ends → engine → binary mask PNG) over the fixtures in turn,
/// with ends from `detector`, or the true ones without.
fn bench_segment(bencher: divan::Bencher, detector: Option<&dyn EndpointDetector>) {
    let fx = fixtures();
    let p = Params::default();
    let mut i = 0;
    bencher.bench_local(|| {
        let f = &fx[i % fx.len()];
        i += 1;
        let ends = detector.is_none().then_some(&f.ends[..]);
        service_path(&f.jpeg, ends, detector, &p)
    });
}

/// The service's path for one photo: the pipeline to a binary mask PNG.
fn service_path(
    bytes: &[u8],
    ends: Option<&[[f64; 2]]>,
    network: Option<&dyn EndpointDetector>,
    params: &Params,
) -> pipeline::Output {
    pipeline::run(&pipeline::Job {
        bytes,
        ends,
        network,
        params,
        max_pixels: u64::MAX,
        mask: MaskKind::Binary,
        overlay: false,
        encode: true,
        deadline: ariadne_dlo::engine::Deadline::NONE,
        overlap: true,
    })
    .unwrap()
}

/// The engine's first step: Lab planes, blurred.
fn blurred_lab(img: &image::RgbImage, p: &Params) -> LabImage {
    let mut lab = LabImage::from_rgb(img.as_raw(), img.width() as usize, img.height() as usize);
    lab.gaussian_blur(p.sigma);
    lab
}

/// The binary mask of `seg` as PNG bytes, as the service sends it.
fn binary_mask_png(seg: &engine::Segmentation, p: &Params) -> Vec<u8> {
    pipeline::mask_png(&render::render_mask(seg, MaskKind::Binary, p.mask_width_px)).unwrap()
}

/// The bundled model on one ONNX Runtime thread.
fn single_thread_detector() -> OnnxDetector {
    let config = DetectorConfig {
        ort_threads: 1,
        ..DetectorConfig::default()
    };
    OnnxDetector::load(&config, 1).expect("bundled model (run `make setup`)")
}

fn settings(p: &Params) -> SlicSettings {
    SlicSettings {
        n_segments: p.n_segments,
        compactness: p.compactness,
        iterations: p.slic_iterations,
        min_size_factor: p.min_size_factor,
    }
}

#[divan::bench(sample_count = 30)]
fn decode_jpeg_640x480(bencher: divan::Bencher) {
    let fx = fixtures();
    bencher.bench_local(|| decode::decode_rgb(&fx[0].jpeg, u64::MAX).unwrap());
}

/// The exposure correction of a dim photo (values times 0.3): the gain read from the
/// photo and applied (a well-exposed photo pays the reading alone).
#[divan::bench(sample_count = 30)]
fn exposure_640x480(bencher: divan::Bencher) {
    let fx = fixtures();
    let p = Params::default();
    let mut dim = fx[0].image.clone();
    dim.iter_mut()
        .for_each(|v| *v = (f32::from(*v) * 0.3) as u8);
    bencher.bench_local(|| {
        let gain = exposure::gain(&dim, p.exposure_level, p.exposure_max_gain);
        exposure::apply(&dim, gain).into_owned()
    });
}

/// Working sizes a second pass resamples a 640x480 photo to: enlarged 1.64 times
/// (thin rods, Catmull-Rom) and shrunk to 0.8 (wide cables, triangle).
const RESAMPLED_SIZES: [(u32, u32); 2] = [(1051, 788), (512, 384)];

/// A development photo resampled to each of [`RESAMPLED_SIZES`].
#[divan::bench(args = RESAMPLED_SIZES, sample_count = 30)]
fn resample_640x480(bencher: divan::Bencher, size: (u32, u32)) {
    let fx = fixtures();
    bencher.bench_local(|| resample::resize_to(&fx[0].image, size.0, size.1));
}

/// The sharpness reading of a development photo (sharp: it pays the reading alone).
#[divan::bench(sample_count = 30)]
fn sharpness_reading_640x480(bencher: divan::Bencher) {
    let fx = fixtures();
    bencher.bench_local(|| sharpness::edge_width(&fx[0].image));
}

/// The sharpness correction of a soft photo (blurred by 1.5 px): read and sharpened.
#[divan::bench(sample_count = 30)]
fn sharpen_soft_640x480(bencher: divan::Bencher) {
    let fx = fixtures();
    let p = Params::default();
    let soft = sharpness::blurred(&fx[0].image, 1.5);
    bencher.bench_local(|| sharpness::apply(&soft, &p).into_owned());
}

/// Lab conversion, blur and SLIC.
#[divan::bench(sample_count = 30)]
fn superpixels_640x480(bencher: divan::Bencher) {
    let fx = fixtures();
    let p = Params::default();
    bencher.bench_local(|| slic(&blurred_lab(&fx[0].image, &p), &settings(&p)));
}

/// SLIC alone (k-means and connectivity) on a prepared Lab image.
#[divan::bench(sample_count = 30)]
fn slic_640x480(bencher: divan::Bencher) {
    let fx = fixtures();
    let p = Params::default();
    let img = &fx[0].image;
    let lab = blurred_lab(img, &p);
    bencher.bench_local(|| slic(&lab, &settings(&p)));
}

/// Lab conversion and blur alone.
#[divan::bench(sample_count = 30)]
fn lab_and_blur_640x480(bencher: divan::Bencher) {
    let fx = fixtures();
    let p = Params::default();
    bencher.bench_local(|| blurred_lab(&fx[0].image, &p));
}

#[divan::bench(sample_count = 30)]
fn graph_640x480(bencher: divan::Bencher) {
    let fx = fixtures();
    let p = Params::default();
    let img = &fx[0].image;
    let lab = blurred_lab(img, &p);
    let sp = slic(&lab, &settings(&p));
    bencher.bench_local(|| Graph::build(&sp, img.as_raw(), &lab, p.hist_bins));
}

#[divan::bench(sample_count = 30)]
fn mask_and_png_640x480(bencher: divan::Bencher) {
    let fx = fixtures();
    let p = Params::default();
    let seg = engine::segment(&fx[0].image, &fx[0].ends, &p).unwrap();
    bencher.bench_local(|| binary_mask_png(&seg, &p));
}
