//! Unit enums written as their serde names: the words reports, the API and
//! the CLI use.
use serde::Serialize;

/// Writes `value`, a unit enum, as its serde name.
pub(crate) fn serde_word(value: &impl Serialize, f: &mut std::fmt::Formatter) -> std::fmt::Result {
    let word = serde_json::to_value(value).map_err(|_| std::fmt::Error)?;
    f.write_str(word.as_str().ok_or(std::fmt::Error)?)
}

/// `Display` as the serde name, for unit enums.
macro_rules! display_as_word {
    ($($t:ty),+ $(,)?) => {$(
        impl std::fmt::Display for $t {
            fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                $crate::words::serde_word(self, f)
            }
        }
    )+};
}
pub(crate) use display_as_word;
