//! Decoding of detector outputs into cable ends, independent of the runtime: a keypoint
//! heatmap (the bundled model) or an ultralytics YOLO detection tensor.

use super::{DetectError, Detection};

/// How the photo was fitted into the network input: resized by `scale_x`, `scale_y`
/// and placed `offset` pixels from the input's top-left corner (the rest is padding).
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
    /// Left and top padding, input pixels (0 unless [`Letterbox::centred`]).
    pub offset: [usize; 2],
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
            offset: [0, 0],
        }
    }

    /// The same fit with the photo centred in the input, as ultralytics letterboxes
    /// (half the padding on each side, the odd pixel right and below).
    pub fn centred(self) -> Self {
        let [rw, rh] = self.resized();
        let half = |input: usize, resized: u32| (input - resized as usize) / 2;
        Self {
            offset: [half(self.input[0], rw), half(self.input[1], rh)],
            ..self
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
        let px = (x - self.offset[0] as f64) / self.scale_x;
        let py = (y - self.offset[1] as f64) / self.scale_y;
        let (w, h) = (self.image[0] as f64, self.image[1] as f64);
        let inside = |v: f64, size: f64| v > -0.5 && v < size + 0.5;
        (inside(px, w) && inside(py, h)).then(|| [px.clamp(0.0, w - 1.0), py.clamp(0.0, h - 1.0)])
    }
}

/// Thresholds shared by both decoders.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decoding {
    /// Lowest confidence kept.
    pub threshold: f32,
    /// Two ends closer than this (photo pixels) are one: the more confident is kept.
    pub nms_radius_px: f64,
    /// With a cable field: an end with no cell of at least this cable probability
    /// within [`END_CABLE_REACH`] cells is dropped (an end lies where a cable does).
    pub min_cable: f32,
}

/// Cells around an end searched for its cable ([`Decoding::min_cable`]): two cells, 16
/// photo pixels at the working size, about two cable widths.
pub const END_CABLE_REACH: usize = 2;

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

/// How an ultralytics YOLO export lays out its detections.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum YoloLayout {
    /// The raw head: `[1, 4 + classes, N]` (or its transpose), box centre and size in
    /// input pixels, then one score per class.
    Raw,
    /// Already suppressed (`nms=True` exports, end-to-end heads such as YOLO26's):
    /// `[1, N, 6]`, rows of x1, y1, x2, y2, score, class in input pixels.
    EndToEnd,
}

impl YoloLayout {
    /// The layout ultralytics records in the model's metadata: its `end2end` entry,
    /// or `'nms': True` in its export `args`. A model without them is taken as raw.
    pub fn from_metadata(end2end: Option<&str>, args: Option<&str>) -> Self {
        let nms = args.is_some_and(|a| a.replace(' ', "").contains("'nms':True"));
        if end2end.is_some_and(|e| e.eq_ignore_ascii_case("true")) || nms {
            Self::EndToEnd
        } else {
            Self::Raw
        }
    }
}

/// Decodes an ultralytics YOLO detection output of the given layout. Each box's centre
/// becomes an end with its (best class) score. Scores outside 0..=1 mean the layout is
/// not the one assumed: an error, not ends at nonsense places.
pub fn yolo(
    shape: &[i64],
    data: &[f32],
    fit: Letterbox,
    decoding: Decoding,
    layout: YoloLayout,
) -> Result<Vec<Detection>, DetectError> {
    let [1, a, b] = *shape else {
        return Err(DetectError::Output(format!(
            "a YOLO model must output [1, 4 + classes, N] or [1, N, 6], got {shape:?}"
        )));
    };
    let (a, b) = (a as usize, b as usize);
    let too_few = match layout {
        YoloLayout::Raw => a.min(b) < 5,
        YoloLayout::EndToEnd => b < 6,
    };
    if data.len() != a * b || too_few {
        return Err(DetectError::Output(format!(
            "YOLO output of shape {shape:?} holds {} values or has no scores",
            data.len()
        )));
    }
    // Ultralytics exports the raw head attributes first; a transposed export has more
    // rows than columns. End-to-end rows are boxes.
    let transposed = layout == YoloLayout::EndToEnd || a > b;
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
        let (confidence, centre) = match layout {
            YoloLayout::Raw => (
                (4..attributes).map(|c| at(c, i)).fold(f32::MIN, f32::max),
                [at(0, i), at(1, i)],
            ),
            YoloLayout::EndToEnd => (
                at(4, i),
                [(at(0, i) + at(2, i)) / 2.0, (at(1, i) + at(3, i)) / 2.0],
            ),
        };
        if !(0.0..=1.0).contains(&confidence) {
            return Err(DetectError::Output(format!(
                "YOLO output {shape:?} read as {layout:?} gives a score of {}: not that layout \
                 (an nms=True or end-to-end export must keep ultralytics' metadata)",
                crate::engine::compact(confidence as f64)
            )));
        }
        if confidence < decoding.threshold {
            continue;
        }
        if let Some(point) = fit.to_image(centre[0] as f64, centre[1] as f64) {
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
        min_cable: 0.0,
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
        assert!(yolo(&[1, 4, 10], &[0.0; 40], fit, DECODING, YoloLayout::Raw).is_err());
        for layout in [YoloLayout::Raw, YoloLayout::EndToEnd] {
            assert!(yolo(&[1, 6, 10, 1], &[0.0; 60], fit, DECODING, layout).is_err());
        }
        assert!(yolo(&[1, 10, 5], &[0.0; 50], fit, DECODING, YoloLayout::EndToEnd).is_err());
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
            let ends = yolo(&shape, &data, fit, DECODING, YoloLayout::Raw).unwrap();
            let points: Vec<_> = ends.iter().map(|e| (e.point, e.confidence)).collect();
            assert_eq!(points, [([200.0, 100.0], 0.9), ([600.0, 400.0], 0.5)]);
        }
    }

    #[test]
    fn end_to_end_rows_are_boxes_with_a_score_and_a_class() {
        // x1, y1, x2, y2, score, class in a centred 640x640 letterbox of a 1280x960 photo
        // (80 px of padding above and below).
        let boxes = [
            [95.0, 125.0, 105.0, 135.0, 0.9, 0.0],
            [290.0, 270.0, 310.0, 290.0, 0.5, 0.0],
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0], // an empty slot
        ];
        let fit = Letterbox::fit(1280, 960, [640, 640]).centred();
        let (shape, data) = yolo_tensor(&boxes, true);
        let ends = yolo(&shape, &data, fit, DECODING, YoloLayout::EndToEnd).unwrap();
        let points: Vec<_> = ends.iter().map(|e| (e.point, e.confidence)).collect();
        assert_eq!(points, [([200.0, 100.0], 0.9), ([600.0, 400.0], 0.5)]);
    }

    #[test]
    fn a_layout_misread_is_an_error_not_ends() {
        // An end-to-end output read as a transposed raw head: the class index (3) is
        // taken for a score.
        let boxes = [[95.0, 45.0, 105.0, 55.0, 0.9, 3.0]; 8];
        let (shape, data) = yolo_tensor(&boxes, true);
        let fit = Letterbox::fit(640, 480, [640, 480]);
        let err = yolo(&shape, &data, fit, DECODING, YoloLayout::Raw).unwrap_err();
        assert!(err.to_string().contains("score of 3:"), "{err}");
    }

    #[test]
    fn the_layout_is_read_from_ultralytics_metadata() {
        let raw = "{'batch': 1, 'nms': None, 'dynamic': False}";
        let nms = "{'batch': 1, 'nms': True, 'dynamic': False}";
        assert_eq!(
            YoloLayout::from_metadata(Some("False"), Some(raw)),
            YoloLayout::Raw
        );
        assert_eq!(
            YoloLayout::from_metadata(Some("False"), Some(nms)),
            YoloLayout::EndToEnd
        );
        assert_eq!(
            YoloLayout::from_metadata(Some("True"), None),
            YoloLayout::EndToEnd
        );
        assert_eq!(YoloLayout::from_metadata(None, None), YoloLayout::Raw);
    }
}
