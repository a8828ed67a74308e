//! Decoding the bundled cable-field model's output `[1, 6, H', W']` (H', W' the input
//! over the stride): channel 0 cable probability, 1 terminal probability, 2-3 the
//! terminal's x/y offset in its cell, 4-5 cos 2θ and sin 2θ of the cable's direction.
//! A terminal peak with no cable beside it ([`Decoding::min_cable`]) is not an end: on
//! backgrounds the network never saw, texture fires the terminal head more often than
//! the cable head (docs/ACCURACY.md).

use super::output::{Decoding, END_CABLE_REACH, Letterbox, heatmap};
use super::{DetectError, Perception};
use crate::engine::CableField;

/// Channels of a cable-field output.
pub const CHANNELS: i64 = 6;

/// The terminals (decoded as a 3-channel heatmap from channels 1-3) and the cable field
/// in photo coordinates.
pub fn decode(
    shape: &[i64],
    data: &[f32],
    fit: Letterbox,
    decoding: Decoding,
) -> Result<Perception, DetectError> {
    let [1, CHANNELS, gh, gw] = *shape else {
        return Err(DetectError::Output(format!(
            "a cable-field model must output [1, {CHANNELS}, H, W], got {shape:?}"
        )));
    };
    let (gh, gw) = (gh as usize, gw as usize);
    let cells = gh * gw;
    if gh == 0 || gw == 0 || data.len() != CHANNELS as usize * cells {
        return Err(DetectError::Output(format!(
            "cable field of shape {shape:?} holds {} values",
            data.len()
        )));
    }
    let plane = |c: usize| &data[c * cells..(c + 1) * cells];
    let mut ends = heatmap(
        &[1, 3, gh as i64, gw as i64],
        &data[cells..4 * cells],
        fit,
        decoding,
    )?;
    // One cell spans input / grid input pixels, each 1 / scale photo pixels.
    let cell_px = [
        (fit.input[0] as f64 / gw as f64 / fit.scale_x) as f32,
        (fit.input[1] as f64 / gh as f64 / fit.scale_y) as f32,
    ];
    let field = CableField {
        width: gw,
        height: gh,
        cell_px,
        cable: plane(0).iter().map(|p| p.clamp(0.0, 1.0)).collect(),
        orientation: plane(4)
            .iter()
            .zip(plane(5))
            .map(|(&c, &s)| [c.clamp(-1.0, 1.0), s.clamp(-1.0, 1.0)])
            .collect(),
    };
    ends.retain(|e| {
        let [x, y] = e.point.map(|v| v as f32);
        field.max_cable_near(x, y, END_CABLE_REACH) >= decoding.min_cable
    });
    Ok(Perception {
        ends,
        candidates: Vec::new(),
        field: Some(field),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 640x480 photo seen at 320x240: its letterbox and an empty 80x60 output
    /// (8 photo px per cell), set with [`Output::set`].
    struct Output {
        fit: Letterbox,
        data: Vec<f32>,
    }

    const GRID: [usize; 2] = [80, 60];

    impl Output {
        fn new() -> Self {
            Self {
                fit: Letterbox::fit(640, 480, [320, 240]),
                data: vec![0.0; CHANNELS as usize * GRID[0] * GRID[1]],
            }
        }

        fn set(&mut self, channel: usize, x: usize, y: usize, value: f32) {
            self.data[(channel * GRID[1] + y) * GRID[0] + x] = value;
        }

        fn decode(&self, threshold: f32, min_cable: f32) -> Result<Perception, DetectError> {
            let decoding = Decoding {
                threshold,
                nms_radius_px: 10.0,
                min_cable,
            };
            let shape = [1, CHANNELS, GRID[1] as i64, GRID[0] as i64];
            decode(&shape, &self.data, self.fit, decoding)
        }
    }

    #[test]
    fn decodes_terminals_and_field_in_photo_coordinates() {
        let mut out = Output::new();
        out.set(0, 10, 20, 0.9); // cable
        out.set(1, 30, 40, 0.8); // terminal, offset (0.5, 0.25)
        out.set(2, 30, 40, 0.5);
        out.set(3, 30, 40, 0.25);
        out.set(4, 10, 20, -1.0); // vertical: cos 2θ = -1
        let seen = out.decode(0.5, 0.0).unwrap();
        assert_eq!(seen.ends.len(), 1);
        assert_eq!(seen.ends[0].point, [30.5 * 8.0, 40.25 * 8.0]);
        let field = seen.field.unwrap();
        assert_eq!(field.cell_px, [8.0, 8.0]);
        assert!((field.cable_at(10.5 * 8.0, 20.5 * 8.0) - 0.9).abs() < 1e-6);
        assert_eq!(field.orientation_at(10.5 * 8.0, 20.5 * 8.0), [-1.0, 0.0]);
        let cells = GRID[0] * GRID[1];
        let decoding = Decoding {
            threshold: 0.5,
            nms_radius_px: 10.0,
            min_cable: 0.0,
        };
        assert!(decode(&[1, 3, 60, 80], &out.data[..3 * cells], out.fit, decoding).is_err());
    }

    #[test]
    fn a_terminal_peak_with_no_cable_beside_it_is_not_an_end() {
        let mut out = Output::new();
        // Two terminal peaks; a cable two cells from the first only.
        out.set(1, 30, 40, 0.8);
        out.set(1, 60, 10, 0.8);
        out.set(0, 32, 42, 0.5);
        let seen = out.decode(0.5, 0.2).unwrap();
        assert_eq!(seen.ends.len(), 1);
        assert_eq!(seen.ends[0].point, [30.0 * 8.0, 40.0 * 8.0]);
        assert_eq!(out.decode(0.5, 0.0).unwrap().ends.len(), 2, "the rule off");
    }
}
