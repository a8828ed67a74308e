//! Decoding of detector outputs into cable ends, independent of the runtime: a keypoint
//! heatmap (the bundled model) or an ultralytics YOLO detection tensor.

use super::{DetectError, Detection};

/// How the photo was fitted into the network input: resized by `scale_x`, `scale_y`
/// and placed at the input's top-left corner (the rest is padding).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Letterbox {
    /// Network input width and height, pixels.
    pub input: [usize; 2],
    /// Photo width and height, pixels.
    pub image: [u32; 2],
    /// Input pixels per photo pixel, horizontally.
    pub scale_x: f64,
    /// Input pixels per photo pixel, vertically.
    pub scale_y: f64,
}

impl Letterbox {
    /// The fit of a `width` x `height` photo into an `input` (width, height) network
    /// input that keeps the aspect ratio.
    pub fn fit(width: u32, height: u32, input: [usize; 2]) -> Self {
        let s = (input[0] as f64 / width as f64).min(input[1] as f64 / height as f64);
        let rw = ((width as f64 * s).round() as usize).clamp(1, input[0]);
        let rh = ((height as f64 * s).round() as usize).clamp(1, input[1]);
        Self {
            input,
            image: [width, height],
            scale_x: rw as f64 / width as f64,
            scale_y: rh as f64 / height as f64,
        }
    }

    /// The fit of a `width` x `height` photo into an input of its own shape: the photo
    /// scaled by `s`, and the input padded on the right and bottom to multiples of
    /// `stride` (a fully convolutional model of any size).
    pub fn fit_scaled(width: u32, height: u32, s: f64, stride: usize) -> Self {
        let pad = |v: u32| {
            let scaled = ((v as f64 * s).round() as usize).max(1);
            scaled.div_ceil(stride) * stride
        };
        Self::fit(width, height, [pad(width), pad(height)])
    }

    /// Size of the resized photo inside the input.
    pub fn resized(&self) -> [u32; 2] {
        [
            (self.image[0] as f64 * self.scale_x).round() as u32,
            (self.image[1] as f64 * self.scale_y).round() as u32,
        ]
    }

    /// Input coordinates to photo coordinates; `None` in the padding.
    fn to_image(self, x: f64, y: f64) -> Option<[f64; 2]> {
        let (px, py) = (x / self.scale_x, y / self.scale_y);
        let (w, h) = (self.image[0] as f64, self.image[1] as f64);
        (px < w + 0.5 && py < h + 0.5).then(|| [px.clamp(0.0, w - 1.0), py.clamp(0.0, h - 1.0)])
    }
}

/// Thresholds shared by both decoders.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decoding {
    /// Lowest confidence kept.
    pub threshold: f32,
    /// Two ends closer than this (photo pixels) are one: the more confident is kept.
    pub nms_radius_px: f64,
}

/// Decodes a keypoint heatmap `[1, C, H', W']`: channel 0 is the probability of an end
/// in each cell; with C = 3, channels 1 and 2 are the end's x and y offset inside the
/// cell in [0, 1] (else the cell centre is used). Ends are cells at or above the
/// threshold that are the maximum of their 3x3 neighbourhood, then suppressed by radius.
pub fn heatmap(
    shape: &[i64],
    data: &[f32],
    fit: Letterbox,
    decoding: Decoding,
) -> Result<Vec<Detection>, DetectError> {
    let [1, channels @ (1 | 3), gh, gw] = *shape else {
        return Err(DetectError::Output(format!(
            "a heatmap model must output [1, 1 or 3, H, W], got {shape:?}"
        )));
    };
    let (gh, gw) = (gh as usize, gw as usize);
    if data.len() != channels as usize * gh * gw || gh == 0 || gw == 0 {
        return Err(DetectError::Output(format!(
            "heatmap of shape {shape:?} holds {} values",
            data.len()
        )));
    }
    let (stride_x, stride_y) = (
        fit.input[0] as f64 / gw as f64,
        fit.input[1] as f64 / gh as f64,
    );
    let plane = |c: usize| &data[c * gh * gw..(c + 1) * gh * gw];
    let heat = plane(0);
    let mut found = Vec::new();
    for gy in 0..gh {
        for gx in 0..gw {
            let p = heat[gy * gw + gx];
            if p < decoding.threshold || !local_maximum(heat, gw, gh, gx, gy) {
                continue;
            }
            let (ox, oy) = if channels == 3 {
                (plane(1)[gy * gw + gx] as f64, plane(2)[gy * gw + gx] as f64)
            } else {
                (0.5, 0.5)
            };
            let x = (gx as f64 + ox.clamp(0.0, 1.0)) * stride_x;
            let y = (gy as f64 + oy.clamp(0.0, 1.0)) * stride_y;
            if let Some(point) = fit.to_image(x, y) {
                found.push(Detection {
                    point,
                    confidence: p,
                });
            }
        }
    }
    Ok(suppress(found, decoding.nms_radius_px))
}

fn local_maximum(heat: &[f32], w: usize, h: usize, x: usize, y: usize) -> bool {
    let p = heat[y * w + x];
    (y.saturating_sub(1)..(y + 2).min(h))
        .all(|ny| (x.saturating_sub(1)..(x + 2).min(w)).all(|nx| heat[ny * w + nx] <= p))
}

/// Decodes an ultralytics YOLO detection output `[1, 4 + classes, N]` (or its transpose
/// `[1, N, 4 + classes]`): box centre and size in input pixels, then one score per
/// class. Each box's centre becomes an end with its best class score.
pub fn yolo(
    shape: &[i64],
    data: &[f32],
    fit: Letterbox,
    decoding: Decoding,
) -> Result<Vec<Detection>, DetectError> {
    let [1, a, b] = *shape else {
        return Err(DetectError::Output(format!(
            "a YOLO model must output [1, 4 + classes, N], got {shape:?}"
        )));
    };
    let (a, b) = (a as usize, b as usize);
    if data.len() != a * b || a.min(b) < 5 {
        return Err(DetectError::Output(format!(
            "YOLO output of shape {shape:?} holds {} values or has no class scores",
            data.len()
        )));
    }
    // Ultralytics exports attributes first; a transposed export has more rows than columns.
    let transposed = a > b;
    let (attributes, boxes) = if transposed { (b, a) } else { (a, b) };
    let at = |attr: usize, i: usize| {
        if transposed {
            data[i * b + attr]
        } else {
            data[attr * b + i]
        }
    };
    let mut found = Vec::new();
    for i in 0..boxes {
        let confidence = (4..attributes).map(|c| at(c, i)).fold(f32::MIN, f32::max);
        if confidence < decoding.threshold {
            continue;
        }
        if let Some(point) = fit.to_image(at(0, i) as f64, at(1, i) as f64) {
            found.push(Detection { point, confidence });
        }
    }
    Ok(suppress(found, decoding.nms_radius_px))
}

/// Greedy suppression: most confident first, dropping any end within `radius` of a kept one.
fn suppress(mut found: Vec<Detection>, radius: f64) -> Vec<Detection> {
    found.sort_by(|a, b| b.confidence.total_cmp(&a.confidence));
    let mut kept: Vec<Detection> = Vec::with_capacity(found.len());
    for d in found {
        let near = |k: &Detection| {
            (k.point[0] - d.point[0]).powi(2) + (k.point[1] - d.point[1]).powi(2) <= radius * radius
        };
        if !kept.iter().any(near) {
            kept.push(d);
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_free_input_takes_the_photo_shape_at_the_same_scale() {
        let landscape = Letterbox::fit_scaled(640, 480, 0.5, 4);
        assert_eq!(landscape.input, [320, 240]);
        // Portrait: the same scale (half), not squeezed into a landscape box.
        let portrait = Letterbox::fit_scaled(480, 640, 0.5, 4);
        assert_eq!(portrait.input, [240, 320]);
        assert_eq!(portrait.scale_x, 0.5);
        // Sides that are no multiple of the stride are padded up to one.
        let odd = Letterbox::fit_scaled(1000, 300, 0.506, 32);
        assert_eq!(odd.input, [512, 160]);
        assert_eq!(odd.resized(), [512, 154]);
    }

    use super::*;

    const DECODING: Decoding = Decoding {
        threshold: 0.3,
        nms_radius_px: 12.0,
    };

    #[test]
    fn letterbox_keeps_the_aspect_ratio() {
        let fit = Letterbox::fit(640, 480, [320, 240]);
        assert_eq!((fit.scale_x, fit.scale_y), (0.5, 0.5));
        let wide = Letterbox::fit(1000, 250, [320, 240]);
        assert_eq!(wide.resized(), [320, 80]);
        assert_eq!(wide.to_image(160.0, 200.0), None, "padding maps to nothing");
    }

    /// A 3-channel 6x8 heatmap for a 64x48 photo seen at 32x24 (cells of 8 photo px).
    fn heat_tensor(cells: &[(usize, usize, f32, f32, f32)]) -> Vec<f32> {
        let (gh, gw) = (6, 8);
        let mut data = vec![0.0; 3 * gh * gw];
        for &(x, y, p, ox, oy) in cells {
            data[y * gw + x] = p;
            data[gh * gw + y * gw + x] = ox;
            data[2 * gh * gw + y * gw + x] = oy;
        }
        data
    }

    #[test]
    fn heatmap_peaks_become_ends_with_offsets() {
        let data = heat_tensor(&[
            (2, 1, 0.9, 0.5, 0.25),
            (3, 1, 0.5, 0.0, 0.0), // beside a stronger peak: not a maximum
            (6, 4, 0.4, 1.0, 0.0),
            (0, 5, 0.2, 0.5, 0.5), // below the threshold
        ]);
        let fit = Letterbox::fit(64, 48, [32, 24]);
        let ends = heatmap(&[1, 3, 6, 8], &data, fit, DECODING).unwrap();
        assert_eq!(ends.len(), 2);
        // Cell (2, 1) with offset (0.5, 0.25): input (10, 5) → photo (20, 10).
        assert_eq!(ends[0].point, [20.0, 10.0]);
        assert_eq!(ends[0].confidence, 0.9);
        assert_eq!(ends[1].point, [56.0, 32.0]);
    }

    #[test]
    fn heatmap_without_offsets_uses_cell_centres_and_suppresses_neighbours() {
        let mut data = vec![0.0; 6 * 8];
        data[8 + 2] = 0.8;
        data[8 + 4] = 0.7; // 16 px away: kept with radius 12, merged with radius 20
        let fit = Letterbox::fit(64, 48, [32, 24]);
        let ends = heatmap(&[1, 1, 6, 8], &data, fit, DECODING).unwrap();
        assert_eq!(
            ends.iter().map(|e| e.point).collect::<Vec<_>>(),
            [[20.0, 12.0], [36.0, 12.0]]
        );
        let wide = Decoding {
            nms_radius_px: 20.0,
            ..DECODING
        };
        assert_eq!(heatmap(&[1, 1, 6, 8], &data, fit, wide).unwrap().len(), 1);
    }

    #[test]
    fn malformed_outputs_are_errors() {
        let fit = Letterbox::fit(64, 48, [32, 24]);
        assert!(heatmap(&[1, 2, 6, 8], &[0.0; 96], fit, DECODING).is_err());
        assert!(heatmap(&[1, 1, 6, 8], &[0.0; 10], fit, DECODING).is_err());
        assert!(yolo(&[1, 4, 10], &[0.0; 40], fit, DECODING).is_err());
        assert!(yolo(&[1, 6, 10, 1], &[0.0; 60], fit, DECODING).is_err());
    }

    /// YOLO output for boxes (cx, cy, w, h, score class 0, score class 1), input pixels.
    fn yolo_tensor(boxes: &[[f32; 6]], transposed: bool) -> (Vec<i64>, Vec<f32>) {
        let n = boxes.len();
        if transposed {
            (
                vec![1, n as i64, 6],
                boxes.iter().flatten().copied().collect(),
            )
        } else {
            let data = (0..6)
                .flat_map(|a| boxes.iter().map(move |b| b[a]))
                .collect();
            (vec![1, 6, n as i64], data)
        }
    }

    #[test]
    fn yolo_box_centres_become_ends_in_either_layout() {
        let mut boxes = vec![[0.0; 6]; 8];
        boxes[1] = [100.0, 50.0, 10.0, 10.0, 0.1, 0.9];
        boxes[5] = [103.0, 52.0, 12.0, 12.0, 0.6, 0.0]; // overlaps box 1: suppressed
        boxes[6] = [300.0, 200.0, 10.0, 10.0, 0.5, 0.2];
        let fit = Letterbox::fit(1280, 960, [640, 480]);
        for transposed in [false, true] {
            let (shape, data) = yolo_tensor(&boxes, transposed);
            let ends = yolo(&shape, &data, fit, DECODING).unwrap();
            let points: Vec<_> = ends.iter().map(|e| (e.point, e.confidence)).collect();
            assert_eq!(points, [([200.0, 100.0], 0.9), ([600.0, 400.0], 0.5)]);
        }
    }
}
