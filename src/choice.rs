//! Settings that take one of a few named values (`--model-kind`, `--log-format`): one
//! parser, one error message shape.

/// The value named `text` among `choices` (name, value), or an error that lists the
/// names; `what` names the setting in the message.
pub fn parse<T: Copy>(text: &str, choices: &[(&str, T)], what: &str) -> Result<T, String> {
    choices
        .iter()
        .find(|(name, _)| *name == text)
        .map(|&(_, value)| value)
        .ok_or_else(|| {
            let names: Vec<&str> = choices.iter().map(|c| c.0).collect();
            format!(
                "unknown {what} `{text}` (expected one of: {})",
                names.join(", ")
            )
        })
}

#[cfg(test)]
mod tests {
    #[test]
    fn names_map_to_values_and_errors_list_them() {
        let choices = [("a", 1), ("b", 2)];
        assert_eq!(super::parse("b", &choices, "letter"), Ok(2));
        let err = super::parse("c", &choices, "letter").unwrap_err();
        assert!(err.contains("letter `c`") && err.contains("a, b"), "{err}");
    }
}
