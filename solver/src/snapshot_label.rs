//! What a snapshot shows ([`SnapshotLabel`]), written as one word: its serde
//! form, the API's `label` and the store's packed label.
use crate::case::StageKind;
use crate::protocol::EventKind;
use crate::words::display_as_word;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// Where a snapshot sits around an event: in the window before it (`near`),
/// the nearest before it (`before`), at it (`at`) or after it (`after`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EventWhen {
    Near,
    Before,
    At,
    After,
}

display_as_word!(EventWhen);

impl EventWhen {
    /// In the order a stage passes them.
    pub const ALL: [Self; 4] = [Self::Near, Self::Before, Self::At, Self::After];
}

/// A snapshot's label; its word is written by `Display` and read by
/// [`SnapshotLabel::parse`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SnapshotLabel {
    /// The relaxed start: `relaxed`.
    Relaxed,
    /// Along a stage, at regular spacing: the stage's key (`pull`, `release`,
    /// `hold`, `rotate`, `soft`).
    Stage(StageKind),
    /// A bend set: its tails let go once the pull has seated it: `set`.
    Set,
    /// Around an event: `{when}_{kind}` (`before_inversion`, `at_flip_back`, ...).
    Event(EventWhen, EventKind),
    /// The end of the program: `final`.
    Final,
    /// Where the case failed: `failure`.
    Failure,
    /// A sample in the runner's history, relabelled when an event's
    /// snapshots are taken from it (never kept as such): `sample`.
    Sample,
}

/// A word that is no snapshot label.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0:?} is not a snapshot label")]
pub struct UnknownLabel(pub String);

impl SnapshotLabel {
    /// Every label, in the order of a program: the start, the stages', the
    /// events', the end.
    pub fn all() -> Vec<Self> {
        let stages = StageKind::ALL.map(Self::Stage);
        let events =
            (EventKind::ALL.into_iter()).flat_map(|kind| EventWhen::ALL.map(|when| Self::Event(when, kind)));
        [Self::Relaxed]
            .into_iter()
            .chain(stages)
            .chain([Self::Set])
            .chain(events)
            .chain([Self::Final, Self::Failure, Self::Sample])
            .collect()
    }

    /// The label written as `word`.
    pub fn parse(word: &str) -> Result<Self, UnknownLabel> {
        (Self::all().into_iter())
            .find(|label| label.to_string() == word)
            .ok_or_else(|| UnknownLabel(word.to_string()))
    }

    /// The event a label is around, if any.
    pub fn event(self) -> Option<EventKind> {
        match self {
            Self::Event(_, kind) => Some(kind),
            _ => None,
        }
    }
}

impl std::fmt::Display for SnapshotLabel {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            Self::Relaxed => f.write_str("relaxed"),
            Self::Stage(kind) => write!(f, "{kind}"),
            Self::Set => f.write_str("set"),
            Self::Event(when, kind) => write!(f, "{when}_{kind}"),
            Self::Final => f.write_str("final"),
            Self::Failure => f.write_str("failure"),
            Self::Sample => f.write_str("sample"),
        }
    }
}

impl std::str::FromStr for SnapshotLabel {
    type Err = UnknownLabel;
    fn from_str(word: &str) -> Result<Self, UnknownLabel> {
        Self::parse(word)
    }
}

impl Serialize for SnapshotLabel {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for SnapshotLabel {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let word = std::borrow::Cow::<str>::deserialize(deserializer)?;
        Self::parse(&word).map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every label's word reads back as the label, and no two labels share
    /// a word.
    #[test]
    fn words_read_back_and_are_distinct() {
        let all = SnapshotLabel::all();
        let words: std::collections::HashSet<String> = all.iter().map(|l| l.to_string()).collect();
        assert_eq!(words.len(), all.len());
        for label in all {
            let json = serde_json::to_string(&label).unwrap();
            assert_eq!(json, format!("\"{label}\""));
            assert_eq!(serde_json::from_str::<SnapshotLabel>(&json).unwrap(), label);
        }
    }

    /// The words reports stored before the labels were typed.
    #[test]
    fn the_stored_words_read() {
        use EventKind::{FlipBack, Inversion};
        for (word, label) in [
            ("relaxed", SnapshotLabel::Relaxed),
            ("pull", SnapshotLabel::Stage(StageKind::Pull)),
            ("near_inversion", SnapshotLabel::Event(EventWhen::Near, Inversion)),
            (
                "before_inversion",
                SnapshotLabel::Event(EventWhen::Before, Inversion),
            ),
            ("at_inversion", SnapshotLabel::Event(EventWhen::At, Inversion)),
            (
                "after_flip_back",
                SnapshotLabel::Event(EventWhen::After, FlipBack),
            ),
            ("set", SnapshotLabel::Set),
            (
                "at_slip_through",
                SnapshotLabel::Event(EventWhen::At, EventKind::SlipThrough),
            ),
            ("final", SnapshotLabel::Final),
            ("failure", SnapshotLabel::Failure),
        ] {
            assert_eq!(SnapshotLabel::parse(word), Ok(label));
        }
        assert_eq!(
            SnapshotLabel::parse("at_knot"),
            Err(UnknownLabel("at_knot".to_string()))
        );
        assert!(serde_json::from_str::<SnapshotLabel>("\"inversion\"").is_err());
    }
}
