//! The allowed range of every numeric parameter, in one table, and the validation that
//! reads it.

use serde_json::Value;

use super::Params;
use crate::engine::EngineError;

impl Params {
    /// Checks every numeric field against its range in [`RANGES`].
    pub fn validate(&self) -> Result<(), EngineError> {
        let fields = self.fields();
        for &(name, min, max) in RANGES {
            let value = fields.get(name).and_then(Value::as_f64).unwrap_or(f64::NAN);
            if !(value.is_finite() && (min..=max).contains(&value)) {
                return Err(EngineError::InvalidParameter {
                    name,
                    value: crate::engine::error::compact(value),
                    expected: format!("{min} ..= {max}"),
                });
            }
        }
        Ok(())
    }
}

/// Allowed range, inclusive, of every numeric parameter: the one table
/// [`Params::validate`] reads.
pub const RANGES: &[(&str, f64, f64)] = &[
    ("n_segments", 16.0, 20_000.0),
    ("compactness", 0.01, 1000.0),
    ("sigma", 0.0, 10.0),
    ("slic_iterations", 1.0, 50.0),
    ("min_size_factor", 0.0, 1.0),
    ("exposure_level", 1.0, 255.0),
    ("exposure_max_gain", 1.0, 16.0),
    ("sharp_edge_px", 0.1, 10.0),
    ("sharpen_amount", 0.0, 5.0),
    ("working_pixels", 20_000.0, 4_000_000.0),
    ("max_upscale", 1.0, 4.0),
    ("nominal_width_px", 1.0, 100.0),
    ("width_tolerance", 1.0, 100.0),
    ("mask_width_tolerance", 1.0, 100.0),
    ("wide_field_ratio", 1.0, 100.0),
    ("empty_rescale", 0.25, 1.0),
    ("hist_bins", 1.0, 16.0),
    ("neighbourhood_order", 1.0, 8.0),
    ("jump_order", 1.0, 12.0),
    ("c_visual", 0.01, 1000.0),
    ("c_distance", 0.01, 1000.0),
    ("max_step_px", 1.0, 1000.0),
    ("kappa", 0.0, 100.0),
    ("max_turn_deg", 1.0, 180.0),
    ("heading_span_px", 1.0, 500.0),
    ("close_radius_px", 1.0, 500.0),
    ("close_max_lateral_steps", 0.0, 100.0),
    ("close_min_steps", 0.0, 100.0),
    ("min_similarity", 0.0, 1.0),
    ("min_contrast", 0.0, 1.0),
    ("model_rate", 0.0, 1.0),
    ("border_margin_px", 0.0, 200.0),
    ("max_steps", 1.0, 10_000.0),
    ("unconfirmed_factor", 0.0, 1.0),
    ("border_factor", 0.0, 1.0),
    ("lost_factor", 0.0, 1.0),
    ("join_radius_px", 0.0, 1000.0),
    ("end_confirm_px", 0.0, 100.0),
    ("min_cable_score", 0.0, 1.0),
    ("min_cable_length_px", 0.0, 10_000.0),
    ("closed_min_length_px", 0.0, 10_000.0),
    ("smoothing", 0.0, 1e6),
    ("knot_spacing_px", 2.0, 10_000.0),
    ("polyline_step_px", 0.1, 100.0),
    ("refine_radius_px", 1.0, 100.0),
    ("mask_width_px", 0.0, 200.0),
    ("contrast_saturation", 0.1, 500.0),
    ("far_contrast_factor", 0.0, 100.0),
    ("border_outward_cos", 0.0, 1.0),
    ("stopped_seed_reach", 0.0, 10.0),
    ("stopped_border_reach", 0.0, 10.0),
    ("seed_region_steps", 0.0, 2.0),
    ("quality_visual_exponent", 0.0, 10.0),
    ("quality_contrast_exponent", 0.0, 10.0),
    ("join_min_length", 0.0, 10.0),
    ("pair_max_shared", 0.0, 1.0),
    ("twin_min_share", 0.0, 1.0),
    ("twin_max_cost", 0.0, 10.0),
    ("end_weight", 0.01, 1e4),
    ("far_end_trim", 0.0, 10.0),
    ("border_exit_steps", 0.0, 100.0),
    ("refine_passes", 0.0, 10.0),
    ("refine_profile_step_px", 0.1, 10.0),
    ("refine_profile_stride", 1.0, 100.0),
    ("refine_min_background_de", 0.0, 200.0),
    ("refine_min_width_px", 0.0, 100.0),
    ("border_min_contrast", 0.0, 200.0),
    ("border_min_crossing_px", 1.0, 10_000.0),
    ("border_max_crossing_px", 1.0, 10_000.0),
    ("border_max_start_px", 1.0, 10_000.0),
    ("border_seed_confidence", 0.0, 1.0),
    ("border_min_score", 0.0, 1.0),
    ("border_min_steps", 0.0, 1000.0),
    ("border_max_covered", 0.0, 1.0),
    ("min_ridge_share", 0.0, 1.0),
    ("ended_min_ridge_share", 0.0, 1.0),
    ("field_floor", 0.0, 1.0),
    ("field_alignment_weight", 0.0, 1.0),
    ("field_min_cable", 0.0, 1.0),
    ("field_gap_min_cable", 0.0, 1.0),
    ("field_trust", 0.0, 1.0),
    ("field_recolour_steps", 0.0, 100.0),
    ("field_collar_head", 0.0, 1.0),
    ("field_close_min_alignment", 0.0, 1.0),
    ("close_own_min_alignment", 0.0, 1.0),
    ("field_through_factor", 0.0, 1.0),
    ("field_opening_weight", 0.0, 1.0),
    ("quality_field_exponent", 0.0, 10.0),
    ("field_level", 0.0, 1.0),
    ("field_min_share", 0.0, 1.0),
    ("field_border_min_score", 0.0, 1.0),
    ("field_border_sure_level", 0.0, 1.0),
    ("field_min_cable_score", 0.0, 1.0),
    ("field_weak_cable_score", 0.0, 1.0),
    ("field_short_min_score", 0.0, 1.0),
    ("field_short_widths", 0.0, 1000.0),
    ("field_pair_short_min_score", 0.0, 1.0),
    ("field_pair_short_widths", 0.0, 1000.0),
    ("field_reached_floor", 0.0, 1.0),
    ("field_orphan_level", 0.0, 1.0),
    ("field_orphan_min_steps", 1.0, 1000.0),
    ("field_trace_level", 0.0, 1.0),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_numeric_field_has_one_range() {
        let fields = Params::default().fields();
        for (name, value) in &fields {
            let ranges = RANGES.iter().filter(|r| r.0 == name).count();
            match value {
                Value::Number(_) => assert_eq!(ranges, 1, "`{name}` needs one entry in RANGES"),
                _ => assert_eq!(ranges, 0, "`{name}` is not numeric"),
            }
        }
        assert!(
            RANGES.iter().all(|r| fields.contains_key(r.0)),
            "stale RANGES entry"
        );
        for (name, min, max) in RANGES {
            assert!(min <= max, "{name}");
        }
    }
}
