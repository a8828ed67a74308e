//! Presets and overrides.

use super::*;

#[test]
fn presets_are_valid_and_published() {
    for name in PRESET_NAMES {
        Params::preset(name).unwrap().validate().unwrap();
    }
    let c = Params::preset("clutter").unwrap();
    assert_eq!((c.n_segments, c.compactness, c.sigma), (1500, 10.0, 1.0));
    // The paper segments a photo at one scale.
    assert_eq!(Params::preset("paper").unwrap().width_tolerance, 100.0);
    let d = Params::preset("default").unwrap();
    assert_eq!((d.n_segments, d.compactness, d.sigma), (2000, 20.0, 1.0));
    assert!(matches!(
        Params::preset("nope"),
        Err(EngineError::UnknownPreset(..))
    ));
}

#[test]
fn overrides_replace_and_validate() {
    let base = Params::default();
    let o: Map<String, Value> = serde_json::from_str(r#"{"n_segments": 1200}"#).unwrap();
    assert_eq!(base.with_overrides(&o).unwrap().n_segments, 1200);
    for bad in [
        r#"{"n_segments": 0}"#,
        r#"{"sigma": -1}"#,
        r#"{"bogus": 1}"#,
        r#"{"kappa": "x"}"#,
    ] {
        let o: Map<String, Value> = serde_json::from_str(bad).unwrap();
        assert!(base.with_overrides(&o).is_err(), "{bad} accepted");
    }
}
