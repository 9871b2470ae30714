//! Unit enums written as their serde names: the words reports, the API and
//! the CLI use.
use serde::Serialize;

/// Writes `value`, a unit enum, as its serde name.
pub(crate) fn serde_word(value: &impl Serialize, f: &mut std::fmt::Formatter) -> std::fmt::Result {
    let word = serde_json::to_value(value).map_err(|_| std::fmt::Error)?;
    f.write_str(word.as_str().ok_or(std::fmt::Error)?)
}
