//! How the engine's width reading (`refine::refine`) scales with a closer camera:
//! the development photos' annotated centrelines read at 1x and on the central
//! 1/zoom of each photo enlarged back to its size (`ariadne eval --zoom`), with the
//! engine's blur and profile reach or others. A reading that scaled with the camera
//! would give a ratio of `zoom`.
//!
//! ```sh
//! cargo run --release --example width_reading -- [ZOOM] [REACH_PX] [SIGMA]
//! ```
//!
//! Defaults: zoom 2, the engine's `refine_radius_px` at 1x and that times `ZOOM`
//! on the zoomed photos unless `REACH_PX` is given, the engine's `sigma`.

use ariadne_dlo::engine::color::LabImage;
use ariadne_dlo::engine::geometry::median;
use ariadne_dlo::engine::{Params, refine, spline};
use ariadne_dlo::eval::{self, Camera, View};

/// `line` resampled every `step` pixels ([`spline::resample`]), the points within
/// `margin` of the border dropped.
fn densified(line: &[[f32; 2]], step: f32, size: (u32, u32), margin: f32) -> Vec<[f32; 2]> {
    let (w, h) = (size.0 as f32, size.1 as f32);
    let mut out = spline::resample(line, step);
    out.retain(|p| p[0] >= margin && p[1] >= margin && p[0] < w - margin && p[1] < h - margin);
    out
}

/// The width read along every centreline of `view` long enough to read.
fn widths(view: &View, params: &Params) -> Vec<f32> {
    let photo = image::load_from_memory(&view.bytes)
        .expect("the view's photo decodes")
        .into_rgb8();
    let (w, h) = photo.dimensions();
    let mut lab = LabImage::from_rgb(photo.as_raw(), w as usize, h as usize);
    lab.gaussian_blur(params.sigma);
    view.centrelines
        .iter()
        .map(|line| densified(line, params.polyline_step_px, view.size, 3.0))
        .filter(|line| line.len() >= 20)
        .filter_map(|line| refine::refine(&line, &lab, params).width_px)
        .collect()
}

fn arg(i: usize) -> Option<f32> {
    std::env::args()
        .nth(i)
        .map(|s| s.parse().expect("a number"))
}

fn main() {
    let zoom = arg(1).unwrap_or(2.0);
    let defaults = Params::default();
    let sigma = arg(3).unwrap_or(defaults.sigma);
    let reach = |z: f32| arg(2).unwrap_or(defaults.refine_radius_px * z);
    let at = |z: f32| Params {
        refine_radius_px: reach(z),
        sigma,
        ..defaults.clone()
    };
    let samples = eval::load_dataset(&eval::default_dataset_dir()).expect("the dataset");
    let (mut near, mut far, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
    for sample in samples.iter().filter(|s| s.set == "simple") {
        let camera = |zoom: f64| Camera {
            zoom,
            ..Camera::default()
        };
        let one = View::of(sample, camera(1.0)).expect("the photo");
        let closer = View::of(sample, camera(f64::from(zoom))).expect("the photo");
        let (mut a, mut b) = (widths(&one, &at(1.0)), widths(&closer, &at(zoom)));
        if let (Some(x), Some(y)) = (
            median(&mut a.clone(), f32::total_cmp),
            median(&mut b.clone(), f32::total_cmp),
        ) {
            ratios.push(y / x);
        }
        far.append(&mut a);
        near.append(&mut b);
    }
    let mid = |v: &mut Vec<f32>| median(v, f32::total_cmp).unwrap_or(f32::NAN);
    println!(
        "sigma {sigma}, reach {} / {} px: cables read {:.2} px at 1x and {:.2} px at {zoom}x \
         (median over cables); per photo, {zoom}x / 1x median {:.2}",
        reach(1.0),
        reach(zoom),
        mid(&mut far),
        mid(&mut near),
        mid(&mut ratios),
    );
}
